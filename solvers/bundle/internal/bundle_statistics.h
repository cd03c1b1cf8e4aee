#pragma once
// The statistics of a converged round of solvers/bundle/bundle_adjustment.h (residuals per group,
// covariances from the reduced normal matrix, redundancy numbers, reliability, self-calibration),
// and the control- and check-point table both solvers share. Not part of the library's interface.

#include <Eigen/Core>
#include <functional>
#include <map>
#include <vector>

#include "core/block.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/bundle/internal/bundle_problem.h"
#include "solvers/bundle/triangulation.h"

namespace photopose::internal {

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
// null, for each row i the vector C_rows J_i^T (the part of the points eliminated folded in): the
// response of the parameters in the rows of C_rows (rows of C, global e columns) to a unit
// whitened error in that row.
Eigen::VectorXd Leverages(const ReducedNormals& reduced, const BlockRows& rows,
                          const Eigen::MatrixXd* C_rows, std::vector<Eigen::VectorXd>* shift);

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

// The images' and cameras' own uncertainty carried into the covariance of a check point: given
// its rays, the marks they come from (indices into Block::marks) and its intersection, the
// unscaled covariance (m^2) that replaces the intersection's a-priori one.
using CheckPointCovariance = std::function<Eigen::Matrix3d(
    const std::vector<RayObservation>& rays, const std::vector<int>& marks,
    const TriangulationResult& intersection)>;

// The control- and check-point table of an adjusted block (the one rule of both solvers; see
// solvers/bundle/check_points.h). The adjusted values: eo[i] the seed exterior orientation of
// image i (null: not oriented, its marks are left out), cameras the adjusted cameras of the block.
// Check points are intersected from their marks (sigmas: the control marks' rule of
// core/mark_weight.h) with covariance = variance_factor times `covariance` of the intersection
// when given, else its a-priori covariance. Control points count with the error_m already set
// unless data snooping removed their coordinates (result->snooping). Sets the counts and RMSEs.
// result->points must have one entry per point of the block.
void TabulateControlAndCheckPoints(const Block& block, const std::vector<const Vector6d*>& eo,
                                   const std::vector<BlockCamera>& cameras,
                                   const BundleAccuracies& accuracies, double variance_factor,
                                   const CheckPointCovariance& covariance,
                                   BundleAdjustmentResult* result);

}  // namespace photopose::internal
