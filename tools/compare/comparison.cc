// The engine of `photopose compare` for single images (tools/compare/comparison.h): the solver
// variants, the Monte-Carlo mode and the dataset mode. One file past ~800 lines on purpose: both
// modes run the same solver variants and reduce their solves by the same file-local measures (Rms,
// Median, RmsNorm, the check residuals); each mode is a list of named steps.
#include "core/io/block_tables.h"
#include "tools/compare/comparison.h"

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <sstream>
#include <thread>

#include "core/collinearity.h"
#include "core/parallel.h"
#include "core/rotation.h"
#include "core/statistics.h"
#include "core/io/tables.h"
#include "core/io/csv.h"

namespace photopose::cli {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Root mean square of the values (NaN for none).
double Rms(const std::vector<double>& values) {
  if (values.empty()) return kNaN;
  double sum = 0.0;
  for (double v : values) sum += v * v;
  return std::sqrt(sum / static_cast<double>(values.size()));
}

double Mean(const std::vector<double>& values) {
  if (values.empty()) return kNaN;
  double sum = 0.0;
  for (double v : values) sum += v;
  return sum / static_cast<double>(values.size());
}

double Median(std::vector<double> values) {
  if (values.empty()) return kNaN;
  const size_t middle = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + middle, values.end());
  const double upper = values[middle];
  if (values.size() % 2 == 1) return upper;
  const double lower = *std::max_element(values.begin(), values.begin() + middle);
  return 0.5 * (lower + upper);
}

// RMS of the norms of 2-D residuals, pooled: sqrt(sum |r|^2 / count).
double RmsNorm(const std::vector<Eigen::Vector2d>& residuals) {
  if (residuals.empty()) return kNaN;
  double sum = 0.0;
  for (const auto& r : residuals) sum += r.squaredNorm();
  return std::sqrt(sum / static_cast<double>(residuals.size()));
}

bool SameExceptAxis(const SweepSetting& a, const SweepSetting& b, const std::string& axis) {
  if (a.scenario != b.scenario) return false;
  if (axis != "noise" && a.noise_px != b.noise_px) return false;
  if (axis != "outliers" && a.outlier_fraction != b.outlier_fraction) return false;
  if (axis != "control" && a.control_points != b.control_points) return false;
  if (axis != "initial" && (a.initial_error.position_m != b.initial_error.position_m ||
                            a.initial_error.angle_deg != b.initial_error.angle_deg))
    return false;
  return true;
}

// The design covariance threshold: success_sigmas * sqrt(trace C_pos), C = (J^T P J)^-1 at the
// true pose over the uncontaminated control observations. NaN when they do not determine the pose.
double SuccessThreshold(const ResectionInput& input, const std::vector<char>& is_outlier,
                        const ExteriorOrientation& truth, double success_sigmas) {
  Matrix6d normal = Matrix6d::Zero();
  int used = 0;
  for (size_t k = 0; k < input.points_in_ground.size(); ++k) {
    if (is_outlier[k]) continue;
    double xy[2];
    Eigen::Matrix<double, 2, 6, Eigen::RowMajor> J;
    if (!ProjectWithJacobians(truth.data(), input.points_in_ground[k].data(), input.focal_length,
                              xy, J.data(), nullptr, nullptr))
      continue;
    const double sigma = input.sigma.empty() || !(input.sigma[k] > 0.0) ? 1.0 : input.sigma[k];
    J /= sigma * (input.observation_units_per_unit.empty() ? 1.0
                                                           : input.observation_units_per_unit[k]);
    normal += J.transpose() * J;
    ++used;
  }
  if (used < 3) return kNaN;
  Eigen::LDLT<Matrix6d> ldlt(normal);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) return kNaN;
  const Matrix6d covariance = ldlt.solve(Matrix6d::Identity());
  return success_sigmas * std::sqrt(covariance.topLeftCorner<3, 3>().trace());
}

// What one solve of image `image` by solver `solver` shows against the truth: solved or why not,
// its errors, NEES, and the RMS of its clean control and check residuals. The paired differences
// to the reference solver are added by AddPairedDifferences.
SolveOutcome OutcomeOfSolve(const SweepSetting& setting, const ResectionJob& job, int trial,
                            size_t image, size_t solver, const ResectionResult& result,
                            const ExteriorOrientation& truth, const std::vector<char>& is_outlier,
                            double threshold) {
  SolveOutcome outcome;
  outcome.trial = trial;
  outcome.image = static_cast<int>(image);
  outcome.solver = static_cast<int>(solver);
  outcome.solved = result.success;
  outcome.message = result.summary.message;
  outcome.success_threshold_m = threshold;
  outcome.iterations = result.summary.iterations;
  outcome.total_seconds = result.summary.total_seconds;
  outcome.refinement_seconds = result.summary.refinement_seconds;
  if (!result.success) return outcome;
  outcome.position_error_m = (result.eo.center_in_ground() - truth.center_in_ground()).norm();
  outcome.rotation_error_arcsec =
      RotationErrorArcSeconds(truth.angles_seed_rad(), result.eo.angles_seed_rad());
  outcome.success = outcome.position_error_m <= threshold;
  outcome.sigma0 = result.sigma0;
  outcome.degrees_of_freedom = result.degrees_of_freedom;
  if (setting.noise_px > 0.0 && result.has_covariance) {
    outcome.nees = NormalizedEstimationErrorSquared(result.eo, truth, result.covariance);
    // The covariance is covariance_factor N^-1 (the resection's one rule,
    // PoseCovarianceFactor): times the factor, the NEES is that of N^-1.
    outcome.nees_apriori = outcome.nees * result.covariance_factor;
    outcome.accuracy_stated = result.accuracy_stated;
  } else {
    outcome.nees = outcome.nees_apriori = kNaN;
  }
  std::vector<Eigen::Vector2d> clean;
  for (size_t k = 0; k < result.residuals.size(); ++k)
    if (!is_outlier[k]) clean.push_back(result.residuals[k]);
  outcome.reprojection_rmse_px = RmsNorm(clean);
  outcome.num_reprojection = static_cast<int>(clean.size());
  std::vector<Eigen::Vector2d> check;
  for (const CheckResidual& c : CheckResiduals(job, image, result.eo)) check.push_back(c.residual);
  outcome.check_rmse_px = RmsNorm(check);
  outcome.num_check = static_cast<int>(check.size());
  return outcome;
}

