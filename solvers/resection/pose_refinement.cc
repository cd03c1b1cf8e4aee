#include "solvers/resection/pose_refinement.h"

#include <ceres/ceres.h>
#include <ceres/tiny_solver.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "core/rotation.h"
#include "core/units.h"

namespace photopose {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// One image's observations in a frame centred on their ground points: large projected coordinates
// would otherwise cost digits and make relative step tolerances meaningless. The observations are
// kept by value and evaluated through EvaluatePoseCostAnalytic (the analytic cost's own body);
// Ceres cost objects are made only for the autodiff path and for ceres::Problem (MakeCosts): one
// heap object per mark per refinement was a tenth of a batch resection's time.
struct CentredProblem {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  JacobianType jacobian = JacobianType::kAnalytic;
  double focal = 0.0;                                       // c of every observation (their unit)
  std::vector<PoseCostFunctor> data;                        // one per observation, whitened
  std::vector<std::unique_ptr<ceres::CostFunction>> costs;  // the same, when made (MakeCosts)

  size_t size() const { return data.size(); }
  // The pose eo (centred) made ready for the analytic path's projections: one per pose, for all
  // observations (the same bits as one per observation).
  SeedProjector ProjectorAt(const double* eo) const { return SeedProjector(eo, focal); }
  // Residual i (2) at eo (centred), `projector` = ProjectorAt(eo), and, when jacobian is not null,
  // its 2 x 6 row-major Jacobian.
  bool Evaluate(size_t i, const double* eo, const SeedProjector& projector, double* residual,
                double* jacobian_row_major) const {
    if (jacobian == JacobianType::kAnalytic)
      return EvaluatePoseCostAnalytic(data[i], projector, residual, jacobian_row_major);
    const double* parameters[] = {eo};
    double* jacobians[] = {jacobian_row_major};
    return costs[i]->Evaluate(parameters, residual,
                              jacobian_row_major != nullptr ? jacobians : nullptr);
  }
  // The Ceres cost objects of the observations (once).
  void MakeCosts() {
    if (costs.size() == data.size()) return;
    costs.clear();
    for (const PoseCostFunctor& observation : data)
      costs.emplace_back(CreatePoseCost(jacobian, observation));
  }
};

// Fills *problem (its storage reused) with the listed observations.
void MakeCentredProblem(JacobianType jacobian, const std::vector<Eigen::Vector2d>& image_plane,
                        const std::vector<Eigen::Vector3d>& points,
                        const std::vector<double>& sigmas, double focal,
                        const std::vector<int>& indices, CentredProblem* problem) {
  problem->origin.setZero();
  problem->jacobian = jacobian;
  problem->focal = focal;
  problem->data.clear();
  problem->costs.clear();
  for (const int i : indices) problem->origin += points[i];
  problem->origin /= std::max<size_t>(1, indices.size());
  for (const int i : indices)
    problem->data.emplace_back(image_plane[i], points[i] - problem->origin, focal, 1.0 / sigmas[i]);
  if (jacobian == JacobianType::kAutodiff) problem->MakeCosts();
}

// Weight of a squared whitened residual under the loss: rho'(s) (1 without a loss).
double LossWeight(const ceres::LossFunction* loss, double s) {
  if (loss == nullptr) return 1.0;
  double rho[3];
  loss->Evaluate(s, rho);
  return std::max(rho[1], 0.0);
}

// The convergence certificate: the (reweighted) Gauss-Newton step that remains at eo,
// d = -(J^T W J)^-1 J^T W r with W = diag(rho'(|r_i|^2)), and its length in standard deviations of
// the pose, sqrt(d^T J^T W J d). It is zero exactly at a stationary point of the (robust) cost,
// whatever the solver; infinity when a point is behind the camera or the normal matrix is
// singular.
double RemainingStepSigmas(const CentredProblem& problem, const Vector6d& eo,
                           const ceres::LossFunction* loss, Vector6d* step = nullptr) {
  Matrix6d normal = Matrix6d::Zero();
  Vector6d gradient = Vector6d::Zero();
  Eigen::Matrix<double, 2, 6, Eigen::RowMajor> J;
  const SeedProjector projector = problem.ProjectorAt(eo.data());
  for (size_t i = 0; i < problem.size(); ++i) {
    Eigen::Vector2d r;
    if (!problem.Evaluate(i, eo.data(), projector, r.data(), J.data())) return kInfinity;
    const double w = LossWeight(loss, r.squaredNorm());
    normal.noalias() += w * J.transpose() * J;
    gradient.noalias() += w * J.transpose() * r;
  }
  const Eigen::LDLT<Matrix6d> ldlt(normal);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) return kInfinity;
  const Vector6d d = -ldlt.solve(gradient);
  if (step != nullptr) *step = d;
  return std::sqrt(std::max(0.0, d.dot(normal * d)));
}

