// The CHOLMOD wrapper (solvers/bundle/internal/cholmod_factor.h): cholmod_common's life, views
// of Eigen's matrices, the analysis, the numeric factorisation, the solves and CHOLMOD's errors as
// Status.
#include "solvers/bundle/internal/cholmod_factor.h"

#include <cholmod.h>

#include <algorithm>
#include <limits>
#include <string>
#include <tuple>
#include <utility>

namespace photopose::internal {
namespace {

// CHOLMOD's last error or warning message on this thread, for the Status (CHOLMOD's error handler
// takes no user data; a factor is used by one thread at a time).
thread_local std::string cholmod_message;

// CHOLMOD's error handler: records, never prints (print level 0) and never stops the process.
void RecordCholmodMessage(int /*status*/, const char* /*file*/, int /*line*/, const char* message) {
  cholmod_message = message != nullptr ? message : "";
}

const char* StatusText(int status) {
  switch (status) {
    case CHOLMOD_OK:
      return "no error";
    case CHOLMOD_NOT_INSTALLED:
      return "method not installed";
    case CHOLMOD_OUT_OF_MEMORY:
      return "out of memory";
    case CHOLMOD_TOO_LARGE:
      return "problem too large (integer overflow)";
    case CHOLMOD_INVALID:
      return "invalid input";
    case CHOLMOD_GPU_PROBLEM:
      return "GPU error";
    case CHOLMOD_NOT_POSDEF:
      return "not positive definite";
    case CHOLMOD_DSMALL:
      return "tiny pivot";
    default:
      return "unknown status";
  }
}

using SparseMatrix = CholmodFactor::SparseMatrix;

// A CHOLMOD view (no copy) of the upper triangle of a symmetric n x n matrix in compressed
// columns, rows sorted, packed; without values: its pattern only.
cholmod_sparse UpperView(int n, size_t entries, const int* column_start, const int* rows,
                         const double* values) {
  // CHOLMOD wants a rows array even for a matrix without entries (Eigen keeps none then).
  static int no_row = 0;
  cholmod_sparse A{};
  A.nrow = A.ncol = static_cast<size_t>(n);
  A.nzmax = entries;
  A.p = const_cast<int*>(column_start);
  A.i = const_cast<int*>(rows != nullptr ? rows : &no_row);
  A.x = const_cast<double*>(values);
  A.stype = 1;
  A.itype = CHOLMOD_INT;
  A.xtype = values == nullptr ? CHOLMOD_PATTERN : CHOLMOD_REAL;
  A.dtype = CHOLMOD_DOUBLE;
  A.sorted = 1;
  A.packed = 1;
  return A;
}

// The view of S (square, compressed: NotViewable says); values even without entries.
cholmod_sparse View(const SparseMatrix& S) {
  static const double no_value = 0.0;
  return UpperView(static_cast<int>(S.cols()), static_cast<size_t>(S.nonZeros()), S.outerIndexPtr(),
                   S.innerIndexPtr(), S.valuePtr() != nullptr ? S.valuePtr() : &no_value);
}

// Why S cannot be viewed (empty when it can).
std::string NotViewable(const SparseMatrix& S) {
  if (S.rows() != S.cols()) return "the matrix is not square";
  if (!S.isCompressed()) return "the matrix is not compressed";
  return "";
}

}  // namespace

struct CholmodFactor::Impl {
  CholmodFactorForm form;
  cholmod_common common;  // CHOLMOD's options, statistics and workspace (also for the solves)
  cholmod_factor* factor = nullptr;
  bool factorized = false;  // the last Factorize succeeded
  bool not_positive_definite = false;
  int bad_pivot_column = -1;