// Paired differences to the reference solver on the same data and start: one image's solves,
// whose outcomes start at outcomes[first].
void AddPairedDifferences(const std::vector<ResectionResult>& results, size_t reference,
                          size_t first, std::vector<SolveOutcome>* outcomes) {
  const ResectionResult& base = results[reference];
  for (size_t s = 0; s < results.size(); ++s) {
    if (s == reference || !base.success || !results[s].success) continue;
    SolveOutcome& outcome = (*outcomes)[first + s];
    outcome.difference_position_m =
        (results[s].eo.center_in_ground() - base.eo.center_in_ground()).norm();
    outcome.difference_rotation_arcsec =
        RotationErrorArcSeconds(base.eo.angles_seed_rad(), results[s].eo.angles_seed_rad());
  }
}

// Runs every solver on every image of one trial.
Status RunTrial(const MonteCarloOptions& options, const SweepSetting& setting, int trial,
                std::vector<SolveOutcome>* outcomes, int* images) {
  const SyntheticSceneOptions scene_options = SceneOptionsFor(options, setting, trial);
  SyntheticScene scene;
  Status status = MakeSyntheticScene(scene_options, &scene);
  if (!status.ok()) return status;
  SceneJob scene_job;
  status = MakeSceneJob(scene, &scene_job);
  if (!status.ok()) return status;
  const ResectionJob& job = scene_job.job;
  std::map<std::string, const FrameRecord*> truth_by_raster;
  for (const FrameRecord& frame : scene.true_frames) truth_by_raster[frame.raster] = &frame;
  *images = static_cast<int>(job.inputs.size());
  std::vector<std::string> names;
  for (const SolverVariant& v : options.solvers) names.push_back(v.Name());
  const size_t reference = ReferenceSolverIndex(names);

  for (size_t i = 0; i < job.inputs.size(); ++i) {
    ResectionInput input = job.inputs[i];
    if (options.initial == InitialValues::kRansac) input.approximate.reset();
    const ExteriorOrientation& truth = truth_by_raster.at(input.raster)->eo;
    const std::vector<char>& is_outlier = scene_job.control_is_outlier[i];
    const double threshold = SuccessThreshold(input, is_outlier, truth, options.success_sigmas);
    std::vector<ResectionResult> results(options.solvers.size());
    const size_t first = outcomes->size();
    for (size_t s = 0; s < options.solvers.size(); ++s) {
      ResectionOptions resection = options.solvers[s].ApplyTo(options.resection);
      // One RANSAC stream per image and trial, the same for every solver.
      resection.consensus.ransac.seed = scene_options.seed * 1000003ull + i;
      results[s] = ResectImage(resection, input);
      outcomes->push_back(
          OutcomeOfSolve(setting, job, trial, i, s, results[s], truth, is_outlier, threshold));
    }
    AddPairedDifferences(results, reference, first, outcomes);
  }
  return Status::Ok();
}

// The kind of a failure message: its text up to the first ':' (photopose's messages read
// "kind: particulars"), to count failures of one kind whatever their numbers.
std::string FailureKind(const std::string& message) {
  if (message.empty()) return "no message";
  return message.substr(0, message.find(':'));
}

// One solver's solves gathered before they are reduced (Aggregate): the measures of the solved
// ones, the pooled squared residuals, and per kind of failure how many, the first message, and
// whether all messages were the same.
struct SolverSamples {
  struct Failures {
    int count = 0;
    std::string first;
    bool same = true;
  };
  int solved = 0, successes = 0;
  std::vector<double> position, rotation, iterations, thresholds, seconds, refinement, nees,
      nees_apriori, expected, all_seconds, all_refinement, difference_position, difference_rotation;
  double check_ssq = 0.0, reprojection_ssq = 0.0;
  int check_count = 0, reprojection_count = 0;
  std::map<std::string, Failures> failures;

  void AddFailure(const std::string& message) {
    Failures& kind = failures[FailureKind(message)];
    if (kind.count++ == 0) kind.first = message;
    kind.same = kind.same && message == kind.first;
  }

