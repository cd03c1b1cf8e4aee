// BundleAdjust (bundle_adjustment.h): options and reports, the rounds (solve, snooping or
// rejection, variance components) as named steps. The plan and the Ceres problem are in
// bundle_problem.cc, the statistics in bundle_statistics.cc, the cross-validation in
// cross_validation.cc.
// It also holds the public types' methods (IsValid, BriefReport, FullReport).
#include "solvers/bundle/bundle_adjustment.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>

#include "core/rotation.h"
#include "core/units.h"
#include "solvers/bundle/internal/bundle_problem.h"
#include "solvers/bundle/internal/bundle_rounds.h"
#include "solvers/bundle/internal/bundle_statistics.h"

namespace photopose {
namespace {

using Clock = std::chrono::steady_clock;
using internal::BundlePlan;
using internal::BundleRound;
using internal::BundleState;
using internal::StartState;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

class ProgressCallback final : public ceres::IterationCallback {
 public:
  // *cancelled is set when the hook asks to stop.
  ProgressCallback(const BundleAdjustmentOptions& options, int round, int redundancy,
                   Clock::time_point start, bool* cancelled)
      : options_(options),
        round_(round),
        redundancy_(redundancy),
        start_(start),
        cancelled_(cancelled) {}
  void set_free_gauge(bool free_gauge) { free_gauge_ = free_gauge; }

  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    BundleIterationInfo info;
    info.round = round_;
    info.iteration = summary.iteration;
    info.cost = summary.cost;
    info.sigma0 = redundancy_ > 0 ? std::sqrt(2.0 * summary.cost / redundancy_) : kNaN;
    info.step_norm = summary.step_norm;
    info.elapsed_seconds = SecondsSince(start_);
    info.free_gauge = free_gauge_;
    info.trust_region_radius = summary.trust_region_radius;
    info.step_quality = summary.relative_decrease;
    info.step_successful = summary.step_is_successful;
    info.linear_solver_seconds = summary.step_solver_time_in_seconds;
    info.iteration_seconds = summary.iteration_time_in_seconds;
    if (options_.solver.progress(info)) return ceres::SOLVER_CONTINUE;
    *cancelled_ = true;
    return ceres::SOLVER_ABORT;
  }

 private:
  const BundleAdjustmentOptions& options_;
  int round_;
  int redundancy_;
  Clock::time_point start_;
  bool* cancelled_;
  bool free_gauge_ = false;
};

void AddSolverTimes(const ceres::Solver::Summary& ceres_summary, BundleAdjustmentSummary* summary) {
  summary->solver_preprocessing_seconds += ceres_summary.preprocessor_time_in_seconds;
  summary->residual_evaluation_seconds += ceres_summary.residual_evaluation_time_in_seconds;
  summary->jacobian_evaluation_seconds += ceres_summary.jacobian_evaluation_time_in_seconds;
  summary->linear_solver_seconds += ceres_summary.linear_solver_time_in_seconds;
  summary->schur_structure = ceres_summary.schur_structure_used;
}

}  // namespace

namespace {

bool Positive(double v) { return v > 0.0 && std::isfinite(v); }

}  // namespace

bool BundleRobustnessOptions::IsValid(std::string* why) const {
  if (!IsBundleTieLoss(tie_loss))
    return InvalidBecause(why, "the tie loss must be " + EnumNameList(kBundleTieLosses) + ", not " +
                                   EnumName(tie_loss));
  if (!Positive(tie_loss_scale_sigmas))
    return InvalidBecause(why, "the tie loss scale must be positive");
  if (!(rejection_threshold >= 0.0) || !std::isfinite(rejection_threshold))
    return InvalidBecause(why, "the rejection threshold must be >= 0 (0: no rejection)");
  if (max_rejection_rounds < 0) return InvalidBecause(why, "max_rejection_rounds must be >= 0");
  if (max_snooping_removals < 0) return InvalidBecause(why, "max_snooping_removals must be >= 0");
  return true;
}

