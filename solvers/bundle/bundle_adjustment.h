#pragma once
// Bundle adjustment of a block (core/block.h): the weighted objective of the bundle-objective seed
// note (001_ad717511fdc5a198.txt), as Metashape's reference settings weight it,
//
//   sum over tie marks       |v|^2 / sigma_tie^2                 (image residuals)
// + sum over control marks   |v|^2 / sigma_marker_projection^2    (image residuals)
// + sum over control points  |X - X_surveyed|^2 / sigma_marker^2  (per axis, m)
// + sum over camera centres  |X0 + R^T l - X_gnss|^2 / sigma_camera^2   (per axis, m; l the GNSS
//                                                                      lever arm, camera frame)
// + sum over attitudes       |angles - measured|^2 / sigma_attitude^2    (per angle, only if asked)
//
// minimised by Ceres over one 6-parameter exterior orientation block per image (seed angles, with
// a rotation manifold so that no attitude is singular), one 3-parameter block per point and one
// block of camera-model parameters per camera (core/camera_models.h), held constant except the
// parameters named for self-calibration. Points are eliminated first (Schur complement); control
// point priors are written as 2-row residual blocks so that every eliminated row has the same size
// and Ceres' fixed-size Schur specialisation (2, 3, 6) applies.
//
// Check points stay out of the adjustment: afterwards each is intersected from the adjusted images
// (solvers/bundle/triangulation.h) and compared with its surveyed coordinates.
//
// The note's warning is part of the result: when tie points are too few or too weak the solution
// bends to the priors, whose residual RMS then falls well below the stated accuracy and whose
// redundancy share (how much of each prior the rest of the block checks) is small. Each prior group
// is flagged `overfit` when either falls below its limit (BundleStatisticsOptions::overfit_ratio,
// overfit_redundancy_share).
//
// Data-dependent failures (no datum, disconnected block, an image with too few marks, a point
// behind a camera, no convergence, a singular normal matrix) are reported in the summary; nothing
// aborts.

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/block.h"
#include "core/enum_names.h"
#include "core/status.h"
#include "core/termination.h"
#include "core/types.h"
#include "cost_functions/collinearity_cost.h"
#include "cost_functions/losses.h"
#include "solvers/resection/pose_refinement.h"