  void AddSolved(const SolveOutcome& o) {
    ++solved;
    successes += o.success;
    seconds.push_back(o.total_seconds);
    refinement.push_back(o.refinement_seconds);
    position.push_back(o.position_error_m);
    rotation.push_back(o.rotation_error_arcsec);
    if (std::isfinite(o.difference_position_m)) {
      difference_position.push_back(o.difference_position_m);
      difference_rotation.push_back(o.difference_rotation_arcsec);
    }
    iterations.push_back(o.iterations);
    if (o.num_check > 0) {
      check_ssq += o.check_rmse_px * o.check_rmse_px * o.num_check;
      check_count += o.num_check;
    }
    if (o.num_reprojection > 0) {
      reprojection_ssq += o.reprojection_rmse_px * o.reprojection_rmse_px * o.num_reprojection;
      reprojection_count += o.num_reprojection;
    }
    if (!std::isfinite(o.nees) || !std::isfinite(o.nees_apriori)) return;
    nees.push_back(o.nees);
    nees_apriori.push_back(o.nees_apriori);
    // The a-priori covariance (stated accuracy): chi-square(6), mean 6; sigma0 from r: 6 F(6, r),
    // mean 6 r / (r - 2) (none for r <= 2).
    const double r = o.degrees_of_freedom;
    if (o.accuracy_stated)
      expected.push_back(6.0);
    else if (r > 2.0)
      expected.push_back(6.0 * r / (r - 2.0));
  }

  void Add(const SolveOutcome& o) {
    all_seconds.push_back(o.total_seconds);
    all_refinement.push_back(o.refinement_seconds);
    if (std::isfinite(o.success_threshold_m)) thresholds.push_back(o.success_threshold_m);
    if (o.solved)
      AddSolved(o);
    else
      AddFailure(o.message);
  }
};

// The failures of `samples` by kind, most frequent first: the message when every one of its kind
// read the same, else "kind, e.g. first message".
std::vector<std::pair<std::string, int>> FailureReasons(const SolverSamples& samples) {
  std::vector<std::pair<std::string, int>> reasons;
  for (const auto& [kind, f] : samples.failures)
    reasons.emplace_back(f.same ? f.first : kind + ", e.g. " + f.first, f.count);
  std::stable_sort(reasons.begin(), reasons.end(),
                   [](const auto& a, const auto& b) { return a.second > b.second; });
  return reasons;
}

SolverStatistics Aggregate(const std::string& name,
                           const std::vector<const SolveOutcome*>& samples) {
  SolverSamples gathered;
  for (const SolveOutcome* o : samples) gathered.Add(*o);
  const SolverSamples& g = gathered;
  SolverStatistics stats;
  stats.solver = name;
  stats.samples = static_cast<int>(samples.size());
  stats.solved = g.solved;
  stats.successes = g.successes;
  stats.success_rate =
      stats.samples > 0 ? static_cast<double>(stats.successes) / stats.samples : kNaN;
  stats.position_rmse_m = Rms(g.position);
  stats.rotation_rmse_arcsec = Rms(g.rotation);
  stats.difference_position_rmse_m = Rms(g.difference_position);
  stats.difference_rotation_rmse_arcsec = Rms(g.difference_rotation);
  stats.check_rmse_px = g.check_count > 0 ? std::sqrt(g.check_ssq / g.check_count) : kNaN;
  stats.reprojection_rmse_px =
      g.reprojection_count > 0 ? std::sqrt(g.reprojection_ssq / g.reprojection_count) : kNaN;
  stats.mean_iterations = Mean(g.iterations);
  stats.mean_success_threshold_m = Mean(g.thresholds);
  stats.median_seconds = Median(g.seconds.empty() ? g.all_seconds : g.seconds);
  stats.median_refinement_seconds = Median(g.refinement.empty() ? g.all_refinement : g.refinement);
  stats.nees_count = static_cast<int>(g.nees.size());
  stats.mean_nees = Mean(g.nees);
  stats.mean_nees_apriori = Mean(g.nees_apriori);
  stats.expected_nees = Mean(g.expected);
  if (stats.nees_count > 0) {
    stats.nees_interval_95 = MeanNeesInterval(stats.nees_count, 0.95);
    stats.nees_interval_99 = MeanNeesInterval(stats.nees_count, 0.99);
  } else {
    stats.nees_interval_95 = stats.nees_interval_99 = NeesInterval{kNaN, kNaN};
  }
  stats.failure_reasons = FailureReasons(g);
  return stats;
}

}  // namespace

size_t ReferenceSolverIndex(const std::vector<std::string>& names) {
  for (size_t s = 0; s < names.size(); ++s)
    if (names[s] == "taylor") return s;
  return 0;
}

// ------------------------------------------------------------------ solver variants

std::string SolverVariant::Name() const {
  if (solver != PoseSolver::kCeres) return EnumName(solver);
  return std::string("ceres_") + EnumName(jacobian) + "/" + EnumName(loss);
}

ResectionOptions SolverVariant::ApplyTo(const ResectionOptions& base) const {
  ResectionOptions options = base;
  options.refinement.solver = solver;
  options.refinement.jacobian = jacobian;
  options.refinement.loss = solver == PoseSolver::kCeres ? loss : LossType::kNone;
  return options;
}