bool BundleStatisticsOptions::IsValid(std::string* why) const {
  if (!(overfit_ratio > 0.0 && overfit_ratio < 1.0))
    return InvalidBecause(why, "overfit_ratio must be in (0, 1)");
  if (!(overfit_redundancy_share >= 0.0 && overfit_redundancy_share < 1.0))
    return InvalidBecause(why, "overfit_redundancy_share must be in [0, 1)");
  if (!(checked_redundancy_share >= overfit_redundancy_share && checked_redundancy_share <= 1.0))
    return InvalidBecause(why, "checked_redundancy_share must be in [overfit_redundancy_share, 1]");
  if (!(high_correlation > 0.0 && high_correlation < 1.0))
    return InvalidBecause(why, "high_correlation must be in (0, 1)");
  if (max_variance_iterations < 1)
    return InvalidBecause(why, "max_variance_iterations must be >= 1");
  if (!Positive(variance_tolerance))
    return InvalidBecause(why, "variance_tolerance must be positive");
  if (!(min_variance_redundancy >= 0.0))
    return InvalidBecause(why, "min_variance_redundancy must be >= 0");
  if (!(snooping_alpha > 0.0 && snooping_alpha < 0.5))
    return InvalidBecause(why, "snooping_alpha must be in (0, 0.5)");
  if (!(snooping_power > 0.0 && snooping_power < 1.0))
    return InvalidBecause(why, "snooping_power must be in (0, 1)");
  if (!(uncontrolled_redundancy >= 0.0 && uncontrolled_redundancy < 1.0))
    return InvalidBecause(why, "uncontrolled_redundancy must be in [0, 1)");
  if (!(weak_sigma_inflation >= 1.0))
    return InvalidBecause(why, "weak_sigma_inflation must be >= 1");
  return true;
}

bool BundleSolverOptions::IsValid(std::string* why) const {
  if (max_iterations < 1) return InvalidBecause(why, "max_iterations must be >= 1");
  if (!Positive(function_tolerance) || !Positive(parameter_tolerance) ||
      !(gradient_tolerance >= 0.0))
    return InvalidBecause(why, "tolerances must be positive");
  if (num_threads < 0) return InvalidBecause(why, "num_threads must be >= 0");
  return true;
}

bool BundleAdjustmentOptions::IsValid(std::string* why) const {
  const BundleAccuracies& a = accuracies;
  if (!Positive(a.tie_px) || !Positive(a.marker_projection_px) || !Positive(a.tie_film_um) ||
      !Positive(a.marker_projection_film_um) || !Positive(a.marker_m) ||
      !Positive(a.camera_m.minCoeff()) || !a.camera_m.allFinite())
    return InvalidBecause(why, "every accuracy must be positive and finite");
  if (a.attitude_deg && !Positive(*a.attitude_deg))
    return InvalidBecause(why, "the attitude accuracy must be positive");
  if (!(robustness.IsValid(why) && solver.IsValid(why) && statistics.IsValid(why))) return false;
  // What needs the statistics, refused without them rather than skipped in silence (both solvers:
  // TaylorBundleOptions::IsValid checks its fields by this rule).
  const bool covariances = statistics.covariances != BundleCovarianceMethod::kNone;
  if (robustness.snoop && !covariances)
    return InvalidBecause(why,
                          "data snooping (robustness.snoop) needs the statistics: the w-test of an "
                          "observation divides by its redundancy number, which comes from the "
                          "covariances, and statistics.covariances is none");
  if (robustness.snoop && !statistics.observation_diagnostics)
    return InvalidBecause(
        why,
        "data snooping (robustness.snoop) needs the w-test of every observation, and "
        "statistics.observation_diagnostics is off");
  if (statistics.estimate_accuracies && !covariances)
    return InvalidBecause(
        why,
        "variance component estimation (statistics.estimate_accuracies) needs the "
        "statistics: a group's variance factor divides by its redundancy, the sum of "
        "its redundancy numbers from the covariances, and statistics.covariances is "
        "none");
  return true;
}

Status BundleAdjustmentConfig::FromCalibrationNames(const Block& block,
                                                    const std::vector<std::string>& names,
                                                    BundleAdjustmentConfig* config) {
  config->calibrated_params.assign(block.cameras.size(), {});
  for (size_t c = 0; c < block.cameras.size(); ++c) {
    for (const std::string& name : names) {
      std::vector<int> indices;
      const Status status = CalibrationParamIndices(block.cameras[c].model, name, &indices);
      if (!status.ok())
        return Status::Error("camera '" + block.cameras[c].camera_id + "': " + status.message());
      config->calibrated_params[c].insert(config->calibrated_params[c].end(), indices.begin(),
                                          indices.end());
    }
  }
  return Status::Ok();
}