namespace photopose {

// The stated accuracies of the objective's groups (one sigma). Defaults: Metashape's reference
// settings. A per-row accuracy in the tables (mark Accuracy, point AccuracyX/Y/Z, frames
// AccuracyX/Y/Z, AccuracyOmega/Phi/Kappa) overrides the default of its row.
struct BundleAccuracies {
  double tie_px = 1.0;                // tie marks measured in pixels (px)
  double marker_projection_px = 0.5;  // control and check marks measured in pixels (px)
  // Marks measured in film coordinates (um) of a camera without a pixel size: the defaults above
  // need a pixel size to become micrometres, so these apply instead (um).
  double tie_film_um = 5.0;
  double marker_projection_film_um = 2.5;
  double marker_m = 0.005;                                // control point coordinates (m, per axis)
  Eigen::Vector3d camera_m = Eigen::Vector3d::Constant(10.0);  // camera centres (m, X, Y, Z)
  // Camera centres are priors: always when an image has per-row accuracies; for the others when
  // this is true (a frames table with measured centres and --camera_accuracy given, or the
  // default on). false: measured centres without per-row accuracy are initial values only.
  bool camera_positions_are_priors = true;
  // Attitude prior (deg per angle, seed angles); none unless set.
  std::optional<double> attitude_deg;
};

// The linear solver of each Levenberg-Marquardt step.
enum class BundleLinearSolver {
  kSparseSchur,                  // SPARSE_SCHUR with SuiteSparse (default)
  kDenseSchur,                   // DENSE_SCHUR (small blocks)
  kIterativeSchurJacobi,         // ITERATIVE_SCHUR with SCHUR_JACOBI
  kIterativeSchurClusterJacobi,  // ITERATIVE_SCHUR with CLUSTER_JACOBI
};
// "iterative_schur" is accepted for "iterative_schur_jacobi".
inline constexpr EnumNameEntry<BundleLinearSolver> kBundleLinearSolverNames[] = {
    {BundleLinearSolver::kSparseSchur, "sparse_schur"},
    {BundleLinearSolver::kDenseSchur, "dense_schur"},
    {BundleLinearSolver::kIterativeSchurJacobi, "iterative_schur_jacobi"},
    {BundleLinearSolver::kIterativeSchurClusterJacobi, "iterative_schur_cluster_jacobi"},
    {BundleLinearSolver::kIterativeSchurJacobi, "iterative_schur"}};
constexpr EnumNameTable<BundleLinearSolver> EnumNames(BundleLinearSolver) {
  return EnumNameTable<BundleLinearSolver>(kBundleLinearSolverNames);
}

// One line of progress, after every iteration (the CLI prints it on stderr).
struct BundleIterationInfo {
  int round = 0;           // adjustment round (1, then one more after each outlier rejection)
  int iteration = 0;       // Ceres iteration within the round
  double cost = 0.0;       // 1/2 sum of squared whitened residuals
  double sigma0 = 0.0;     // sqrt(2 cost / redundancy)
  double step_norm = 0.0;  // |step| of the iteration (parameter units)
  double elapsed_seconds = 0.0;
  // A relative block's first solve, without a gauge (BundleSolverOptions::
  // free_gauge_for_relative_blocks); its sigma0 counts the 7 free directions as unknowns.
  bool free_gauge = false;
  // Levenberg-Marquardt state (Ceres solver only; NaN for the Taylor solver): the trust region
  // radius after the iteration (1 / damping, unitless) and the step quality (actual over
  // predicted cost decrease, unitless; 1 on a quadratic model).
  double trust_region_radius = std::numeric_limits<double>::quiet_NaN();
  double step_quality = std::numeric_limits<double>::quiet_NaN();
  bool step_successful = true;
  // Where the iteration went: the linear solve of the step (Schur elimination, factorisation,
  // back-substitution) and the whole iteration (plus residual and Jacobian evaluation), s.
  double linear_solver_seconds = 0.0;
  double iteration_seconds = 0.0;
};

// The robust losses the adjustment offers on tie marks, the ones its tests and `photopose compare`
// cover. Not tukey: it gives a mark beyond its scale zero weight, and a tie point whose marks all
// lie beyond it is left undetermined; nor arctan, not validated on blocks.
inline constexpr LossType kBundleTieLosses[] = {LossType::kNone, LossType::kHuber,
                                                LossType::kCauchy, LossType::kSoftL1};
inline bool IsBundleTieLoss(LossType loss) {
  for (const LossType offered : kBundleTieLosses)
    if (loss == offered) return true;
  return false;
}

// What the adjustment does with observations that do not fit: a robust loss on tie marks, the
// rejection rounds of marks, and data snooping (which uses the w-test of BundleStatisticsOptions).
struct BundleRobustnessOptions {
  // Robust loss on tie marks (kNone: plain least squares; one of kBundleTieLosses), scale in
  // sigmas of the mark (unitless). Control marks and priors are never robustified.
  LossType tie_loss = LossType::kNone;
  double tie_loss_scale_sigmas = 3.0;
  // After convergence, marks whose normalized residual exceeds this (unitless) are rejected and the
  // block adjusted again, at most max_rejection_rounds times (count; 0 disables rejection). The
  // normalized residual of a mark is the larger of |w_x|, |w_y| (see
  // BundleStatisticsOptions::observation_diagnostics) when the diagnostics are computed, otherwise
  // |v| / (max(1, s0) sigma) (the whitened residual, 2-D). Only tie marks are rejected: control
  // and check marks are a surveyor's measurements, tested and reported in the diagnostics and
  // removed only by data snooping. Per point and round its worst mark above the threshold goes (a
  // blunder raises the other marks of its track too).
  double rejection_threshold = 4.5;
  int max_rejection_rounds = 3;
  // Data snooping: while the largest |w_i| exceeds k(alpha) (BundleStatisticsOptions::
  // snooping_alpha), remove that observation (a mark, or the whole prior of a control point, camera
  // position or attitude) and adjust again, one at a time, at most max_snooping_removals times
  // (count). Replaces the rejection rounds above. Needs the covariances and the observation
  // diagnostics (BundleStatisticsOptions; BundleAdjustmentOptions::IsValid refuses it without).
  bool snoop = false;
  int max_snooping_removals = 200;
  // Batch snooping: one round's statistics remove every observation one-at-a-time snooping would
  // remove next, as far as the round can tell: of the rejected observations (the 64 largest |w|),
  // the one with the largest |w| conditioned on those already taken, while it exceeds k(alpha)
  // (with sigma0 and k of the block without them), beats every other observation's |w| and
  // correlates at most 0.3 with each taken (internal/bundle_rounds.h, docs/diagnostics.md §2).
  // false: one removal per round, a fresh adjustment and statistics each time.
  bool snooping_batch = true;

