#include "solvers/resection.h"

#include <ceres/ceres.h>

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
      return new ceres::ArctanLoss(scale);
    case LossType::kTukey:
      return new ceres::TukeyLoss(scale);
  }
  return nullptr;
}

// Whitened residuals, optional whitened Jacobian rows, for the statistics after any solver.
struct Evaluation {
  std::vector<Eigen::Vector2d> residuals_px;
  bool all_in_front = true;
};

Evaluation EvaluateResiduals(const ResectionInput& input, const ExteriorOrientation& eo) {
  Evaluation evaluation;
  evaluation.residuals_px.resize(input.image_plane_um.size());
  for (size_t i = 0; i < input.image_plane_um.size(); ++i) {
    double xy[2];
    if (!ProjectToImagePlane(eo.data(), input.points_in_ground[i].data(), input.focal_length_um, xy)) {
      evaluation.all_in_front = false;
      evaluation.residuals_px[i].setConstant(std::numeric_limits<double>::infinity());
      continue;
    }
    evaluation.residuals_px[i] =
        (input.image_plane_um[i] - Eigen::Vector2d(xy[0], xy[1])) / input.pixel_size_um;
  }
  return evaluation;
}

struct CeresOutcome {
  bool usable = false;
  int iterations = 0;
  double initial_cost = 0.0, final_cost = 0.0;
  std::string message;
};

CeresOutcome RefineWithCeres(const ResectionOptions& options, const ResectionInput& input,
                             const std::vector<char>& use, ExteriorOrientation* eo) {
  ceres::Problem::Options problem_options;
  problem_options.enable_fast_removal = false;
  problem_options.disable_all_safety_checks = true;
  ceres::Problem problem(problem_options);
  std::map<double, ceres::LossFunction*> loss_by_sigma;  // one loss object per distinct sigma
  for (size_t i = 0; i < input.image_plane_um.size(); ++i) {
    if (!use[i]) continue;
    const double sigma_px = input.sigma_px[i];
    const PoseCostFunctor data(input.image_plane_um[i], input.points_in_ground[i],
                               input.focal_length_um, 1.0 / (input.pixel_size_um * sigma_px));
    ceres::LossFunction*& loss = loss_by_sigma[sigma_px];
    if (loss == nullptr) loss = MakeLoss(options.loss, options.loss_scale_px / sigma_px);
    problem.AddResidualBlock(CreatePoseCost(options.jacobian, data), loss, eo->data());
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

bool ResectionOptions::IsValid(std::string* why) const {
  auto fail = [why](const char* text) {
    if (why != nullptr) *why = text;
    return false;
  };
  if (!(loss_scale_px > 0.0)) return fail("loss_scale_px must be positive");
  if (!(ransac_threshold_px > 0.0)) return fail("ransac_threshold_px must be positive");
  if (max_iterations < 1) return fail("max_iterations must be at least 1");
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
  const Eigen::Vector3d s = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter).eigenvalues();
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
    for (size_t i = 0; i < n; ++i) {
      double xy[2];
      if (!ProjectToImagePlane(eo.data(), input.points_in_ground[i].data(), input.focal_length_um, xy)) {
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
    std::vector<Eigen::Vector2d> observations;
    std::vector<Eigen::Vector3d> points;
    std::vector<double> sigmas_um;
    for (size_t i = 0; i < n; ++i) {
      if (!use[i]) continue;
      observations.push_back(input.image_plane_um[i]);
      points.push_back(input.points_in_ground[i]);
      sigmas_um.push_back(input.sigma_px[i] * input.pixel_size_um);
    }
    TaylorResectionResult taylor;
    const Status status = TaylorResection(taylor_options, observations, points, sigmas_um,
                                          input.focal_length_um, eo, &taylor);
    summary.iterations = taylor.summary.iterations;
    summary.initial_cost = taylor.summary.initial_cost;
    summary.final_cost = taylor.summary.final_cost;
    if (!status.ok()) return fail("Taylor: " + status.message());
    if (!taylor.summary.IsSolutionUsable()) return fail("Taylor: " + taylor.summary.message);
    eo = taylor.eo;
  }
  summary.refinement_seconds = SecondsSince(refine_start);
  eo.parameters[3] = WrapAngle(eo.parameters[3]);
  eo.parameters[4] = WrapAngle(eo.parameters[4]);
  eo.parameters[5] = WrapAngle(eo.parameters[5]);

  // 3. Residuals, inlier flags and statistics over the inliers.
  const Evaluation evaluation = EvaluateResiduals(input, eo);
  result.residuals_px = evaluation.residuals_px;
  result.inliers.assign(n, 0);
  Eigen::Matrix<double, 6, 6> normal = Eigen::Matrix<double, 6, 6>::Zero();
  double weighted_ssq = 0.0;
  int num_inliers = 0;
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d& r = evaluation.residuals_px[i];
    if (!r.allFinite() || r.norm() > options.ransac_threshold_px) continue;
    result.inliers[i] = 1;
    ++num_inliers;
    double xy[2];
    Eigen::Matrix<double, 2, 6, Eigen::RowMajor> J;
    ProjectWithJacobians(eo.data(), input.points_in_ground[i].data(), input.focal_length_um, xy,
                         J.data(), nullptr, nullptr);
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
