#pragma once
// Space resection of one or many images: the robust path of photopose.
//
//   1. Initial values: the approximate pose when given; otherwise LO-RANSAC over P3P (Lambda Twist)
//      and, with six or more non-coplanar points, the DLT (solvers/absolute_pose.h).
//   2. Refinement: Ceres with the analytic or autodiff collinearity cost and a robust loss, or the
//      seed's Taylor linearisation (corrected or as printed), on the observations RANSAC kept.
//   3. Statistics: residual per observation (pixels), inlier flag, sigma0, the 6x6 covariance
//      sigma0^2 (J^T P J)^-1 over the inliers and the standard deviations.
// Data-dependent failures (too few points, collinear points, all behind the camera, no consensus,
// no convergence) return success = false with a reason, never a pose.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/status.h"
#include "core/types.h"
#include "cost_functions/collinearity_cost.h"
#include "solvers/ransac.h"

namespace photopose {

// The one selector of the pose solver, shared by the library, the CLI and the comparison tool.
enum class PoseSolver {
  kCeres,            // Ceres Levenberg-Marquardt, derivative path from ResectionOptions::jacobian
  kTaylor,           // the seed's Taylor linearisation, corrected partials (solvers/taylor_resection.h)
  kTaylorAsPrinted,  // the same with the partial derivatives exactly as printed in the seed
};
std::optional<PoseSolver> ParsePoseSolver(const std::string& name);  // ceres|taylor|taylor_as_printed
const char* PoseSolverName(PoseSolver solver);

enum class LossType { kNone, kHuber, kSoftL1, kCauchy, kArctan, kTukey };

// How Ceres minimises one image's robust least-squares problem. Both use the same cost functions
// (cost_functions/collinearity_cost.h) and Ceres loss functions, on coordinates centred on the
// control points.
enum class CeresMinimizer {
  // ceres::TinySolver (dense Levenberg-Marquardt for small problems, no Problem set-up), wrapped in
  // iteratively reweighted least squares for the robust loss: weights rho'(s_i) are held fixed per
  // round; the fixed point is the M-estimator's stationarity condition, the same as (2). Default.
  kTinySolver,
  // (2) ceres::Problem + ceres::Solve: trust-region LM, DENSE_QR, loss applied by Ceres.
  kProblem,
};
std::optional<CeresMinimizer> ParseCeresMinimizer(const std::string& name);  // tiny_solver|problem
const char* CeresMinimizerName(CeresMinimizer minimizer);
std::optional<LossType> ParseLossType(const std::string& name);  // none|huber|softl1|cauchy|arctan|tukey
const char* LossTypeName(LossType loss);

struct ResectionOptions {
  PoseSolver solver = PoseSolver::kCeres;
  JacobianType jacobian = JacobianType::kAnalytic;
  LossType loss = LossType::kHuber;
  CeresMinimizer minimizer = CeresMinimizer::kTinySolver;
  double loss_scale_px = 2.0;          // robust-loss scale (pixels); whitened by each mark's sigma
  double ransac_threshold_px = 6.0;    // inlier threshold for RANSAC and the final flags (pixels)
  RansacOptions ransac;                // trials, confidence, seed
  int max_iterations = 50;             // Ceres / Taylor iterations (per reweighting round)
  int max_reweighting_rounds = 30;     // kTinySolver with a robust loss: IRLS rounds before the
                                       // remaining descent is left to ceres::Solve
  double function_tolerance = 1e-12;   // Ceres relative cost change to stop (unitless)
  double parameter_tolerance = 1e-12;  // Ceres relative step size to stop (unitless)
  bool IsValid(std::string* why) const;
};

enum class ResectionTermination { kConverged, kNoConvergence, kFailure };

struct ResectionSummary {
  ResectionTermination termination = ResectionTermination::kFailure;
  std::string message;            // why it failed, or a short note
  bool used_approximate = false;  // initial pose from the caller, not RANSAC
  int ransac_trials = 0;          // RANSAC hypotheses drawn
  int iterations = 0;             // refinement iterations
  double initial_cost = 0.0;      // 1/2 sum of squared whitened residuals before refinement
  double final_cost = 0.0;        // same after refinement
  double ransac_seconds = 0.0;
  double refinement_seconds = 0.0;
  double total_seconds = 0.0;
  std::string BriefReport() const;
  bool IsSolutionUsable() const { return termination == ResectionTermination::kConverged; }
};

// One image: ideal image-plane observations and their ground points, as prepared by
// PrepareResectionInput from the tables.
struct ResectionInput {
  std::string raster;
  double focal_length_um = 0.0;                // c
  double pixel_size_um = 1.0;                  // film micrometres per pixel, to report pixels
  std::vector<Eigen::Vector2d> image_plane_um; // ideal (distortion-free) observations, um
  std::vector<Eigen::Vector3d> points_in_ground;
  std::vector<double> sigma_px;                // one sigma per observation (pixels)
  std::vector<std::string> point_ids;          // optional, names points in messages
  std::optional<ExteriorOrientation> approximate;
};

struct ResectionResult {
  bool success = false;
  ExteriorOrientation eo;
  Matrix6d covariance = Matrix6d::Zero();        // sigma0^2 (J^T P J)^-1, m and rad
  Vector6d standard_deviations = Vector6d::Zero();
  double sigma0 = 0.0;                           // a posteriori, unitless (1 = as weighted)
  int degrees_of_freedom = 0;                    // 2 n_inliers - 6
  int num_inliers = 0;
  std::vector<Eigen::Vector2d> residuals_px;     // observed - projected, pixels, per observation
  std::vector<char> inliers;                     // per observation
  ResectionSummary summary;
};

ResectionResult ResectImage(const ResectionOptions& options, const ResectionInput& input);

// Many images, resected in parallel on num_threads threads (0: all cores); results in input order.
std::vector<ResectionResult> ResectImages(const ResectionOptions& options,
                                          const std::vector<ResectionInput>& inputs,
                                          int num_threads);

// Checks the control configuration of one image: at least three points, finite values, not all on
// one line. Returns the reason when it is not.
Status CheckControlConfiguration(const std::vector<Eigen::Vector3d>& points_in_ground);

}  // namespace photopose
