#pragma once
// The engine of `photopose compare`: the pose solvers side by side.
//
//  - Monte-Carlo mode (RunMonteCarlo): synthetic scenes of core/simulation/synthetic_scene.h swept over image
//    noise, outlier fraction, number of control points and initial-value error, N seeded trials per
//    setting. Every solver of one trial gets the same scene and the same initial values (the
//    scene's approximate frames, or one seeded RANSAC run per image), so the differences are the
//    solvers' alone. Each solve is compared with the truth.
//  - Dataset mode (RunDatasetComparison): real tables with no truth; every solver's pose, sigma0
//  and
//    residuals, the differences between solvers and, when given, to a reference orientation.
//
// Both return plain structs; tables, CSV and Markdown are rendered here, the HTML report in
// tools/report/comparison_html.h, and the command (tools/commands/compare_command.cc) only parses flags and writes.
//
// Definitions used throughout (docs/comparison.md explains them):
//  - position error: |X0_est - X0_true| (m); rotation error: the angle of R_true^T R_est
//  (arc-seconds).
//  - success: the solver returned a pose and its position error is at most success_sigmas times
//    the design standard deviation sqrt(trace C_pos), C = (J^T P J)^-1 at the true pose over the
//    image's uncontaminated control observations weighted by their stated accuracy (m). The
//    threshold depends on the geometry and noise, not on the solver, so it is the same yardstick
//    for every solver of a sample.
//  - NEES: e^T C_solver^-1 e with e = (X0 - X0_true, wrap(angles - angles_true)) in the seed
//    parametrisation (m, rad) and C_solver the 6x6 covariance the solver returned (sigma0^2
//    (J^T P J)^-1); "a priori" NEES uses C_solver / sigma0^2, i.e. sigma0 fixed at 1. For an honest
//    covariance and Gaussian noise the a-priori NEES is chi-square with 6 degrees of freedom; the
//    mean of N of them lies in [q(a/2), q(1 - a/2)] / N, q the quantiles of chi-square with 6N
//    degrees of freedom. With sigma0 estimated from r = 2n - 6 redundant observations the expected
//    value is 6 r / (r - 2) instead of 6.

#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/enum_names.h"
#include "core/status.h"
#include "core/simulation/synthetic_scene.h"
#include "core/types.h"
#include "cost_functions/collinearity_cost.h"
#include "solvers/resection/resection.h"
#include "tools/jobs/resection_job.h"

namespace photopose::cli {

// ------------------------------------------------------------------ solvers under comparison

// One solver configuration. The loss and the Jacobian apply to Ceres only; the Taylor solvers are
// plain (unweighted-loss) least squares.
struct SolverVariant {
  PoseSolver solver = PoseSolver::kCeres;
  JacobianType jacobian = JacobianType::kAnalytic;  // Ceres only
  LossType loss = LossType::kNone;                  // Ceres only