// Numbers in the fixed units and decimals of core/units.h, never an exponent.
std::string BundleAdjustmentSummary::BriefReport() const {
  std::ostringstream os;
  os << EnumName(termination) << ": " << FormatCount(num_images, "image") << ", "
     << FormatCount(num_points, "point") << ", " << FormatCount(num_marks, "mark") << ", "
     << FormatCount(rounds, "round") << ", " << FormatCount(iterations, "iteration") << ", cost "
     << FormatSignificant(initial_cost, 6) << " -> " << FormatSignificant(final_cost, 6)
     << ", sigma0 " << FormatUnitless(sigma0, 3) << " (redundancy " << redundancy << ")";
  if (num_rejected_marks > 0) os << ", " << FormatCount(num_rejected_marks, "mark") << " rejected";
  if (!tie_points_left_out.empty())
    os << ", " << FormatCount(static_cast<long long>(tie_points_left_out.size()), "tie point")
       << " without initial coordinates left out";
  os << ", " << FormatSignificant(time_seconds, 3) << " s";
  if (!message.empty()) os << ": " << message;
  return os.str();
}

std::vector<char> BundleAdjustmentResult::RemovedMarks(size_t num_marks) const {
  std::vector<char> removed(num_marks, 0);
  for (const BundleRejectedMark& r : rejected_marks)
    if (r.mark >= 0 && static_cast<size_t>(r.mark) < num_marks) removed[r.mark] = 1;
  for (const BundleSnoopingStep& s : snooping)
    if ((s.group == kTieMarks || s.group == kControlMarks) && s.item >= 0 &&
        static_cast<size_t>(s.item) < num_marks)
      removed[s.item] = 1;
  return removed;
}

bool StatedPerAxis(const BundleGroupStatistics& g) {
  const Eigen::Vector3d& a = g.stated_accuracy;
  return g.num_axes == 3 && a.y() > 0.0 && a.z() > 0.0 && (a.x() != a.y() || a.x() != a.z());
}

BundleGroupFigures FormatGroupFigures(const BundleGroupStatistics& g) {
  const bool per_axis = StatedPerAxis(g);
  std::vector<double> values = {g.stated_accuracy.x(), g.rms_total, g.estimated_accuracy.x()};
  if (per_axis) {
    values.push_back(g.stated_accuracy.y());
    values.push_back(g.stated_accuracy.z());
  }
  const ValuesInOneUnit row = FormatRowInOneUnit(values, g.unit);
  BundleGroupFigures figures;
  figures.unit = row.unit;
  figures.stated_x = row.texts[0];
  figures.stated = per_axis ? row.texts[0] + "/" + row.texts[3] + "/" + row.texts[4] : row.texts[0];
  figures.rms = row.texts[1];
  figures.estimated = row.texts[2];
  return figures;
}

