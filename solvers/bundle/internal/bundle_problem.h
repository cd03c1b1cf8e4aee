#pragma once
// The inside of solvers/bundle/bundle_adjustment.h, shared by its three files: the plan of an
// adjustment (which observations, weights and datum), the Ceres problem of one round, and the
// reduced normal matrix behind its statistics. Not part of the library's interface.

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/block.h"
#include "solvers/bundle/bundle_adjustment.h"

namespace photopose::internal {

// An image needs at least this many marks for its six unknowns.
constexpr int kMinMarksPerImage = 3;

// One residual block of the problem: which group, which item (mark, point or image), how many of
// its rows are observations (the zero row of a control point's Z prior is not) and the axis of its
// first row (priors: 0 for X / omega, 2 for Z).
// One residual block of the round (24 bytes: a 1000-image block has 1.7 million of them). Its
// parameter blocks come from Ceres when needed (Problem::GetParameterBlocksForResidualBlock).
struct ResidualInfo {
  BundleGroup group;
  int item;
  int rows;
  int first_axis;
  ceres::ResidualBlockId id;
};

// The values being adjusted, copied from the block so that a failure leaves it untouched.
struct BundleState {
  std::vector<Vector6d> eo;
  std::vector<Eigen::Vector3d> points;
  std::vector<std::vector<double>> cameras;
  Eigen::Vector3d lever = Eigen::Vector3d::Zero();
};

// Everything decided before a round: observations in use, their sigmas, the datum.
struct BundlePlan {
  std::vector<char> mark_used;                 // per mark: in the adjustment
  std::vector<double> mark_sigma;              // per mark: sigma in the observation unit
  std::vector<BundleGroup> mark_group;         // per mark: tie or control marks
  std::vector<char> point_in_problem;          // per point
  std::vector<char> point_prior;               // per point: control-point prior active
  std::vector<Eigen::Vector3d> point_sigma;    // per point: prior sigma (m)
  std::vector<char> image_prior;               // per image: camera-position prior active
  std::vector<Eigen::Vector3d> image_prior_sigma;     // (m)
  std::vector<char> image_attitude;            // per image: attitude prior active
  std::vector<Eigen::Vector3d> image_attitude_sigma;  // (rad)
  std::vector<std::vector<int>> calibrated;    // per camera: parameter indices estimated
  BundleDatum datum = BundleDatum::kControl;
  std::string datum_description;
  // Tie points seen twice or more but without initial coordinates (the initialisation could not
  // intersect them): left out of the adjustment with their marks.
  std::vector<int> tie_points_left_out;
  int relative_fixed_image = -1;  // kRelative: the image held fixed
  int relative_scale_image = -1;  // and the image whose one coordinate fixes the scale
  int relative_scale_axis = -1;
  bool use_lever = false;
};

// The plan of a block: marks, priors, calibration, connectivity and datum. Errors name what makes
// the block unusable.
Status MakeBundlePlan(const BundleAdjustmentOptions& options, const BundleAdjustmentConfig& config,
                      const Block& block, BundlePlan* plan);
// After observations were removed: tie points left with one ray leave, every image keeps three
// marks, and the datum still holds (plan->datum unchanged). An error says which fails.
Status RecheckBundlePlan(const BundleAdjustmentConfig& config, const Block& block,
                         BundlePlan* plan);

// One round's Ceres problem and what it needs to stay alive.
struct BundleRound {
  // Declared before the problem, which refers to them, so that they outlive it.
  std::vector<std::unique_ptr<ceres::Manifold>> manifolds;
  std::unique_ptr<ceres::LossFunction> tie_loss;
  std::unique_ptr<ceres::Problem> problem;
  std::vector<ResidualInfo> residuals;
  // The variable blocks: exterior orientations, camera parameters, lever arm ("e" blocks, the
  // reduced system) with their tangent sizes, then the points (eliminated).
  std::vector<double*> e_blocks;
  std::vector<int> e_sizes;
  std::vector<double*> point_blocks;
  std::vector<int> point_of_block;  // point index of each point block
  int num_free_parameters = 0;
  int num_observations = 0;
  int redundancy() const { return num_observations - num_free_parameters; }
};

void BuildBundleRound(const BundleAdjustmentOptions& options, const BundleAdjustmentConfig& config,
                      const Block& block, const BundlePlan& plan, BundleState* state,
                      BundleRound* round);
// Turns a round built without a gauge (plan.relative_fixed_image = -1) into one in the relative
// gauge of `plan` (kRelative): holds the first image and one coordinate of the second, without
// building the problem again.
void ApplyRelativeGauge(const BundlePlan& plan, BundleState* state, BundleRound* round);
ceres::Solver::Options BundleSolverOptions(const BundleAdjustmentOptions& options,
                                           const BundleRound& round);

// The reduced normal matrix S (e blocks; points eliminated 3 x 3 at a time) of the whitened
// problem, its inverse C and what the statistics need of the point blocks.
struct ReducedNormals {
  int size = 0;                                 // number of e columns
  std::vector<int> e_offset;                    // per e block
  std::map<const double*, int> e_index;         // e block -> index
  std::map<const double*, int> point_index;     // point block -> index into the point data
  std::vector<Eigen::Matrix3d> V_inverse;       // per point block
  std::vector<std::vector<int>> W_columns;      // per point block: e columns it touches
  std::vector<Eigen::MatrixXd> W;               // per point block: (columns x 3) of J_e^T J_p
  Eigen::MatrixXd C;                            // S^-1 (unscaled)
  bool ok = false;
};
void BuildReducedNormals(const BundleRound& round, ReducedNormals* reduced);

// The tangent-space Jacobian rows of one residual block: e columns (global) and point columns.
struct BlockRows {
  int rows = 0;
  std::vector<double> residuals;                 // whitened
  std::vector<int> e_columns;
  Eigen::MatrixXd J_e;                           // rows x e_columns
  Eigen::Matrix<double, Eigen::Dynamic, 3> J_p;  // rows x 3, when `point` >= 0
  int point = -1;                                // index into the reduced point data, or -1
};
bool EvaluateBlockRows(const BundleRound& round, const ReducedNormals& reduced,
                       const ResidualInfo& info, BlockRows* rows);

// Unscaled covariance of point block p: V^-1 + V^-1 W^T C W V^-1.
Eigen::Matrix3d PointCovariance(const ReducedNormals& reduced, int p);
// The diagonal of the hat matrix J C J^T of a block's rows (unscaled C), and, when `shift` is not
// null, for each row i the vector C J_i^T (global e columns; the part of the points eliminated
// folded in) that gives the parameters' response to a unit whitened error in that row.
Eigen::VectorXd Leverages(const ReducedNormals& reduced, const BlockRows& rows,
                          std::vector<Eigen::VectorXd>* shift);

// Per group, what variance component estimation needs: the whitened sum of squares and the
// redundancy (sum of redundancy numbers; NaN when not computed).
struct GroupVariance {
  double whitened_ssq[kNumBundleGroups] = {};
  double redundancy[kNumBundleGroups] = {};
  int scalar_rows[kNumBundleGroups] = {};
};

// Everything the result reports about a converged round: residuals, groups, covariances,
// calibration, per-observation diagnostics (with the whitened normalized residual of each of the
// round's observations in `normalized`, aligned with `round.residuals` rows), check points.
void ComputeBundleStatistics(const BundleAdjustmentOptions& options, const Block& block,
                             const BundlePlan& plan, const BundleState& state,
                             const BundleRound& round, BundleAdjustmentResult* result,
                             GroupVariance* variance);

// The standard normal quantile: Phi^-1(p), p in (0, 1), by bisection on erfc to 1e-12.
double NormalQuantile(double p);

}  // namespace photopose::internal
