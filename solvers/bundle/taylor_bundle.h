#pragma once
// Bundle adjustment by the seed's Taylor linearisation: the classical photogrammetric block
// adjustment that the exterior-orientation lecture ("カメラの幾何学2", eqs. 7-28) leads to, written
// from its formulas with Eigen only (no Ceres), as the independent baseline the Ceres adjustment
// (solvers/bundle/bundle_adjustment.h) is compared with. It minimises the SAME weighted objective
// on the SAME block:
//
//   sum over tie and control marks   |F|^2 / sigma_mark^2      F = (Fu, Fv), seed eqs. 7-8 (um)
// + sum over control points          |X - X_surveyed|^2 / sigma_marker^2        (per axis, m)
// + sum over camera centres          |X0 + R^T l - X_gnss|^2 / sigma_camera^2   (per axis, m)
// + sum over attitudes               |angles - measured|^2 / sigma_attitude^2   (per angle, rad)
//
// with the accuracies, per-row overrides, check points, datum and gauge rules of BundleAdjust.
//
// Unknowns: per image not held constant its X0, Y0, Z0 (m), omega, phi, kappa (rad, seed angles,
// used directly as the lecture does: singular only at phi = +-90 deg); per tie or control point
// not held constant X, Y, Z (m); the self-calibrated cameras' estimated parameters and the
// estimated lever arm (m). Every observation equation is linearised as in eqs. 9-16,
//
//   F(p) ~ F(p0) - A d,   p = p0 - d,   A = dF/dp,
//
// with A from eqs. 17-28 for the exterior orientation (TaylorPartials: eq. 21 corrected, or as
// printed), the ground-point partials dF/dX = -dF/dX0 (docs/taylor_derivatives.md, "Ground-point
// partials"), and the identity (and R^T l's derivative) for the priors. The camera model enters on
// the observation side: for the ArcGIS frame model (kFrame) with fixed interior orientation the
// measured film point is corrected (affinity, principal point, distortion, Polarity) into the
// ideal image plane once, a constant. The COLMAP forward models distort the ideal point, so
// their equation stays in pixels: F = model(a, b) - observation of the ray's normalised
// coordinates (a, b), its rows the lecture's rows of (a, b) (written with c = 1) times the
// model's 2 x 2 derivative d model / d(a, b) at the current point (chain rule; the one model of
// core/camera_models.h, differentiated by a Jet). Its cost is then BundleAdjust's, exactly.
//
// Self-calibration (config.calibrated_params) and an estimated lever arm
// (config.estimate_lever_arm): the camera's estimated parameters and the lever arm's x, y, z are
// global unknowns, the last columns of the reduced system (a dense border). A self-calibrated
// camera's marks, kFrame too, go through the model per mark as the forward models do, and the
// same Jet carries a derivative per estimated parameter: for kFrame F = c (a, b) - ideal(film;
// calibration), so dF/dc = (a, b) and dF/dk = -d ideal/dk. The lever arm's rows are R^T in the
// camera-position priors.
//
// Normal equations (A^T P A) d = A^T P F, assembled by hand and reduced to the cameras (the
// classical reduced normal equations): with N = [U W; W^T V] (U cameras, V points, block-diagonal
// 3 x 3) the points are eliminated one 3 x 3 block at a time,
//
//   S = U - sum_p W_p V_p^-1 W_p^T,   r = g_e - sum_p W_p V_p^-1 g_p,
//
// (U and W_p with the global columns below the camera blocks' rows: a point's global rows are the
// sum of its marks'),
// S d_e = r is solved by a sparse Cholesky factor of the Jacobi-scaled S, the images ordered by AMD
// on the image graph (CHOLMOD's supernodal LL^T, the pattern analysed once per round and
// refactorised per iteration; or Eigen::SimplicialLDLT, the first implementation, kept as the
// reference), and the point corrections are back-substituted, d_p = V_p^-1 (g_p - W_p^T d_e).
//
// Damping: plain Gauss-Newton (kNone) is the lecture's method and diverges from poor starts. The
// default is Levenberg-Marquardt on the same normal equations: the diagonal of the full normal
// matrix is scaled by (1 + lambda) before the points are eliminated (U + lambda diag U, V_p +
// lambda diag V_p), a step is taken when its gain ratio rho = (actual decrease) / (decrease
// predicted by the linearisation) exceeds min_gain_ratio, and lambda follows Nielsen's rule (taken:
// lambda *= max(1/3, 1 - (2 rho - 1)^3); refused: lambda *= nu, nu *= 2). A refused step is retried
// from the same linearisation (only the reduction and the factorisation are redone). When a step is
// below the tolerances the undamped Gauss-Newton step is solved at that point: the round has
// converged when it too is below them (it is also the datum check: a singular S fails the round as
// before).
//
// Threads: the linearisation (per image), the elimination of the points (in kReductionChunks fixed
// chunks whose partial sums are added in chunk order) and the back-substitution (per point) run on
// num_threads threads; the result does not depend on the thread count, bit for bit.
//
// Supported: kFrame cameras (any distortion model or table, affinity, Polarity) and the COLMAP
// models (SIMPLE_PINHOLE ... OPENCV_FISHEYE), with fixed or self-calibrated interior orientation;
// control, check and tie points; GNSS camera positions with a lever arm, applied or estimated;
// attitude priors;
// images and points held constant; the relative gauge (COLMAP's convention) when nothing ties the
// block to the ground; rejection rounds, data snooping and accuracy estimation as in BundleAdjust;
// the camera table's earth-curvature correction (ApplyECC: each point seen lowered by D^2 / (2R),
// the centre's partials chained through the drop; TaylorPoseLinearization).
//
// Robust losses (tie_loss, on tie marks as in BundleAdjust): iteratively reweighted least squares
// in the same normal equations. Each linearisation weights a tie mark by rho'(s) (s its squared
// whitened residual) and counts rho(s) in the cost; Levenberg-Marquardt's gain ratio compares that
// cost with the reweighted model's decrease. A fixed point is a stationary point of the robust
// cost, BundleAdjust's minimum (which Ceres reaches with its own Hessian correction).
//
// Statistics and rounds: each round's solution goes through BundleAdjust's own statistics
// (internal::ComputeBundleStatistics: groups and verdicts, covariances, redundancy numbers,
// w-tests, MDBs, reliability, control and check points), evaluated on the Ceres problem of the
// solution (built once, never solved, updated in place when marks are rejected), and then through
// BundleAdjust's steps between rounds (internal/bundle_rounds.h: rejection rounds, data snooping,
// variance components); both solvers report one set of figures.
//
// Data-dependent failures (no datum, a singular reduced normal matrix, a point behind a camera,
// divergence, no convergence) are reported in the summary with the block left at its input
// values; nothing aborts.