std::string BundleAdjustmentResult::FullReport(const Block& block) const {
  auto seconds = [](double value) { return FormatSignificant(value, 3) + " s"; };
  std::ostringstream os;
  os << "Bundle adjustment: " << summary.BriefReport() << "\n";
  os << "Time: problem " << seconds(summary.problem_build_seconds) << ", Ceres preprocessing "
     << seconds(summary.solver_preprocessing_seconds) << ", residuals "
     << seconds(summary.residual_evaluation_seconds) << ", Jacobians "
     << seconds(summary.jacobian_evaluation_seconds) << ", linear solves "
     << seconds(summary.linear_solver_seconds) << ", statistics "
     << seconds(summary.statistics_seconds) << " (Schur structure " << summary.schur_structure
     << ")\n";
  os << "Datum: " << summary.datum_description << "\n";
  os << "Groups (count, stated, RMS, RMS/stated, redundancy share):\n";
  for (const BundleGroupStatistics& g : groups) {
    if (g.fixed()) {
      os << "  " << EnumName(g.group) << ": " << g.num_fixed
         << " held fixed (no residuals, no verdict)\n";
      continue;
    }
    // Stated and RMS in the unit of the group's own figures, as the CLI prints them.
    const BundleGroupFigures figures = FormatGroupFigures(g);
    const std::string unit = " " + figures.unit;
    os << "  " << EnumName(g.group) << ": " << g.count << ", " << (StatedPerAxis(g) ? "X/Y/Z " : "")
       << figures.stated << unit << ", " << figures.rms << unit << ", " << FormatUnitless(g.ratio)
       << ", " << FormatUnitless(g.redundancy_share) << (g.overfit ? "  OVERFIT" : "");
    if (g.num_fixed > 0) os << "; " << g.num_fixed << " more held fixed";
    os << "\n";
    if (!g.message.empty()) os << "    " << g.message << "\n";
  }
  for (const BundleGroupStatistics& g : groups) {
    if (std::isfinite(g.estimated_accuracy.x())) {
      const BundleGroupFigures figures = FormatGroupFigures(g);
      os << "  " << EnumName(g.group) << " accuracy estimated from the data: " << figures.estimated
         << " " << figures.unit << " (stated " << figures.stated_x << " " << figures.unit
         << ", relative standard error " << FormatUnitless(g.estimated_accuracy_standard_error)
         << ")\n";
    } else if (!g.estimation_message.empty()) {
      os << "  " << EnumName(g.group) << ": " << g.estimation_message << "\n";
    }
  }
  for (const BundleSnoopingStep& step : snooping)
    os << "Snooping removed " << EnumName(step.group) << " #" << step.item << " axis " << step.axis
       << ": |w| = " << FormatUnitless(step.normalized, 1) << "\n";
  if (num_control_points > 0)
    os << "Control points: " << num_control_points << ", RMSE "
       << FormatLengthWithUnit(control_rmse_total_m) << "\n";
  if (num_check_points > 0)
    os << "Check points: " << num_check_points << ", RMSE "
       << FormatLengthWithUnit(check_rmse_total_m) << "\n";
  for (const BundleCalibrationResult& c : calibration) {
    const BlockCamera& camera = block.cameras[c.camera];
    os << "Camera '" << camera.camera_id << "':\n";
    for (size_t k = 0; k < c.names.size(); ++k) {
      const CoefficientTexts texts =
          FormatCoefficient(c.values[k], k < c.sigmas.size() ? c.sigmas[k] : kNaN);
      const std::string unit = CameraParamUnit(camera.model, c.names[k]);
      os << "  " << c.names[k] << " = " << texts.value;
      if (k < c.sigmas.size()) os << " +- " << texts.sigma;
      os << " " << (texts.scale.empty() ? unit : texts.scale + " " + unit) << "\n";
    }
    for (const std::string& h : c.high_correlations) os << "  high correlation " << h << "\n";
  }
  return os.str();
}

