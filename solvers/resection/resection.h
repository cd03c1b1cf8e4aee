#pragma once
// Space resection of one or many images: the robust path of photopose, built for the surveyor's
// four to ten control points per image as much as for hundreds.
//
//   1. Initial values: the approximate pose when given (every mark a candidate; when the image
//      is not solved from it, or solved with marks left out, the consensus start is tried too and
//      taken when it solves the image with more marks: an approximate pose 500 m or 90 degrees
//      off does not converge, or converges elsewhere); otherwise a
//      consensus over minimal samples (LO-RANSAC over P3P and the DLT, solvers/resection/absolute_pose.h),
//      which tries every sample when there are few (C(n, 3) <= max_exhaustive_samples), so the
//      result does not depend on the seed. Its threshold comes from the marks' stated accuracy:
//      sqrt of the chi-square(2) quantile at the test confidence (3.72 sigma at 0.999). With no
//      accuracy stated the consensus is by least median of squares, which needs no threshold.
//      With stated accuracy and six or more marks the enumeration stops at the first model that
//      every mark fits (consensus.ransac.stop_enumeration_when_all_inliers, on by default) when
//      the least squares of all marks then passes the global test and the snooping: the marks
//      the full enumeration leads to are then all of them too (its best model fits all, or the
//      all-marks check below takes all back), so only the start of that least squares differs.
//      When the check fails the enumeration runs in full.
//   2. Decisions, repeated until nothing changes: least squares over the candidates
//      (solvers/resection/pose_refinement.h); every mark left out that fits within the threshold at that
//      solution is taken back (so when all marks fit the least-squares solution of all, all are
//      kept); then, with five or more candidates, the test statistics of the marks with their
//      redundancy numbers (solvers/resection/data_snooping.h: Baarda's data snooping with the stated
//      accuracy, Pope's tau test with sigma0 from the data when none is stated) reject the worst
//      mark if the test rejects it, one at a time, each followed by a new adjustment.
//   3. Verdict, in this order; each refusal says why with its numbers:
//      - three marks left (no redundancy) is not a solution (unless allow_no_redundancy, and never
//        when P3P leaves several poses); every marked control point, kept or not, must lie in
//        front of the camera at the solution;
//      - with stated accuracy, the accepted marks must pass the global test (Omega against
//        chi-square(r) at the test confidence): marks that disagree with their accuracy are not a
//        solution, whatever their number (sigma0 says by how much);
//      - ambiguity (stated accuracy): a competing consensus set, at least as large as the
//        accepted one and with a mark outside it, that passes the same tests and gives a pose more
//        than ambiguous_pose_sigmas of the accepted pose's standard deviations away, makes the
//        image ambiguous: not solved, both poses and their marks in the result. The competitors
//        come from P3P on every triple with a mark outside the accepted set (a random
//        consensus.ransac.max_exhaustive_samples of them when there are more);
//      - reliability: per accepted mark its minimal detectable blunder (MDB, the mark's unit) and
//        the largest pose shift such a blunder causes unseen (data_snooping.h); a pose that the
//        MDB of some mark moves by more than weak_pose_shift_sigmas is weak: reported with a
//        warning, or refused under refuse_weak.
//   4. Statistics: per mark its residual (in its own unit), normalized residual, redundancy number,
//      MDB and status; sigma0 (for every image that reached an adjustment, solved or not) and the
//      covariance f N^-1 over the accepted marks, f by PoseCovarianceFactor (data_snooping.h): 1
//      with stated accuracy (the a-priori covariance; the global test has passed), sigma0^2
//      without, with a warning when sigma0 rests on fewer than kMinSigmaDegreesOfFreedom.
// Without stated accuracy (sigma = 0: the block initialization's initial values only; photopose
// resect always states one) sigma0 comes from the data, with Pope's tau test, and there is no
// global test and no ambiguity search: a blunder then inflates sigma0 and may hide itself.
// The final estimate is least squares over the accepted marks by default; a robust loss is an
// option of the refinement. Data-dependent failures return success = false with a reason (numbers
// included), never a pose.
//
// Units: every mark keeps its own unit (pixels for Column/Row, um for film marks); its standard
// deviation and residuals are in that unit, and observation_units_per_unit takes it to the unit of
// the image plane (the camera model's observation unit: um for film cameras).

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/block.h"
#include "core/enum_names.h"
#include "core/status.h"
#include "core/termination.h"
#include "core/types.h"
#include "cost_functions/collinearity_cost.h"
#include "solvers/resection/absolute_pose.h"
#include "solvers/resection/data_snooping.h"
#include "solvers/resection/pose_refinement.h"
#include "solvers/resection/ransac.h"

