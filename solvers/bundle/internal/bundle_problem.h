#pragma once
// The inside of solvers/bundle/bundle_adjustment.h and solvers/bundle/taylor_bundle.h: the plan of
// an adjustment (which observations, weights and datum; both solvers make it here) and the Ceres
// problem of one round. The statistics of a round are in internal/bundle_statistics.h. Not part of
// the library's interface.

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/block.h"
#include "core/mark_weight.h"
#include "cost_functions/collinearity_cost.h"
#include "solvers/bundle/bundle_adjustment.h"

namespace photopose::internal {

// An image needs at least this many marks for its six unknowns.
constexpr int kMinMarksPerImage = 3;

// The seven datum parameters are fixed when the smallest singular value of the (scaled) datum
// Jacobian (SimilarityRows of the fixing positions) is above this fraction of the largest: below
// it one similarity motion is all but free (control points 1 mm off a line 1 km long, say), and
// the adjustment would rest on noise.
constexpr double kDatumConditioning = 1e-3;

// How a small similarity of the ground frame moves a position p: dp / d(t, rotation, scale) =
// [I, -[d]x, d] with d = (p - centroid) / extent, i.e. dp = t + w x d + s d: translation (m),
// rotation (rad) and scale (unitless) about `centroid`, the last four columns per `extent` (m) so
// that the three kinds are comparable. The datum check's and the inner constraints' one rule.
Eigen::Matrix<double, 3, 7> SimilarityRows(const Eigen::Vector3d& p,
                                           const Eigen::Vector3d& centroid, double extent);

// The default sigmas of the marks of `group` (kTieMarks or kControlMarks; check marks weigh as
// control marks) under `accuracies`, for the rule of core/mark_weight.h.
MarkSigmaDefaults GroupMarkDefaults(const BundleAccuracies& accuracies, BundleGroup group);

// One residual block of the round: which group, which item (mark, point or image), how many of
// its rows are observations (the zero row of a control point's Z prior is not) and the axis of its
// first row (priors: 0 for X / omega, 2 for Z). 24 bytes: a 1000-image block has 1.7 million of
// them; their parameter blocks come from Ceres when needed
// (Problem::GetParameterBlocksForResidualBlock).
// One per residual block of a round (a mark's, or a prior's two or three rows): 16 bytes, 1.7
// million at a thousand images.
struct ResidualInfo {
  ceres::ResidualBlockId id = nullptr;  // in the round's problem; null in a round of rows alone
  int item = -1;                        // mark, point or image index, by group
  BundleGroup group = kTieMarks;
  std::int8_t rows = 0;        // its rows: 2 for a mark, 1..3 for a prior
  std::int8_t first_axis = 0;  // the axis of its first row (a control point's Z block: 2)
};
static_assert(sizeof(ResidualInfo) <= 16, "one per residual block: keep it small");
ResidualInfo MakeResidualInfo(BundleGroup group, int item, int rows, int first_axis);

// The values being adjusted, copied from the block so that a failure leaves it untouched.
struct BundleState {
  std::vector<Vector6d> eo;
  std::vector<Eigen::Vector3d> points;
  std::vector<std::vector<double>> cameras;
  Eigen::Vector3d lever = Eigen::Vector3d::Zero();
};

// What the plan takes from the options of either solver.
struct BundlePlanOptions {
  BundleAccuracies accuracies;
  bool use_lever = false;  // a lever arm enters the camera-position priors
  // A datum that fixes fewer than the 7 similarity parameters of the block: refused with the reason
  // (BundleAdjust), or accepted so that it shows as a singular normal matrix in the round (the
  // Taylor adjustment, which reports it as a failed round).
  bool refuse_weak_datum = true;
};

// Everything decided before a round: observations in use, their sigmas, the datum.
struct BundlePlan {
  std::vector<char> mark_used;                     // per mark: in the adjustment
  std::vector<double> mark_sigma;                  // per mark: sigma in the observation unit
  std::vector<BundleGroup> mark_group;             // per mark: tie or control marks
  std::vector<char> point_in_problem;              // per point
  std::vector<char> point_prior;                   // per point: control-point prior active
  std::vector<Eigen::Vector3d> point_sigma;        // per point: prior sigma (m)
  std::vector<char> image_prior;                   // per image: camera-position prior active
  std::vector<Eigen::Vector3d> image_prior_sigma;  // (m)
  // Per image with a prior: 1 when it constrains the height too; 0 for a position without height
  // (two rows, X and Y): its Z sigma is +infinity, so a solver weighting by 1 / sigma^2 gives
  // the Z row no weight, and the rows counted are two (ImagePriorRows).
  std::vector<char> image_prior_height;
  std::vector<char> image_attitude;                   // per image: attitude prior active
  std::vector<Eigen::Vector3d> image_attitude_sigma;  // (rad)
  std::vector<std::vector<int>> calibrated;           // per camera: parameter indices estimated
  BundleDatum datum = BundleDatum::kControl;
  std::string datum_description;
  // Tie points seen twice or more but without initial coordinates (the initialisation could not
  // intersect them): left out of the adjustment with their marks.
  std::vector<int> tie_points_left_out;
  int relative_fixed_image = -1;  // kRelative: the image held fixed
  int relative_scale_image = -1;  // and the image whose one coordinate fixes the scale
  int relative_scale_axis = -1;
  bool use_lever = false;
  bool refuse_weak_datum = true;  // from BundlePlanOptions
};

// The scalar observations of image `image`'s camera-position prior: 3, 2 without height, 0 none.
inline int ImagePriorRows(const BundlePlan& plan, size_t image) {
  return plan.image_prior[image] ? (plan.image_prior_height[image] ? 3 : 2) : 0;
}

// The full tangent component (0..5: centre X, Y, Z, then the small rotation about the seed's
// omega, phi, kappa axes; cost_functions/exterior_orientation_manifold.h) of tangent column
// `column` of image `image`'s e block: the relative gauge's scale image lacks its held coordinate.
int OrientationComponent(const BundlePlan& plan, int image, int column);

// The kinds of unknown an adjustment names in its messages.
enum class UnknownKind {
  kOrientation,  // of an image: component 0..5 = X, Y, Z, omega, phi, kappa
  kCalibration,  // of a camera: component = index into its model's parameters
  kLeverArm,     // component 0..2 = x, y, z in the camera frame
};

// An unknown in words, the one wording of both solvers' messages: "image 'IMG_12': omega",
// "camera 'c1': the self-calibrated K1", "the lever arm's z (camera frame)". `index` is the image
// or the camera (unused for the lever arm).
std::string UnknownName(const Block& block, UnknownKind kind, int index, int component);

// The rule for a robust round that stopped at its iteration limit (both solvers; the reason is at
// its definition in bundle_problem.cc): true when a round that ended with `termination` under the
// tie loss `tie_loss` has stalled and goes on from where it stopped as least squares, and so do
// the rounds after it.
bool TieLossStalled(SolverTermination termination, LossType tie_loss);
// The summary's message for it: "round 1: the huber tie loss stalled (no convergence in 100
// iterations: ...); adjusted by least squares from there, blunders left to the rejection".
std::string TieLossStalledMessage(int round, LossType tie_loss, int stalled_iterations);

// A relative block's gauge in words: "image 'A' held fixed and the X coordinate of image 'B'
// fixes the scale" (the datum description and the covariance datum).
std::string RelativeGaugeInWords(const Block& block, const BundlePlan& plan);

// The plan of a block: marks (weights by core/mark_weight.h), points, priors, calibration,
// connectivity and datum. Errors name what makes the block unusable. The one place that decides
// which observations an adjustment uses, for BundleAdjust and TaylorBundleAdjust alike.
Status MakeBundlePlan(const BundlePlanOptions& options, const BundleAdjustmentConfig& config,
                      const Block& block, BundlePlan* plan);
// BundleAdjust's options for the plan.
BundlePlanOptions PlanOptionsOf(const BundleAdjustmentOptions& options,
                                const BundleAdjustmentConfig& config);
// After observations were removed: tie points left with one ray leave, every image keeps three
// marks, and the datum still holds (plan->datum unchanged). An error says which fails.
Status RecheckBundlePlan(const BundleAdjustmentConfig& config, const Block& block,
                         BundlePlan* plan);

// The values an adjustment starts from: the block's orientations, points (tie points from their
// coordinates, control points from their survey) and cameras, and the config's lever arm. Also
// the values a solution is evaluated at once it is written into the block (the Taylor
// adjustment's statistics).
BundleState StartState(const BundleAdjustmentConfig& config, const Block& block);

// The Ceres problem of an adjustment's rounds and what it needs to stay alive. Built once; a
// rejection round switches the rejected marks off in place (UpdateBundleRound). Or a round of
// rows alone, without a problem (BuildBundleRoundRows): what the statistics read of a round (its
// residual blocks' costs and parameter blocks, ResidualBlockOf; its variable blocks), made when
// asked by the rule a problem is built by, for an adjustment that never solves it (the Taylor
// adjustment's statistics): no Ceres objects and no cost per mark held (about 190 bytes a mark
// less).
struct BundleRound {
  // Declared before the problem, which refers to them, so that they outlive it. The problem owns
  // none of them: Ceres keeps an ordered map of the cost functions it owns (48 bytes and a tree
  // insertion per mark).
  std::vector<std::unique_ptr<ceres::Manifold>> manifolds;
  std::unique_ptr<ceres::LossFunction> tie_loss;
  std::vector<CollinearityCamera> cameras;             // per camera: what its marks' costs share
  std::vector<CollinearityMarkFunctor*> mark_functor;  // per mark (block order): inside its cost
  std::vector<std::unique_ptr<ceres::CostFunction>> costs;
  std::unique_ptr<ceres::Problem> problem;  // null: a round of rows alone
  // What a round of rows alone makes its residual blocks from (ResidualBlockOf): the block, the
  // plan, the values the parameter blocks point into, the collinearity costs' derivative path.
  const Block* block = nullptr;
  const BundlePlan* plan = nullptr;
  BundleState* state = nullptr;
  JacobianType jacobian = JacobianType::kAnalytic;
  // The residual blocks in use (switched-off marks are not listed; id null in a round of rows
  // alone).
  std::vector<ResidualInfo> residuals;
  // The variable blocks: exterior orientations, camera parameters, lever arm ("e" blocks, the
  // reduced system) with their tangent sizes, ambient sizes and manifolds (null: none), then the
  // points (eliminated; 3 ambient and tangent, no manifold).
  std::vector<double*> e_blocks;
  std::vector<int> e_sizes;
  std::vector<int> e_ambient_sizes;
  std::vector<const ceres::Manifold*> e_manifolds;
  std::vector<double*> point_blocks;
  std::vector<int> point_of_block;  // point index of each point block
  int num_free_parameters = 0;
  int num_observations = 0;
  int redundancy() const { return num_observations - num_free_parameters; }
};

void BuildBundleRound(const BundleAdjustmentOptions& options, const BundleAdjustmentConfig& config,
                      const Block& block, const BundlePlan& plan, BundleState* state,
                      BundleRound* round);
// The same round without a Ceres problem: its rows alone, for statistics that never solve it.
// block, plan and *state must outlive it.
void BuildBundleRoundRows(const BundleAdjustmentOptions& options,
                          const BundleAdjustmentConfig& config, const Block& block,
                          const BundlePlan& plan, BundleState* state, BundleRound* round);
// The cost function of residual block `info` and its parameter blocks (ambient, in the cost's
// order): the problem's own, or in a round of rows alone made for the call (owned by *made) by
// the rule the problem is built by, so that both evaluate the same. Safe on several threads at
// once, each with its own *made and *parameters.
const ceres::CostFunction* ResidualBlockOf(const BundleRound& round, const ResidualInfo& info,
                                           std::unique_ptr<ceres::CostFunction>* made,
                                           std::vector<double*>* parameters);
// Its parameter blocks alone.
void ResidualParameters(const BundleRound& round, const ResidualInfo& info,
                        std::vector<double*>* parameters);
// Brings a built round up to `plan` after marks were rejected (plan.mark_used cleared; tie points
// left with too few rays out of plan.point_in_problem), without building the problem again: the
// marks get a zero weight (their residual blocks stay, with zero residuals and Jacobians, so that
// Ceres' structure is unchanged), a point that left is held constant, and neither is listed in
// the round any more. False when the plan changed otherwise (a prior removed): the round must be
// built again.
bool UpdateBundleRound(const BundlePlan& plan, BundleRound* round);
// Moves a relative block solved without any gauge into COLMAP's gauge (plan kRelative): the
// similarity X -> s R_s (X - C0) + C0_fixed that returns the first image to its fixed pose
// (fixed_eo, seed) and the scale image's fixed coordinate to its value. Reprojection errors are
// invariant under a similarity of the whole block, and a relative block has no priors, so the cost
// does not change. Any frame works for the positions (the Taylor solver's is centred) as long as
// fixed_eo and the state share it. Returns false, leaving the state as it was, when the free
// solution cannot be moved (the second image collapsed onto the first or passed to its other side:
// no positive scale). Both solvers' free-gauge solves end here.
bool MoveToRelativeGauge(const BundlePlan& plan, const Vector6d& fixed_eo, double fixed_coordinate,
                         std::vector<Vector6d>* eo_seed, std::vector<Eigen::Vector3d>* points);
// Turns a round built without a gauge (plan.relative_fixed_image = -1) into one in the relative
// gauge of `plan` (kRelative): holds the first image and one coordinate of the second, without
// building the problem again.
void ApplyRelativeGauge(const BundlePlan& plan, BundleState* state, BundleRound* round);
ceres::Solver::Options CeresSolverOptions(const BundleAdjustmentOptions& options,
                                          const BundleRound& round);

}  // namespace photopose::internal