namespace {

// One adjustment across its rounds: what BundleAdjust's steps share.
struct Adjustment {
  Adjustment(const BundleAdjustmentOptions& options, const BundleAdjustmentConfig& config,
             Block* block, BundleAdjustmentResult* result)
      : options(options),
        build_options(options),
        config(config),
        block(block),
        result(result),
        start(Clock::now()) {}
  const BundleAdjustmentOptions& options;
  // The options the rounds' problems are built with: `options`, without the tie loss once a
  // robust round stalled (SolveRound).
  BundleAdjustmentOptions build_options;
  const BundleAdjustmentConfig& config;
  Block* block;
  BundleAdjustmentResult* result;
  Clock::time_point start;
  BundlePlan plan;
  BundleState state;
  BundleRound round;
  internal::GroupVariance variance;
  internal::RoundChanges changes{options, config, *block, &plan, result, &variance};
  // The last change of the plan removed marks only (rejection, or snooping a mark): the round's
  // problem is updated in place instead of built again.
  bool marks_removed_only = false;
  bool cancelled = false;  // the progress hook asked to stop
};

Status CheckInputs(const BundleAdjustmentOptions& options, const BundleAdjustmentConfig& config,
                   Block* block) {
  PHOTOPOSE_RETURN_IF_ERROR(Validate(options, "invalid options: "));
  // The lever arm moved from the options to the config; its message stays the one it had.
  if (config.lever_arm_m && !config.lever_arm_m->allFinite())
    return Status::Error("invalid options: the lever arm must be finite");
  PHOTOPOSE_RETURN_IF_ERROR(CheckBlock(*block));
  block->BuildIndex();
  for (const int i : config.constant_images)
    if (i < 0 || i >= static_cast<int>(block->images.size()))
      return Status::Error("the config holds a non-existent image constant");
  for (const int p : config.constant_points)
    if (p < 0 || p >= static_cast<int>(block->points.size()))
      return Status::Error("the config holds a non-existent point constant");
  return Status::Ok();
}

// Runs Ceres on the round's problem, with the progress callback when asked.
void Solve(Adjustment* a, int r, bool free_gauge, ceres::Solver::Summary* ceres_summary) {
  ceres::Solver::Options solver_options = internal::CeresSolverOptions(a->options, a->round);
  std::unique_ptr<ProgressCallback> callback;
  if (a->options.solver.progress) {
    callback = std::make_unique<ProgressCallback>(a->options, r, a->round.redundancy(), a->start,
                                                  &a->cancelled);
    callback->set_free_gauge(free_gauge);
    solver_options.callbacks.push_back(callback.get());
  }
  ceres::Solve(solver_options, a->round.problem.get(), ceres_summary);
  AddSolverTimes(*ceres_summary, &a->result->summary);
}

// The first round of a relative block, solved without a gauge first. COLMAP's gauge holds the
// first image at its approximate pose, so that the whole block has to turn about it: at 1 deg and
// 750 m, 13 m at the far corner, along a direction the damped steps follow slowly (39 iterations
// instead of 6 on a 200-image block, 59 instead of 7 on 1000 images). Solved first with no gauge
// at all (Levenberg-Marquardt's damping keeps the 7 free directions still), then moved into
// COLMAP's gauge by a similarity. The cost is invariant and the gradient has no component along
// the similarity, so a converged free solve is the minimum in COLMAP's gauge too: no second solve,
// only the round's bookkeeping switched to the gauge (the statistics need it). A free solve that
// did not converge goes on in the gauge from where it stopped; one that cannot be moved (no
// positive scale) starts over in the gauge. Returns whether the round's solve is done.
bool SolveInFreeGaugeFirst(Adjustment* a, int r, ceres::Solver::Summary* ceres_summary,
                           int* free_iterations) {
  BundleAdjustmentSummary& summary = a->result->summary;
  BundlePlan free_plan = a->plan;
  free_plan.relative_fixed_image = -1;
  free_plan.relative_scale_image = -1;
  const BundleState start_state = a->state;
  const Vector6d fixed_eo = a->state.eo[a->plan.relative_fixed_image];
  const double fixed_coordinate =
      a->state.eo[a->plan.relative_scale_image][a->plan.relative_scale_axis];
  const Clock::time_point build_start = Clock::now();
  internal::BuildBundleRound(a->build_options, a->config, *a->block, free_plan, &a->state, &a->round);
  summary.problem_build_seconds += SecondsSince(build_start);
  Solve(a, r, /*free_gauge=*/true, ceres_summary);
  summary.initial_cost = ceres_summary->initial_cost;
  *free_iterations = static_cast<int>(ceres_summary->iterations.size()) - 1;
  if (a->cancelled) return true;  // done: the adjustment ends here
  if (internal::MoveToRelativeGauge(a->plan, fixed_eo, fixed_coordinate, &a->state.eo,
                                    &a->state.points)) {
    internal::ApplyRelativeGauge(a->plan, &a->state, &a->round);
    return ceres_summary->termination_type == ceres::CONVERGENCE;
  }
  // No similarity reaches COLMAP's gauge from there: solved in that gauge from the start.
  a->state = start_state;
  internal::BuildBundleRound(a->build_options, a->config, *a->block, a->plan, &a->state, &a->round);
  return false;
}

// A robust round that stalled (internal::TieLossStalled) goes on from where it stopped as least
// squares, and so do the rounds after it; the summary's message says so.
void ContinueWithoutTieLoss(Adjustment* a, int r, ceres::Solver::Summary* ceres_summary) {
  BundleAdjustmentSummary& summary = a->result->summary;
  const int stalled_iterations = static_cast<int>(ceres_summary->iterations.size()) - 1;
  const LossType loss = a->build_options.robustness.tie_loss;
  a->build_options.robustness.tie_loss = LossType::kNone;
  const Clock::time_point build_start = Clock::now();
  internal::BuildBundleRound(a->build_options, a->config, *a->block, a->plan, &a->state, &a->round);
  summary.problem_build_seconds += SecondsSince(build_start);
  Solve(a, r, /*free_gauge=*/false, ceres_summary);
  summary.iterations += static_cast<int>(ceres_summary->iterations.size()) - 1;
  summary.message = internal::TieLossStalledMessage(r, loss, stalled_iterations);
}

// Builds and solves round r; the summary's iteration counts, costs and redundancy follow.
void SolveRound(Adjustment* a, int r, ceres::Solver::Summary* ceres_summary) {
  BundleAdjustmentSummary& summary = a->result->summary;
  const Clock::time_point round_start = Clock::now();
  bool solved = false;      // the round's solve is done (the free-gauge solve converged)
  int free_iterations = 0;  // iterations of the free-gauge solve
  if (r == 1 && a->plan.datum == BundleDatum::kRelative &&
      a->options.solver.free_gauge_for_relative_blocks) {
    solved = SolveInFreeGaugeFirst(a, r, ceres_summary, &free_iterations);
  } else {
    const Clock::time_point build_start = Clock::now();
    if (!(r > 1 && a->marks_removed_only && internal::UpdateBundleRound(a->plan, &a->round)))
      internal::BuildBundleRound(a->build_options, a->config, *a->block, a->plan, &a->state, &a->round);
    summary.problem_build_seconds += SecondsSince(build_start);
  }
  if (!solved) {
    Solve(a, r, /*free_gauge=*/false, ceres_summary);
    if (r == 1 && free_iterations == 0) summary.initial_cost = ceres_summary->initial_cost;
    summary.iterations += static_cast<int>(ceres_summary->iterations.size()) - 1;
  }
  const SolverTermination ended =
      ceres_summary->termination_type == ceres::CONVERGENCE      ? SolverTermination::kConverged
      : ceres_summary->termination_type == ceres::NO_CONVERGENCE ? SolverTermination::kNoConvergence
                                                                 : SolverTermination::kFailure;
  if (!a->cancelled && internal::TieLossStalled(ended, a->build_options.robustness.tie_loss)) {
    ContinueWithoutTieLoss(a, r, ceres_summary);
  }
  summary.iterations += free_iterations;
  summary.rounds = r;
  summary.final_cost = ceres_summary->final_cost;
  summary.redundancy = a->round.redundancy();
  summary.round_seconds.push_back(SecondsSince(round_start));
}

// A round that did not converge (or was cancelled by the progress hook) ends the adjustment: the
// summary says so, with what the round adjusted (the statistics, which count them otherwise, are
// not computed).
void EndWithFailedRound(const Adjustment& a, int r, const ceres::Solver::Summary& ceres_summary) {
  BundleAdjustmentSummary& summary = a.result->summary;
  summary.termination = a.cancelled ? SolverTermination::kCancelled
                        : ceres_summary.termination_type == ceres::NO_CONVERGENCE
                            ? SolverTermination::kNoConvergence
                            : SolverTermination::kFailure;
  summary.message = "round " + std::to_string(r) + ": " +
                    (a.cancelled ? "cancelled by the progress hook after iteration " +
                                       std::to_string(ceres_summary.iterations.empty()
                                                          ? 0
                                                          : ceres_summary.iterations.back().iteration)
                                 : ceres_summary.message);
  summary.num_images = static_cast<int>(a.block->images.size());
  summary.num_points = static_cast<int>(
      std::count(a.plan.point_in_problem.begin(), a.plan.point_in_problem.end(), 1));
  summary.num_marks =
      static_cast<int>(std::count(a.plan.mark_used.begin(), a.plan.mark_used.end(), 1));
  summary.time_seconds = SecondsSince(a.start);
}

// The adjusted orientations, points and cameras, written into the block.
void WriteBack(const BundlePlan& plan, const BundleState& state, Block* block) {
  for (size_t i = 0; i < block->images.size(); ++i) {
    ExteriorOrientation eo;
    eo.parameters = state.eo[i];
    block->images[i].eo = eo;
  }
  for (size_t p = 0; p < block->points.size(); ++p)
    if (plan.point_in_problem[p]) block->points[p].position_m = state.points[p];
  for (size_t c = 0; c < block->cameras.size(); ++c) block->cameras[c].params = state.cameras[c];
}

}  // namespace