Status ParseSolverVariants(const std::string& solvers, const std::string& losses,
                           std::vector<SolverVariant>* variants) {
  variants->clear();
  std::vector<LossType> loss_types;
  for (const std::string& name : SplitCommaList(losses)) {
    if (name == "all") {
      for (const EnumNameEntry<LossType>& entry : kLossTypeNames) loss_types.push_back(entry.value);
      continue;
    }
    LossType loss;
    if (!ParseEnum(name, &loss))
      return Status::Error("unknown loss '" + name + "' (" + EnumChoices<LossType>() + " or all)");
    loss_types.push_back(loss);
  }
  std::vector<std::string> names;
  for (const std::string& name : SplitCommaList(solvers)) {
    if (name == "all") {
      for (const char* n : {"taylor_as_printed", "taylor", "ceres_analytic", "ceres_autodiff"})
        names.push_back(n);
    } else {
      names.push_back(name);
    }
  }
  for (const std::string& name : names) {
    std::vector<SolverVariant> add;
    SolverVariant taylor;
    if ((name == "taylor_as_printed" || name == "taylor") && ParseEnum(name, &taylor.solver)) {
      add.push_back(taylor);
    } else if (name == "ceres_analytic" || name == "ceres_autodiff") {
      if (loss_types.empty()) return Status::Error("the Ceres solvers need at least one loss");
      for (LossType loss : loss_types) {
        SolverVariant v;
        v.solver = PoseSolver::kCeres;
        v.jacobian = name == "ceres_analytic" ? JacobianType::kAnalytic : JacobianType::kAutodiff;
        v.loss = loss;
        add.push_back(v);
      }
    } else {
      return Status::Error("unknown solver '" + name +
                           "' (taylor_as_printed, taylor, ceres_analytic, ceres_autodiff or all)");
    }
    for (const SolverVariant& v : add) {
      const bool duplicate =
          std::any_of(variants->begin(), variants->end(),
                      [&](const SolverVariant& w) { return w.Name() == v.Name(); });
      if (!duplicate) variants->push_back(v);
    }
  }
  if (variants->empty()) return Status::Error("no solver to compare");
  return Status::Ok();
}

// ------------------------------------------------------------------ statistics helpers

NeesInterval MeanNeesInterval(int count, double confidence) {
  const double alpha = 1.0 - confidence;
  const double dof = 6.0 * count;
  return NeesInterval{ChiSquaredQuantile(0.5 * alpha, dof) / count,
                      ChiSquaredQuantile(1.0 - 0.5 * alpha, dof) / count};
}

double RotationErrorArcSeconds(const Eigen::Vector3d& angles_a_rad,
                               const Eigen::Vector3d& angles_b_rad) {
  return RotationErrorArcSeconds(RotationFromAngles(RotationConvention::kSeed, angles_a_rad),
                                 RotationFromAngles(RotationConvention::kSeed, angles_b_rad));
}

double RotationErrorArcSeconds(const Eigen::Matrix3d& R_a, const Eigen::Matrix3d& R_b) {
  const Eigen::Matrix3d R = R_a.transpose() * R_b;
  // atan2 of the sine and cosine parts: accurate for small angles, unlike acos of the trace.
  const Eigen::Vector3d axis(R(2, 1) - R(1, 2), R(0, 2) - R(2, 0), R(1, 0) - R(0, 1));
  const double angle = std::atan2(0.5 * axis.norm(), 0.5 * (R.trace() - 1.0));
  return angle * kArcSecondsPerRadian;
}

double NormalizedEstimationErrorSquared(const ExteriorOrientation& estimate,
                                        const ExteriorOrientation& truth,
                                        const Matrix6d& covariance) {
  if (!covariance.allFinite() || !estimate.parameters.allFinite()) return kNaN;
  // The seed angles (omega, phi, kappa) and (omega + pi, pi - phi, kappa + pi) are the same
  // rotation; a solver may converge to either. The error is taken in the one closer to the truth,
  // with the covariance carried over (d phi' / d phi = -1).
  Vector6d error = estimate.parameters - truth.parameters;
  Vector6d alternate_error = error;
  alternate_error[3] += kPi;
  alternate_error[4] = kPi - estimate.parameters[4] - truth.parameters[4];
  alternate_error[5] += kPi;
  for (int k = 3; k < 6; ++k) {
    error[k] = WrapAngle(error[k]);
    alternate_error[k] = WrapAngle(alternate_error[k]);
  }
  Matrix6d C = covariance;
  if (alternate_error.tail<3>().norm() < error.tail<3>().norm()) {
    error = alternate_error;
    Vector6d flip = Vector6d::Ones();
    flip[4] = -1.0;
    C = flip.asDiagonal() * covariance * flip.asDiagonal();
  }
  const Eigen::LDLT<Matrix6d> ldlt(C);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) return kNaN;
  return error.dot(ldlt.solve(error));
}

// ------------------------------------------------------------------ Monte-Carlo mode