  bool IsValid(std::string* why) const;
};

// How the posterior covariances (and all that follows from them: redundancy numbers, reliability,
// variance components, calibration correlations) are computed from the reduced camera system S.
enum class BundleCovarianceMethod {
  // The entries of S^-1 on the pattern of S's sparse Cholesky factor (selected inversion,
  // solvers/bundle/internal/selected_inversion.h): every block size, memory ~ the factor's.
  kSelectedInversion,
  // S inverted densely: the tests' oracle. n^2 memory and n^3 time in the reduced parameters.
  kDenseInverse,
  kNone,  // not computed: group RMS and check points only (the last round's S is still
          // factorised once, to check that every parameter is determined)
};
inline constexpr EnumNameEntry<BundleCovarianceMethod> kBundleCovarianceMethodNames[] = {
    {BundleCovarianceMethod::kSelectedInversion, "full"},
    {BundleCovarianceMethod::kDenseInverse, "dense"},
    {BundleCovarianceMethod::kNone, "none"}};
constexpr EnumNameTable<BundleCovarianceMethod> EnumNames(BundleCovarianceMethod) {
  return EnumNameTable<BundleCovarianceMethod>(kBundleCovarianceMethodNames);
}

// How CrossValidateControlPoints finds each control point's left-out solution.
enum class BundleCrossValidationMethod {
  // From the full adjustment's reduced camera system S and its selected inverse C = S^-1: the
  // point's share of S (M, on the reduced blocks its rows touch) and of the reduced gradient taken
  // out by a low-rank (Woodbury) update, one Gauss-Newton step of the left-out problem from the
  // full solution. One factorisation for all points (as the statistics' own), then per point a
  // few small dense matrices.
  kUpdate,
  // One adjustment per point (warm-started, until convergence): the oracle of kUpdate, and what
  // it replaces. Ceres' adjustments whatever solver adjusted the block.
  kRefit,
};
inline constexpr EnumNameEntry<BundleCrossValidationMethod> kBundleCrossValidationMethodNames[] = {
    {BundleCrossValidationMethod::kUpdate, "update"},
    {BundleCrossValidationMethod::kRefit, "refit"}};
constexpr EnumNameTable<BundleCrossValidationMethod> EnumNames(BundleCrossValidationMethod) {
  return EnumNameTable<BundleCrossValidationMethod>(kBundleCrossValidationMethodNames);
}

// The datum the covariances of a relative block refer to (no control points, no camera positions:
// the seven similarity parameters are free and any covariance is one gauge's). Residuals,
// redundancy numbers, w-tests, the smallest detectable errors and the calibration's covariance are
// the same in every datum; orientation and point covariances are not. A block with an absolute
// datum has its own, and this does not apply to it.
enum class BundleRelativeCovariance {
  // Inner constraints on the adjusted points: of all datums, the one with the smallest trace of
  // the points' covariance (the free network of close-range photogrammetry; Polic et al. 2018 at
  // scale). Every image, the first too, then has a covariance.
  kInnerPoints,
  // Inner constraints on the camera centres: the smallest trace of the centres' covariance.
  kInnerCentres,
  // The adjustment's own gauge (COLMAP's): the first image held (covariance zero), one centre
  // coordinate of the second held (its variance zero).
  kFirstImage,
};
inline constexpr EnumNameEntry<BundleRelativeCovariance> kBundleRelativeCovarianceNames[] = {
    {BundleRelativeCovariance::kInnerPoints, "points"},
    {BundleRelativeCovariance::kInnerCentres, "centres"},
    {BundleRelativeCovariance::kFirstImage, "first_image"}};
constexpr EnumNameTable<BundleRelativeCovariance> EnumNames(BundleRelativeCovariance) {
  return EnumNameTable<BundleRelativeCovariance>(kBundleRelativeCovarianceNames);
}

// What the adjustment computes after convergence, and the thresholds of its verdicts: posterior
// covariances, over-fitting, correlations, per-observation diagnostics with their w-test, and the
// variance component estimation.
struct BundleStatisticsOptions {
  // Posterior covariances, redundancy numbers and everything that needs them, at every block size
  // (kNone: not computed).
  BundleCovarianceMethod covariances = BundleCovarianceMethod::kSelectedInversion;
  // A parameter of an absolute block whose sigma exceeds this many times (unitless) what the
  // observations would give it were every other parameter known (sqrt(C_jj S_jj) on the reduced
  // camera system) is listed as weakly determined: it trades off with others nearly exactly (a
  // lever arm against the flying height, an image turning about a line of points), so its value
  // rests on noise even though the normal matrix is regular. 1000: the blocks of the tests reach
  // 250 (DBAT's close-range self-calibration 76, a GNSS-only block with lever arm and focal length
  // 360).
  double weak_sigma_inflation = 1000.0;
  // The datum of a relative block's orientation and point covariances.
  BundleRelativeCovariance relative_covariance = BundleRelativeCovariance::kInnerPoints;
  // A prior group is flagged `overfit` when its RMS / stated accuracy is below overfit_ratio
  // (unitless, the note's "well below"), or its redundancy share below overfit_redundancy_share
  // (unitless: the tie points check less than a fifth of it, the solution follows the priors). A
  // share near 0.4 is normal when the priors are as accurate as the block itself.
  double overfit_ratio = 0.5;
  double overfit_redundancy_share = 0.2;
  // A prior group whose redundancy share is at least checked_redundancy_share (unitless) is checked
  // by the block: an RMS below overfit_ratio of its stated accuracy there says that the stated
  // accuracy is looser than the data (10 m start values of GNSS-less frames that fit to 4 cm), not
  // that the solution bends to the priors. Not flagged over-fitted; its message says so. (A
  // rightly stated group's RMS / stated is about sqrt(share): 0.71 at 0.5.)
  double checked_redundancy_share = 0.5;
  // Camera-model parameters whose |correlation| exceeds this are named (unitless, DBAT's 0.95).
  double high_correlation = 0.95;

  // Per-observation diagnostics (Baarda, Foerstner), computed with the covariance: redundancy
  // number r_i, normalized residual w_i = v_i / (s sigma_i sqrt(r_i)) with s = max(1, sigma0) (the
  // stated accuracy, or Pope's tau-test with the a-posteriori sigma0 when that is larger: never more
  // sensitive than the stated accuracies allow), the smallest detectable error (internal reliability)
  // nabla_i = delta0 sigma_i / sqrt(r_i) with delta0 = k(alpha) + k(beta), and its largest effect on
  // the centre of an image the observation bears on (external reliability: the images of its point,
  // or a prior's own image, whose covariances with it lie on the reduced system's pattern). Marks
  // per coordinate, priors per axis.
  bool observation_diagnostics = true;
  double snooping_alpha = 0.001;  // two-sided significance of the w-test (unitless)
  // snooping_alpha is the block's (family-wise): each observation is tested at alpha / n, n the
  // number of scalar observations (Bonferroni), so that a block of 30 000 observations gives about
  // alpha false alarms, not 30. false: alpha per observation (Baarda's classical alpha_0).
  bool snooping_family_wise = true;
  double snooping_power = 0.8;    // power of the test behind the smallest detectable error (unitless)
  // Observations with r_i below this (unitless) are listed as uncontrolled (a blunder there cannot
  // be seen).
  double uncontrolled_redundancy = 0.1;