namespace photopose {

// Composed as PoseLib composes its options: every knob of every stage is reachable.
struct ResectionOptions {
  // The consensus when no approximate pose is given: RANSAC (seed, trials, exhaustive limit, local
  // optimisation, stopping the enumeration at a model every mark fits: on here, honoured with
  // stated accuracy and six or more marks, step 1 above) and its Gauss-Newton iterations. Its
  // inlier_threshold and score are set per image from the tests below and the marks' accuracy.
  AbsolutePoseRansacOptions consensus = [] {
    AbsolutePoseRansacOptions defaults;
    defaults.ransac.stop_enumeration_when_all_inliers = true;
    return defaults;
  }();
  // The confidence of the consensus threshold and of every test.
  OutlierTestOptions test;
  // The least-squares refinement: solver, Jacobian, loss (none by default), Ceres and Taylor
  // options.
  PoseRefinementOptions refinement;
  // Report a pose whose accepted marks leave no redundancy (three points), without covariance.
  // Off: nothing checks such a pose, and P3P may fit three points with up to four poses.
  bool allow_no_redundancy = false;
  // A competing pose farther than this many of the accepted pose's standard deviations (largest
  // over the six parameters) makes the image ambiguous. Below it the two are one pose in the
  // noise.
  double ambiguous_pose_sigmas = 3.0;
  // Power of the tests for the minimal detectable blunder (Baarda's beta0 = 0.8).
  double detection_power = 0.8;
  // A pose that an undetected blunder of MDB size could move by more than this many of its
  // standard deviations (one parameter) is weak.
  double weak_pose_shift_sigmas = 3.0;
  // Refuse weak poses (photopose resect --strict) instead of reporting them with a warning.
  bool refuse_weak = false;
  // When an approximate pose is given and the image is not solved from it with every mark, try
  // the consensus start too and keep it when it solves the image with more marks (step 1;
  // ResectionSummary::consensus_after_approximate). Off: the approximate pose's result as it is.
  bool consensus_after_approximate = true;

