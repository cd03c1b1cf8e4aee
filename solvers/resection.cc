#include "solvers/resection.h"

#include <ceres/ceres.h>
#include <ceres/tiny_solver.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <sstream>
#include <thread>

#include "core/collinearity.h"
#include "solvers/absolute_pose.h"
#include "solvers/taylor_resection.h"

namespace photopose {
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

ceres::LossFunction* MakeLoss(LossType type, double scale) {
  switch (type) {
    case LossType::kNone:
      return nullptr;
    case LossType::kHuber:
      return new ceres::HuberLoss(scale);
    case LossType::kSoftL1:
      return new ceres::SoftLOneLoss(scale);
    case LossType::kCauchy:
      return new ceres::CauchyLoss(scale);
    case LossType::kArctan:
      // Ceres' ArctanLoss(a) is rho(s) = a atan(s / a): a is on the squared scale.
      return new ceres::ArctanLoss(scale * scale);
    case LossType::kTukey:
      return new ceres::TukeyLoss(scale);
  }
  return nullptr;
}

struct CeresOutcome {
  bool usable = false;
  int iterations = 0;
  int rounds = 1;  // IRLS rounds (TinySolver with a robust loss)
  double initial_cost = 0.0, final_cost = 0.0;
  std::string message;
};

// One image's observations in a frame centred on the control points: large projected coordinates
// would otherwise cost digits and make relative step tolerances meaningless.
struct CentredProblem {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  std::vector<std::unique_ptr<ceres::CostFunction>> costs;  // one per used observation
  std::vector<double> sigma_px;                              // of each cost
};

CentredProblem MakeCentredProblem(const ResectionOptions& options, const ResectionInput& input,
                                  const std::vector<char>& use) {
  CentredProblem problem;
  int count = 0;
  for (size_t i = 0; i < input.points_in_ground.size(); ++i) {
    if (!use[i]) continue;
    problem.origin += input.points_in_ground[i];
    ++count;
  }
  problem.origin /= std::max(1, count);
  for (size_t i = 0; i < input.image_plane_um.size(); ++i) {
    if (!use[i]) continue;
    const PoseCostFunctor data(input.image_plane_um[i], input.points_in_ground[i] - problem.origin,
                               input.focal_length_um, 1.0 / (input.pixel_size_um * input.sigma_px[i]));
    problem.costs.emplace_back(CreatePoseCost(options.jacobian, data));
    problem.sigma_px.push_back(input.sigma_px[i]);
  }
  return problem;
}

// The stacked, weighted residuals of all observations for ceres::TinySolver. Weight i multiplies
// residual block i (IRLS); the Jacobian is column-major (2n x 6), as TinySolver expects.
class StackedPoseFunction {
 public:
  using Scalar = double;
  enum { NUM_RESIDUALS = Eigen::Dynamic, NUM_PARAMETERS = kExteriorOrientationSize };

  StackedPoseFunction(const CentredProblem& problem, const std::vector<double>& sqrt_weights)
      : problem_(problem), sqrt_weights_(sqrt_weights) {}

  int NumResiduals() const { return 2 * static_cast<int>(problem_.costs.size()); }

  bool operator()(const double* eo, double* residuals, double* jacobian) const {
    const double* parameters[] = {eo};
    double block[2 * kExteriorOrientationSize];
    double* jacobians[] = {block};
    const int rows = NumResiduals();
    for (size_t i = 0; i < problem_.costs.size(); ++i) {
      if (!problem_.costs[i]->Evaluate(parameters, residuals + 2 * i, jacobian ? jacobians : nullptr)) {
        // Behind the camera: a huge residual makes TinySolver reject the step that led here.
        residuals[2 * i] = residuals[2 * i + 1] = 1e10;
        if (jacobian != nullptr) return false;
        continue;
      }
      const double w = sqrt_weights_[i];
      residuals[2 * i] *= w;
      residuals[2 * i + 1] *= w;
      if (jacobian != nullptr) {
        for (int k = 0; k < kExteriorOrientationSize; ++k) {
          jacobian[k * rows + 2 * i] = w * block[k];
          jacobian[k * rows + 2 * i + 1] = w * block[kExteriorOrientationSize + k];
        }
      }
    }
    return true;
  }