  // Variance component estimation (Helmert / Foerstner): after the adjustment, every group's
  // variance factor s_g^2 = (its whitened residuals' sum of squares) / (its redundancy, the sum of
  // its redundancy numbers) rescales the group's accuracies, and the block is adjusted again, until
  // every estimated factor is 1 within variance_tolerance or max_variance_iterations is reached.
  // Needs the covariances (not kNone: BundleAdjustmentOptions::IsValid refuses it without). A
  // group whose redundancy is below
  // min_variance_redundancy is not estimated (its accuracy stays as stated, and says why).
  bool estimate_accuracies = false;
  int max_variance_iterations = 20;     // count
  double variance_tolerance = 0.01;     // |s_g^2 - 1| (unitless)
  double min_variance_redundancy = 5.0; // summed redundancy numbers (unitless)

  // How CrossValidateControlPoints leaves each control point out (the adjustment itself does not
  // read it): a low-rank update of the full adjustment's reduced system (kUpdate, one
  // factorisation in all) or one adjustment per point (kRefit).
  BundleCrossValidationMethod cross_validation = BundleCrossValidationMethod::kUpdate;

  bool IsValid(std::string* why) const;
};

// How the minimum is found: the derivative path, Levenberg-Marquardt's limits and linear solver,
// the gauge of a relative block's first solve, threads and progress. None of it changes the
// minimum (within the tolerances).
struct BundleSolverOptions {
  JacobianType jacobian = JacobianType::kAnalytic;  // derivative path of the collinearity costs
  int max_iterations = 100;             // Levenberg-Marquardt iterations per round (count)
  double function_tolerance = 1e-10;    // relative cost change (unitless)
  // Relative step (unitless): Ceres compares the step with the norm of ALL parameters, which map
  // coordinates make huge (a 1000-image block in UTM: ~2.5e9 m), so 1e-10 would stop 0.25 m short
  // of the minimum (measured on a 24-image block: 0.5 mm, 0.05 sigma); the cost and gradient
  // tolerances decide convergence.
  double parameter_tolerance = 1e-16;
  double gradient_tolerance = 1e-12;    // max-norm of the projected gradient (unitless)
  BundleLinearSolver linear_solver = BundleLinearSolver::kSparseSchur;
  // A relative block (no control points, no camera positions) is solved first without a gauge
  // and then moved by a similarity into COLMAP's gauge (first image fixed, one coordinate of the
  // second) and polished there: the same minimum, in far fewer iterations when the first image's
  // approximate attitude is off (the gauge turns the whole block about it). false: solved in
  // COLMAP's gauge from the start.
  bool free_gauge_for_relative_blocks = true;
  int num_threads = 0;                  // 0: all cores (count)
  // Progress callback after every iteration (may be empty). Returning false stops the adjustment
  // after that iteration: the summary's termination is kCancelled and the block is left as it
  // was. Called from the adjusting thread. The Taylor solvers (taylor_bundle.h) report through it
  // too but ignore what it returns.
  std::function<bool(const BundleIterationInfo&)> progress;

  bool IsValid(std::string* why) const;
};

// The options of BundleAdjust, composed of named parts as PoseLib composes its options. What the
// block holds constant or estimates (datum, self-calibration, the GNSS lever arm) is
// BundleAdjustmentConfig, not an option.
struct BundleAdjustmentOptions {
  BundleAccuracies accuracies;         // the weights of the objective's groups
  BundleRobustnessOptions robustness;  // robust loss, rejection rounds, data snooping
  BundleStatisticsOptions statistics;  // covariances, verdicts, diagnostics, variance components
  BundleSolverOptions solver;          // how the minimum is found