  bool IsValid(std::string* why) const;
};

struct ResectionSummary {
  SolverTermination termination = SolverTermination::kFailure;
  std::string message;            // why it failed (with its numbers), empty on success
  bool used_approximate = false;  // initial pose from the caller, not the consensus
  // The caller's approximate pose was tried first and the result is from the consensus start
  // (used_approximate false): from the approximate pose the image was not solved, or kept fewer
  // marks; approximate_message says what that start gave ("no convergence in ...", "kept 5 of
  // 8 marks").
  bool consensus_after_approximate = false;
  std::string approximate_message;
  int ransac_trials = 0;          // minimal samples tried
  bool ransac_exhaustive = false;  // the minimal samples were enumerated: every one of them, unless
                                   // ransac_stopped_early
  // The enumeration stopped at the first model every mark fits, and the least squares of all
  // marks passed the tests (step 1).
  bool ransac_stopped_early = false;
  int adjustments = 0;            // least-squares adjustments (each rejection or readmission adds one)
  int iterations = 0;             // refinement iterations over all adjustments
  double initial_cost = 0.0;      // 1/2 sum of squared whitened residuals, first adjustment start
  double final_cost = 0.0;        // the same at the solution
  double ransac_seconds = 0.0;
  double refinement_seconds = 0.0;
  double total_seconds = 0.0;
  std::string BriefReport() const;
  bool IsSolutionUsable() const { return termination == SolverTermination::kConverged; }
};

// One image: its marks as ideal image-plane points with their control points (MakeResectionInput
// builds it from a block).
struct ResectionInput {
  std::string raster;
  // Principal distance in the unit of image_plane (um for film cameras, pixels for the COLMAP
  // models).
  double focal_length = 0.0;
  // Per mark, parallel vectors: the ideal image-plane point (distortion removed, principal point at
  // the origin, x right and y up: the seed's x, y), its ground point (m).
  std::vector<Eigen::Vector2d> image_plane;
  std::vector<Eigen::Vector3d> points_in_ground;
  // Per mark: its standard deviation in its own unit (0: not stated), the image-plane units per
  // unit of the mark (um per pixel for a pixel mark of a film camera, 1 otherwise) and that unit.
  // Empty vectors mean: nothing stated, 1, pixels. When every mark states its accuracy the tests
  // use it; otherwise sigma0 is estimated from the data (unstated marks weighted as 1 unit).
  std::vector<double> sigma;
  std::vector<double> observation_units_per_unit;
  std::vector<MarkUnit> units;
  std::vector<std::string> point_ids;  // optional, names points in messages
  std::optional<ExteriorOrientation> approximate;
  // Earth-curvature correction (camera table ApplyECC): earth radius (m); 0 for none. Control
  // points are lowered by D^2 / (2 R) at horizontal distance D from the projection centre, as in
  // projection (core/collinearity.h), iterated with the centre.
  double earth_radius_m = 0.0;
};

// Why a mark is, or is not, in the final adjustment.
enum class MarkStatus {
  kAccepted,          // in the adjustment
  kConsensusOutlier,  // beyond the threshold of the consensus and of every adjustment
  kRejected,          // rejected by data snooping / the tau test
};
inline constexpr EnumNameEntry<MarkStatus> kMarkStatusNames[] = {
    {MarkStatus::kAccepted, "accepted"},
    {MarkStatus::kConsensusOutlier, "outlier"},
    {MarkStatus::kRejected, "rejected"}};
constexpr EnumNameTable<MarkStatus> EnumNames(MarkStatus) {
  return EnumNameTable<MarkStatus>(kMarkStatusNames);
}

struct ResectionResult {
  bool success = false;
  ExteriorOrientation eo;
  // covariance_factor N^-1 over the accepted marks (m, rad; seed angles). Not given
  // (has_covariance false) for a pose without redundancy.
  bool has_covariance = false;
  Matrix6d covariance = Matrix6d::Zero();
  Vector6d standard_deviations = Vector6d::Zero();
  // The covariance's factor over N^-1 (PoseCovarianceFactor, data_snooping.h; unitless with stated
  // accuracies, the marks' unit squared without): 1 with stated accuracies (the a-priori
  // covariance, sigma0 = 1), sigma0^2 when the accuracy comes from the data.
  double covariance_factor = 1.0;
  // The factor by which the true standard deviations may exceed standard_deviations at 95 %
  // (SigmaUpperFactor, data_snooping.h; unitless): 1 with stated accuracies, above 1 when they
  // rest on sigma0 from degrees_of_freedom (4.4 at 2, 2.4 at 4); infinite without covariance.
  double sigma_upper_factor = 1.0;
  // The marks' accuracy was stated (tests with known sigma) or estimated from the data.
  bool accuracy_stated = false;
  // A-posteriori sigma0 = sqrt(Omega / r): unitless with stated accuracies (1 = as stated), in the
  // marks' own unit when none was stated (then it estimates their accuracy). 0 without redundancy.
  // Set whenever an adjustment was reached, also for an image that is not solved.
  double sigma0 = 0.0;
  int degrees_of_freedom = 0;  // 2 accepted - 6
  int num_inliers = 0;         // accepted marks
  // Per mark (input order): observed minus computed on the ideal image plane (x right, y up) in the
  // mark's own unit; normalized residual, the square root of its test statistic in standard
  // deviations (known sigma) or in units of sigma0 (estimated), NaN where it cannot be tested;
  // redundancy number (0 for marks left out); minimal detectable blunder (the mark's unit; 0 for
  // marks left out, infinite for a mark the others do not check) and the largest shift of a pose
  // parameter it causes unseen (that parameter's standard deviations); status; accepted flag.
  std::vector<Eigen::Vector2d> residuals;
  std::vector<double> normalized_residuals;
  std::vector<double> redundancy_numbers;
  std::vector<double> minimal_detectable_blunders;
  std::vector<double> pose_shifts_sigmas;
  std::vector<MarkStatus> mark_status;
  std::vector<char> inliers;
  // The normalized residual beyond which the test rejects (NaN with four marks or fewer).
  double critical_normalized_residual = 0.0;
  // The largest of pose_shifts_sigmas and its mark (-1: none); weak when above
  // ResectionOptions::weak_pose_shift_sigmas or without redundancy.
  double max_pose_shift_sigmas = 0.0;
  int weakest_mark = -1;
  bool weak = false;
  // The accepted marks failed the global test with their stated accuracy (not solved; sigma0 and
  // degrees_of_freedom say by how much).
  bool accuracy_disagrees = false;
  // Not solved because another consensus set fits a materially different pose: eo and inliers
  // hold the first pose and its marks, these the competitor.
  bool ambiguous = false;
  ExteriorOrientation competing_eo;
  std::vector<char> competing_inliers;
  // Findings that do not stop the solution, one sentence each (stated accuracy too optimistic,
  // four marks that cannot be tested, sigmas on sigma0 from fewer than kMinSigmaDegreesOfFreedom,
  // no redundancy allowed).
  std::vector<std::string> warnings;
  // Not resected: a batch's progress hook cancelled the batch before this image started
  // (ResectImages with ResectionBatchOptions::progress). No pose and no statistics; success is
  // false, summary.termination is kCancelled (not a failure: nothing was tried) and
  // summary.message starts "cancelled".
  bool cancelled = false;
  ResectionSummary summary;
};

ResectionResult ResectImage(const ResectionOptions& options, const ResectionInput& input);

// ------------------------------------------------------------------ many images

// Where a batch is, as its progress hook receives it.
struct ResectionProgress {
  int images_done = 0;           // images whose result is final (count), increasing to images_total
  int images_total = 0;          // images of the batch (count)
  double elapsed_seconds = 0.0;  // since the batch started (s, wall clock)
};

// A batch's progress hook: called from the resecting threads, one call at a time, images_done
// increasing from call to call. Returns false to cancel the batch: the images not yet started are
// not resected (ResectionResult::cancelled), those under way finish. Must not throw.
using ResectionProgressHook = std::function<bool(const ResectionProgress&)>;

struct ResectionBatchOptions {
  // Threads (0: all cores, core/parallel.h) and the images handed to a free thread at a time
  // (count; 0 counts as 1).
  int num_threads = 0;
  size_t chunk_size = 1;
  // Empty: no hook, and the batch runs as without one (no lock, no clock, no shared counter).
  ResectionProgressHook progress;
  // Throttle: the hook is called when an image finishes and, since the hook's last call, either
  // progress_fraction of the batch has finished (fraction of images_total; 0: every image) or
  // progress_interval_seconds have passed (s; 0: every image); and once more with images_done ==
  // images_total unless cancelled. So at most 1 / progress_fraction + elapsed /
  // progress_interval_seconds + 1 calls. A thread that finds the hook busy goes on resecting.
  double progress_fraction = 0.01;
  double progress_interval_seconds = 0.1;