 private:
  const CentredProblem& problem_;
  const std::vector<double>& sqrt_weights_;
};

// Squared whitened residual norms of every cost at eo (centred); false if a point is behind.
bool SquaredNorms(const CentredProblem& problem, const double* eo, std::vector<double>* s) {
  const double* parameters[] = {eo};
  s->resize(problem.costs.size());
  for (size_t i = 0; i < problem.costs.size(); ++i) {
    double r[2];
    if (!problem.costs[i]->Evaluate(parameters, r, nullptr)) return false;
    (*s)[i] = r[0] * r[0] + r[1] * r[1];
  }
  return true;
}

// IRLS stops when a round moves the pose by less than this, relative (1e-9 of a 100 m flying
// height is 0.1 um: far below any pose uncertainty).
constexpr double kReweightingTolerance = 1e-9;

CeresOutcome RefineWithTinySolver(const ResectionOptions& options, const CentredProblem& problem,
                                  Vector6d* eo_centred) {
  CeresOutcome outcome;
  std::vector<std::unique_ptr<ceres::LossFunction>> losses;
  std::map<double, ceres::LossFunction*> loss_by_sigma;
  std::vector<ceres::LossFunction*> loss_of(problem.costs.size(), nullptr);
  for (size_t i = 0; i < problem.costs.size(); ++i) {
    ceres::LossFunction*& loss = loss_by_sigma[problem.sigma_px[i]];
    if (loss == nullptr && options.loss != LossType::kNone) {
      losses.emplace_back(MakeLoss(options.loss, options.loss_scale_px / problem.sigma_px[i]));
      loss = losses.back().get();
    }
    loss_of[i] = loss;
  }
  auto robust_cost = [&](const std::vector<double>& s) {
    double cost = 0.0;
    for (size_t i = 0; i < s.size(); ++i) {
      double rho[3] = {s[i], 1.0, 0.0};
      if (loss_of[i] != nullptr) loss_of[i]->Evaluate(s[i], rho);
      cost += 0.5 * rho[0];
    }
    return cost;
  };
  std::vector<double> s;
  if (!SquaredNorms(problem, eo_centred->data(), &s)) {
    outcome.message = "Ceres: a control point is behind the camera at the initial pose";
    return outcome;
  }
  outcome.initial_cost = robust_cost(s);
  std::vector<double> sqrt_weights(problem.costs.size(), 1.0);
  const int rounds = options.loss == LossType::kNone ? 1 : options.max_reweighting_rounds;
  bool converged = false;
  for (int round = 0; round < rounds && !converged; ++round) {
    bool weights_changed = round == 0;
    for (size_t i = 0; i < s.size(); ++i) {
      double rho[3] = {s[i], 1.0, 0.0};
      if (loss_of[i] != nullptr) loss_of[i]->Evaluate(s[i], rho);
      const double w = std::sqrt(std::max(rho[1], 0.0));
      weights_changed |= w != sqrt_weights[i];
      sqrt_weights[i] = w;
    }
    if (round == 0 && *std::max_element(sqrt_weights.begin(), sqrt_weights.end()) == 0.0) {
      outcome.message = std::string("Ceres: every residual is beyond the ") + LossTypeName(options.loss) +
                        " loss at the initial pose, so nothing pulls the pose; give a larger "
                        "--loss_scale or better initial values";
      return outcome;
    }
    // The same weights as the round that produced this pose: it is the fixed point already (e.g.
    // Huber with every residual inside its quadratic zone).
    if (!weights_changed) {
      converged = true;
      break;
    }
    StackedPoseFunction function(problem, sqrt_weights);
    ceres::TinySolver<StackedPoseFunction> solver;
    solver.options.max_num_iterations = options.max_iterations;
    solver.options.parameter_tolerance = options.parameter_tolerance;
    solver.options.gradient_tolerance = 1e-14;
    // TinySolver's function tolerance is absolute; the final cost of whitened residuals is about
    // half their number, so this is options.function_tolerance relative to it.
    solver.options.function_tolerance = options.function_tolerance * function.NumResiduals();
    const Vector6d before = *eo_centred;
    const auto& summary = solver.Solve(function, eo_centred);
    outcome.iterations += summary.iterations;
    if (!eo_centred->allFinite() || !SquaredNorms(problem, eo_centred->data(), &s)) {
      outcome.message = "Ceres TinySolver: the pose left the valid region (a point behind the camera)";
      return outcome;
    }
    if (summary.status == ceres::TinySolver<StackedPoseFunction>::HIT_MAX_ITERATIONS) {
      outcome.message = "Ceres TinySolver: no convergence in " + std::to_string(options.max_iterations) + " iterations";
      return outcome;
    }
    // Without a loss one round is the whole solve; with one, reweighting has converged when a
    // round no longer moves the pose (kReweightingTolerance).
    const double step = (*eo_centred - before).norm();
    converged = options.loss == LossType::kNone ||
                step <= kReweightingTolerance * (eo_centred->norm() + 1.0);
    outcome.rounds = round + 1;
  }
  outcome.final_cost = robust_cost(s);
  outcome.usable = converged;
  if (!converged) outcome.message = "Ceres TinySolver: reweighting did not converge";
  return outcome;
}

CeresOutcome RefineWithCeresProblem(const ResectionOptions& options, CentredProblem* problem_data,
                                    Vector6d* eo_centred) {
  ceres::Problem::Options problem_options;
  problem_options.enable_fast_removal = false;
  problem_options.disable_all_safety_checks = true;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  std::map<double, ceres::LossFunction*> loss_by_sigma;  // one loss object per distinct sigma
  for (size_t i = 0; i < problem_data->costs.size(); ++i) {
    const double sigma_px = problem_data->sigma_px[i];
    ceres::LossFunction*& loss = loss_by_sigma[sigma_px];
    if (loss == nullptr) loss = MakeLoss(options.loss, options.loss_scale_px / sigma_px);
    problem.AddResidualBlock(problem_data->costs[i].get(), loss, eo_centred->data());
  }
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_QR;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.function_tolerance = options.function_tolerance;
  solver_options.parameter_tolerance = options.parameter_tolerance;
  solver_options.gradient_tolerance = 1e-16;
  solver_options.num_threads = 1;
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
  CeresOutcome outcome;
  outcome.iterations = static_cast<int>(summary.iterations.size()) - 1;
  outcome.initial_cost = summary.initial_cost;
  outcome.final_cost = summary.final_cost;
  outcome.usable = summary.IsSolutionUsable() && summary.termination_type == ceres::CONVERGENCE;
  if (!outcome.usable) outcome.message = "Ceres: " + summary.message;
  return outcome;
}

CeresOutcome RefineWithCeres(const ResectionOptions& options, const ResectionInput& input,
                             const std::vector<char>& use, ExteriorOrientation* eo) {
  CentredProblem problem = MakeCentredProblem(options, input, use);
  Vector6d eo_centred = eo->parameters;
  eo_centred.head<3>() -= problem.origin;
  CeresOutcome outcome;
  if (options.minimizer == CeresMinimizer::kTinySolver) {
    const Vector6d start = eo_centred;
    outcome = RefineWithTinySolver(options, problem, &eo_centred);
    if (!outcome.usable && outcome.rounds >= options.max_reweighting_rounds) {
      // Reweighting still creeping (a loss with many points near its scale): let ceres::Solve
      // finish from where it got, with the loss applied exactly.
      const int iterations = outcome.iterations;
      outcome = RefineWithCeresProblem(options, &problem, &eo_centred);
      outcome.iterations += iterations;
      if (!outcome.usable) eo_centred = start;
    }
  } else {
    outcome = RefineWithCeresProblem(options, &problem, &eo_centred);
  }
  eo->parameters = eo_centred;
  eo->parameters.head<3>() += problem.origin;
  return outcome;
}

}  // namespace