  explicit Impl(CholmodFactorForm form_in) : form(form_in) {
    cholmod_start(&common);
    common.print = 0;  // a matrix that is not positive definite is a result, not a message
    common.error_handler = &RecordCholmodMessage;
    if (form == CholmodFactorForm::kSupernodal) {
      common.supernodal = CHOLMOD_SUPERNODAL;
    } else {
      // CHOLMOD's choice of method, then converted to the simplicial L L^T the columns need.
      common.supernodal = CHOLMOD_AUTO;
      common.final_asis = 0;
      common.final_super = 0;
      common.final_ll = 1;
      common.final_pack = 1;
      common.final_monotonic = 1;
    }
  }
  ~Impl() {
    DropFactor();
    cholmod_finish(&common);
  }
  void DropFactor() {
    if (factor != nullptr) cholmod_free_factor(&factor, &common);
    factorized = false;
    not_positive_definite = false;
    bad_pivot_column = -1;
  }
  // "CHOLMOD's <step> failed: <what CHOLMOD said>".
  Status Failure(const char* step) const {
    std::string message =
        std::string("CHOLMOD's ") + step + " failed: " + StatusText(common.status);
    if (!cholmod_message.empty()) message += " (" + cholmod_message + ")";
    return Status::Error(message);
  }
  // Calls f(j, L_jj) for every column of the factor, either form.
  template <typename Function>
  void ForEachDiagonal(Function f) const {
    const double* Lx = static_cast<const double*>(factor->x);
    if (factor->is_super) {
      const auto* super = static_cast<const int*>(factor->super);
      const auto* pi = static_cast<const int*>(factor->pi);
      const auto* px = static_cast<const int*>(factor->px);
      for (size_t s = 0; s < factor->nsuper; ++s) {
        const int rows = pi[s + 1] - pi[s];
        for (int j = super[s]; j < super[s + 1]; ++j) {
          const int k = j - super[s];
          f(j, Lx[px[s] + k * rows + k]);
        }
      }
    } else {
      const auto* Lp = static_cast<const int*>(factor->p);
      for (int j = 0; j < static_cast<int>(factor->n); ++j) f(j, Lx[Lp[j]]);
    }
  }
  // The simplicial factor's columns sorted by row with the diagonal first (CHOLMOD keeps them
  // so; sorted here if not). False when a diagonal is missing.
  bool SortColumns() {
    const auto* Lp = static_cast<const int*>(factor->p);
    auto* Li = static_cast<int*>(factor->i);
    auto* Lx = static_cast<double*>(factor->x);
    const int n = static_cast<int>(factor->n);
    for (int col = 0; col < n; ++col) {
      if (!std::is_sorted(Li + Lp[col], Li + Lp[col + 1])) {
        std::vector<std::pair<int, double>> entries;
        for (int t = Lp[col]; t < Lp[col + 1]; ++t) entries.emplace_back(Li[t], Lx[t]);
        std::sort(entries.begin(), entries.end());
        for (int t = Lp[col]; t < Lp[col + 1]; ++t) std::tie(Li[t], Lx[t]) = entries[t - Lp[col]];
      }
      if (Lp[col] == Lp[col + 1] || Li[Lp[col]] != col) return false;
    }
    return true;
  }
  // S^-1 rhs for every column of rhs (viewed, not copied); NaN when there is no usable factor of
  // rhs's size or CHOLMOD fails.
  template <typename Dense>
  Dense Solve(const Dense& rhs) {
    const int n = static_cast<int>(rhs.rows()), columns = static_cast<int>(rhs.cols());
    Dense x = Dense::Constant(n, columns, std::numeric_limits<double>::quiet_NaN());
    if (!factorized || n != static_cast<int>(factor->n) || x.size() == 0) return x;
    cholmod_dense B{};
    B.nrow = B.d = static_cast<size_t>(n);
    B.ncol = static_cast<size_t>(columns);
    B.nzmax = static_cast<size_t>(x.size());
    B.x = const_cast<double*>(rhs.data());
    B.xtype = CHOLMOD_REAL;
    B.dtype = CHOLMOD_DOUBLE;
    cholmod_message.clear();
    cholmod_dense* X = cholmod_solve(CHOLMOD_A, factor, &B, &common);
    if (X == nullptr) return x;
    const double* values = static_cast<const double*>(X->x);
    std::copy(values, values + x.size(), x.data());
    cholmod_free_dense(&X, &common);
    return x;
  }
};

CholmodFactor::CholmodFactor(CholmodFactorForm form) : impl_(std::make_unique<Impl>(form)) {}
CholmodFactor::~CholmodFactor() = default;

Status CholmodFactor::AmdOrder(int n, const std::vector<int>& column_start,
                               const std::vector<int>& rows, std::vector<int>* order) {
  if (n < 0 || column_start.size() != static_cast<size_t>(n) + 1 || column_start.front() != 0 ||
      column_start.back() != static_cast<int>(rows.size()))
    return Status::Error("CHOLMOD's ordering: the pattern's column starts do not fit its rows");
  order->assign(n, 0);
  if (n == 0) return Status::Ok();
  cholmod_sparse B = UpperView(n, rows.size(), column_start.data(), rows.data(), nullptr);
  cholmod_message.clear();
  if (!cholmod_amd(&B, nullptr, 0, order->data(), &impl_->common))
    return impl_->Failure("ordering");
  return Status::Ok();
}

Status CholmodFactor::Analyze(const SparseMatrix& S_upper) {
  impl_->DropFactor();
  const std::string why = NotViewable(S_upper);
  if (!why.empty()) return Status::Error("CHOLMOD's analysis: " + why);
  impl_->common.nmethods = 1;
  impl_->common.method[0].ordering = CHOLMOD_NATURAL;  // the caller's order (already fill-reducing)
  impl_->common.postorder = 1;
  cholmod_sparse A = View(S_upper);
  cholmod_message.clear();
  impl_->factor = cholmod_analyze(&A, &impl_->common);
  if (impl_->factor == nullptr) return impl_->Failure("analysis");
  return Status::Ok();
}

Status CholmodFactor::Analyze(const SparseMatrix& S_upper, const std::vector<int>& permutation) {
  impl_->DropFactor();
  const std::string why = NotViewable(S_upper);
  if (!why.empty()) return Status::Error("CHOLMOD's analysis: " + why);
  if (permutation.size() != static_cast<size_t>(S_upper.cols()))
    return Status::Error("CHOLMOD's analysis: the permutation does not fit the matrix");
  // Exactly this order: no postordering (which could interleave the caller's blocks).
  impl_->common.nmethods = 1;
  impl_->common.method[0].ordering = CHOLMOD_GIVEN;
  impl_->common.postorder = 0;
  cholmod_sparse A = View(S_upper);
  cholmod_message.clear();
  impl_->factor =
      cholmod_analyze_p(&A, const_cast<int*>(permutation.data()), nullptr, 0, &impl_->common);
  if (impl_->factor == nullptr) return impl_->Failure("analysis");
  return Status::Ok();
}

bool CholmodFactor::analyzed() const { return impl_->factor != nullptr; }

Status CholmodFactor::Factorize(const SparseMatrix& S_upper) {
  Impl& m = *impl_;
  m.factorized = false;
  m.not_positive_definite = false;
  m.bad_pivot_column = -1;
  if (m.factor == nullptr)
    return Status::Error("CHOLMOD's factorisation: the pattern is not analysed");
  const std::string why = NotViewable(S_upper);
  if (!why.empty()) return Status::Error("CHOLMOD's factorisation: " + why);
  const int n = static_cast<int>(m.factor->n);
  if (S_upper.cols() != n)
    return Status::Error("CHOLMOD's factorisation: the matrix is not the one analysed");
  if (n == 0) {
    m.factorized = true;
    return Status::Ok();
  }
  cholmod_sparse A = View(S_upper);
  cholmod_message.clear();
  if (!cholmod_factorize(&A, m.factor, &m.common)) return m.Failure("factorisation");
  if (m.common.status == CHOLMOD_NOT_POSDEF || static_cast<int>(m.factor->minor) < n) {
    // L->minor: the permuted column where the factorisation met a pivot <= 0.
    m.not_positive_definite = true;
    const int minor = static_cast<int>(m.factor->minor);
    m.bad_pivot_column = minor < n ? minor : -1;
    return Status::Error("the matrix is not positive definite (a pivot <= 0 at column " +
                         std::to_string(m.bad_pivot_column) + " of the factor)");
  }
  if (m.form == CholmodFactorForm::kSimplicialColumns) {
    if (m.factor->is_super || !m.factor->is_ll)
      return Status::Error("CHOLMOD did not give a simplicial L L^T factor");
    if (!m.SortColumns())
      return Status::Error("CHOLMOD's factor has an unexpected layout (a diagonal not first)");
  }
  m.factorized = true;
  return Status::Ok();
}

bool CholmodFactor::not_positive_definite() const { return impl_->not_positive_definite; }
int CholmodFactor::bad_pivot_column() const { return impl_->bad_pivot_column; }

double CholmodFactor::pivot_ratio() const {
  if (!impl_->factorized) return 0.0;
  if (impl_->factor->n == 0) return 1.0;
  // cholmod_rcond: (min L_jj / max L_jj)^2 of an L L^T factor, the L D L^T's pivot ratio.
  return cholmod_rcond(impl_->factor, &impl_->common);
}

int CholmodFactor::smallest_pivot_column() const {
  if (!impl_->factorized) return -1;
  double smallest = std::numeric_limits<double>::infinity();
  int column = -1;
  impl_->ForEachDiagonal([&](int j, double L_jj) {
    const double pivot = L_jj * L_jj;  // the D of L D L^T
    if (pivot < smallest) {
      smallest = pivot;
      column = j;
    }
  });
  return column;
}

std::vector<int> CholmodFactor::permutation() const {
  if (impl_->factor == nullptr) return {};
  const auto* perm = static_cast<const int*>(impl_->factor->Perm);
  return std::vector<int>(perm, perm + impl_->factor->n);
}

CholmodFactor::Columns CholmodFactor::columns() const {
  const cholmod_factor* L = impl_->factor;
  if (!impl_->factorized || L->is_super || L->n == 0) return {};
  Columns view;
  view.n = static_cast<int>(L->n);
  view.column_start = static_cast<const int*>(L->p);
  view.row = static_cast<const int*>(L->i);
  view.value = static_cast<const double*>(L->x);
  return view;
}

Eigen::VectorXd CholmodFactor::Solve(const Eigen::VectorXd& rhs) const { return impl_->Solve(rhs); }

Eigen::MatrixXd CholmodFactor::Solve(const Eigen::MatrixXd& rhs) const { return impl_->Solve(rhs); }

}  // namespace photopose::internal
