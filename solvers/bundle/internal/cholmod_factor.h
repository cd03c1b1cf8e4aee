#pragma once
// The one wrapper of CHOLMOD (SuiteSparse, Debian's libsuitesparse-dev) in photopose: the Cholesky
// factor P S P^T = L L^T of a sparse symmetric positive definite matrix S given by its upper
// triangle. Its users are the reduced camera systems of the bundle adjustment: the Taylor
// bundle's steps (solvers/bundle/internal/taylor_normals.h: the pattern analysed once, the values
// factorised at every step, supernodal solves) and the selected inversion of the statistics
// (solvers/bundle/internal/selected_inversion.h: a block order given, the factor's columns read
// by the Takahashi recursion).
//
// The matrices are viewed, not copied (an Eigen compressed column matrix is what CHOLMOD reads);
// the right-hand sides of a solve likewise. Every CHOLMOD failure, a matrix that is not positive
// definite among them, is a Status: CHOLMOD never prints (print level 0, its error handler only
// records the message for the Status) and never stops the process. One CholmodFactor is used by
// one thread at a time (CHOLMOD's workspace is in it), the const methods included. Not part of
// the library's interface.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <vector>

#include "core/status.h"

namespace photopose::internal {

// What CHOLMOD keeps after a numeric factorisation.
enum class CholmodFactorForm {
  // The supernodal L L^T, kept so: the fastest solves (the Taylor bundle's steps).
  kSupernodal,
  // Factorised the way CHOLMOD finds fastest (supernodal on a bundle's reduced system, simplicial
  // on a tiny one), then kept as a simplicial, packed L L^T whose columns' rows ascend with the
  // diagonal first: columns() reads it (the Takahashi recursion of the selected inversion).
  kSimplicialColumns,
};

class CholmodFactor {
 public:
  using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

  // One column-compressed view of a simplicial factor (form kSimplicialColumns), in the permuted
  // order: column j of L holds rows row[column_start[j]] .. row[column_start[j + 1] - 1],
  // ascending, the diagonal first, with the values value[...]. Valid until the next Analyze or
  // Factorize.
  struct Columns {
    int n = 0;
    const int* column_start = nullptr;  // n + 1 entries
    const int* row = nullptr;           // column_start[n] entries
    const double* value = nullptr;      // column_start[n] entries
  };

  explicit CholmodFactor(CholmodFactorForm form = CholmodFactorForm::kSupernodal);
  ~CholmodFactor();
  CholmodFactor(const CholmodFactor&) = delete;
  CholmodFactor& operator=(const CholmodFactor&) = delete;

  // An approximate minimum degree order (CHOLMOD's AMD) of a symmetric n x n pattern given by its
  // upper triangle in compressed columns: column c's rows are rows[column_start[c]] ..
  // rows[column_start[c + 1] - 1], ascending. order[k] is the k-th column eliminated. For a
  // permutation to give Analyze (e.g. AMD on the blocks' graph, expanded block by block).
  [[nodiscard]] Status AmdOrder(int n, const std::vector<int>& column_start,
                                const std::vector<int>& rows, std::vector<int>* order);

  // The symbolic analysis of S's pattern (upper triangle, compressed; rows sorted in each
  // column), the previous factor dropped. Without a permutation: S's own order (CHOLMOD_NATURAL,
  // postordered by the elimination tree), for a matrix already in a fill-reducing order. With
  // one: exactly that order, no postordering (permutation[k] = the column of S eliminated k-th).
  // An error when the input is not of that form or CHOLMOD fails (out of memory).
  [[nodiscard]] Status Analyze(const SparseMatrix& S_upper);
  [[nodiscard]] Status Analyze(const SparseMatrix& S_upper, const std::vector<int>& permutation);
  bool analyzed() const;

  // The numeric factorisation of S's values on the analysed pattern (as often as they change).
  // An error when S is not positive definite or CHOLMOD fails; the factor is not usable then
  // until a Factorize succeeds.
  [[nodiscard]] Status Factorize(const SparseMatrix& S_upper);
  // After a Factorize that failed: whether S was found not positive definite (rather than
  // CHOLMOD failing), and the permuted column where the factorisation met a pivot <= 0 (L->minor;
  // -1 when not known).
  bool not_positive_definite() const;
  int bad_pivot_column() const;

  // After a successful Factorize: (min_j L_jj / max_j L_jj)^2, the smallest over the largest
  // pivot of the equivalent L D L^T (CHOLMOD's rcond; 1 for an empty matrix, 0 with a NaN).
  // 0 when the last Factorize failed.
  double pivot_ratio() const;
  // After a successful Factorize: the permuted column of the smallest pivot L_jj^2 (the first
  // of equals); -1 for an empty matrix or when the last Factorize failed.
  int smallest_pivot_column() const;
  // The fill-reducing permutation of the analysis: permutation()[k] = the column of S that is
  // column k of L (the identity or the given order, or S's order postordered). Empty before
  // Analyze.
  std::vector<int> permutation() const;
  // The factor's columns (form kSimplicialColumns, after a successful Factorize); an empty view
  // otherwise.
  Columns columns() const;

  // S^-1 rhs through the factor, one solve for all columns of rhs (rhs viewed, not copied). NaN
  // when there is no usable factor or CHOLMOD fails (out of memory).
  Eigen::VectorXd Solve(const Eigen::VectorXd& rhs) const;
  Eigen::MatrixXd Solve(const Eigen::MatrixXd& rhs) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace photopose::internal