#include <Eigen/Core>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "core/block.h"
#include "core/enum_names.h"
#include "core/status.h"
#include "core/types.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/resection/resection.h"
#include "solvers/resection/taylor_resection.h"

namespace photopose {

// How a correction is damped (see the header comment).
enum class TaylorDamping {
  kNone,                // plain Gauss-Newton: the lecture's method
  kLevenbergMarquardt,  // the production default
};
inline constexpr EnumNameEntry<TaylorDamping> kTaylorDampingNames[] = {
    {TaylorDamping::kNone, "none"},
    {TaylorDamping::kLevenbergMarquardt, "levenberg_marquardt"},
    {TaylorDamping::kNone, "gauss_newton"},
    {TaylorDamping::kLevenbergMarquardt, "lm"}};
constexpr EnumNameTable<TaylorDamping> EnumNames(TaylorDamping) {
  return EnumNameTable<TaylorDamping>(kTaylorDampingNames, NameMatch::kIgnoreCase);
}

// The factorisation of the reduced camera system.
enum class TaylorLinearSolver {
  kCholmodSupernodal,  // CHOLMOD's supernodal LL^T (SuiteSparse): the production default
  kEigenLdlt,          // Eigen::SimplicialLDLT: the first implementation, kept as the reference
};
inline constexpr EnumNameEntry<TaylorLinearSolver> kTaylorLinearSolverNames[] = {
    {TaylorLinearSolver::kCholmodSupernodal, "cholmod_supernodal"},
    {TaylorLinearSolver::kEigenLdlt, "eigen_ldlt"}};
constexpr EnumNameTable<TaylorLinearSolver> EnumNames(TaylorLinearSolver) {
  return EnumNameTable<TaylorLinearSolver>(kTaylorLinearSolverNames, NameMatch::kIgnoreCase);
}

// The damping the Taylor path runs with by default: Levenberg-Marquardt with the corrected
// partials; plain Gauss-Newton, the lecture's method, with the as-printed ones (not the
// derivative of the objective: a gain ratio against them means nothing).
constexpr TaylorDamping DefaultTaylorDamping(TaylorPartials partials) {
  return partials == TaylorPartials::kAsPrinted ? TaylorDamping::kNone
                                                : TaylorDamping::kLevenbergMarquardt;
}

struct TaylorBundleOptions {
  // Partial derivatives of the exterior orientation (eqs. 17-28): eq. 21 corrected or as printed.
  TaylorPartials partials = TaylorPartials::kCorrected;
  // kLevenbergMarquardt needs the corrected partials (IsValid).
  TaylorDamping damping = TaylorDamping::kLevenbergMarquardt;
  // Levenberg-Marquardt: lambda at the start of every round (unitless, relative to the diagonal;
  // Ceres' default trust region radius 1e4 is lambda 1e-4), the smallest gain ratio of a step
  // taken (unitless), and the lambda beyond which the round fails (unitless).
  double initial_damping = 1e-4;
  double min_gain_ratio = 1e-3;
  double max_damping = 1e16;
  TaylorLinearSolver linear_solver = TaylorLinearSolver::kCholmodSupernodal;
  // A relative block (BundleDatum::kRelative) is solved first without a gauge, as BundleAdjust
  // does (BundleSolverOptions::free_gauge_for_relative_blocks): Levenberg-Marquardt with lambda
  // kept at or above free_gauge_min_damping (unitless), so that the 7 free directions of the
  // reduced system stay damped and still; then moved by the similarity into COLMAP's gauge and
  // polished there (the undamped step of the held gauge is the datum check). Needs the damping;
  // false, or Gauss-Newton: held in COLMAP's gauge from the start, where the damping creeps
  // while the whole block turns about the first image.
  bool free_gauge_for_relative_blocks = true;
  double free_gauge_min_damping = 1e-8;
  // Threads of the linearisation, the elimination and the back-substitution (count; 0: every
  // core); never more than one per 1000 marks. The result is the same for every count.
  int num_threads = 1;
  // The objective's accuracies, defaults and per-row overrides exactly as BundleAdjust takes them.
  BundleAccuracies accuracies;
  // Between rounds, BundleAdjust's steps (internal/bundle_rounds.h) with the meaning of
  // BundleRobustnessOptions' fields of the same names: tie marks whose normalized residual (or,
  // without diagnostics, whitened residual over max(1, sigma0)) exceeds rejection_threshold
  // (unitless; 0: no rejection) are rejected and the block adjusted again, at most
  // max_rejection_rounds times (count); or, with snoop, data snooping removes one observation at
  // a time, at most max_snooping_removals (count). Variance components: statistics'
  // estimate_accuracies.
  double rejection_threshold = 4.5;
  int max_rejection_rounds = 3;
  // Robust loss on tie marks and its scale (sigmas of the mark, unitless), as
  // BundleRobustnessOptions::tie_loss (one of kBundleTieLosses), by iteratively reweighted least
  // squares (see the header comment).
  LossType tie_loss = LossType::kNone;
  double tie_loss_scale_sigmas = 3.0;
  bool snoop = false;
  // As BundleRobustnessOptions::snooping_batch: several removals per round's statistics.
  bool snooping_batch = true;
  int max_snooping_removals = 200;
  // Corrections per round, taken or refused (count). With the corrected partials a block converges
  // in 3-6; the as-printed partials converge linearly and can need several times more.
  int max_iterations = 50;
  // Convergence: a round stops after the first correction whose every camera-centre and
  // ground-point component is at most position_tolerance_m (m) and every angle component at most
  // angle_tolerance_rad (rad). 1 um is three orders below the millimetre a block's control carries;
  // 1e-9 rad is 1 um at 1 km. Gauss-Newton on a small-residual block converges with a linear rate
  // of ~1e-3 or better, so the error left after that correction is far smaller still. The position
  // test is never tighter than 256 epsilon times the extent of the block around its centroid (the
  // solver works in coordinates relative to that centroid), so map coordinates cannot make
  // convergence unreachable.
  double position_tolerance_m = 1e-6;
  double angle_tolerance_rad = 1e-9;
  // Divergence: a round fails when a camera centre or a point moves farther from the block's
  // centroid than this factor times the block's extent (unitless).
  double divergence_distance_factor = 1e3;
  // The reduced normal matrix is taken as singular (a datum defect or an undetermined image) when a
  // pivot of the LDL^T of its Jacobi-scaled form is at most this fraction of the largest
  // (unitless; the threshold BundleAdjust's statistics use).
  double min_pivot_ratio = 1e-12;
  // The statistics at the solution, exactly as BundleAdjust computes them (the one path,
  // internal::ComputeBundleStatistics): covariances (statistics.covariances: selected inversion,
  // kDenseInverse the tests' oracle, kNone none), group verdicts, redundancy numbers, w-tests,
  // reliability, check points. Units and limits as in BundleStatisticsOptions.
  BundleStatisticsOptions statistics;
  // Called after every Gauss-Newton correction (may be empty); the fields as BundleAdjust fills
  // them (round, iteration, cost, sigma0, step_norm = |d| over all unknowns, elapsed, free_gauge).
  // Returning false stops the adjustment after that correction, as BundleAdjust's hook does: the
  // summary's termination is kCancelled ("round R: cancelled by the progress hook after iteration
  // N") and the block is left as it was given.
  std::function<bool(const BundleIterationInfo&)> progress;

