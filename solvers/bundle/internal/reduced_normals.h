#pragma once
// The reduced normal matrix of a converged bundle round, for its statistics
// (internal/bundle_statistics.h): every residual block's tangent-space rows evaluated on several
// threads at once, the points eliminated 3 x 3 at a time, the reduced camera system S assembled
// and inverted on its sparse factor's pattern (internal/selected_inversion.h), and what each
// point's rows need of that inverse (its support covariance, the leverages of its rows). Not part
// of the library's interface.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "solvers/bundle/internal/bundle_problem.h"
#include "solvers/bundle/internal/selected_inversion.h"

namespace photopose::internal {

// One variable parameter block of a round as the statistics see it: its place (an e block of the
// reduced system, or a point, eliminated) and its manifold's Jacobian at the solution.
struct VariableBlock {
  int e_block = -1;  // index into the round's e blocks, or -1
  int point = -1;    // index into the point data, or -1
  int ambient = 0;   // size of the parameter block
  int tangent = 0;   // size of its tangent space
  // The manifold's PlusJacobian at the solution (ambient x tangent, row-major); empty: the
  // identity (no manifold).
  std::vector<double> plus_jacobian;
};

// The reduced normal matrix S (e blocks; points eliminated 3 x 3 at a time) of the whitened
// problem, the entries of its inverse C the statistics need (internal/selected_inversion.h) and
// what they need of the point blocks. Memory: the point data grow with the marks, C with the
// nonzeros of S's sparse factor; nothing is n^2 (unless `dense`, the test oracle).
struct ReducedNormals {
  int size = 0;                                          // number of e columns
  std::vector<int> e_offset;                             // per e block, its first column
  std::unordered_map<const double*, int> e_index;        // e block -> index
  std::unordered_map<const double*, int> point_index;    // point block -> index into the point data
  std::unordered_map<const double*, VariableBlock> variables;  // every variable block of the round
  // The round's residual blocks grouped by point: those of point data index p are
  // residual_order[point_residual_start[p] .. point_residual_start[p + 1]) (round order), then
  // every residual block without a point (a prior on e blocks alone), in round order.
  std::vector<int> point_residual_start;
  std::vector<int> residual_order;
  // The point data indices in the order of their first e block (points taken one after another
  // then share images: their blocks of S and C stay in the cache).
  std::vector<int> point_order;
  std::vector<Eigen::Matrix3d> V_inverse;       // per point block
  std::vector<std::vector<int>> W_blocks;       // per point block: e blocks it touches, ascending
  // A point's W (J_e^T J_p on its W_blocks) is not kept (144 bytes a mark, 247 MB at 1000
  // images): PointW makes it again from the point's rows where it is needed.
  SelectedInverse C;                            // S^-1 (unscaled) on the filled pattern
  int64_t S_nonzeros = 0;                       // stored entries of S (both triangles)
  bool ok = false;
  std::string message;                          // why not ok
  // Why not ok, when it is a rank defect: S singular (singular_block: the e block of the column
  // where the factorisation found it, singular_component: that column's place in the block's
  // tangent space; -1 when not known) or a point whose rays do not determine it
  // (undetermined_point: index into the point data).
  bool singular = false;
  int singular_block = -1;
  int singular_component = -1;
  int undetermined_point = -1;
};
// With options.dense, C is S inverted densely (the oracle of the tests); with options.factor_only
// S is only factorised (ok: every parameter determined; C holds no entry: not for the statistics).
// The points' rows are evaluated and eliminated on num_threads threads (0: every core), in chunks
// of a fixed size summed in a fixed order: S does not depend on the thread count.
void BuildReducedNormals(const BundleRound& round, const SelectedInversionOptions& options,
                         int num_threads, ReducedNormals* reduced);

// The tangent-space Jacobian rows of one residual block: e columns (global) and point columns.
struct BlockRows {
  int rows = 0;
  std::vector<double> residuals;                 // whitened
  std::vector<int> e_blocks;                     // e blocks, their columns in this order in J_e
  std::vector<int> e_columns;
  Eigen::MatrixXd J_e;                           // rows x e_columns
  Eigen::Matrix<double, Eigen::Dynamic, 3> J_p;  // rows x 3, when `point` >= 0
  int point = -1;                                // index into the reduced point data, or -1
  // Scratch of the evaluation, kept to spare allocations when one BlockRows is reused.
  std::unique_ptr<ceres::CostFunction> made;  // the cost made in a round of rows alone
  std::vector<double*> parameters;
  std::vector<double*> jacobians;
  std::vector<double> ambient;
};
// The rows of residual block `info` at the round's solution, without loss function. Calls the
// cost function itself (ResidualBlockOf; Ceres' Problem::EvaluateResidualBlock resets the state of
// every parameter block it touches, so two threads must not call it), with the manifolds'
// Jacobians of reduced.variables: safe on several threads at once, each with its own `rows`.
// False when the cost function fails.
bool EvaluateBlockRows(const BundleRound& round, const ReducedNormals& reduced,
                       const ResidualInfo& info, BlockRows* rows);

// Point p's W = J_e^T J_p (the columns of its W_blocks, in that order, x 3), made again from its
// rows by the arithmetic of BuildReducedNormals' elimination (the same products summed in the
// same order: the same bits). rows[k]: the rows of residual block
// reduced.residual_order[reduced.point_residual_start[p] + k] (EvaluateBlockRows).
void PointW(const BundleRound& round, const ReducedNormals& reduced, int p, const BlockRows* rows,
            Eigen::MatrixXd* W);
// The same with the point's rows evaluated here (`scratch`: the rows, kept to spare
// allocations). False when a residual block cannot be evaluated.
bool EvaluatePointW(const BundleRound& round, const ReducedNormals& reduced, int p,
                    std::vector<BlockRows>* scratch, Eigen::MatrixXd* W);
// target -= stacked where stacked's rows follow point p's W_blocks (rows of a product W X) and
// target's are the reduced system's (e_offset): how a point's eliminated share reaches the e rows.
inline void SubtractAtPointBlocks(const ReducedNormals& reduced, int p,
                                  const Eigen::Ref<const Eigen::MatrixXd>& stacked,
                                  Eigen::Ref<Eigen::MatrixXd> target) {
  int at = 0;
  for (const int b : reduced.W_blocks[p]) {
    const int size = reduced.C.block_size(b);
    target.middleRows(reduced.e_offset[b], size) -= stacked.middleRows(at, size);
    at += size;
  }
}
// Every point's W (EvaluatePointW), made on num_threads threads (0: every core) a wave of chunks
// at a time and handed to `use` one point after another in point index order, on the calling
// thread (a sum over the points in `use` is the same on any number of threads). False when a
// residual block cannot be evaluated (`use` then sees only some points).
bool ForEachPointW(const BundleRound& round, const ReducedNormals& reduced, int num_threads,
                   const std::function<void(int p, const Eigen::MatrixXd& W)>& use);

// What the rows of one point (or of a prior on e blocks alone) need of C: its submatrix on the e
// blocks they touch (a point's: every pair of its images, which share it, so on the pattern of
// S) and its products with the point's elimination W V^-1.
struct SupportCovariance {
  std::vector<int> blocks;        // e blocks, ascending
  std::vector<int> block_offset;  // their first row in `C`
  Eigen::MatrixXd C;              // k x k
  Eigen::MatrixXd WV;             // k x 3: W V^-1 (a point; else k x 0)
  Eigen::MatrixXd T;              // C WV
  Eigen::Matrix3d Q = Eigen::Matrix3d::Zero();  // WV^T C WV
  int Offset(int e_block) const;  // row of an e block in `C`, or -1
};
// For point block p (blocks: its W_blocks; W: its PointW) or, with p = -1 (W null), the given e
// blocks. False when C is not known on them.
bool MakeSupportCovariance(const ReducedNormals& reduced, int p, const Eigen::MatrixXd* W,
                           const std::vector<int>& blocks, SupportCovariance* support);

// Unscaled covariance of point block p: V^-1 + V^-1 W^T C W V^-1 (support: MakeSupportCovariance
// of p).
Eigen::Matrix3d PointCovariance(const ReducedNormals& reduced, const SupportCovariance& support,
                                int p);
// The diagonal of the hat matrix J C J^T of a block's rows (unscaled C; support: of its point, or
// of its own e blocks), and, when `centres` is not null, per row the largest shift of the centre
// of an image in the support per unit whitened error in that row (the external reliability's
// factor; centres[b] the number of centre components leading e block b's tangent space, 0 for a
// block that is not an image).
Eigen::VectorXd Leverages(const ReducedNormals& reduced, const SupportCovariance& support,
                          const BlockRows& rows, const std::vector<int>* centres,
                          Eigen::VectorXd* largest_shift);

}  // namespace photopose::internal