std::optional<PoseSolver> ParsePoseSolver(const std::string& name) {
  if (name == "ceres") return PoseSolver::kCeres;
  if (name == "taylor") return PoseSolver::kTaylor;
  if (name == "taylor_as_printed") return PoseSolver::kTaylorAsPrinted;
  return std::nullopt;
}

const char* PoseSolverName(PoseSolver solver) {
  switch (solver) {
    case PoseSolver::kCeres:
      return "ceres";
    case PoseSolver::kTaylor:
      return "taylor";
    case PoseSolver::kTaylorAsPrinted:
      return "taylor_as_printed";
  }
  return "?";
}

std::optional<LossType> ParseLossType(const std::string& name) {
  static const std::pair<const char*, LossType> kNames[] = {
      {"none", LossType::kNone},     {"huber", LossType::kHuber},   {"softl1", LossType::kSoftL1},
      {"cauchy", LossType::kCauchy}, {"arctan", LossType::kArctan}, {"tukey", LossType::kTukey}};
  for (const auto& [text, type] : kNames)
    if (name == text) return type;
  return std::nullopt;
}

const char* LossTypeName(LossType loss) {
  switch (loss) {
    case LossType::kNone:
      return "none";
    case LossType::kHuber:
      return "huber";
    case LossType::kSoftL1:
      return "softl1";
    case LossType::kCauchy:
      return "cauchy";
    case LossType::kArctan:
      return "arctan";
    case LossType::kTukey:
      return "tukey";
  }
  return "?";
}

