#pragma once
// CHOLMOD's supernodal Cholesky factor (SuiteSparse, Debian's libsuitesparse-dev) of a sparse
// symmetric positive definite matrix given by its upper triangle: the pattern analysed once, the
// values factorised as often as they change, LL^T solves. The reduced camera system of the Taylor
// bundle adjustment (solvers/bundle/taylor_bundle.h) is its user; the matrix comes already in a
// fill-reducing order (the images ordered by AMD on the image graph), so the factor keeps it
// (CHOLMOD_NATURAL) and the supernodes are the images' dense 6 x 6 blocks and their fill. Not part of
// the library's interface.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>

#include "core/status.h"

namespace photopose::internal {

class SupernodalCholesky {
 public:
  using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

  SupernodalCholesky();
  ~SupernodalCholesky();
  SupernodalCholesky(const SupernodalCholesky&) = delete;
  SupernodalCholesky& operator=(const SupernodalCholesky&) = delete;

  // The symbolic analysis of S's pattern (upper triangle, compressed, sorted). An error when
  // CHOLMOD fails (out of memory).
  [[nodiscard]] Status Analyze(const SparseMatrix& S_upper);
  bool analyzed() const;
  // The numeric factorisation S = L L^T of values on the analysed pattern. False when S is not
  // positive definite, or its pivot ratio (smallest / largest of L_jj^2, the pivots of the
  // LDL^T) is at most min_pivot_ratio; *pivot_ratio receives the ratio (0 when not positive
  // definite).
  bool Factorize(const SparseMatrix& S_upper, double min_pivot_ratio, double* pivot_ratio);
  // S^-1 rhs through the factor; NaN when CHOLMOD fails.
  Eigen::VectorXd Solve(const Eigen::VectorXd& rhs) const;
  // Nonzeros of L (count), after Analyze.
  long long factor_nonzeros() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace photopose::internal