Status ParseInitialErrors(const std::string& text, std::vector<InitialError>* errors) {
  errors->clear();
  for (const std::string& item : SplitCommaList(text)) {
    const size_t colon = item.find(':');
    InitialError error;
    char* end = nullptr;
    bool ok = colon != std::string::npos;
    if (ok) {
      const std::string position = item.substr(0, colon), angle = item.substr(colon + 1);
      error.position_m = std::strtod(position.c_str(), &end);
      ok = !position.empty() && *end == '\0';
      error.angle_deg = std::strtod(angle.c_str(), &end);
      ok = ok && !angle.empty() && *end == '\0';
    }
    if (!ok || !(error.position_m >= 0.0) || !(error.angle_deg >= 0.0) ||
        !std::isfinite(error.position_m) || !std::isfinite(error.angle_deg))
      return Status::Error("initial error '" + item +
                           "' is not POSITION_M:ANGLE_DEG with two non-negative numbers");
    errors->push_back(error);
  }
  if (errors->empty()) return Status::Error("no initial error given");
  return Status::Ok();
}

bool MonteCarloOptions::IsValid(std::string* why) const {
  if (scenarios.empty()) return InvalidBecause(why, "no scenario");
  if (noise_px.empty() || outlier_fractions.empty() || control_points.empty() ||
      initial_errors.empty())
    return InvalidBecause(why, "every sweep axis needs at least one value");
  for (double noise : noise_px)
    if (!(noise >= 0.0) || !std::isfinite(noise))
      return InvalidBecause(why, "image noise must be >= 0 px");
  for (double fraction : outlier_fractions)
    if (!(fraction >= 0.0 && fraction < 1.0))
      return InvalidBecause(why, "outlier fractions must be in [0, 1)");
  for (int count : control_points)
    if (count < 3) return InvalidBecause(why, "every image needs at least 3 control points");
  for (const InitialError& e : initial_errors)
    if (!(e.position_m >= 0.0) || !(e.angle_deg >= 0.0))
      return InvalidBecause(why, "initial errors must be >= 0");
  if (check_points < 0) return InvalidBecause(why, "check points must be >= 0");
  if (trials < 1) return InvalidBecause(why, "trials must be at least 1");
  if (solvers.empty()) return InvalidBecause(why, "no solver to compare");
  if (!(success_sigmas > 0.0)) return InvalidBecause(why, "success_sigmas must be positive");
  if (num_threads < 0) return InvalidBecause(why, "threads must be >= 0");
  return resection.IsValid(why);
}

std::vector<SweepSetting> MakeSweepSettings(const MonteCarloOptions& options) {
  std::vector<SweepSetting> settings;
  for (Scenario scenario : options.scenarios) {
    SweepSetting baseline;
    baseline.scenario = scenario;
    baseline.noise_px = options.noise_px.front();
    baseline.outlier_fraction = options.outlier_fractions.front();
    baseline.control_points = options.control_points.front();
    baseline.initial_error = options.initial_errors.front();
    if (options.sweep == SweepType::kGrid) {
      for (double noise : options.noise_px)
        for (double fraction : options.outlier_fractions)
          for (int control : options.control_points)
            for (const InitialError& initial : options.initial_errors) {
              SweepSetting s = baseline;
              s.noise_px = noise;
              s.outlier_fraction = fraction;
              s.control_points = control;
              s.initial_error = initial;
              s.axis = "grid";
              settings.push_back(s);
            }
      continue;
    }
    settings.push_back(baseline);
    // One axis at a time: the baseline with the k-th value (k >= 1) of one swept quantity.
    auto sweep_axis = [&](const auto& values, const char* axis, auto set) {
      for (size_t k = 1; k < values.size(); ++k) {
        SweepSetting s = baseline;
        set(&s, values[k]);
        s.axis = axis;
        settings.push_back(s);
      }
    };
    sweep_axis(options.noise_px, "noise", [](SweepSetting* s, double v) { s->noise_px = v; });
    sweep_axis(options.outlier_fractions, "outliers",
               [](SweepSetting* s, double v) { s->outlier_fraction = v; });
    sweep_axis(options.control_points, "control",
               [](SweepSetting* s, int v) { s->control_points = v; });
    sweep_axis(options.initial_errors, "initial",
               [](SweepSetting* s, const InitialError& v) { s->initial_error = v; });
  }
  return settings;
}

double AxisValue(const SweepSetting& setting, const std::string& axis) {
  if (axis == "noise") return setting.noise_px;
  if (axis == "outliers") return setting.outlier_fraction;
  if (axis == "control") return setting.control_points;
  if (axis == "initial") return setting.initial_error.angle_deg;
  return kNaN;
}

std::vector<size_t> SettingsAlongAxis(const MonteCarloOptions& options,
                                      const MonteCarloResult& result, Scenario scenario,
                                      const std::string& axis) {
  SweepSetting baseline;
  baseline.scenario = scenario;
  baseline.noise_px = options.noise_px.front();
  baseline.outlier_fraction = options.outlier_fractions.front();
  baseline.control_points = options.control_points.front();
  baseline.initial_error = options.initial_errors.front();
  std::vector<size_t> indices;
  std::vector<double> seen;
  for (size_t k = 0; k < result.settings.size(); ++k) {
    const SweepSetting& s = result.settings[k].setting;
    if (!SameExceptAxis(s, baseline, axis)) continue;
    const double value = AxisValue(s, axis);
    if (std::find(seen.begin(), seen.end(), value) != seen.end()) continue;
    seen.push_back(value);
    indices.push_back(k);
  }
  if (indices.size() < 2) return {};
  std::stable_sort(indices.begin(), indices.end(), [&](size_t a, size_t b) {
    return AxisValue(result.settings[a].setting, axis) <
           AxisValue(result.settings[b].setting, axis);
  });
  return indices;
}