  // Checks every part (the accuracies here, the others by their own IsValid), then what one part
  // needs of another: data snooping and variance components need the covariances (and snooping
  // the observation diagnostics).
  bool IsValid(std::string* why) const;
};

// What the adjustment holds constant or estimates about the block (in the manner of COLMAP's
// BundleAdjustmentConfig).
struct BundleAdjustmentConfig {
  // Per camera (index into Block::cameras): the parameter indices to estimate (self-calibration).
  // Cameras not listed are held constant.
  std::vector<std::vector<int>> calibrated_params;
  std::set<int> constant_images;  // exterior orientations held fixed
  std::set<int> constant_points;  // points held fixed (e.g. control points taken as error-free)
  // GNSS lever arm: antenna offset from the projection centre in the camera frame (u, v, w; m).
  // It lives here, not in the options, because it is data about the camera rig, held constant or
  // estimated like the calibrated parameters above; not in the Block because no table carries it
  // (it is given on the command line) and a Block is what the readers build from the files.
  std::optional<Eigen::Vector3d> lever_arm_m;
  bool estimate_lever_arm = false;  // estimate it (starting from lever_arm_m or zero)
  // Parses `photopose bundle --calibrate` names (core/camera_models.h) for every camera of the
  // block; an error names a parameter a camera's model lacks.
  static Status FromCalibrationNames(const Block& block, const std::vector<std::string>& names,
                                     BundleAdjustmentConfig* config);
};

// The config an adjustment of `block` runs with: `config` with every control point stated
// error-free (IsHeldFixed, core/block.h: AccuracyX/Y/Z all 0) added to constant_points. BundleAdjust
// and TaylorBundleAdjust apply it on entry, so a caller states fixed control in the block alone.
BundleAdjustmentConfig WithFixedControlPoints(const BundleAdjustmentConfig& config,
                                              const Block& block);

// How the adjustment is tied to the ground.
enum class BundleDatum {
  kControl,   // control points and/or camera positions fix all seven similarity parameters
  kRelative,  // neither: COLMAP's convention (first image fixed, one coordinate of the second)
};
inline constexpr EnumNameEntry<BundleDatum> kBundleDatumNames[] = {
    {BundleDatum::kControl, "absolute"}, {BundleDatum::kRelative, "relative"}};
constexpr EnumNameTable<BundleDatum> EnumNames(BundleDatum) {
  return EnumNameTable<BundleDatum>(kBundleDatumNames);
}

// The groups of observations in the objective, in report order; an index into per-group arrays.
enum BundleGroup : std::uint8_t {
  kTieMarks = 0,     // image marks of tie points
  kControlMarks,     // image marks of control points
  kControlPoints,    // surveyed coordinates of control points (priors)
  kCameraPositions,  // measured camera centres (priors)
  kAttitudes,        // measured attitudes (priors)
};
constexpr int kNumBundleGroups = 5;
// The groups of priors (measured coordinates of the unknowns), the ones an over-fitting verdict is
// about; the mark groups are observations of the images.
constexpr bool IsPriorGroup(BundleGroup g) {
  return g == kControlPoints || g == kCameraPositions || g == kAttitudes;
}
inline constexpr EnumNameEntry<BundleGroup> kBundleGroupNames[] = {
    {kTieMarks, "tie_marks"},
    {kControlMarks, "control_marks"},
    {kControlPoints, "control_points"},
    {kCameraPositions, "camera_positions"},
    {kAttitudes, "attitudes"}};
constexpr EnumNameTable<BundleGroup> EnumNames(BundleGroup) {
  return EnumNameTable<BundleGroup>(kBundleGroupNames);
}

// The statistics of one group of the objective.
struct BundleGroupStatistics {
  BundleGroup group = kTieMarks;
  int count = 0;     // observations (marks, points, cameras)
  std::string unit;  // px, um, m or deg
  // Stated accuracy: mean over the group per axis (unit above); 0 on an axis without rows (the
  // marks' Z; the Z of camera positions that are all without height).
  Eigen::Vector3d stated_accuracy = Eigen::Vector3d::Zero();
  int num_axes = 2;  // 2 for marks, 3 otherwise
  Eigen::Vector3d rms = Eigen::Vector3d::Zero();  // residual RMS per axis (unit above; 0 as above)
  double rms_total = 0.0;  // sqrt(mean of the squared residuals over the group's scalar rows)
  // rms / stated accuracy (unitless): the whitened RMS, 1 when the accuracy was right.
  double ratio = 0.0;
  // The group's summed redundancy numbers over its number of scalar observations (unitless,
  // 0..1): how much of it the rest of the block checks. NaN when not computed.
  double redundancy_share = 0.0;
  // A prior group with redundancy share < overfit_redundancy_share, or with ratio < overfit_ratio
  // and a share below checked_redundancy_share (BundleStatisticsOptions). Without statistics (share
  // NaN) a ratio below overfit_ratio is no verdict: false, and `message` says it was not judged.
  bool overfit = false;
  // The over-fitting warning; for a checked prior group with ratio < overfit_ratio, the note that
  // its stated accuracy is loose; for one with an unknown share, that it was not judged; else
  // empty.
  std::string message;
  // Items of the group held fixed (control points stated error-free, core/block.h IsHeldFixed, or
  // in BundleAdjustmentConfig::constant_points): no observations, so not in count, RMS, ratio or
  // verdict. A group whose items are all fixed (count 0) is listed as fixed: stated accuracy 0,
  // RMS 0, ratio and redundancy share NaN, never over-fitted.
  int num_fixed = 0;
  bool fixed() const { return count == 0 && num_fixed > 0; }
  // Variance component estimation (estimate_accuracies): the group's accuracy estimated from the
  // data (mean per axis, unit above; NaN when not estimated) and its standard error
  // s / sqrt(2 r_g); why it was not estimated otherwise.
  Eigen::Vector3d estimated_accuracy = Eigen::Vector3d::Constant(std::nan(""));
  double estimated_accuracy_standard_error = std::nan("");  // relative (unitless)
  std::string estimation_message;
};

// Whether a three-axis group's stated accuracy differs between its axes (GNSS at 3/3/6 cm; every
// axis with rows): reports then show it as X/Y/Z, since its RMS / stated is the whitened ratio
// over all three axes, which the X accuracy alone would not explain.
bool StatedPerAxis(const BundleGroupStatistics& g);

// A group's figures as every report prints them (FullReport, the CLI's console lines and HTML
// page), one rule for all, so that a value reads the same in each: stated (X, or X/Y/Z when
// StatedPerAxis), RMS and estimated accuracy in the one unit and decimals FormatRowInOneUnit
// (core/units.h) chooses from the group's own values (a control-point group in mm beside camera
// positions in m; a stated 10 m beside an RMS of 0.5 mm each with two significant digits), without
// the unit; "n/a" where not finite. `unit` is the ASCII name ("um"); a page shows
// Utf8UnitName(unit).
struct BundleGroupFigures {
  std::string unit;       // "px", "um", "sigma", "mm", "cm", "m" or "arcsec"
  std::string stated_x;   // the X axis's (a mark group's one) stated accuracy
  std::string stated;     // stated_x, or "X/Y/Z" when StatedPerAxis
  std::string rms;        // rms_total
  std::string estimated;  // estimated_accuracy X; "n/a" when not estimated
};
BundleGroupFigures FormatGroupFigures(const BundleGroupStatistics& g);

// The diagnostics of one scalar observation (observation_diagnostics). A 1000-image block has
// 3.4 million: 40 bytes each. The redundancy number and the normalized residual, which the
// decisions (rejected, uncontrolled, data snooping) read, are double; the four values only
// reported are single precision (7 significant digits), each rounded once from its double.
struct BundleObservationDiagnostics {
  double redundancy = 0.0;  // r_i in [0, 1]
  double normalized = 0.0;  // w_i (unitless); NaN when r_i is below 1e-6
  float residual = 0.0f;    // observed - computed (marks: px or um; points, cameras: m; deg)
  float sigma = 0.0f;       // its accuracy, same unit
  float mdb = 0.0f;         // smallest detectable error, same unit as residual; inf when r_i ~ 0
  // Largest shift of the centre of an image it bears on (its point's images; a prior's own image)
  // caused by an error of size mdb (m).
  float external_m = 0.0f;
  int item = -1;  // mark (marks), point (control_points) or image (priors) index
  BundleGroup group = kTieMarks;
  std::int8_t axis = 0;   // marks: 0 x, 1 y; priors: 0..2 (X, Y, Z or omega, phi, kappa)
  bool rejected = false;  // |w_i| > k(alpha)
};
static_assert(sizeof(BundleObservationDiagnostics) <= 40,
              "one per scalar observation: keep it small");

// One step of data snooping.
struct BundleSnoopingStep {
  BundleGroup group = kTieMarks;
  int item = -1;
  int axis = 0;
  double normalized = 0.0;  // |w| of the removed observation
  double residual = 0.0;    // its residual (unit of its group)
  // The adjustment round (1-based) whose statistics chose it; with batch snooping |w| and the
  // residual are conditioned on the removals chosen before it in that round.
  int round = 0;
};

struct BundleImageResult {
  bool adjusted = false;
  std::string message;  // why not, or empty
  // Posterior covariance sigma0^2 (J^T P J)^-1 of the exterior orientation (m, rad, seed), in the
  // datum of BundleAdjustmentSummary::covariance_datum; zero when not computed (and for an image
  // the datum holds fixed).
  Matrix6d covariance = Matrix6d::Zero();
  bool has_covariance = false;
  int num_marks = 0;         // marks used in the final round
  double rms_residual = 0.0; // of those, RMS of the residual vector length in the marks' unit
  // "px" or "um"; "sigma" when the image has pixel and film marks (the RMS of the whitened
  // residual vector: residual / sigma, the stated accuracy 1).
  std::string unit;
};

struct BundlePointResult {
  int num_observations = 0;  // marks used in the final round
  // sigma0^2-scaled (m^2). Control points: from the adjustment. Check points: of the
  // intersection, with the uncertainty of the adjusted images and cameras carried into it (when
  // the covariance was computed; the measurements' part alone otherwise).
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  bool has_covariance = false;
  // False for a check point whose covariance is the measurements' part alone (the images and
  // cameras taken as error-free: no statistics): too small to test its error against.
  bool covariance_complete = false;
  // Control points: adjusted - surveyed; check points: intersected - surveyed (m).
  std::optional<Eigen::Vector3d> error_m;
  std::string message;  // e.g. why a check point could not be intersected
};

// A weakly determined parameter (BundleStatisticsOptions::weak_sigma_inflation).
struct BundleWeakParameter {
  std::string parameter;         // "image 'IMG_12': omega", "the lever arm's z (camera frame)", ...
  double sigma_inflation = 0.0;  // its sigma over what its own observations give it (unitless)
};

struct BundleCalibrationResult {
  int camera = -1;
  std::vector<std::string> names;    // estimated parameters
  std::vector<int> indices;          // their indices in the camera's params
  std::vector<double> values;        // adjusted values (units of core/camera_models.h)
  std::vector<double> sigmas;        // sigma0-scaled standard deviations; empty without covariance
  Eigen::MatrixXd correlation;       // of the estimated parameters (empty without covariance)
  std::vector<std::string> high_correlations;  // "K2~K3: -0.979"
};

struct BundleRejectedMark {
  int mark = -1;               // index into Block::marks
  int round = 0;               // the round after which it was rejected
  double whitened_residual = 0.0;  // |v| / (sigma sigma0) when rejected
};

// A tie point whose marks disagree beyond the rejection threshold but whose blundered mark the
// block cannot single out (internal/bundle_rounds.h, RejectMarks): removing its worst mark would
// not explain the disagreement more than 1 / snooping_alpha times better (likelihood ratio) than
// removing runner_up_mark. All its marks are left out (in rejected_marks); the point is not
// adjusted and not written to the points table.
struct BundleUnresolvedPoint {
  int point = -1;           // index into Block::points
  int round = 0;            // the round after which it was left out
  int worst_mark = -1;      // the mark with the largest normalized residual (Block::marks)
  int runner_up_mark = -1;  // the other mark whose removal explains the point nearly as well
  // The drop of the sum of squares each removal gives, w_x^2 + w_y^2 (unitless).
  double worst_drop = 0.0;
  double runner_up_drop = 0.0;
};

// A mark of a check point rejected by the w-test of its intersection (solvers/bundle/check_points.h).
struct BundleRejectedCheckMark {
  int mark = -1;            // index into Block::marks
  double normalized = 0.0;  // the larger |w| of its x and y (unitless)
  // observed - computed at the intersection that still held it (the mark's unit, px or um).
  Eigen::Vector2d residual = Eigen::Vector2d::Zero();
};

struct BundleAdjustmentSummary {
  SolverTermination termination = SolverTermination::kFailure;
  std::string message;
  BundleDatum datum = BundleDatum::kControl;
  std::string datum_description;  // in words, for the report
  int rounds = 0;                 // adjustment rounds (rejections re-adjust)
  // Rounds whose statistics data snooping examined (count): one per removal one at a time, fewer
  // with batch snooping (BundleRobustnessOptions::snooping_batch).
  int snooping_rounds = 0;
  // Of statistics_seconds: batch snooping's candidates and their cofactors, over all rounds (s).
  double snooping_seconds = 0.0;
  int iterations = 0;             // over all rounds
  double initial_cost = 0.0;      // 1/2 sum of squared whitened residuals, first round start
  double final_cost = 0.0;        // at the end of the last round
  double sigma0 = 0.0;            // sqrt(2 final_cost / redundancy) (unitless)
  int redundancy = 0;             // scalar observations - free parameters
  int num_images = 0, num_points = 0, num_marks = 0;  // in the final round
  int num_rejected_marks = 0;
  // Tie points left out because they had no initial coordinates (seen twice or more, but not
  // intersected: rays too close to parallel or marks that do not meet), by PointID.
  std::vector<std::string> tie_points_left_out;
  double time_seconds = 0.0;
  double statistics_seconds = 0.0;  // covariances and redundancy shares, all of the statistics
  // Of the last round's statistics: the factorisation of the reduced camera system and the
  // selected inversion on its pattern (s; part of statistics_seconds), the entries of its inverse
  // computed (count) and the bytes they and the factor held.
  double factorization_seconds = 0.0;
  double inversion_seconds = 0.0;
  int64_t covariance_entries = 0;
  int64_t covariance_memory_bytes = 0;
  // The datum the orientation and point covariances refer to, in words ("the block's datum", or a
  // relative block's BundleRelativeCovariance with its size); empty without covariances.
  std::string covariance_datum;
  // Where the adjustment's time went, over all rounds (s): building the Ceres problems; Ceres'
  // preprocessing (program, ordering, Schur structure, symbolic factorisation); residual and
  // Jacobian evaluation; the linear solves of the Levenberg-Marquardt steps (Schur elimination,
  // factorisation of the reduced camera system, back-substitution).
  double problem_build_seconds = 0.0;
  double solver_preprocessing_seconds = 0.0;
  // Before any round: the checks of the inputs, the plan and the start values (s).
  double plan_seconds = 0.0;
  // Per round: its problem (built, or updated in place after a rejection) and Ceres' solve, wall
  // clock (s); the statistics are not part of it.
  std::vector<double> round_seconds;
  // Choosing the marks to reject and checking that the block still holds without them, over all
  // rounds (s).
  double rejection_seconds = 0.0;
  double residual_evaluation_seconds = 0.0;
  double jacobian_evaluation_seconds = 0.0;
  double linear_solver_seconds = 0.0;
  // Ceres' fixed-size Schur specialisation of the last solve, "row,point,image" block sizes ("d":
  // dynamic, the slower generic path): "2,3,6" when every image block has 6 free parameters.
  std::string schur_structure;
  // The solver that adjusted the block. The Taylor solvers (taylor_bundle.h) fill round_seconds
  // (their own normal equations, a relative block's solve without a gauge included),
  // problem_build_seconds (the Ceres problem their statistics evaluate) and the statistics; the
  // Ceres-only times above stay 0.
  PoseSolver solver = PoseSolver::kCeres;