// Ends a solve that stopped on its own tolerances. A solver judges convergence by the cost, whose
// rounding (~1e-12 of whitened residuals summed over the marks) hides steps of about 1e-6 standard
// deviations; the Gauss-Newton step itself is accurate far below that. So while the certificate's
// step is longer than `tolerance` but shorter than one standard deviation (the solver has done the
// rest), it is taken as it is, a bounded number of times (plain least squares converges quadratically
// there, a reweighted loss linearly).
// Returns the length of the step that remains.
double PolishToTolerance(const CentredProblem& problem, const ceres::LossFunction* loss,
                         double tolerance, Vector6d* eo) {
  // Plain least squares needs one or two; a reweighted loss converges linearly, at worst slowly.
  const int max_steps = loss == nullptr ? 5 : 100;
  Vector6d step;
  double remaining = RemainingStepSigmas(problem, *eo, loss, &step);
  for (int k = 0; k < max_steps && remaining > tolerance && remaining < 1.0; ++k) {
    *eo += step;
    remaining = RemainingStepSigmas(problem, *eo, loss, &step);
  }
  return remaining;
}

// The stacked, weighted residuals of all observations for ceres::TinySolver. Weight i multiplies
// residual block i (IRLS); the Jacobian is column-major (2n x 6), as TinySolver expects.
class StackedPoseFunction {
 public:
  using Scalar = double;
  enum { NUM_RESIDUALS = Eigen::Dynamic, NUM_PARAMETERS = kExteriorOrientationSize };

  StackedPoseFunction(const CentredProblem& problem, const std::vector<double>& sqrt_weights)
      : problem_(problem), sqrt_weights_(sqrt_weights) {}

  int NumResiduals() const { return 2 * static_cast<int>(problem_.size()); }