std::optional<CeresMinimizer> ParseCeresMinimizer(const std::string& name) {
  if (name == "tiny_solver") return CeresMinimizer::kTinySolver;
  if (name == "problem") return CeresMinimizer::kProblem;
  return std::nullopt;
}

const char* CeresMinimizerName(CeresMinimizer minimizer) {
  return minimizer == CeresMinimizer::kTinySolver ? "tiny_solver" : "problem";
}

bool ResectionOptions::IsValid(std::string* why) const {
  auto fail = [why](const char* text) {
    if (why != nullptr) *why = text;
    return false;
  };
  if (!(loss_scale_px > 0.0)) return fail("loss_scale_px must be positive");
  if (!(ransac_threshold_px > 0.0)) return fail("ransac_threshold_px must be positive");
  if (max_iterations < 1) return fail("max_iterations must be at least 1");
  if (max_reweighting_rounds < 1) return fail("max_reweighting_rounds must be at least 1");
  if (!(function_tolerance > 0.0) || !(parameter_tolerance > 0.0))
    return fail("tolerances must be positive");
  return ransac.IsValid(why);
}

std::string ResectionSummary::BriefReport() const {
  std::ostringstream os;
  os << (termination == ResectionTermination::kConverged       ? "CONVERGED"
         : termination == ResectionTermination::kNoConvergence ? "NO_CONVERGENCE"
                                                               : "FAILURE")
     << ", " << (used_approximate ? "approximate pose given" : "RANSAC") << ", trials "
     << ransac_trials << ", iterations " << iterations << ", cost " << initial_cost << " -> "
     << final_cost << ", " << total_seconds * 1e3 << " ms";
  if (!message.empty()) os << ": " << message;
  return os.str();
}

Status CheckControlConfiguration(const std::vector<Eigen::Vector3d>& points) {
  if (points.size() < 3) {
    return Status::Error("needs at least three control points, has " + std::to_string(points.size()));
  }
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) {
    if (!p.allFinite()) return Status::Error("a control point has a non-finite coordinate");
    mean += p;
  }
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& p : points) scatter += (p - mean) * (p - mean).transpose();
  // The iterative solver: the closed form (computeDirect) loses the small eigenvalue's digits.
  const Eigen::Vector3d s =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter, Eigen::EigenvaluesOnly).eigenvalues();
  // Eigenvalues ascending: collinear when the second largest spread is negligible.
  if (!(s[1] > 1e-12 * s[2])) return Status::Error("all control points lie on one line");
  return Status::Ok();
}

