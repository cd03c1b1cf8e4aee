// Selected inversion (solvers/bundle/internal/selected_inversion.h): the block order, the
// Takahashi recursion on the pattern of the factor (solvers/bundle/internal/cholmod_factor.h), and
// the lookups of blocks of the inverse.
#include "solvers/bundle/internal/selected_inversion.h"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>
#include <utility>

#include "solvers/bundle/internal/cholmod_factor.h"

namespace photopose::internal {
namespace {

using Clock = std::chrono::steady_clock;
double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// The Takahashi recursion for columns j0 .. j1 - 1 of the simplicial factor (Lp, Li, Lx), whose
// columns after j1 - 1 are done in z: one block of S, dense on its diagonal, every column with
// the rows of the block below it and then the same rows R. (A panel of one column is the scalar
// recursion.) `position` is -1 everywhere on entry and exit.
void TakahashiPanel(int j0, int j1, const int* Lp, const int* Li, const double* Lx,
                    std::vector<int>* position, std::vector<double>* z_values) {
  const int s = j1 - j0;
  const int* R = Li + Lp[j1 - 1] + 1;
  const int m = Lp[j1] - Lp[j1 - 1] - 1;
  for (int c = 0; c < s; ++c) {
    // Column j0 + c: rows j0 + c .. j1 - 1, then R.
    const int start = Lp[j0 + c];
    bool same = Lp[j0 + c + 1] - start == s - c + m;
    for (int r = 0; same && r < s - c; ++r) same = Li[start + r] == j0 + c + r;
    for (int a = 0; same && a < m; ++a) same = Li[start + s - c + a] == R[a];
    if (!same) {
      // Not one pattern (never seen with CHOLMOD's factors): column by column.
      for (int j = j1 - 1; j >= j0; --j) TakahashiPanel(j, j + 1, Lp, Li, Lx, position, z_values);
      return;
    }
  }
  std::vector<double>& z = *z_values;
  RowMatrix L_RJ(m, s);
  Eigen::MatrixXd L_JJ = Eigen::MatrixXd::Zero(s, s);
  for (int c = 0; c < s; ++c) {
    const int start = Lp[j0 + c];
    for (int r = c; r < s; ++r) L_JJ(r, c) = Lx[start + r - c];
    for (int a = 0; a < m; ++a) L_RJ(a, c) = Lx[start + s - c + a];
  }
  // Y = Z_RR L_RJ.
  RowMatrix Y = RowMatrix::Zero(m, s);
  for (int a = 0; a < m; ++a) (*position)[R[a]] = a;
  for (int a = 0; a < m; ++a) {
    const int i = R[a];
    double* y_a = Y.row(a).data();
    const double* l_a = L_RJ.row(a).data();
    const double z_ii = z[Lp[i]];
    for (int c = 0; c < s; ++c) y_a[c] += z_ii * l_a[c];
    for (int u = Lp[i] + 1; u < Lp[i + 1]; ++u) {
      const int b = (*position)[Li[u]];
      if (b < 0) continue;
      const double z_ki = z[u];
      double* y_b = Y.row(b).data();
      const double* l_b = L_RJ.row(b).data();
      for (int c = 0; c < s; ++c) {
        y_a[c] += z_ki * l_b[c];
        y_b[c] += z_ki * l_a[c];
      }
    }
  }
  for (int a = 0; a < m; ++a) (*position)[R[a]] = -1;
  // Z_RJ = -Y L_JJ^-1; Z_JJ = L_JJ^-T L_JJ^-1 - Z_RJ^T L_RJ L_JJ^-1.
  Eigen::MatrixXd Z_RJ = -Y;
  // The last panels have no rows below them (m = 0): Eigen's triangular solve must not see an
  // empty right-hand side (it takes a reference to its first coefficient).
  if (m > 0) L_JJ.triangularView<Eigen::Lower>().solveInPlace<Eigen::OnTheRight>(Z_RJ);
  const Eigen::MatrixXd L_inverse =
      L_JJ.triangularView<Eigen::Lower>().solve(Eigen::MatrixXd::Identity(s, s));
  Eigen::MatrixXd Z_JJ =
      L_inverse.transpose() * L_inverse - (Z_RJ.transpose() * L_RJ) * L_inverse;
  for (int c = 0; c < s; ++c) {
    const int start = Lp[j0 + c];
    for (int r = c; r < s; ++r) z[start + r - c] = 0.5 * (Z_JJ(r, c) + Z_JJ(c, r));
    for (int a = 0; a < m; ++a) z[start + s - c + a] = Z_RJ(a, c);
  }
}

// S_upper's upper triangle scaled to D S D (D = diag(scale)), every stored entry kept (a block's
// structural zeros too, so that its columns share one pattern in L).
SelectedInverse::SparseMatrix ScaledUpperTriangle(const SelectedInverse::SparseMatrix& S_upper,
                                                  const Eigen::VectorXd& scale) {
  using SparseMatrix = SelectedInverse::SparseMatrix;
  const int n = static_cast<int>(S_upper.cols());
  int64_t nnz = 0;
  for (int col = 0; col < n; ++col)
    for (SparseMatrix::InnerIterator it(S_upper, col); it; ++it) nnz += it.row() <= col;
  SparseMatrix A(n, n);
  A.resizeNonZeros(static_cast<Eigen::Index>(nnz));
  int* Ap = A.outerIndexPtr();
  int* Ai = A.innerIndexPtr();
  double* Ax = A.valuePtr();
  int64_t k = 0;
  for (int col = 0; col < n; ++col) {
    Ap[col] = static_cast<int>(k);
    for (SparseMatrix::InnerIterator it(S_upper, col); it; ++it) {
      if (it.row() > col) continue;
      Ai[k] = it.row();
      Ax[k++] = scale[it.row()] * it.value() * scale[col];
    }
  }
  Ap[n] = static_cast<int>(k);
  return A;
}

// Approximate minimum degree on the block graph of S_upper, expanded block by block: the
// permutation of S's columns, and per block its first permuted column (*first).
Status BlockAmdOrder(const SelectedInverse::SparseMatrix& S_upper,
                     const std::vector<int>& block_start, CholmodFactor* factor,
                     std::vector<int>* permutation, std::vector<int>* first) {
  const int n = static_cast<int>(S_upper.cols());
  const int num_blocks = static_cast<int>(block_start.size()) - 1;
  std::vector<int> block_of(n);
  for (int b = 0; b < num_blocks; ++b)
    for (int col = block_start[b]; col < block_start[b + 1]; ++col) block_of[col] = b;
  std::vector<std::vector<int>> block_rows(num_blocks);
  for (int col = 0; col < n; ++col) {
    for (SelectedInverse::SparseMatrix::InnerIterator it(S_upper, col); it; ++it) {
      if (it.row() > col) continue;
      const int a = block_of[it.row()], b = block_of[col];
      if (block_rows[b].empty() || block_rows[b].back() != a) block_rows[b].push_back(a);
    }
  }
  std::vector<int> block_column_start(num_blocks + 1, 0), block_pattern;
  for (int b = 0; b < num_blocks; ++b) {
    std::vector<int>& rows = block_rows[b];
    std::sort(rows.begin(), rows.end());
    rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
    block_pattern.insert(block_pattern.end(), rows.begin(), rows.end());
    block_column_start[b + 1] = static_cast<int>(block_pattern.size());
    rows = std::vector<int>();
  }
  std::vector<int> block_order;
  const Status ordered =
      factor->AmdOrder(num_blocks, block_column_start, block_pattern, &block_order);
  if (!ordered.ok()) return Status::Error("selected inversion: " + ordered.message());
  permutation->clear();
  permutation->reserve(n);
  first->assign(num_blocks, 0);
  for (const int b : block_order) {
    (*first)[b] = static_cast<int>(permutation->size());
    for (int col = block_start[b]; col < block_start[b + 1]; ++col) permutation->push_back(col);
  }
  return Status::Ok();
}

// Takahashi, backwards, one block of S (a panel of columns J with one pattern R below it) at a
// time: Z_RJ = -Z_RR L_RJ L_JJ^-1 and Z_JJ = (L_JJ^-T - Z_RJ^T L_RJ) L_JJ^-1. The products need
// Z_ik for i, k in R; they lie in the columns i of R (L's pattern is closed: R is a clique of the
// filled graph), found by walking each such column once per panel with R marked. panel_end: per
// first permuted column of a block one past its last, 0 elsewhere; z: zero on L's pattern.
void InvertOnPattern(const CholmodFactor::Columns& L, const std::vector<int>& panel_end,
                     std::vector<double>* z) {
  const int n = static_cast<int>(panel_end.size());
  std::vector<int> position(n, -1);
  int j1 = n;
  while (j1 > 0) {
    int j0 = j1 - 1;
    while (panel_end[j0] == 0) --j0;  // the block's first column
    TakahashiPanel(j0, j1, L.column_start, L.row, L.value, &position, z);
    j1 = j0;
  }
}

}  // namespace

// The factor A = P^T L L^T P (simplicial, packed, each column's rows ascending with the diagonal
// first) and Z = A^-1 on the pattern of L, in the permuted order; `first` maps a block of S to
// its first permuted column (its columns stay together and in order).
struct SelectedInverse::Sparse {
  CholmodFactor factor{CholmodFactorForm::kSimplicialColumns};
  CholmodFactor::Columns L;  // the factor's columns
  std::vector<double> z;     // aligned with L.row
  std::vector<int> first;    // per block of S: first permuted column
  // Position in z of permuted (row, column), row >= column, of the first of `count` consecutive
  // rows; -1 when any of them is off the pattern.
  int64_t Run(int row, int column, int count) const {
    const int* begin = L.row + L.column_start[column];
    const int* end = L.row + L.column_start[column + 1];
    const int* found = std::lower_bound(begin, end, row);
    if (end - found < count) return -1;
    if (found[count - 1] != row + count - 1) return -1;  // sorted and unique: all present
    return found - L.row;
  }
};

SelectedInverse::SelectedInverse() = default;
SelectedInverse::~SelectedInverse() = default;
SelectedInverse::SelectedInverse(SelectedInverse&&) noexcept = default;
SelectedInverse& SelectedInverse::operator=(SelectedInverse&&) noexcept = default;

Status SelectedInverse::Singular(int column) {
  singular_ = true;
  singular_column_ = column;
  return Status::Error("the reduced normal matrix is singular (not positive definite)");
}

Status SelectedInverse::Compute(const SparseMatrix& S_upper, const std::vector<int>& block_start,
                                const SelectedInversionOptions& options) {
  sparse_.reset();
  dense_.resize(0, 0);
  factorization_seconds_ = inversion_seconds_ = 0.0;
  singular_ = false;
  singular_column_ = -1;
  const int n = static_cast<int>(S_upper.cols());
  if (S_upper.rows() != n || block_start.empty() || block_start.front() != 0 ||
      block_start.back() != n)
    return Status::Error("selected inversion: the blocks do not partition the matrix");
  block_start_ = block_start;
  // Jacobi scaling first: camera parameters in mixed units (um next to mm^-6) give diagonals
  // twenty orders of magnitude apart, which would hide a real rank defect or fake one.
  scale_.resize(n);
  for (int c = 0; c < n; ++c) {
    const double d = S_upper.coeff(c, c);
    if (!std::isfinite(d)) return Status::Error("the reduced normal matrix is not finite");
    if (!(d > 0.0)) return Singular(c);  // a column without weight
    scale_[c] = 1.0 / std::sqrt(d);
  }
  return options.dense ? ComputeDense(S_upper, options) : ComputeSparse(S_upper, options);
}

Status SelectedInverse::ComputeDense(const SparseMatrix& S_upper,
                                     const SelectedInversionOptions& options) {
  const Clock::time_point start = Clock::now();
  const int n = size();
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  for (int col = 0; col < n; ++col) {
    for (SparseMatrix::InnerIterator it(S_upper, col); it; ++it) {
      if (it.row() > col) continue;
      A(it.row(), col) = A(col, it.row()) = scale_[it.row()] * it.value() * scale_[col];
    }
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(A);
  const double pivot = ldlt.vectorD().minCoeff();
  if (ldlt.info() != Eigen::Success || !(pivot > 0.0) ||
      !(pivot > options.min_pivot_ratio * ldlt.vectorD().maxCoeff())) {
    // Eigen's LDL^T picks its pivots by size, which would name any member of the undetermined
    // combination; a Cholesky in the blocks' own order names the last of it, as the sparse
    // factor does in its order (A's diagonal is 1: the first pivot <= the ratio).
    Eigen::MatrixXd L = A;
    for (int k = 0; k < n; ++k) {
      const double d = L(k, k) - L.row(k).head(k).squaredNorm();
      if (!(d > options.min_pivot_ratio)) return Singular(k);
      L(k, k) = std::sqrt(d);
      for (int i = k + 1; i < n; ++i)
        L(i, k) = (L(i, k) - L.row(i).head(k).dot(L.row(k).head(k))) / L(k, k);
    }
    return Singular(-1);
  }
  factorization_seconds_ = SecondsSince(start);
  if (options.factor_only) return Status::Ok();
  dense_ = scale_.asDiagonal() * ldlt.solve(Eigen::MatrixXd::Identity(n, n)) * scale_.asDiagonal();
  inversion_seconds_ = SecondsSince(start) - factorization_seconds_;
  if (!dense_.allFinite()) return Singular(-1);
  return Status::Ok();
}

Status SelectedInverse::ComputeSparse(const SparseMatrix& S_upper,
                                      const SelectedInversionOptions& options) {
  const Clock::time_point start = Clock::now();
  const int n = size();
  auto sparse = std::make_unique<Sparse>();
  CholmodFactor& factor = sparse->factor;
  SparseMatrix A = ScaledUpperTriangle(S_upper, scale_);
  std::vector<int> permutation;
  const Status ordered =
      BlockAmdOrder(S_upper, block_start_, &factor, &permutation, &sparse->first);
  if (!ordered.ok()) return ordered;
  // Exactly this order; a simplicial L L^T for the recursion.
  const Status analysed = factor.Analyze(A, permutation);
  if (!analysed.ok()) return Status::Error("selected inversion: " + analysed.message());
  const Status factored = factor.Factorize(A);
  A = SparseMatrix();
  if (!factored.ok()) {
    if (!factor.not_positive_definite())
      return Status::Error("selected inversion: " + factored.message());
    const int column = factor.bad_pivot_column();
    return Singular(column >= 0 ? permutation[column] : -1);
  }
  factorization_seconds_ = SecondsSince(start);
  if (!(factor.pivot_ratio() > options.min_pivot_ratio)) {
    const int column = factor.smallest_pivot_column();
    return Singular(column >= 0 ? permutation[column] : -1);
  }
  if (options.factor_only) return Status::Ok();

  const Clock::time_point inversion_start = Clock::now();
  sparse->L = factor.columns();
  sparse->z.assign(static_cast<size_t>(n > 0 ? sparse->L.column_start[n] : 0), 0.0);
  std::vector<int> panel_end(n, 0);  // per first column of a block: one past its last
  for (int b = 0; b < num_blocks(); ++b) {
    const int first = sparse->first[b];
    panel_end[first] = first + block_size(b);
  }
  InvertOnPattern(sparse->L, panel_end, &sparse->z);
  inversion_seconds_ = SecondsSince(inversion_start);
  for (const double value : sparse->z)
    if (!std::isfinite(value)) return Singular(-1);
  sparse_ = std::move(sparse);
  return Status::Ok();
}

bool SelectedInverse::CopyBlock(int a, int b, double* out, Eigen::Index stride) const {
  // out(i, j) at out[i + j stride], i in block a, j in block b.
  if (sparse_ == nullptr) {
    if (dense_.size() == 0) return false;
    const int ra = block_start_[a], cb = block_start_[b];
    for (int j = 0; j < block_size(b); ++j)
      for (int i = 0; i < block_size(a); ++i) out[i + j * stride] = dense_(ra + i, cb + j);
    return true;
  }
  // Read from the lower triangle of Z: rows of the later block in the columns of the earlier.
  const bool transpose = sparse_->first[a] < sparse_->first[b];
  const int row_block = transpose ? b : a, col_block = transpose ? a : b;
  const int rows = block_size(row_block), cols = block_size(col_block);
  const int row0 = sparse_->first[row_block], col0 = sparse_->first[col_block];
  const double* s_row = scale_.data() + block_start_[row_block];
  const double* s_col = scale_.data() + block_start_[col_block];
  // Z(r, c) of the (row_block, col_block) block, unscaled, into out(r, c) or out(c, r).
  const auto put = [&](int r, int c, double z) {
    const double value = s_row[r] * z * s_col[c];
    if (transpose)
      out[c + r * stride] = value;
    else
      out[r + c * stride] = value;
  };
  const int* Lp = sparse_->L.column_start;
  const int* Li = sparse_->L.row;
  int64_t first_at = -1;
  for (int c = 0; c < cols; ++c) {
    if (row_block == col_block) {
      // Diagonal block: rows c.. of column c, which lead the column (the diagonal first, the
      // block dense on it); the rest by symmetry.
      int64_t at = Lp[col0 + c];
      if (!(at + rows - c <= Lp[col0 + c + 1] && Li[at] == row0 + c &&
            Li[at + rows - c - 1] == row0 + rows - 1))
        at = sparse_->Run(row0 + c, col0 + c, rows - c);
      if (at < 0) return false;
      for (int r = c; r < rows; ++r) {
        put(r, c, sparse_->z[at + r - c]);
        put(c, r, sparse_->z[at + r - c]);
      }
    } else {
      // The block's columns share their pattern below it: where the rows sit in the first
      // column, less one per column, is where they sit in the others (checked; else searched).
      int64_t at = -1;
      if (c > 0 && first_at >= 0) {
        const int64_t guess = Lp[col0 + c] + (first_at - Lp[col0]) - c;
        if (guess + rows <= Lp[col0 + c + 1] && Li[guess] == row0 &&
            Li[guess + rows - 1] == row0 + rows - 1)
          at = guess;
      }
      if (at < 0) at = sparse_->Run(row0, col0 + c, rows);
      if (at < 0) return false;
      if (c == 0) first_at = at;
      for (int r = 0; r < rows; ++r) put(r, c, sparse_->z[at + r]);
    }
  }
  return true;
}

bool SelectedInverse::Block(int a, int b, Eigen::MatrixXd* out) const {
  Eigen::MatrixXd C(block_size(a), block_size(b));
  if (!CopyBlock(a, b, C.data(), C.rows())) return false;
  *out = std::move(C);
  return true;
}

bool SelectedInverse::Blocks(const std::vector<int>& blocks, Eigen::MatrixXd* out) const {
  std::vector<int> offset(blocks.size() + 1, 0);
  for (size_t k = 0; k < blocks.size(); ++k) offset[k + 1] = offset[k] + block_size(blocks[k]);
  Eigen::MatrixXd C(offset.back(), offset.back());
  for (size_t k = 0; k < blocks.size(); ++k) {
    for (size_t l = k; l < blocks.size(); ++l) {
      if (!CopyBlock(blocks[l], blocks[k], &C(offset[l], offset[k]), C.rows())) return false;
      if (l != k)
        C.block(offset[k], offset[l], offset[k + 1] - offset[k], offset[l + 1] - offset[l]) =
            C.block(offset[l], offset[k], offset[l + 1] - offset[l], offset[k + 1] - offset[k])
                .transpose();
    }
  }
  *out = std::move(C);
  return true;
}

Eigen::VectorXd SelectedInverse::VarianceInflation(int b) const {
  const int size = block_size(b);
  Eigen::MatrixXd C;
  if (!Block(b, b, &C)) return Eigen::VectorXd::Constant(size, std::numeric_limits<double>::quiet_NaN());
  const Eigen::VectorXd s = scale_.segment(block_start_[b], size);
  return C.diagonal().cwiseQuotient(s.cwiseAbs2());
}

Eigen::MatrixXd SelectedInverse::Solve(const Eigen::MatrixXd& rhs) const {
  if (sparse_ == nullptr && dense_.size() == 0)  // not computed (or factor_only): no figure
    return Eigen::MatrixXd::Constant(rhs.rows(), rhs.cols(),
                                     std::numeric_limits<double>::quiet_NaN());
  if (sparse_ == nullptr) return dense_ * rhs;
  // NaN when CHOLMOD fails (out of memory): no figure rather than an abort.
  const Eigen::MatrixXd scaled_rhs = scale_.asDiagonal() * rhs;
  return scale_.asDiagonal() * sparse_->factor.Solve(scaled_rhs);
}

int64_t SelectedInverse::num_entries() const {
  if (sparse_ != nullptr) return static_cast<int64_t>(sparse_->z.size());
  return static_cast<int64_t>(dense_.size());
}

int64_t SelectedInverse::memory_bytes() const {
  if (sparse_ == nullptr) return static_cast<int64_t>(dense_.size()) * 8;
  const int64_t nnz = static_cast<int64_t>(sparse_->z.size());
  // L's column pointers and rows, its values and Z's.
  return (size() + 1 + nnz) * 4 + 2 * nnz * 8 + static_cast<int64_t>(sparse_->first.size()) * 4;
}

}  // namespace photopose::internal