  bool IsValid(std::string* why) const;
};

// The Taylor options that minimise the same objective as `ceres` and take the same steps between
// rounds (accuracies, robust tie loss, rejection, snooping, statistics, threads, progress, the
// iterations per round; the lever arm is the config's, BundleAdjustmentConfig::lever_arm_m). Ceres'
// derivative path and linear solver have no Taylor counterpart and are not read. An error would name what the
// Taylor path does not do; no field of BundleAdjustmentOptions is refused today. The Taylor
// options keep their own flat fields rather than BundleAdjustmentOptions' parts: they take only a
// few fields of each.
Status TaylorBundleOptionsFromBundleOptions(const BundleAdjustmentOptions& ceres,
                                            TaylorPartials partials, TaylorBundleOptions* options);

// One correction (Gauss-Newton, or a Levenberg-Marquardt step taken or refused).
struct TaylorBundleIteration {
  int round = 0;
  int iteration = 0;
  double cost = 0.0;  // 1/2 sum of squared whitened residuals at the linearisation point
  double max_position_correction_m = 0.0;  // camera centres and points (m)
  double max_angle_correction_rad = 0.0;   // rad
  double seconds = 0.0;                    // wall time of this correction (linearise + solve)
  double damping = 0.0;                    // lambda of the step (unitless; 0 for Gauss-Newton)
  double gain_ratio = 1.0;  // actual / predicted decrease (unitless; 1 for Gauss-Newton)
  bool taken = true;        // false: refused, the state unchanged
};

struct TaylorBundleSummary {
  SolverTermination termination_type = SolverTermination::kFailure;
  std::string message;  // why it stopped (one line)
  TaylorPartials partials = TaylorPartials::kCorrected;
  BundleDatum datum = BundleDatum::kControl;
  std::string datum_description;
  // Tie points seen twice or more without initial coordinates: left out with their marks.
  std::vector<std::string> tie_points_left_out;
  int rounds = 0;         // adjustment rounds (rejections re-adjust)
  int iterations = 0;     // corrections over all rounds, taken or refused (count)
  int refused_steps = 0;  // Levenberg-Marquardt steps refused (count)
  // The last round's final undamped factorisation of the Jacobi-scaled reduced normal matrix:
  // its smallest over its largest LDL^T pivot (unitless; NaN before one).
  double pivot_ratio = std::numeric_limits<double>::quiet_NaN();
  // Of `iterations`, those of a relative block's first solve without a gauge
  // (free_gauge_for_relative_blocks; count, 0 when none ran).
  int free_gauge_iterations = 0;
  TaylorDamping damping = TaylorDamping::kLevenbergMarquardt;
  TaylorLinearSolver linear_solver = TaylorLinearSolver::kCholmodSupernodal;
  int num_threads = 1;  // threads used (count)
  // 1/2 sum of squared whitened residuals (unitless, the Ceres cost): at the start of the first
  // round and at the end of the last.
  double initial_cost = 0.0;
  double final_cost = 0.0;
  double sigma0 = 0.0;  // sqrt(2 final_cost / redundancy) (unitless); NaN without redundancy
  int redundancy = 0;   // scalar observations - unknowns (count)
  int num_images = 0, num_points = 0, num_marks = 0;  // in the final round
  int num_rejected_marks = 0;
  // Unknowns of the reduced system: the exterior orientations' and the global ones (estimated
  // calibration, lever arm) (count).
  int num_camera_unknowns = 0;
  int reduced_nonzeros = 0;     // stored (upper) entries of the reduced normal matrix (count)
  // Largest components of the last correction (m, rad).
  double last_position_correction_m = 0.0;
  double last_angle_correction_rad = 0.0;
  double time_seconds = 0.0;       // the whole call (s)
  double iteration_seconds = 0.0;  // the Gauss-Newton corrections alone, over all rounds (s)
  // Per round, wall clock (s): its layout, a relative block's solve without a gauge (round 1) and
  // its corrections; the statistics are not part of it.
  std::vector<double> round_seconds;
  // The statistics of every round (s): building or updating their evaluation structure (the Ceres
  // problem of the solution, never solved) and computing them.
  double statistics_setup_seconds = 0.0;
  double statistics_seconds = 0.0;