BundleAdjustmentConfig WithFixedControlPoints(const BundleAdjustmentConfig& config,
                                              const Block& block) {
  BundleAdjustmentConfig held = config;
  for (size_t p = 0; p < block.points.size(); ++p)
    if (IsHeldFixed(block.points[p])) held.constant_points.insert(static_cast<int>(p));
  return held;
}

Status BundleAdjust(const BundleAdjustmentOptions& options,
                    const BundleAdjustmentConfig& stated_config, Block* block,
                    BundleAdjustmentResult* result) {
  const BundleAdjustmentConfig config = WithFixedControlPoints(stated_config, *block);
  Adjustment a(options, config, block, result);
  *result = BundleAdjustmentResult();
  BundleAdjustmentSummary& summary = result->summary;
  PHOTOPOSE_RETURN_IF_ERROR(CheckInputs(options, config, block));
  PHOTOPOSE_RETURN_IF_ERROR(
      internal::MakeBundlePlan(internal::PlanOptionsOf(options, config), config, *block, &a.plan));
  summary.datum = a.plan.datum;
  summary.datum_description = a.plan.datum_description;
  for (const int p : a.plan.tie_points_left_out)
    summary.tie_points_left_out.push_back(block->points[p].id);
  a.state = StartState(config, *block);
  summary.plan_seconds = SecondsSince(a.start);

  // Rounds: adjust; then remove blunders (rejection rounds or data snooping, one at a time) or
  // rescale the groups (variance component estimation) and adjust again, until neither changes
  // (internal/bundle_rounds.h).
  for (int r = 1;; ++r) {
    ceres::Solver::Summary ceres_summary;
    SolveRound(&a, r, &ceres_summary);
    if (ceres_summary.termination_type != ceres::CONVERGENCE || a.cancelled) {
      EndWithFailedRound(a, r, ceres_summary);
      return Status::Ok();
    }
    summary.sigma0 = summary.redundancy > 0
                         ? std::sqrt(2.0 * ceres_summary.final_cost / summary.redundancy)
                         : kNaN;
    const Clock::time_point statistics_start = Clock::now();
    const Status determined = internal::ComputeBundleStatistics(options, *block, a.plan, a.state,
                                                                a.round, result, &a.variance);
    summary.statistics_seconds += SecondsSince(statistics_start);
    if (!determined.ok()) {
      // Converged, but to one of infinitely many minima: a failure, the block left as it was.
      summary.termination = SolverTermination::kFailure;
      summary.message = "round " + std::to_string(r) + ": " + determined.message();
      summary.time_seconds = SecondsSince(a.start);
      return Status::Ok();
    }
    const internal::RoundChange change = internal::ChangeAfterRound(&a.changes, r);
    if (change == internal::RoundChange::kFailed) {
      summary.time_seconds = SecondsSince(a.start);
      return Status::Ok();
    }
    if (change == internal::RoundChange::kNone) break;
    a.marks_removed_only = change == internal::RoundChange::kMarksRemoved;
  }
  if (options.statistics.covariances == BundleCovarianceMethod::kNone) {
    // No covariances: the last round's normal matrix factorised once all the same.
    const Clock::time_point check_start = Clock::now();
    const Status determined =
        internal::CheckBundleDeterminacy(*block, a.plan, a.state, a.round,
                                         options.solver.num_threads, &summary.factorization_seconds);
    summary.statistics_seconds += SecondsSince(check_start);
    if (!determined.ok()) {
      summary.termination = SolverTermination::kFailure;
      summary.message = "round " + std::to_string(summary.rounds) + ": " + determined.message();
      summary.time_seconds = SecondsSince(a.start);
      return Status::Ok();
    }
  }
  summary.termination = SolverTermination::kConverged;
  summary.num_rejected_marks = static_cast<int>(result->rejected_marks.size());
  if (options.statistics.estimate_accuracies) internal::ReportEstimatedAccuracies(a.changes);
  WriteBack(a.plan, a.state, block);
  summary.time_seconds = SecondsSince(a.start);
  return Status::Ok();
}

}  // namespace photopose
