#pragma once
// Selected inversion of a sparse symmetric positive definite matrix S (the reduced camera system
// of a bundle adjustment): the entries of C = S^-1 on the filled pattern of S's Cholesky factor,
// never the dense inverse. Every entry of C that lies on the pattern of S itself (the blocks of
// two parameter blocks that share an observation or a point) lies on that filled pattern, which is
// all the statistics of a block need (solvers/bundle/internal/bundle_statistics.h).
//
// Method: S is Jacobi-scaled (A = D S D, D = diag(S)^-1/2), ordered by approximate minimum degree
// on its block graph (every parameter block's columns stay contiguous), factorised by CHOLMOD
// (SuiteSparse, through internal/cholmod_factor.h) as A = P^T L L^T P, and Z = A^-1 computed on
// the pattern of L by the Takahashi recursion (Takahashi, Fagan, Chin 1973; Erisman and Tinney
// 1975), backwards over the columns:
//   Z_ij = -(1/L_jj) sum_{k>j, L_kj != 0} Z_ik L_kj                (i > j, L_ij != 0)
//   Z_jj = (1/L_jj) (1/L_jj - sum_{k>j, L_kj != 0} L_kj Z_kj).
// Cost about that of the factorisation; memory one double per nonzero of L beside L itself.
// C = D P^T Z P D. Not part of the library's interface.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/status.h"

namespace photopose::internal {

struct SelectedInversionOptions {
  // The test oracle (and nothing else): S inverted densely with Eigen's LDL^T, every entry kept.
  bool dense = false;
  // S is singular (a datum defect in all but name) when a pivot of the LDL^T of its Jacobi-scaled
  // form is at most this fraction of the largest (unitless). Above the rounding of the Schur
  // complement: an exactly singular S (tests/support/singular_block.h) gives pivots of either
  // sign up to 7e-11 of the largest. A parameter at this ratio has a sigma 3e4 times the one it
  // would have with the parameters factorised before it held.
  double min_pivot_ratio = 1e-9;
  // Factorise only (S checked positive definite, singular_column() found), compute no entry of
  // the inverse: Block and Blocks then return false. What a bundle without statistics needs to
  // know that every parameter is determined, at the cost of one factorisation.
  bool factor_only = false;
};

class SelectedInverse {
 public:
  using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

  SelectedInverse();
  ~SelectedInverse();
  SelectedInverse(SelectedInverse&&) noexcept;
  SelectedInverse& operator=(SelectedInverse&&) noexcept;

  // S symmetric positive definite, given by its upper triangle (entries below the diagonal are
  // ignored). block_start partitions its columns into parameter blocks: block b is columns
  // block_start[b] .. block_start[b + 1] - 1 (block_start.back() = S.cols()). An error when S is
  // singular to min_pivot_ratio, not finite, or CHOLMOD fails; singular() then says whether S
  // was found singular and singular_column() where.
  [[nodiscard]] Status Compute(const SparseMatrix& S_upper, const std::vector<int>& block_start,
                               const SelectedInversionOptions& options);

  // C restricted to the rows of block a and the columns of block b (unscaled, S's units) into
  // *out (resized). False, *out untouched, when that pair lies off the filled pattern.
  bool Block(int a, int b, Eigen::MatrixXd* out) const;
  // The submatrix of C of the given blocks (rows and columns in that order, each block's columns
  // together). False when a pair of them lies off the filled pattern.
  bool Blocks(const std::vector<int>& blocks, Eigen::MatrixXd* out) const;
  // C rhs, through the factor (or the dense inverse): what lies off the pattern, e.g. a check
  // point's images that share no tie point. NaN when out of memory or not computed. Uses CHOLMOD's
  // workspace: one thread at a time (Block and Blocks are safe to call concurrently).
  Eigen::MatrixXd Solve(const Eigen::MatrixXd& rhs) const;

  // After Compute failed: S is singular (not positive definite to min_pivot_ratio), and the
  // column of S (its own order, 0-based; -1 when not known, e.g. an inverse that is not finite)
  // that depends on the columns factorised before it: a column without weight, the column where
  // CHOLMOD's factorisation stopped (L->minor, mapped back through the fill-reducing
  // permutation), or the one with the smallest pivot of the LDL^T of the Jacobi-scaled S. That
  // parameter is not determined given the others ordered before it: one member of the
  // undetermined combination.
  bool singular() const { return singular_; }
  int singular_column() const { return singular_column_; }

  // Per column j of block b, C_jj S_jj: how many times the parameter's variance exceeds what it
  // would be were every other parameter known (1 / (1 - R_j^2), R_j its multiple correlation with
  // the rest; the diagonal of the Jacobi-scaled inverse). NaN when not computed.
  Eigen::VectorXd VarianceInflation(int b) const;

  int size() const { return static_cast<int>(scale_.size()); }
  int num_blocks() const { return static_cast<int>(block_start_.size()) - 1; }
  int block_size(int b) const { return block_start_[b + 1] - block_start_[b]; }
  // Entries of C computed and kept (the nonzeros of L, lower triangle with diagonal; n^2 dense).
  int64_t num_entries() const;
  // Bytes held (pattern, factor, inverse entries).
  int64_t memory_bytes() const;
  double factorization_seconds() const { return factorization_seconds_; }
  double inversion_seconds() const { return inversion_seconds_; }

 private:
  // Block (a, b) of C into out(i, j) = out[i + j stride] (column-major, leading dimension
  // `stride`); false when off the pattern (out then partly written).
  bool CopyBlock(int a, int b, double* out, Eigen::Index stride) const;
  // Compute's two paths on the scaled S (scale_, block_start_ set): the dense oracle, and the
  // sparse factor with the recursion on its pattern.
  Status ComputeDense(const SparseMatrix& S_upper, const SelectedInversionOptions& options);
  Status ComputeSparse(const SparseMatrix& S_upper, const SelectedInversionOptions& options);
  // A singular S: the column found (-1: none named), and the one message of every such case.
  Status Singular(int column);
  struct Sparse;  // the CHOLMOD factor and the entries of Z (scaled, permuted) on its pattern
  std::unique_ptr<Sparse> sparse_;
  Eigen::MatrixXd dense_;         // the oracle: C itself
  Eigen::VectorXd scale_;         // D
  std::vector<int> block_start_;  // S's blocks
  double factorization_seconds_ = 0.0;
  double inversion_seconds_ = 0.0;
  bool singular_ = false;
  int singular_column_ = -1;
};

}  // namespace photopose::internal