SyntheticSceneOptions SceneOptionsFor(const MonteCarloOptions& options, const SweepSetting& setting,
                                      int trial) {
  SyntheticSceneOptions scene;
  scene.scenario = setting.scenario;
  scene.seed = options.seed + static_cast<uint64_t>(trial);
  scene.noise_px = setting.noise_px;
  scene.outlier_fraction = setting.outlier_fraction;
  scene.num_control_points = setting.control_points;
  scene.num_check_points = options.check_points;
  scene.initial_position_error_m = setting.initial_error.position_m;
  scene.initial_angle_error_deg = setting.initial_error.angle_deg;
  return scene;
}

Status MakeSceneJob(const SyntheticScene& scene, SceneJob* scene_job) {
  *scene_job = SceneJob();
  Block block;
  Status status = AssembleBlock(SceneBlockTables(scene), &block);
  if (!status.ok()) return Status::Error("synthetic scene: " + status.message());
  ResectionJob& job = scene_job->job;
  status = PrepareResectionJob(std::move(block), ResectionInputOptions(), &job);
  if (!status.ok()) return Status::Error("synthetic scene: " + status.message());
  // Block mark m is scene mark m (SceneBlockTables).
  for (size_t i = 0; i < job.inputs.size(); ++i) {
    std::vector<char> is_outlier;
    for (const int m : job.input_marks[i]) is_outlier.push_back(scene.mark_is_outlier[m] ? 1 : 0);
    scene_job->control_is_outlier.push_back(std::move(is_outlier));
    // A check mark with a simulated gross error would measure the blunder, not the pose.
    std::vector<int>& checks = job.check_marks[i];
    checks.erase(std::remove_if(checks.begin(), checks.end(),
                                [&](int m) { return scene.mark_is_outlier[m]; }),
                 checks.end());
  }
  return Status::Ok();
}

Status RunMonteCarlo(const MonteCarloOptions& options, MonteCarloResult* result) {
  *result = MonteCarloResult();
  PHOTOPOSE_RETURN_IF_ERROR(Validate(options));
  const auto start = std::chrono::steady_clock::now();
  for (const SolverVariant& v : options.solvers) result->solver_names.push_back(v.Name());
  const std::vector<SweepSetting> settings = MakeSweepSettings(options);

  // One task per (setting, trial); each writes only its own slot.
  const size_t num_tasks = settings.size() * static_cast<size_t>(options.trials);
  std::vector<std::vector<SolveOutcome>> outcomes(num_tasks);
  std::vector<int> images(num_tasks, 0);
  std::vector<Status> statuses(num_tasks);
  std::atomic<size_t> done{0};
  std::atomic<bool> cancelled{false};
  ParallelFor(num_tasks, options.num_threads, [&](size_t task) {
    if (cancelled.load()) return;
    const size_t setting = task / options.trials;
    const int trial = static_cast<int>(task % options.trials);
    statuses[task] = RunTrial(options, settings[setting], trial, &outcomes[task], &images[task]);
    if (options.progress && !options.progress(++done, num_tasks)) cancelled = true;
  });
  if (cancelled) {
    return Status::Error("cancelled by the progress hook after " + std::to_string(done.load()) +
                         " of " + std::to_string(num_tasks) + " trials");
  }
  for (size_t task = 0; task < num_tasks; ++task) {
    if (!statuses[task].ok()) {
      const size_t setting = task / options.trials;
      // Which setting by its place (the engine writes no numbers; the reports' title,
      // tools/report/comparison_tables.h SweepSettingTitle, prints its values).
      const int trial = static_cast<int>(task % options.trials);
      return Status::Error(std::string(EnumName(settings[setting].scenario)) + ", sweep setting " +
                           std::to_string(setting + 1) + " of " + std::to_string(settings.size()) +
                           " (axis " + settings[setting].axis + "), trial " +
                           std::to_string(trial) + " (scene seed " +
                           std::to_string(options.seed + trial) + "): " + statuses[task].message());
    }
  }

  for (size_t k = 0; k < settings.size(); ++k) {
    SettingResult setting_result;
    setting_result.setting = settings[k];
    setting_result.images_per_trial = images[k * options.trials];
    std::vector<std::vector<const SolveOutcome*>> by_solver(options.solvers.size());
    for (int t = 0; t < options.trials; ++t)
      for (const SolveOutcome& o : outcomes[k * options.trials + t])
        by_solver[o.solver].push_back(&o);
    for (size_t s = 0; s < options.solvers.size(); ++s)
      setting_result.solvers.push_back(Aggregate(result->solver_names[s], by_solver[s]));
    if (options.keep_samples) {
      for (int t = 0; t < options.trials; ++t) {
        const auto& trial = outcomes[k * options.trials + t];
        setting_result.samples.insert(setting_result.samples.end(), trial.begin(), trial.end());
      }
    }
    result->settings.push_back(std::move(setting_result));
  }
  result->wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return Status::Ok();
}