  bool IsSolutionUsable() const { return termination == SolverTermination::kConverged; }
  std::string BriefReport() const;
};

struct BundleAdjustmentResult {
  BundleAdjustmentSummary summary;
  std::vector<BundleImageResult> images;  // per Block::images
  std::vector<BundlePointResult> points;  // per Block::points
  std::vector<BundleGroupStatistics> groups;
  std::vector<BundleCalibrationResult> calibration;
  // Weakly determined parameters of an absolute block, the worst first (empty without covariances).
  std::vector<BundleWeakParameter> weakly_determined;
  std::vector<BundleRejectedMark> rejected_marks;
  // Tie points the rejection could not resolve, all their marks left out (in rejected_marks).
  std::vector<BundleUnresolvedPoint> unresolved_points;
  // Check marks rejected by the w-test of their point's intersection, in order of rejection.
  std::vector<BundleRejectedCheckMark> rejected_check_marks;
  std::optional<Eigen::Vector3d> lever_arm_m;  // estimated (or applied) lever arm
  // Check points intersected and compared: RMSE per axis and total (m); count. NaN without a
  // point (no figure, not a zero error).
  int num_check_points = 0;
  Eigen::Vector3d check_rmse_m = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  double check_rmse_total_m = std::numeric_limits<double>::quiet_NaN();
  // Control points: RMSE of adjusted - surveyed per axis and total (m); NaN without a point.
  int num_control_points = 0;
  Eigen::Vector3d control_rmse_m = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  double control_rmse_total_m = std::numeric_limits<double>::quiet_NaN();
  // Residual per mark used in the final round (observed - computed, in the mark's own unit); NaN
  // for marks not used (check marks, rejected marks, marks of images not adjusted).
  std::vector<Eigen::Vector2d> mark_residuals;