  bool operator()(const double* eo, double* residuals, double* jacobian) const {
    double block[2 * kExteriorOrientationSize];
    const int rows = NumResiduals();
    const SeedProjector projector = problem_.ProjectorAt(eo);
    for (size_t i = 0; i < problem_.size(); ++i) {
      if (!problem_.Evaluate(i, eo, projector, residuals + 2 * i,
                             jacobian != nullptr ? block : nullptr)) {
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
  s->resize(problem.size());
  const SeedProjector projector = problem.ProjectorAt(eo);
  for (size_t i = 0; i < problem.size(); ++i) {
    double r[2];
    if (!problem.Evaluate(i, eo, projector, r, nullptr)) return false;
    (*s)[i] = r[0] * r[0] + r[1] * r[1];
  }
  return true;
}

double RobustCost(const ceres::LossFunction* loss, const std::vector<double>& s) {
  double cost = 0.0;
  for (const double value : s) {
    double rho[3] = {value, 1.0, 0.0};
    if (loss != nullptr) loss->Evaluate(value, rho);
    cost += 0.5 * rho[0];
  }
  return cost;
}

// TinySolver, wrapped in iteratively reweighted least squares when there is a loss. Returns
// kFailure with the reason, kNoConvergence when the reweighting rounds ran out (the caller may
// finish with ceres::Solve), or kConverged.
SolverTermination RefineWithTinySolver(const PoseRefinementOptions& options,
                                               const CentredProblem& problem,
                                               const ceres::LossFunction* loss,
                                               Vector6d* eo_centred,
                                               PoseRefinementSummary* summary) {
  const CeresPoseOptions& ceres_options = options.ceres;
  // Per thread, reused: a batch refines tens of sets per image.
  thread_local std::vector<double> s;
  thread_local std::vector<double> sqrt_weights;
  thread_local ceres::TinySolver<StackedPoseFunction> solver;
  if (!SquaredNorms(problem, eo_centred->data(), &s)) {
    summary->message = "Ceres: a control point is behind the camera at the initial pose";
    return SolverTermination::kFailure;
  }
  summary->initial_cost = RobustCost(loss, s);
  sqrt_weights.assign(problem.size(), 1.0);
  const int rounds = loss == nullptr ? 1 : ceres_options.max_reweighting_rounds;
  for (int round = 0; round < rounds; ++round) {
    for (size_t i = 0; i < s.size(); ++i) sqrt_weights[i] = std::sqrt(LossWeight(loss, s[i]));
    if (round == 0 && *std::max_element(sqrt_weights.begin(), sqrt_weights.end()) == 0.0) {
      summary->message = std::string("Ceres: every residual is beyond the ") +
                         EnumName(options.loss) +
                         " loss at the initial pose, so nothing pulls the pose; give a larger "
                         "loss scale or better initial values";
      return SolverTermination::kFailure;
    }
    StackedPoseFunction function(problem, sqrt_weights);
    // Solve starts from its options and the function alone (its buffers are only resized), so
    // one solver per thread gives the same steps as a fresh one.
    solver.options = ceres::TinySolver<StackedPoseFunction>::Options();
    solver.options.max_num_iterations = ceres_options.max_iterations;
    solver.options.parameter_tolerance = ceres_options.parameter_tolerance;
    solver.options.gradient_tolerance = 1e-14;
    // TinySolver's function tolerance is absolute; the final cost of whitened residuals is about
    // half their number, so this is function_tolerance relative to it.
    solver.options.function_tolerance = ceres_options.function_tolerance * function.NumResiduals();
    const auto& tiny = solver.Solve(function, eo_centred);
    summary->iterations += tiny.iterations;
    if (!eo_centred->allFinite() || !SquaredNorms(problem, eo_centred->data(), &s)) {
      summary->message =
          "Ceres TinySolver: the pose left the valid region (a point behind the camera)";
      return SolverTermination::kFailure;
    }
    // Converged when no (reweighted) Gauss-Newton step of consequence is left, whatever stopped
    // TinySolver: its own tolerances can stop it a hair short (a cost change below its function
    // tolerance), its iteration limit can be hit by steps far below the pose's uncertainty.
    const double remaining =
        PolishToTolerance(problem, loss, ceres_options.step_tolerance_sigmas, eo_centred);
    if (!SquaredNorms(problem, eo_centred->data(), &s)) {
      summary->message = "Ceres TinySolver: a control point is behind the camera at the solution";
      return SolverTermination::kFailure;
    }
    summary->final_cost = RobustCost(loss, s);
    if (remaining <= ceres_options.step_tolerance_sigmas)
      return SolverTermination::kConverged;
    if (loss == nullptr) {
      const bool limit = tiny.status == ceres::TinySolver<StackedPoseFunction>::HIT_MAX_ITERATIONS;
      summary->message =
          (limit ? "Ceres TinySolver: no convergence in " +
                       std::to_string(ceres_options.max_iterations) + " iterations"
                 : std::string("Ceres TinySolver: stopped short of the minimum")) +
          " (a step of " + FormatSignificant(remaining, 3) + " standard deviations remains)";
      return SolverTermination::kNoConvergence;
    }
  }
  summary->message = "Ceres TinySolver: reweighting did not settle in " +
                     std::to_string(rounds) + " rounds";
  return SolverTermination::kNoConvergence;
}

// Stops ceres::Solve once the remaining Gauss-Newton step is below the tolerance (the parameters
// are updated every iteration for it).
class StepInSigmasCallback : public ceres::IterationCallback {
 public:
  StepInSigmasCallback(const CentredProblem& problem, const ceres::LossFunction* loss,
                       const Vector6d* eo, double tolerance)
      : problem_(problem), loss_(loss), eo_(eo), tolerance_(tolerance) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    if (summary.iteration == 0 || !summary.step_is_successful) return ceres::SOLVER_CONTINUE;
    // Far from the minimum a step lowers the cost by much more than a tiny one could: the
    // certificate (a pass over every residual) is only worth computing near convergence.
    if (summary.cost_change > 1e-6 * summary.cost) return ceres::SOLVER_CONTINUE;
    return RemainingStepSigmas(problem_, *eo_, loss_) <= tolerance_
               ? ceres::SOLVER_TERMINATE_SUCCESSFULLY
               : ceres::SOLVER_CONTINUE;
  }

 private:
  const CentredProblem& problem_;
  const ceres::LossFunction* loss_;
  const Vector6d* eo_;
  double tolerance_;
};

SolverTermination RefineWithCeresProblem(const PoseRefinementOptions& options,
                                                 CentredProblem* problem_data,
                                                 Vector6d* eo_centred, int* iterations,
                                                 double* initial_cost, double* final_cost,
                                                 std::string* message) {
  const CeresPoseOptions& ceres_options = options.ceres;
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  problem_data->MakeCosts();
  // One loss object shared by every residual: the residuals are whitened, so one scale fits all.
  const std::unique_ptr<ceres::LossFunction> loss(MakeLoss(options.loss, options.loss_scale));
  for (auto& cost : problem_data->costs)
    problem.AddResidualBlock(cost.get(), loss.get(), eo_centred->data());
  StepInSigmasCallback callback(*problem_data, loss.get(), eo_centred,
                                ceres_options.step_tolerance_sigmas);
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_QR;
  solver_options.max_num_iterations = ceres_options.max_iterations;
  solver_options.function_tolerance = ceres_options.function_tolerance;
  solver_options.parameter_tolerance = ceres_options.parameter_tolerance;
  solver_options.gradient_tolerance = 1e-16;
  solver_options.num_threads = 1;
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;
  solver_options.update_state_every_iteration = true;
  solver_options.callbacks.push_back(&callback);
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
  const double remaining = PolishToTolerance(*problem_data, loss.get(),
                                             ceres_options.step_tolerance_sigmas, eo_centred);
  *iterations += static_cast<int>(summary.iterations.size()) - 1;
  *initial_cost = summary.initial_cost;
  *final_cost = summary.final_cost;
  if (!summary.IsSolutionUsable() || !eo_centred->allFinite()) {
    *message = "Ceres: " + summary.message;
    return SolverTermination::kFailure;
  }
  if (remaining <= ceres_options.step_tolerance_sigmas) return SolverTermination::kConverged;
  *message = "Ceres: " + summary.message + " (a step of " + FormatSignificant(remaining, 3) +
             " standard deviations remains)";
  return summary.termination_type == ceres::NO_CONVERGENCE ? SolverTermination::kNoConvergence
                                                           : SolverTermination::kFailure;
}

bool RefineWithCeres(const PoseRefinementOptions& options,
                     const std::vector<Eigen::Vector2d>& image_plane,
                     const std::vector<Eigen::Vector3d>& points, const std::vector<double>& sigmas,
                     double focal, const std::vector<int>& indices, ExteriorOrientation* eo,
                     PoseRefinementSummary* summary) {
  thread_local CentredProblem problem;
  MakeCentredProblem(options.jacobian, image_plane, points, sigmas, focal, indices, &problem);
  Vector6d eo_centred = eo->parameters;
  eo_centred.head<3>() -= problem.origin;
  SolverTermination termination;
  if (options.ceres.minimizer == CeresMinimizer::kTinySolver) {
    const std::unique_ptr<ceres::LossFunction> loss(MakeLoss(options.loss, options.loss_scale));
    const Vector6d start = eo_centred;
    termination = RefineWithTinySolver(options, problem, loss.get(), &eo_centred, summary);
    if (termination == SolverTermination::kNoConvergence && loss != nullptr) {
      // Reweighting still creeping (a loss with many points near its scale): let ceres::Solve
      // finish from where it got, with the loss applied exactly.
      double initial_cost = 0.0;
      termination = RefineWithCeresProblem(options, &problem, &eo_centred, &summary->iterations,
                                           &initial_cost, &summary->final_cost, &summary->message);
      if (termination != SolverTermination::kConverged) eo_centred = start;
    }
  } else {
    termination = RefineWithCeresProblem(options, &problem, &eo_centred, &summary->iterations,
                                         &summary->initial_cost, &summary->final_cost,
                                         &summary->message);
  }
  summary->termination = termination;
  if (termination != SolverTermination::kConverged) return false;
  summary->message.clear();
  eo->parameters = eo_centred;
  eo->parameters.head<3>() += problem.origin;
  return true;
}

bool RefineWithTaylor(const PoseRefinementOptions& options,
                      const std::vector<Eigen::Vector2d>& image_plane,
                      const std::vector<Eigen::Vector3d>& points, const std::vector<double>& sigmas,
                      double focal, const std::vector<int>& indices, ExteriorOrientation* eo,
                      PoseRefinementSummary* summary) {
  TaylorResectionOptions taylor_options = options.taylor;
  taylor_options.partials = options.solver == PoseSolver::kTaylor ? TaylorPartials::kCorrected
                                                                  : TaylorPartials::kAsPrinted;
  // The listed observations (all of them in order: no copies then).
  bool all = indices.size() == image_plane.size();
  for (size_t k = 0; all && k < indices.size(); ++k) all = indices[k] == static_cast<int>(k);
  std::vector<Eigen::Vector2d> observations;
  std::vector<Eigen::Vector3d> used_points;
  std::vector<double> used_sigmas;
  if (!all) {
    for (const int i : indices) {
      observations.push_back(image_plane[i]);
      used_points.push_back(points[i]);
      used_sigmas.push_back(sigmas[i]);
    }
  }
  TaylorResectionResult taylor;
  const Status status =
      TaylorResection(taylor_options, all ? image_plane : observations, all ? points : used_points,
                      all ? sigmas : used_sigmas, focal, *eo, &taylor);
  summary->iterations = taylor.summary.iterations;
  summary->initial_cost = taylor.summary.initial_cost;
  summary->final_cost = taylor.summary.final_cost;
  if (!status.ok() || !taylor.summary.IsSolutionUsable()) {
    summary->termination = taylor.summary.termination_type == SolverTermination::kNoConvergence
                               ? SolverTermination::kNoConvergence
                               : SolverTermination::kFailure;
    summary->message = "Taylor: " + (status.ok() ? taylor.summary.message : status.message());
    return false;
  }
  summary->termination = SolverTermination::kConverged;
  *eo = taylor.eo;
  return true;
}

}  // namespace

bool CeresPoseOptions::IsValid(std::string* why) const {
  if (max_iterations < 1) return InvalidBecause(why, "max_iterations must be at least 1");
  if (max_reweighting_rounds < 1)
    return InvalidBecause(why, "max_reweighting_rounds must be at least 1");
  if (!(step_tolerance_sigmas > 0.0) || !std::isfinite(step_tolerance_sigmas))
    return InvalidBecause(why, "step_tolerance_sigmas must be positive and finite");
  if (!(function_tolerance > 0.0) || !(parameter_tolerance > 0.0))
    return InvalidBecause(why, "tolerances must be positive");
  return true;
}

bool PoseRefinementOptions::IsValid(std::string* why) const {
  if (!(loss_scale > 0.0) || !std::isfinite(loss_scale))
    return InvalidBecause(why, "loss_scale must be positive and finite");
  // The Taylor solvers are plain least squares (the seed's): a loss would be ignored, not applied.
  if (solver != PoseSolver::kCeres && loss != LossType::kNone) {
    if (why != nullptr)
      *why = "the Taylor solvers have no robust loss: loss must be none with them (the loss is "
             "for the Ceres solver)";
    return false;
  }
  return ceres.IsValid(why) && taylor.IsValid(why);
}

bool RefinePose(const PoseRefinementOptions& options,
                const std::vector<Eigen::Vector2d>& image_plane,
                const std::vector<Eigen::Vector3d>& points_in_ground,
                const std::vector<double>& sigmas, double focal, const std::vector<int>& indices,
                ExteriorOrientation* eo, PoseRefinementSummary* summary) {
  *summary = PoseRefinementSummary();
  ExteriorOrientation refined = *eo;
  const bool ok =
      options.solver == PoseSolver::kCeres
          ? RefineWithCeres(options, image_plane, points_in_ground, sigmas, focal, indices,
                            &refined, summary)
          : RefineWithTaylor(options, image_plane, points_in_ground, sigmas, focal, indices,
                             &refined, summary);
  if (!ok) return false;
  // The canonical triple of the rotation (|phi| <= 90 deg, the others in (-180, 180]): a solver
  // may end on the equivalent (omega + 180, 180 - phi, kappa + 180).
  refined.set_angles_seed_rad(AnglesFromRotation(
      RotationConvention::kSeed,
      RotationFromAngles(RotationConvention::kSeed, refined.angles_seed_rad())));
  *eo = refined;
  return true;
}

}  // namespace photopose