// ------------------------------------------------------------------ dataset mode

bool DatasetComparisonOptions::IsValid(std::string* why) const {
  if (solvers.empty()) return InvalidBecause(why, "no solver to compare");
  if (num_threads < 0) return InvalidBecause(why, "threads must be >= 0");
  return job.resection.IsValid(why);
}

namespace {

// One solver's figures over the images of a dataset, gathered for its summary.
struct DatasetTally {
  int check_beyond = 0;
  std::vector<double> sigma0, seconds, refinement, iterations, difference_position,
      difference_rotation, reference_position, reference_rotation;
  std::vector<Eigen::Vector2d> residuals, checks;
};

// The reference frames (--reference) by raster; none without one.
Status ReadReferenceFrames(const DatasetComparisonOptions& options, const ResectionJob& job,
                           std::map<std::string, ExteriorOrientation>* reference) {
  if (options.reference_path.empty()) return Status::Ok();
  std::vector<FrameCamera> cameras;
  for (const BlockCamera& camera : job.block.cameras) cameras.push_back(camera.table);
  FramesTableOptions frames_options;
  frames_options.convention = options.job.files.rotation;
  frames_options.cameras = &cameras;
  std::vector<FrameRecord> frames;
  PHOTOPOSE_RETURN_IF_ERROR(ReadFramesTable(options.reference_path, frames_options, &frames));
  for (const FrameRecord& frame : frames) (*reference)[frame.raster] = frame.eo;
  return Status::Ok();
}

// Every image by every solver. ResectImages gives image i the RANSAC seed seed + constant *
// (i + 1) whatever the solver, so every solver starts from the same initial values.
Status ResectWithEverySolver(const DatasetComparisonOptions& options, const ResectionJob& job,
                             std::vector<std::vector<ResectionResult>>* results) {
  for (const SolverVariant& v : options.solvers) {
    results->push_back(
        ResectImages(v.ApplyTo(options.job.resection), job.inputs, options.num_threads));
    if (options.progress && !options.progress(results->size(), options.solvers.size())) {
      return Status::Error("cancelled by the progress hook after " +
                           std::to_string(results->size()) + " of " +
                           std::to_string(options.solvers.size()) + " solvers");
    }
  }
  return Status::Ok();
}

// The inlier residuals of a solved image: their RMS and largest into `solve`.
std::vector<Eigen::Vector2d> InlierResiduals(const ResectionResult& r, DatasetSolve* solve) {
  std::vector<Eigen::Vector2d> inlier_residuals;
  for (size_t k = 0; k < r.residuals.size(); ++k) {
    if (!r.inliers[k]) continue;
    inlier_residuals.push_back(r.residuals[k]);
    solve->max_px = std::max(solve->max_px, r.residuals[k].norm());
  }
  solve->rms_px = RmsNorm(inlier_residuals);
  return inlier_residuals;
}

// The check residuals of a solved image within `threshold` times their accuracy (the mark's
// stated accuracy, else sigma0, in the mark unit); those beyond are counted in `solve`.
std::vector<Eigen::Vector2d> CheckResidualsWithin(const DatasetComparisonOptions& options,
                                                  const ResectionJob& job, size_t i,
                                                  const ResectionResult& r, double threshold,
                                                  DatasetSolve* solve) {
  std::vector<Eigen::Vector2d> check;
  for (const CheckResidual& c : CheckResiduals(job, i, r.eo)) {
    const std::optional<double> accuracy = job.block.marks[c.mark].accuracy;
    const double sigma = accuracy ? *accuracy
                         : options.job.input.default_accuracy > 0.0
                             ? options.job.input.default_accuracy
                         : r.accuracy_stated || !(r.sigma0 > 0.0) ? 1.0
                                                                  : r.sigma0;
    if (c.residual.norm() <= threshold * sigma) {
      check.push_back(c.residual);
    } else {
      ++solve->num_check_beyond;
    }
  }
  solve->check_rmse_px = RmsNorm(check);
  solve->num_check = static_cast<int>(check.size());
  return check;
}

// A solved image's pose against the reference solver's (`first`, unless it is the reference
// itself) and against the reference frame (`reference`, when given for the image).
void CompareSolvedPose(const ResectionResult& r, const ResectionResult* first,
                       const ExteriorOrientation* reference, DatasetSolve* solve,
                       DatasetTally* tally) {
  if (first != nullptr && first->success) {
    solve->has_difference = true;
    solve->difference_position_m = (r.eo.center_in_ground() - first->eo.center_in_ground()).norm();
    solve->difference_rotation_arcsec =
        RotationErrorArcSeconds(first->eo.angles_seed_rad(), r.eo.angles_seed_rad());
    tally->difference_position.push_back(solve->difference_position_m);
    tally->difference_rotation.push_back(solve->difference_rotation_arcsec);
  }
  if (reference != nullptr) {
    solve->has_reference = true;
    solve->reference_position_m = (r.eo.center_in_ground() - reference->center_in_ground()).norm();
    solve->reference_rotation_arcsec =
        RotationErrorArcSeconds(reference->angles_seed_rad(), r.eo.angles_seed_rad());
    tally->reference_position.push_back(solve->reference_position_m);
    tally->reference_rotation.push_back(solve->reference_rotation_arcsec);
  }
}

// Solver `s`'s solve of image i, its figures added to the solver's tally. `first`: the reference
// solver's result of the image (nullptr for the reference solver itself).
DatasetSolve DatasetSolveOf(const DatasetComparisonOptions& options, const ResectionJob& job,
                            size_t i, size_t s, const ResectionResult& r,
                            const ResectionResult* first, const ExteriorOrientation* reference,
                            RotationConvention rotation, DatasetTally* tally) {
  DatasetSolve solve;
  solve.raster = job.inputs[i].raster;
  solve.solver = static_cast<int>(s);
  solve.success = r.success;
  solve.message = r.summary.message;
  solve.iterations = r.summary.iterations;
  solve.seconds = r.summary.total_seconds;
  solve.refinement_seconds = r.summary.refinement_seconds;
  solve.num_observations = static_cast<int>(job.inputs[i].image_plane.size());
  tally->seconds.push_back(r.summary.total_seconds);
  tally->refinement.push_back(r.summary.refinement_seconds);
  if (!r.success) return solve;
  solve.eo = r.eo;
  solve.angles_deg = OutputAnglesDeg(job, i, rotation, r.eo);
  solve.standard_deviations = r.standard_deviations;
  solve.sigma0 = r.sigma0;
  solve.num_inliers = r.num_inliers;
  const std::vector<Eigen::Vector2d> inliers = InlierResiduals(r, &solve);
  tally->residuals.insert(tally->residuals.end(), inliers.begin(), inliers.end());
  const double threshold = MarkThresholdSigmas(options.job.resection.test.confidence);
  const std::vector<Eigen::Vector2d> check =
      CheckResidualsWithin(options, job, i, r, threshold, &solve);
  tally->checks.insert(tally->checks.end(), check.begin(), check.end());
  tally->check_beyond += solve.num_check_beyond;
  tally->sigma0.push_back(r.sigma0);
  tally->iterations.push_back(r.summary.iterations);
  CompareSolvedPose(r, first, reference, &solve, tally);
  return solve;
}

DatasetSolverSummary SummaryOf(const std::string& solver, int images, const DatasetTally& t) {
  DatasetSolverSummary summary;
  summary.solver = solver;
  summary.images = images;
  summary.solved = static_cast<int>(t.sigma0.size());
  summary.rms_sigma0 = Rms(t.sigma0);
  summary.rms_px = RmsNorm(t.residuals);
  summary.check_rmse_px = RmsNorm(t.checks);
  summary.check_beyond = t.check_beyond;
  summary.median_seconds = Median(t.seconds);
  summary.median_refinement_seconds = Median(t.refinement);
  summary.mean_iterations = Mean(t.iterations);
  summary.compared = static_cast<int>(t.difference_position.size());
  summary.difference_position_m = Rms(t.difference_position);
  summary.difference_rotation_arcsec = Rms(t.difference_rotation);
  summary.referenced = static_cast<int>(t.reference_position.size());
  summary.reference_position_m = Rms(t.reference_position);
  summary.reference_rotation_arcsec = Rms(t.reference_rotation);
  return summary;
}

}  // namespace