  // "taylor_as_printed", "taylor", "ceres_analytic/none", "ceres_autodiff/huber", ...
  std::string Name() const;
  // `base` with the solver, Jacobian and loss of this variant.
  ResectionOptions ApplyTo(const ResectionOptions& base) const;
};

// Comma-separated solver names (taylor_as_printed, taylor, ceres_analytic, ceres_autodiff; "all"
// for the four) and robust losses of the Ceres solvers (none, huber, softl1, cauchy, arctan, tukey;
// "all" for the six): every Ceres solver is run with every loss. Order is kept, duplicates are
// dropped. An unknown name is an error naming it.
Status ParseSolverVariants(const std::string& solvers, const std::string& losses,
                           std::vector<SolverVariant>* variants);

// ------------------------------------------------------------------ statistics helpers

// Interval of the mean of `count` chi-square(6) variables: [q(a/2), q(1 - a/2)] / count with q the
// quantiles of chi-square(6 count), a = 1 - confidence.
struct NeesInterval {
  double lower = 0.0;
  double upper = 0.0;
  bool Contains(double mean) const { return mean >= lower && mean <= upper; }
};
NeesInterval MeanNeesInterval(int count, double confidence);

// Angle of R_a^T R_b (arc-seconds) for two poses in seed angles (rad), or for two rotations.
double RotationErrorArcSeconds(const Eigen::Vector3d& angles_a_rad,
                               const Eigen::Vector3d& angles_b_rad);
double RotationErrorArcSeconds(const Eigen::Matrix3d& R_a, const Eigen::Matrix3d& R_b);

// e^T C^-1 e for the 6-vector e = (estimate - truth) with the angles wrapped to (-pi, pi]. The seed
// angles (omega + pi, pi - phi, kappa + pi) are the same rotation as (omega, phi, kappa): when the
// estimate is nearer the truth in that form, e and C are taken in it. NaN when C is not positive
// definite.
double NormalizedEstimationErrorSquared(const ExteriorOrientation& estimate,
                                        const ExteriorOrientation& truth,
                                        const Matrix6d& covariance);

// ------------------------------------------------------------------ Monte-Carlo mode

enum class InitialValues {
  kApproximateFrames,  // the scene's approximate frames (the initial-value error of the sweep)
  kRansac,             // LO-RANSAC per image, seeded by the trial: the same start for every solver
};
inline constexpr EnumNameEntry<InitialValues> kInitialValuesNames[] = {
    {InitialValues::kApproximateFrames, "frames"}, {InitialValues::kRansac, "ransac"}};
constexpr EnumNameTable<InitialValues> EnumNames(InitialValues) {
  return EnumNameTable<InitialValues>(kInitialValuesNames);
}

// How the per-axis value lists combine into settings.
enum class SweepType {
  // The baseline is the first value of every list; each further value of one list is a setting
  // with the other axes at their baseline (1 + sum (n_i - 1) settings per scenario).
  kAxes,
  // Every combination (prod n_i settings per scenario).
  kGrid,
};
inline constexpr EnumNameEntry<SweepType> kSweepTypeNames[] = {{SweepType::kAxes, "axes"},
                                                              {SweepType::kGrid, "grid"}};
constexpr EnumNameTable<SweepType> EnumNames(SweepType) {
  return EnumNameTable<SweepType>(kSweepTypeNames);
}

// Error of the approximate frames: uniform in +- position_m per axis and +- angle_deg per angle.
struct InitialError {
  double position_m = 5.0;
  double angle_deg = 2.0;
};

// "P:A[,P:A...]" (metres : degrees) -> errors; an error naming the bad item otherwise.
Status ParseInitialErrors(const std::string& text, std::vector<InitialError>* errors);

struct MonteCarloOptions {
  std::vector<Scenario> scenarios = {Scenario::kNadir};
  std::vector<double> noise_px = {0.5};           // image noise, one sigma (pixels)
  std::vector<double> outlier_fractions = {0.0};  // fraction of marks with gross errors, [0, 1)
  std::vector<int> control_points = {20};         // control points per image footprint (count)
  std::vector<InitialError> initial_errors = {InitialError()};
  int check_points = 5;  // check points per image footprint (count)
  int trials = 50;       // trials per setting (count)
  uint64_t seed = 1;     // trial t of every setting uses scene seed `seed + t`
  SweepType sweep = SweepType::kAxes;
  InitialValues initial = InitialValues::kApproximateFrames;
  std::vector<SolverVariant> solvers;
  // Options shared by every solver (loss scale, RANSAC threshold, iterations); solver, Jacobian
  // and loss come from each SolverVariant.
  ResectionOptions resection;
  double success_sigmas = 10.0;  // success: position error <= this many design sigmas (unitless)
  int num_threads = 1;           // trials run in parallel (0: all cores)
  bool keep_samples = false;     // keep every solve's outcome in MonteCarloResult (tests, CSV)
  // Called after every trial with (trials done, trials in all), from the worker threads (so it
  // must be thread-safe); may be empty. The command prints a progress line from it. Returning
  // false cancels the run: no trial starts after it, and RunMonteCarlo returns an error that
  // says so (no result).
  std::function<bool(size_t, size_t)> progress;