ResectionResult ResectImage(const ResectionOptions& options, const ResectionInput& input) {
  const Clock::time_point start = Clock::now();
  ResectionResult result;
  ResectionSummary& summary = result.summary;
  auto fail = [&](const std::string& message) {
    summary.termination = ResectionTermination::kFailure;
    summary.message = message;
    summary.total_seconds = SecondsSince(start);
    result.success = false;
    return result;
  };
  std::string why;
  if (!options.IsValid(&why)) return fail("invalid options: " + why);
  const size_t n = input.image_plane_um.size();
  if (input.points_in_ground.size() != n || input.sigma_px.size() != n)
    return fail("observations, points and sigmas differ in number");
  if (!(input.focal_length_um > 0.0) || !(input.pixel_size_um > 0.0))
    return fail("focal length and pixel size must be positive");
  for (size_t i = 0; i < n; ++i) {
    if (!input.image_plane_um[i].allFinite()) return fail("an image observation is not finite");
    if (!(input.sigma_px[i] > 0.0)) return fail("an observation accuracy is not positive");
  }
  const Status configuration = CheckControlConfiguration(input.points_in_ground);
  if (!configuration.ok()) return fail(configuration.message());

  // 1. Initial values.
  ExteriorOrientation eo;
  std::vector<char> use(n, 1);
  if (input.approximate.has_value()) {
    eo = *input.approximate;
    summary.used_approximate = true;
    if (!eo.parameters.allFinite()) return fail("the approximate pose is not finite");
    const SeedProjector projector(eo.data(), input.focal_length_um);
    for (size_t i = 0; i < n; ++i) {
      double xy[2];
      if (!projector.Project(input.points_in_ground[i].data(), xy, nullptr, nullptr, nullptr)) {
        const std::string name = i < input.point_ids.size() ? "'" + input.point_ids[i] + "'"
                                                            : "#" + std::to_string(i + 1);
        return fail("control point " + name + " is behind the camera at the approximate pose");
      }
    }
  } else {
    const Clock::time_point ransac_start = Clock::now();
    AbsolutePoseRansacOptions ransac_options;
    ransac_options.ransac = options.ransac;
    ransac_options.inlier_threshold_um = options.ransac_threshold_px * input.pixel_size_um;
    RansacSummary ransac_summary;
    const Status status = EstimateAbsolutePoseRansac(ransac_options, input.image_plane_um,
                                                     input.points_in_ground, input.focal_length_um,
                                                     &eo, &use, &ransac_summary);
    summary.ransac_trials = ransac_summary.num_trials;
    summary.ransac_seconds = SecondsSince(ransac_start);
    if (!status.ok()) return fail("no initial pose: " + status.message());
  }

  // 2. Refinement.
  const Clock::time_point refine_start = Clock::now();
  if (options.solver == PoseSolver::kCeres) {
    const CeresOutcome outcome = RefineWithCeres(options, input, use, &eo);
    summary.iterations = outcome.iterations;
    summary.initial_cost = outcome.initial_cost;
    summary.final_cost = outcome.final_cost;
    if (!outcome.usable) return fail(outcome.message);
  } else {
    TaylorResectionOptions taylor_options;
    taylor_options.partials = options.solver == PoseSolver::kTaylor ? TaylorPartials::kCorrected
                                                                    : TaylorPartials::kAsPrinted;
    taylor_options.max_iterations = options.max_iterations;
    // The observations RANSAC kept (all of them when it did not run: no copies then).
    const bool all_used = std::all_of(use.begin(), use.end(), [](char u) { return u != 0; });
    std::vector<Eigen::Vector2d> observations;
    std::vector<Eigen::Vector3d> points;
    std::vector<double> sigmas_um;
    for (size_t i = 0; i < n; ++i) {
      if (!use[i]) continue;
      sigmas_um.push_back(input.sigma_px[i] * input.pixel_size_um);
      if (all_used) continue;
      observations.push_back(input.image_plane_um[i]);
      points.push_back(input.points_in_ground[i]);
    }
    TaylorResectionResult taylor;
    const Status status = TaylorResection(
        taylor_options, all_used ? input.image_plane_um : observations,
        all_used ? input.points_in_ground : points, sigmas_um, input.focal_length_um, eo, &taylor);
    summary.iterations = taylor.summary.iterations;
    summary.initial_cost = taylor.summary.initial_cost;
    summary.final_cost = taylor.summary.final_cost;
    if (!status.ok()) return fail("Taylor: " + status.message());
    if (!taylor.summary.IsSolutionUsable()) return fail("Taylor: " + taylor.summary.message);
    eo = taylor.eo;
  }
  summary.refinement_seconds = SecondsSince(refine_start);
  // The canonical triple of the rotation (|phi| <= 90 deg, the others in (-180, 180]): a solver may
  // end on the equivalent (omega + 180, 180 - phi, kappa + 180).
  eo.set_angles_seed_rad(AnglesFromRotation(
      RotationConvention::kSeed, RotationFromAngles(RotationConvention::kSeed, eo.angles_seed_rad())));

  // 3. Residuals, inlier flags and statistics over the inliers, in one pass.
  result.residuals_px.resize(n);
  result.inliers.assign(n, 0);
  Eigen::Matrix<double, 6, 6> normal = Eigen::Matrix<double, 6, 6>::Zero();
  double weighted_ssq = 0.0;
  int num_inliers = 0;
  const SeedProjector projector(eo.data(), input.focal_length_um);
  for (size_t i = 0; i < n; ++i) {
    double xy[2];
    Eigen::Matrix<double, 2, 6, Eigen::RowMajor> J;
    Eigen::Vector2d& r = result.residuals_px[i];
    if (!projector.Project(input.points_in_ground[i].data(), xy, J.data(), nullptr, nullptr)) {
      r.setConstant(std::numeric_limits<double>::infinity());
      continue;
    }
    r = (input.image_plane_um[i] - Eigen::Vector2d(xy[0], xy[1])) / input.pixel_size_um;
    if (r.norm() > options.ransac_threshold_px) continue;
    result.inliers[i] = 1;
    ++num_inliers;
    const double inverse_sigma_um = 1.0 / (input.sigma_px[i] * input.pixel_size_um);
    J *= inverse_sigma_um;
    normal += J.transpose() * J;
    weighted_ssq += (r / input.sigma_px[i]).squaredNorm();
  }
  result.num_inliers = num_inliers;
  if (num_inliers < 3) {
    return fail("only " + std::to_string(num_inliers) + " observations within " +
                std::to_string(options.ransac_threshold_px) + " px of the solution");
  }
  result.degrees_of_freedom = 2 * num_inliers - 6;
  // With no redundancy sigma0 is undefined; the covariance is then the a-priori one (sigma0 = 1).
  result.sigma0 = result.degrees_of_freedom > 0 ? std::sqrt(weighted_ssq / result.degrees_of_freedom)
                                                : 0.0;
  Eigen::LDLT<Matrix6d> ldlt(normal);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0))
    return fail("the normal matrix is singular: the pose is not determined by these points");
  const double variance_factor = result.degrees_of_freedom > 0 ? result.sigma0 * result.sigma0 : 1.0;
  result.covariance = variance_factor * ldlt.solve(Matrix6d::Identity());
  result.standard_deviations = result.covariance.diagonal().cwiseSqrt();
  result.eo = eo;
  result.success = true;
  summary.termination = ResectionTermination::kConverged;
  if (input.approximate.has_value() == false && n == 3)
    summary.message = "three points: P3P may have up to four solutions; the one kept fits exactly";
  summary.total_seconds = SecondsSince(start);
  return result;
}

std::vector<ResectionResult> ResectImages(const ResectionOptions& options,
                                          const std::vector<ResectionInput>& inputs, int num_threads) {
  std::vector<ResectionResult> results(inputs.size());
  if (num_threads <= 0) num_threads = std::max(1u, std::thread::hardware_concurrency());
  num_threads = std::min<int>(num_threads, std::max<size_t>(1, inputs.size()));
  std::atomic<size_t> next{0};
  auto worker = [&]() {
    for (size_t i = next++; i < inputs.size(); i = next++) {
      ResectionOptions image_options = options;
      // A distinct, reproducible RANSAC stream per image, whatever the thread schedule.
      image_options.ransac.seed = options.ransac.seed + 0x9E3779B97F4A7C15ull * (i + 1);
      results[i] = ResectImage(image_options, inputs[i]);
    }
  };
  std::vector<std::thread> threads;
  for (int t = 1; t < num_threads; ++t) threads.emplace_back(worker);
  worker();
  for (auto& thread : threads) thread.join();
  return results;
}

}  // namespace photopose