  // Variance component estimation: iterations run (0 when not asked).
  int variance_iterations = 0;
  // Per-observation diagnostics, in the order marks (x, y), control points (X, Y, Z), camera
  // positions, attitudes; empty when not computed. critical_value is k(alpha) of the w-test and
  // delta0 the non-centrality behind the smallest detectable errors.
  std::vector<BundleObservationDiagnostics> observations;
  double critical_value = 0.0;
  double alpha_per_observation = 0.0;  // the w-test's two-sided level per observation
  double delta0 = 0.0;
  int num_uncontrolled = 0;  // observations with r_i below uncontrolled_redundancy
  std::vector<BundleSnoopingStep> snooping;  // removals in order (snoop)

  // A multi-line report: summary, groups with their verdicts, images, points, calibration.
  std::string FullReport(const Block& block) const;
  // Per mark of the block adjusted (num_marks of them): 1 for those the adjustment left out of
  // its final round, rejected (rejected_marks) or removed by data snooping (either axis), else 0.
  std::vector<char> RemovedMarks(size_t num_marks) const;
};

// Adjusts the block in place: on success the images' eo, the points' position_m and the cameras'
// params hold the adjusted values. Every image needs an initial eo and every tie point an initial
// position (see solvers/bundle/block_initialization.h); control and check points start at their
// surveyed coordinates. Returns an error (nothing changed) for invalid options or a block the
// adjustment cannot use (no datum for the asked output, disconnected, an image with fewer than 3
// marks, a parameter to calibrate that the model lacks); a failed or unconverged adjustment is
// reported in result->summary with the block left at its input values. A round that converges with
// a singular normal matrix (a parameter the observations do not determine: an image whose marks lie
// on one line in space, a self-calibrated parameter no mark constrains, a lever arm component the
// attitudes cannot separate from the datum) fails: termination kFailure, and the message names the
// parameter where the factorisation of the reduced camera system found the rank defect ("image
// 'IMG_12': omega is not determined by the observations"; its image, camera or the lever arm).
// This is checked with every statistics option: with covariances kNone the last round's reduced
// camera system is still built and factorised once (not inverted).
Status BundleAdjust(const BundleAdjustmentOptions& options, const BundleAdjustmentConfig& config,
                    Block* block, BundleAdjustmentResult* result);

// ------------------------------------------------------------------ leave-one-out cross-validation

struct BundleCrossValidationPoint {
  int point = -1;           // index into Block::points (a control point of the full adjustment)
  bool ok = false;          // adjusted and intersected without it
  std::string message;      // why not
  Eigen::Vector3d error_m = Eigen::Vector3d::Zero();  // intersected - surveyed, left out (m)
  int num_images = 0;       // rays of its intersection
  // e^T (C_intersection + C_surveyed)^-1 e: chi-square with 3 degrees of freedom for a point
  // that agrees with the rest of the block within the stated accuracies.
  double normalized = 0.0;
  bool stands_out = false;  // normalized above the chi-square(3) quantile at 1 - snooping_alpha
};

struct BundleCrossValidationResult {
  BundleCrossValidationMethod method = BundleCrossValidationMethod::kUpdate;  // how it was found
  std::vector<BundleCrossValidationPoint> points;
  int count = 0;  // points cross-validated
  Eigen::Vector3d rmse_m = Eigen::Vector3d::Zero();  // per axis over those (m)
  double rmse_total_m = 0.0;
  double threshold = 0.0;  // of `normalized` for stands_out
  double time_seconds = 0.0;
};

// Each control point of the adjusted block in turn becomes a check point: its prior and its marks
// leave the adjustment (what `full` removed stays out: its rejected marks, except the point's own,
// and the priors data snooping removed), and it is intersected from the images of the adjustment
// without it, its error recorded. options.statistics.cross_validation says how that adjustment is
// found: by a low-rank update of `full`'s reduced system, one linearised step from the full
// solution (kUpdate; the statistics' code, so for a block adjusted by either solver), or adjusted
// again from `adjusted` (kRefit: num_threads Ceres adjustments in parallel, 0: all cores). A point
// whose removal leaves no datum (or an image with too few marks) is reported as not
// cross-validated, with the plan's reason, by both; kUpdate also when the removal leaves S
// singular (BundleCrossValidationPoint::message says so). Needs the covariances (an error with
// statistics.covariances kNone: the normalized error would take the images as error-free).
// `adjusted` and `full` are the block and the result of the full adjustment with `options` and
// `config` (the update assumes its solution is that adjustment's minimum within its tolerances;
// with estimated accuracies the left-out problem's gradient there is taken into the step).
Status CrossValidateControlPoints(const BundleAdjustmentOptions& options,
                                  const BundleAdjustmentConfig& config, const Block& adjusted,
                                  const BundleAdjustmentResult& full, int num_threads,
                                  BundleCrossValidationResult* result);

}  // namespace photopose