  // One line: variant, termination, rounds, iterations, costs, sigma0, time, message.
  std::string BriefReport() const;
  // True only for kConverged.
  bool IsSolutionUsable() const;
};

struct TaylorBundleResult {
  TaylorBundleSummary summary;
  // The result in BundleAdjust's shape, for the same report writers: the summary filled from
  // `summary` (termination kConverged / kNoConvergence / kFailure, the same costs, sigma0,
  // redundancy, counts and times; problem_build_seconds is statistics_setup_seconds),
  // rejected_marks, and, at a converged solution, every statistic BundleAdjust reports, computed by
  // the same code on the same observations (internal::ComputeBundleStatistics): residuals per mark
  // and image, groups with their RMS, redundancy shares and over-fitting verdicts, covariances of
  // the orientations and control points, per-observation redundancy numbers, w-tests, MDBs and
  // external reliability, control and check points with their w-tested marks, the lever arm. With
  // the as-printed partials the solution is that variant's fixed point, and the statistics are
  // those of the objective there.
  BundleAdjustmentResult adjustment;
  // Every correction of every round, in order.
  std::vector<TaylorBundleIteration> history;
};

// Adjusts the block in place with the seed's Gauss-Newton. On success the images' eo and the
// points' position_m hold the adjusted values. Same preconditions as BundleAdjust: every image an
// initial eo, every tie point an initial position. Returns an error (nothing changed) for invalid
// options or a block it cannot adjust (see BundleAdjust, plus the unsupported features named in
// the header comment); a failed or unconverged adjustment is reported in result->summary with the
// block left at its input values and no image marked adjusted.
Status TaylorBundleAdjust(const TaylorBundleOptions& options, const BundleAdjustmentConfig& config,
                          Block* block, TaylorBundleResult* result);

// The block adjustment that `photopose bundle --solver=ceres|taylor|taylor_as_printed` and the
// block mode of `photopose compare` run, selected by the same PoseSolver switch as resection:
// kCeres calls BundleAdjust(options, ...) (its derivative path from options.solver.jacobian);
// kTaylor and kTaylorAsPrinted call TaylorBundleAdjust with
// TaylorBundleOptionsFromBundleOptions(options) and return its result in BundleAdjust's shape
// (taylor_result, when not null, receives the whole Taylor result: its summary and iteration
// history; damping, when given, replaces the Taylor path's default, DefaultTaylorDamping). Errors
// as the solver called returns them, plus the options the Taylor path refuses.
Status BundleAdjustWithSolver(PoseSolver solver, const BundleAdjustmentOptions& options,
                              const BundleAdjustmentConfig& config, Block* block,
                              BundleAdjustmentResult* result,
                              TaylorBundleResult* taylor_result = nullptr,
                              std::optional<TaylorDamping> damping = std::nullopt);

// ------------------------------------------------------------------ the linearisation, exposed

// One mark's observation equation for the block: Fu, Fv (um, seed eqs. 7-8: computed minus
// observed ideal image-plane coordinates) with the partials with respect to the exterior
// orientation (2 x 6, eqs. 17-28 per `partials`; um per m, um per rad) and to the ground point
// (2 x 3, um per m; dF/dX = -dF/dX0). Returns false when the point is not in front of the camera
// (w >= 0); then nothing is written.
bool TaylorMarkPartials(TaylorPartials partials, const ExteriorOrientation& eo,
                        const Eigen::Vector3d& point_in_ground, double focal_um,
                        const Eigen::Vector2d& observed_um, Eigen::Matrix<double, 2, 6>* d_eo,
                        Eigen::Matrix<double, 2, 3>* d_point, Eigen::Vector2d* f_um);

// The antenna position X0 + R^T l of a camera (R = R_camera_from_ground of eo's seed angles, l the
// lever arm in the camera frame, m) and its derivative with respect to (omega, phi, kappa) (3 x 3,
// m per rad): dR/domega = [e1]x R, dR/dphi = [Rx(omega) e2]x R, dR/dkappa = R [e3]x.
Eigen::Vector3d TaylorAntennaPosition(const ExteriorOrientation& eo, const Eigen::Vector3d& lever_m,
                                      Eigen::Matrix3d* d_angles);

// One linearisation of the whole block at its current values, dense, for tests and teaching
// (small blocks only). Unknowns in order: per image not held constant its six parameters, then
// the global unknowns (each self-calibrated camera's estimated parameters, in index order, then
// the estimated lever arm's x, y, z), then per point in the adjustment and not held constant its
// three. The relative gauge's fixed
// coordinate keeps its column, zeroed, and a zero correction. Plain least squares: the dense rows
// carry no robust loss's weights (the reduced system and the correction do).
struct TaylorBundleLinearSystem {
  std::vector<int> image_columns;  // per Block::images: first column, or -1 (held constant)
  std::vector<int> point_columns;  // per Block::points: first column, or -1 (not an unknown)
  // Per Block::cameras: the column of its first estimated parameter, or -1 (held constant).
  std::vector<int> camera_columns;
  int lever_column = -1;           // the estimated lever arm's x column, or -1
  Eigen::MatrixXd jacobian;        // whitened A: rows observation equations, columns unknowns
  Eigen::VectorXd residual;        // whitened F (computed - observed) at the current values
  Eigen::MatrixXd reduced_matrix;  // S (camera and global columns), as assembled block by block
  Eigen::VectorXd reduced_rhs;     // r
  Eigen::VectorXd correction;      // d: cameras from S d_e = r, points back-substituted
};
Status LinearizeTaylorBundle(const TaylorBundleOptions& options,
                             const BundleAdjustmentConfig& config, const Block& block,
                             TaylorBundleLinearSystem* system);

}  // namespace photopose