  bool IsValid(std::string* why) const;
};

// One point of the sweep.
struct SweepSetting {
  Scenario scenario = Scenario::kNadir;
  double noise_px = 0.5;
  double outlier_fraction = 0.0;
  int control_points = 20;
  InitialError initial_error;
  // Which axis this setting varies from the baseline ("baseline", "noise", "outliers", "control",
  // "initial"; "grid" for a grid sweep).
  std::string axis = "baseline";
};

std::vector<SweepSetting> MakeSweepSettings(const MonteCarloOptions& options);

// The scene of trial `trial` (0-based) of a setting: `photopose simulate` with the same values and
// --seed=options.seed + trial makes the same dataset.
SyntheticSceneOptions SceneOptionsFor(const MonteCarloOptions& options, const SweepSetting& setting,
                                      int trial);

// One solve of one image of one trial, against the truth.
struct SolveOutcome {
  int trial = 0;
  int image = 0;        // index of the image in the scene
  int solver = 0;       // index into MonteCarloOptions::solvers
  bool solved = false;  // the solver returned a pose
  bool success = false;
  std::string message;  // why it was not solved
  double position_error_m = 0.0;
  double rotation_error_arcsec = 0.0;
  // To the reference solver ("taylor" when compared, otherwise the first) on the same image, when
  // both solved (NaN otherwise and for the reference itself): |dX0| (m), rotation angle (arcsec).
  double difference_position_m = std::numeric_limits<double>::quiet_NaN();
  double difference_rotation_arcsec = std::numeric_limits<double>::quiet_NaN();
  double success_threshold_m = 0.0;  // success_sigmas * design sigma of this image (m)
  double nees = 0.0;                 // with the solver's covariance (NaN when not available)
  double nees_apriori = 0.0;         // with N^-1: the covariance / its covariance_factor
  bool accuracy_stated = false;      // the solver's covariance is N^-1 (ResectionResult)
  double check_rmse_px = 0.0;        // check points, observed - projected (pixels)
  int num_check = 0;
  double reprojection_rmse_px = 0.0;  // uncontaminated control observations (pixels)
  int num_reprojection = 0;
  int degrees_of_freedom = 0;  // of the solver's sigma0: 2 inliers - 6
  double sigma0 = 0.0;
  int iterations = 0;
  double total_seconds = 0.0;       // ResectImage wall time (s)
  double refinement_seconds = 0.0;  // its refinement part (s)
};

// One solver over all samples (trials x images) of one setting.
struct SolverStatistics {
  std::string solver;
  int samples = 0;    // trials x images attempted
  int solved = 0;     // a pose was returned
  int successes = 0;  // solved and within the success threshold
  double success_rate = 0.0;
  // Over the solved samples: RMS of the position error (m), rotation error (arc-seconds), of the
  // check-point and reprojection residuals (pixels); mean iterations.
  double position_rmse_m = 0.0;
  double rotation_rmse_arcsec = 0.0;
  // RMS of the paired differences to the reference solver (m, arc-seconds).
  double difference_position_rmse_m = 0.0;
  double difference_rotation_rmse_arcsec = 0.0;
  double check_rmse_px = 0.0;
  double reprojection_rmse_px = 0.0;
  double mean_iterations = 0.0;
  double mean_success_threshold_m = 0.0;
  // Median wall time per solve over the solved samples (over all when none was solved) (s): whole
  // ResectImage call and refinement only.
  double median_seconds = 0.0;
  double median_refinement_seconds = 0.0;
  // Mean NEES over the solved samples with a finite value (NaN when there is none, e.g. noise 0),
  // the number of such samples, and the intervals of the mean for that number.
  double mean_nees = 0.0;
  double mean_nees_apriori = 0.0;
  int nees_count = 0;
  NeesInterval nees_interval_95;
  NeesInterval nees_interval_99;
  // The expected mean NEES of the solver's covariance: 6 per sample with stated accuracy (the
  // a-priori covariance), 6 r / (r - 2) with sigma0 from the data, r the redundancy 2 n - 6
  // (samples with r <= 2 left out); their mean.
  double expected_nees = 0.0;
  // Why samples were not solved: the solver's message with numbers and quoted names replaced by
  // '#' and '...', most frequent first, with their counts.
  std::vector<std::pair<std::string, int>> failure_reasons;
};

struct SettingResult {
  SweepSetting setting;
  int images_per_trial = 0;
  std::vector<SolverStatistics> solvers;  // in MonteCarloOptions::solvers order
  std::vector<SolveOutcome> samples;      // when keep_samples
};

struct MonteCarloResult {
  std::vector<SettingResult> settings;
  std::vector<std::string> solver_names;
  double wall_seconds = 0.0;
};

// Runs the sweep. Errors: invalid options, or a scene the generator cannot make.
Status RunMonteCarlo(const MonteCarloOptions& options, MonteCarloResult* result);

// The baseline value of every axis is the first of its list. Indices of the settings of `scenario`
// that vary `axis` ("noise", "outliers", "control", "initial") with every other axis at its
// baseline, the baseline included, sorted by the value of `axis`; empty when the axis has one
// value.
std::vector<size_t> SettingsAlongAxis(const MonteCarloOptions& options,
                                      const MonteCarloResult& result, Scenario scenario,
                                      const std::string& axis);
// The value of `axis` of a setting: noise (px), outlier fraction, control points (count), initial
// angle error (deg).
double AxisValue(const SweepSetting& setting, const std::string& axis);

// The in-memory equivalent of PrepareResectionJob for a synthetic scene (corner pixel origin,
// marks' Accuracy as sigma), and for every input the outlier flag of each control observation.
struct SceneJob {
  ResectionJob job;
  std::vector<std::vector<char>> control_is_outlier;
};
Status MakeSceneJob(const SyntheticScene& scene, SceneJob* scene_job);

// ------------------------------------------------------------------ dataset mode

struct DatasetComparisonOptions {
  // The tables, as for `photopose resect` (job.frames_path: optional approximate frames, used by
  // every solver; otherwise RANSAC with job.resection.ransac.seed for every solver). job.resection
  // holds the shared options.
  ResectionJobOptions job;
  std::vector<SolverVariant> solvers;
  // Optional frames table with a reference orientation (same --rotation convention).
  std::string reference_path;
  int num_threads = 1;  // images in parallel (0: all cores)
  // Called after each solver with (solvers done, solvers in all); may be empty. Returning false
  // cancels the run: no solver starts after it, and RunDatasetComparison returns an error that
  // says so (no result).
  std::function<bool(size_t, size_t)> progress;

