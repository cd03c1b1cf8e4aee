#pragma once
// Least-squares refinement of one exterior orientation from an approximate pose: the collinearity
// equations of the listed marks, weighted by their standard deviations, minimised by Ceres (with an
// optional robust loss) or by the seed's Taylor linearisation (solvers/resection/taylor_resection.h). This is
// the "refine" step of resection (solvers/resection/resection.h), kept apart from the decisions about which
// marks to use.
//
// Residuals are whitened: (observed - projected) / sigma on the ideal image plane, so one unit is
// one standard deviation of the mark and a loss scale is in standard deviations. Observations,
// sigmas and the principal distance share one unit (the camera model's observation unit: um for
// film cameras, pixels for the COLMAP models).

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "core/enum_names.h"
#include "core/termination.h"
#include "core/types.h"
#include "cost_functions/collinearity_cost.h"
#include "cost_functions/losses.h"
#include "solvers/resection/taylor_resection.h"

namespace photopose {

// The one selector of the pose solver, shared by the library, the CLI and the comparison tool.
enum class PoseSolver {
  kCeres,            // Ceres Levenberg-Marquardt, derivative path from PoseRefinementOptions::jacobian
  kTaylor,           // the seed's Taylor linearisation, corrected partials (solvers/resection/taylor_resection.h)
  kTaylorAsPrinted,  // the same with the partial derivatives exactly as printed in the seed
};
inline constexpr EnumNameEntry<PoseSolver> kPoseSolverNames[] = {
    {PoseSolver::kCeres, "ceres"},
    {PoseSolver::kTaylor, "taylor"},
    {PoseSolver::kTaylorAsPrinted, "taylor_as_printed"}};
constexpr EnumNameTable<PoseSolver> EnumNames(PoseSolver) {
  return EnumNameTable<PoseSolver>(kPoseSolverNames);
}

// How Ceres minimises one image's problem. Both use the same cost functions
// (cost_functions/collinearity_cost.h) and Ceres loss functions, on coordinates centred on the
// control points.
enum class CeresMinimizer {
  // ceres::TinySolver (dense Levenberg-Marquardt for small problems, no Problem set-up), wrapped in
  // iteratively reweighted least squares for a robust loss: weights rho'(s_i) are held fixed per
  // round; the fixed point is the M-estimator's stationarity condition, the same as (2). Default.
  kTinySolver,
  // (2) ceres::Problem + ceres::Solve: trust-region LM, DENSE_QR, loss applied by Ceres.
  kProblem,
};
inline constexpr EnumNameEntry<CeresMinimizer> kCeresMinimizerNames[] = {
    {CeresMinimizer::kTinySolver, "tiny_solver"}, {CeresMinimizer::kProblem, "problem"}};
constexpr EnumNameTable<CeresMinimizer> EnumNames(CeresMinimizer) {
  return EnumNameTable<CeresMinimizer>(kCeresMinimizerNames);
}

struct CeresPoseOptions {
  CeresMinimizer minimizer = CeresMinimizer::kTinySolver;
  // Levenberg-Marquardt iterations per solve (per reweighting round with kTinySolver), >= 1.
  int max_iterations = 50;
  // kTinySolver with a robust loss: reweighting rounds before the remaining descent is left to
  // ceres::Solve, >= 1.
  int max_reweighting_rounds = 30;
  // Convergence, in the pose's own standard deviations: an iteration (or a reweighting round)
  // whose step d satisfies sqrt(d^T N d) <= step_tolerance_sigmas, N the normal matrix of the
  // whitened residuals, ends the solve (unitless, > 0). A step of 1e-6 sigma changes nothing a
  // user can see, and it stays reachable where the convergence is only linear (a robust loss with
  // a residual at the kink of its weight function).
  double step_tolerance_sigmas = 1e-6;
  // Ceres' own stopping rules, kept as a backstop (relative, unitless, > 0).
  double function_tolerance = 1e-12;
  double parameter_tolerance = 1e-12;

  bool IsValid(std::string* why) const;
};

struct PoseRefinementOptions {
  PoseSolver solver = PoseSolver::kCeres;
  JacobianType jacobian = JacobianType::kAnalytic;  // Ceres only
  // Plain least squares by default; a robust loss is an option (Ceres only; the Taylor solvers are
  // always least squares).
  LossType loss = LossType::kNone;
  double loss_scale = 2.0;  // standard deviations of the marks (whitened units), > 0
  CeresPoseOptions ceres;
  // The Taylor solvers' options; `partials` is set from `solver`.
  TaylorResectionOptions taylor;

  bool IsValid(std::string* why) const;
};

struct PoseRefinementSummary {
  SolverTermination termination = SolverTermination::kFailure;
  std::string message;  // why it did not converge (numbers included), empty otherwise
  int iterations = 0;   // solver iterations (all rounds)
  // 1/2 sum rho(|whitened residual|^2) at the start and at the end (unitless).
  double initial_cost = 0.0;
  double final_cost = 0.0;
  bool converged() const { return termination == SolverTermination::kConverged; }
};

// Refines *eo on the observations listed in `indices` (into image_plane, points_in_ground and
// sigmas, which have one entry per observation): image_plane[i] the ideal image-plane point of
// points_in_ground[i] (m), sigmas[i] its standard deviation (same unit as image_plane and focal).
// On convergence writes *eo with the canonical angle triple (|phi| <= 90 deg) and returns true;
// otherwise leaves *eo unchanged and says why in *summary.
bool RefinePose(const PoseRefinementOptions& options,
                const std::vector<Eigen::Vector2d>& image_plane,
                const std::vector<Eigen::Vector3d>& points_in_ground,
                const std::vector<double>& sigmas, double focal, const std::vector<int>& indices,
                ExteriorOrientation* eo, PoseRefinementSummary* summary);

}  // namespace photopose
