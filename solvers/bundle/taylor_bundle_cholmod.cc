// CHOLMOD's supernodal factor of the Taylor bundle adjustment's reduced camera system
// (solvers/bundle/internal/supernodal_cholesky.h).
#include <cholmod.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "solvers/bundle/internal/supernodal_cholesky.h"

namespace photopose::internal {

struct SupernodalCholesky::Impl {
  cholmod_common common;
  cholmod_factor* factor = nullptr;
  Impl() {
    cholmod_start(&common);
    common.print = 0;  // a matrix that is not positive definite is a result, not a message
    common.nmethods = 1;
    common.method[0].ordering = CHOLMOD_NATURAL;  // the caller's order (AMD on the images)
    common.supernodal = CHOLMOD_SUPERNODAL;
  }
  ~Impl() {
    if (factor != nullptr) cholmod_free_factor(&factor, &common);
    cholmod_finish(&common);
  }
  // A CHOLMOD view of the Eigen matrix (no copy): upper triangle, sorted, packed.
  static cholmod_sparse View(const SparseMatrix& S) {
    cholmod_sparse A{};
    A.nrow = A.ncol = static_cast<size_t>(S.cols());
    A.nzmax = static_cast<size_t>(S.nonZeros());
    A.p = const_cast<int*>(S.outerIndexPtr());
    A.i = const_cast<int*>(S.innerIndexPtr());
    A.x = const_cast<double*>(S.valuePtr());
    A.stype = 1;
    A.itype = CHOLMOD_INT;
    A.xtype = CHOLMOD_REAL;
    A.dtype = CHOLMOD_DOUBLE;
    A.sorted = 1;
    A.packed = 1;
    return A;
  }
};

SupernodalCholesky::SupernodalCholesky() : impl_(std::make_unique<Impl>()) {}
SupernodalCholesky::~SupernodalCholesky() = default;

Status SupernodalCholesky::Analyze(const SparseMatrix& S_upper) {
  if (!S_upper.isCompressed()) return Status::Error("supernodal Cholesky: S is not compressed");
  if (impl_->factor != nullptr) cholmod_free_factor(&impl_->factor, &impl_->common);
  cholmod_sparse A = Impl::View(S_upper);
  impl_->factor = cholmod_analyze(&A, &impl_->common);
  if (impl_->factor == nullptr)
    return Status::Error("supernodal Cholesky: CHOLMOD's analysis failed (out of memory?)");
  return Status::Ok();
}

bool SupernodalCholesky::analyzed() const { return impl_->factor != nullptr; }

bool SupernodalCholesky::Factorize(const SparseMatrix& S_upper, double min_pivot_ratio,
                                   double* pivot_ratio) {
  *pivot_ratio = 0.0;
  if (impl_->factor == nullptr) return false;
  if (S_upper.cols() == 0) {
    *pivot_ratio = 1.0;
    return true;
  }
  cholmod_sparse A = Impl::View(S_upper);
  if (!cholmod_factorize(&A, impl_->factor, &impl_->common)) return false;
  if (impl_->common.status == CHOLMOD_NOT_POSDEF || impl_->factor->minor < impl_->factor->n)
    return false;
  // cholmod_rcond: (min L_jj / max L_jj)^2 of an LL^T factor, the LDL^T's pivot ratio.
  *pivot_ratio = cholmod_rcond(impl_->factor, &impl_->common);
  return *pivot_ratio > min_pivot_ratio;
}

Eigen::VectorXd SupernodalCholesky::Solve(const Eigen::VectorXd& rhs) const {
  const int n = static_cast<int>(rhs.size());
  Eigen::VectorXd x = Eigen::VectorXd::Constant(n, std::numeric_limits<double>::quiet_NaN());
  if (impl_->factor == nullptr) return x;
  if (n == 0) return x;
  cholmod_dense b{};
  b.nrow = b.d = static_cast<size_t>(n);
  b.ncol = 1;
  b.nzmax = static_cast<size_t>(n);
  b.x = const_cast<double*>(rhs.data());
  b.xtype = CHOLMOD_REAL;
  b.dtype = CHOLMOD_DOUBLE;
  cholmod_dense* solution = cholmod_solve(CHOLMOD_A, impl_->factor, &b, &impl_->common);
  if (solution == nullptr) return x;
  const double* values = static_cast<const double*>(solution->x);
  std::copy(values, values + n, x.data());
  cholmod_free_dense(&solution, &impl_->common);
  return x;
}

long long SupernodalCholesky::factor_nonzeros() const {
  if (impl_->factor == nullptr) return 0;
  if (impl_->factor->is_super) return static_cast<long long>(impl_->factor->xsize);
  return static_cast<long long>(impl_->factor->nzmax);
}

}  // namespace photopose::internal