  bool IsValid(std::string* why) const;
};

struct DatasetSolve {
  std::string raster;
  int solver = 0;
  bool success = false;
  std::string message;
  ExteriorOrientation eo;
  // The angles as every output shows them: the result's convention, AngleDirection applied (deg).
  Eigen::Vector3d angles_deg = Eigen::Vector3d::Zero();
  Vector6d standard_deviations = Vector6d::Zero();  // m, rad
  double sigma0 = 0.0;
  int num_observations = 0;
  int num_inliers = 0;
  double rms_px = 0.0;  // inlier control residuals (pixels)
  double max_px = 0.0;  // largest inlier residual (pixels)
  // Check points (pixels): RMS of the residual norms within the inlier threshold, how many, and how
  // many lie beyond it (blunders of the check marks, or a wrong pose).
  double check_rmse_px = 0.0;
  int num_check = 0;
  int num_check_beyond = 0;
  int iterations = 0;
  double seconds = 0.0;             // ResectImage wall time (s), RANSAC included when it ran
  double refinement_seconds = 0.0;  // its refinement part (s)
  // To the reference solver (reference_solver of the result), when both solved this image (not
  // for the reference itself): |dX0| (m), rotation angle between the two (arc-seconds).
  bool has_difference = false;
  double difference_position_m = 0.0;
  double difference_rotation_arcsec = 0.0;
  // To the reference orientation, when one is given for this image.
  bool has_reference = false;
  double reference_position_m = 0.0;
  double reference_rotation_arcsec = 0.0;
};

struct DatasetSolverSummary {
  std::string solver;
  int images = 0;
  int solved = 0;
  double rms_sigma0 = 0.0;     // RMS of sigma0 over solved images
  double rms_px = 0.0;         // RMS of the inlier residuals over all solved images (pixels)
  double check_rmse_px = 0.0;  // over the check marks within the inlier threshold (pixels)
  int check_beyond = 0;        // check marks beyond it
  double median_seconds = 0.0;
  double median_refinement_seconds = 0.0;
  double mean_iterations = 0.0;
  // RMS over images of the differences to the reference solver (m, arcsec); compared images.
  int compared = 0;
  double difference_position_m = 0.0;
  double difference_rotation_arcsec = 0.0;
  // RMS over images of the differences to the reference (m, arcsec).
  int referenced = 0;
  double reference_position_m = 0.0;
  double reference_rotation_arcsec = 0.0;
};

struct DatasetComparisonResult {
  std::vector<std::string> solver_names;
  // The base of the differences and time ratios: "taylor" when compared, otherwise the first.
  std::string reference_solver;
  bool has_reference = false;
  std::vector<DatasetSolve> solves;  // image-major: for each image, every solver in order
  std::vector<DatasetSolverSummary> summaries;
  RotationConvention rotation = RotationConvention::kSeed;  // of the printed angles
};

// Reads the tables and runs every solver on every image. Errors: unreadable or inconsistent input.
Status RunDatasetComparison(const DatasetComparisonOptions& options,
                            DatasetComparisonResult* result);

// Index of the solver the differences and time ratios refer to: "taylor" when present, otherwise
// the first.
size_t ReferenceSolverIndex(const std::vector<std::string>& names);

}  // namespace photopose::cli