  bool IsValid(std::string* why) const;
};

struct ResectionBatchSummary {
  int images_total = 0;      // count
  int images_solved = 0;     // results with success (count)
  int images_cancelled = 0;  // results with cancelled (count)
  bool cancelled = false;    // the hook returned false
  int progress_calls = 0;    // calls of the hook (count)
  double total_seconds = 0.0;  // wall clock (s)
  // "10000 images: 9996 solved, 4 not solved, 0 cancelled; 101 progress calls; 0.45 s".
  std::string BriefReport() const;
};

// Many images, resected in parallel on batch.num_threads threads, handed to the threads
// batch.chunk_size images at a time as they become free (core/parallel.h); *results in input
// order, one per input. Image i gets its own reproducible RANSAC seed, so every result is the
// same, bit for bit, whatever the thread count, chunk size, schedule and hook. An error (invalid
// options: the batch's or the resection's) leaves *results and *summary untouched; a cancelled
// batch is not an error (summary->cancelled). summary may be null.
[[nodiscard]] Status ResectImages(const ResectionOptions& options,
                                  const std::vector<ResectionInput>& inputs,
                                  const ResectionBatchOptions& batch,
                                  std::vector<ResectionResult>* results,
                                  ResectionBatchSummary* summary = nullptr);

// The same without a hook, for valid options: num_threads threads (0 or less: all cores).
std::vector<ResectionResult> ResectImages(const ResectionOptions& options,
                                          const std::vector<ResectionInput>& inputs,
                                          int num_threads, size_t chunk_size = 1);

// ------------------------------------------------------------------ from a block

struct ResectionInputOptions {
  // Standard deviation of marks without an Accuracy (MarkSigma, core/mark_weight.h, with
  // film_from_pixel_size off): pixel marks take default_accuracy (px), film marks
  // default_film_accuracy_um (um). default_accuracy 0: nothing stated, the tests take sigma0 from
  // the data (the block initialization's initial values; not offered by photopose resect).
  double default_accuracy = 1.0;
  double default_film_accuracy_um = 5.0;
  // Also marks of tie points that have coordinates (position_m: intersected or approximate), as
  // if they were control points: the block initialization orients images from them.
  bool include_tie_points_with_positions = false;
};

// The control marks of block image `image` as a resection input: each mark's observation through
// its camera model (NormalizedFromObservation) times the model's focal length, its control point's
// surveyed coordinates, its accuracy (own unit), observation_units_per_unit and unit; the image's
// exterior orientation as approximate values; the camera table's ApplyECC. Check and tie marks are
// left out. *marks (may be null) receives the block index of each mark of the input.
Status MakeResectionInput(const Block& block, int image, const ResectionInputOptions& options,
                          ResectionInput* input, std::vector<int>* marks);

// Observed minus computed of one mark of a surveyed point at a pose, on the ideal image plane
// (x right, y up) in the mark's own unit, with the camera table's earth-curvature correction: the
// check-point residuals of reports.
Status MarkResidual(const Block& block, int mark, const ExteriorOrientation& eo,
                    Eigen::Vector2d* residual);

}  // namespace photopose
