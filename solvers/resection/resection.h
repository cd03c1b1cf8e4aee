#pragma once
// Space resection of one or many images: the robust path of photopose, built for the surveyor's
// four to ten control points per image as much as for hundreds.
//
//   1. Initial values: the approximate pose when given (every mark a candidate); otherwise a
//      consensus over minimal samples (LO-RANSAC over P3P and the DLT, solvers/resection/absolute_pose.h),
//      which tries every sample when there are few (C(n, 3) <= max_exhaustive_samples), so the
//      result does not depend on the seed. Its threshold comes from the marks' stated accuracy:
//      sqrt of the chi-square(2) quantile at the test confidence (3.72 sigma at 0.999). With no
//      accuracy stated the consensus is by least median of squares, which needs no threshold.
//   2. Decisions, repeated until nothing changes: least squares over the candidates
//      (solvers/resection/pose_refinement.h); every mark left out that fits within the threshold at that
//      solution is taken back (so when all marks fit the least-squares solution of all, all are
//      kept); then, with five or more candidates, the test statistics of the marks with their
//      redundancy numbers (solvers/resection/data_snooping.h: Baarda's data snooping with the stated
//      accuracy, Pope's tau test with sigma0 from the data when none is stated) reject the worst
//      mark if the test rejects it, one at a time, each followed by a new adjustment.
//   3. Verdict: three marks left (no redundancy) is not a solution (unless allow_no_redundancy,
//      and never when P3P leaves several poses); four marks with stated accuracy must pass the
//      global test (a blunder among four can be detected but not localised); every marked control
//      point, kept or not, must lie in front of the camera at the solution.
//   4. Statistics: per mark its residual (in its own unit), normalized residual, redundancy number
//      and status; sigma0 and the covariance sigma0^2 N^-1 over the accepted marks.
// The final estimate is least squares over the accepted marks by default; a robust loss is an
// option of the refinement. Data-dependent failures return success = false with a reason (numbers
// included), never a pose.
//
// Units: every mark keeps its own unit (pixels for Column/Row, um for film marks); its standard
// deviation and residuals are in that unit, and observation_units_per_unit takes it to the unit of
// the image plane (the camera model's observation unit: um for film cameras).

#include <Eigen/Core>
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
  // optimisation) and its Gauss-Newton iterations. Its inlier_threshold and score are set per image
  // from the tests below and the marks' accuracy.
  AbsolutePoseRansacOptions consensus;
  // The confidence of the consensus threshold and of every test.
  OutlierTestOptions test;
  // The least-squares refinement: solver, Jacobian, loss (none by default), Ceres and Taylor
  // options.
  PoseRefinementOptions refinement;
  // Report a pose whose accepted marks leave no redundancy (three points), without covariance.
  // Off: nothing checks such a pose, and P3P may fit three points with up to four poses.
  bool allow_no_redundancy = false;

  bool IsValid(std::string* why) const;
};

struct ResectionSummary {
  SolverTermination termination = SolverTermination::kFailure;
  std::string message;            // why it failed (with its numbers), empty on success
  bool used_approximate = false;  // initial pose from the caller, not the consensus
  int ransac_trials = 0;          // minimal samples tried
  bool ransac_exhaustive = false;  // every minimal sample was tried
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
  // sigma0^2 N^-1 over the accepted marks (m, rad; seed angles). Not given (has_covariance false)
  // for a pose without redundancy.
  bool has_covariance = false;
  Matrix6d covariance = Matrix6d::Zero();
  Vector6d standard_deviations = Vector6d::Zero();
  // The marks' accuracy was stated (tests with known sigma) or estimated from the data.
  bool accuracy_stated = false;
  // A-posteriori sigma0 = sqrt(Omega / r): unitless with stated accuracies (1 = as stated), in the
  // marks' own unit when none was stated (then it estimates their accuracy). 0 without redundancy.
  double sigma0 = 0.0;
  int degrees_of_freedom = 0;  // 2 accepted - 6
  int num_inliers = 0;         // accepted marks
  // Per mark (input order): observed minus computed on the ideal image plane (x right, y up) in the
  // mark's own unit; normalized residual, the square root of its test statistic in standard
  // deviations (known sigma) or in units of sigma0 (estimated), NaN where it cannot be tested;
  // redundancy number (0 for marks left out); status; accepted flag.
  std::vector<Eigen::Vector2d> residuals;
  std::vector<double> normalized_residuals;
  std::vector<double> redundancy_numbers;
  std::vector<MarkStatus> mark_status;
  std::vector<char> inliers;
  // The normalized residual beyond which the test rejects (NaN with four marks or fewer).
  double critical_normalized_residual = 0.0;
  // Findings that do not stop the solution, one sentence each (stated accuracy too optimistic,
  // four marks that cannot be tested, no redundancy allowed).
  std::vector<std::string> warnings;
  ResectionSummary summary;
};

ResectionResult ResectImage(const ResectionOptions& options, const ResectionInput& input);

// Many images, resected in parallel on num_threads threads (0: all cores); results in input order.
// Image i gets its own reproducible RANSAC seed, whatever the thread schedule.
std::vector<ResectionResult> ResectImages(const ResectionOptions& options,
                                          const std::vector<ResectionInput>& inputs,
                                          int num_threads);

// ------------------------------------------------------------------ from a block

struct ResectionInputOptions {
  // Standard deviation of marks without an Accuracy, in their own unit (pixels for pixel marks, um
  // for film marks); 0: not stated, so the tests estimate it from the data.
  double default_accuracy = 0.0;
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