Status RunDatasetComparison(const DatasetComparisonOptions& options,
                            DatasetComparisonResult* result) {
  *result = DatasetComparisonResult();
  PHOTOPOSE_RETURN_IF_ERROR(Validate(options));
  ResectionJob job;
  PHOTOPOSE_RETURN_IF_ERROR(PrepareResectionJob(options.job, &job));
  if (job.inputs.empty()) return Status::Error("no image has marks");
  std::map<std::string, ExteriorOrientation> reference;
  PHOTOPOSE_RETURN_IF_ERROR(ReadReferenceFrames(options, job, &reference));
  result->has_reference = !options.reference_path.empty();
  result->rotation = options.job.files.rotation;
  for (const SolverVariant& v : options.solvers) result->solver_names.push_back(v.Name());
  const size_t reference_index = ReferenceSolverIndex(result->solver_names);
  result->reference_solver = result->solver_names[reference_index];
  std::vector<std::vector<ResectionResult>> results;
  PHOTOPOSE_RETURN_IF_ERROR(ResectWithEverySolver(options, job, &results));

  const size_t num_solvers = options.solvers.size();
  std::vector<DatasetTally> tallies(num_solvers);
  for (size_t i = 0; i < job.inputs.size(); ++i) {
    const auto ref = reference.find(job.inputs[i].raster);
    const ExteriorOrientation* reference_eo = ref != reference.end() ? &ref->second : nullptr;
    for (size_t s = 0; s < num_solvers; ++s) {
      const ResectionResult* first = s != reference_index ? &results[reference_index][i] : nullptr;
      result->solves.push_back(DatasetSolveOf(options, job, i, s, results[s][i], first,
                                              reference_eo, result->rotation, &tallies[s]));
    }
  }
  for (size_t s = 0; s < num_solvers; ++s)
    result->summaries.push_back(
        SummaryOf(result->solver_names[s], static_cast<int>(job.inputs.size()), tallies[s]));
  return Status::Ok();
}

}  // namespace photopose::cli
