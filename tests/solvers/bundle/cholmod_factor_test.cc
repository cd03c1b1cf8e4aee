// The CHOLMOD wrapper (solvers/bundle/internal/cholmod_factor.h): solves against Eigen's dense
// Cholesky, a matrix that is not positive definite and CHOLMOD's own errors as Status (nothing
// printed), the pattern analysed once and refactorised against a fresh analysis, the given order
// and the factor's columns.
#include "solvers/bundle/internal/cholmod_factor.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <string>
#include <vector>

namespace photopose::internal {
namespace PHOTOPOSE_UNITY_ID {

using SparseMatrix = CholmodFactor::SparseMatrix;

// A direct solve with the factor of a well-conditioned (condition < 1e2) SPD matrix against
// Eigen's dense L L^T: rounding only, relative to the solution's largest entry.
constexpr double kDirectSolveAgreement = 1e-12;
// L L^T rebuilt from the factor's columns against P S P^T, relative to S's largest entry.
constexpr double kFactorAgreement = 1e-13;

const CholmodFactorForm kForms[] = {CholmodFactorForm::kSupernodal,
                                    CholmodFactorForm::kSimplicialColumns};

const char* FormName(CholmodFactorForm form) {
  return form == CholmodFactorForm::kSupernodal ? "supernodal" : "simplicial columns";
}

// A banded SPD matrix of n columns with dense 6 x 6 diagonal blocks (a reduced camera system's
// shape), diagonally dominant: its pivots all lie near `diagonal`.
Eigen::MatrixXd BandedSpd(int n, uint64_t seed, double diagonal = 20.0) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(n, n);
  for (int c = 0; c < n; ++c)
    for (int r = std::max(0, c - 8); r < c; ++r) dense(r, c) = dense(c, r) = uniform(rng);
  for (int c = 0; c < n; ++c) dense(c, c) = diagonal + uniform(rng);
  return dense;
}

SparseMatrix Upper(const Eigen::MatrixXd& dense) {
  SparseMatrix upper = dense.triangularView<Eigen::Upper>().toDenseMatrix().sparseView();
  upper.makeCompressed();
  return upper;
}

Eigen::MatrixXd RandomRhs(int n, int columns, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::MatrixXd rhs(n, columns);
  for (int k = 0; k < rhs.size(); ++k) rhs.data()[k] = uniform(rng);
  return rhs;
}

double MaxAbs(const Eigen::MatrixXd& m) { return m.cwiseAbs().maxCoeff(); }

TEST(CholmodFactor, SolvesAsEigensDenseLlt) {
  const int n = 60;
  const Eigen::MatrixXd dense = BandedSpd(n, 3);
  const SparseMatrix upper = Upper(dense);
  const Eigen::LLT<Eigen::MatrixXd> llt(dense);
  ASSERT_EQ(llt.info(), Eigen::Success);
  const Eigen::MatrixXd rhs = RandomRhs(n, 3, 4);
  const Eigen::MatrixXd expected = llt.solve(rhs);
  for (const CholmodFactorForm form : kForms) {
    SCOPED_TRACE(FormName(form));
    CholmodFactor factor(form);
    EXPECT_FALSE(factor.analyzed());
    const Status analysed = factor.Analyze(upper);
    ASSERT_TRUE(analysed.ok()) << analysed.message();
    EXPECT_TRUE(factor.analyzed());
    const Status factorized = factor.Factorize(upper);
    ASSERT_TRUE(factorized.ok()) << factorized.message();
    // Several right-hand sides at once, and one as a vector.
    const Eigen::MatrixXd x = factor.Solve(rhs);
    EXPECT_LT(MaxAbs(x - expected), kDirectSolveAgreement * MaxAbs(expected));
    const Eigen::VectorXd x0 = factor.Solve(Eigen::VectorXd(rhs.col(0)));
    EXPECT_LT(MaxAbs(x0 - expected.col(0)), kDirectSolveAgreement * MaxAbs(expected));
    // The pivots of a diagonally dominant matrix all lie near 20: their ratio near 1, and it is
    // the ratio of the smallest L_jj^2 to the largest.
    EXPECT_GT(factor.pivot_ratio(), 0.5);
    EXPECT_LE(factor.pivot_ratio(), 1.0);
    const int smallest = factor.smallest_pivot_column();
    EXPECT_GE(smallest, 0);
    EXPECT_LT(smallest, n);
    // The permutation is one.
    std::vector<int> permutation = factor.permutation();
    ASSERT_EQ(static_cast<int>(permutation.size()), n);
    std::sort(permutation.begin(), permutation.end());
    for (int k = 0; k < n; ++k) EXPECT_EQ(permutation[k], k);
  }
}

TEST(CholmodFactor, NotPositiveDefiniteIsAnErrorStatusAndNothingIsPrinted) {
  const int n = 60;
  const Eigen::MatrixXd dense = BandedSpd(n, 5);
  const SparseMatrix upper = Upper(dense);
  SparseMatrix indefinite = upper;
  indefinite.coeffRef(n / 2, n / 2) = -1.0;  // a negative diagonal: no pivot order saves it
  const Eigen::MatrixXd rhs = RandomRhs(n, 1, 6);
  for (const CholmodFactorForm form : kForms) {
    SCOPED_TRACE(FormName(form));
    CholmodFactor factor(form);
    ASSERT_TRUE(factor.Analyze(upper).ok());
    ::testing::internal::CaptureStdout();
    ::testing::internal::CaptureStderr();
    const Status status = factor.Factorize(indefinite);
    const std::string out = ::testing::internal::GetCapturedStdout();
    const std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_FALSE(status.ok());
    EXPECT_NE(status.message().find("not positive definite"), std::string::npos)
        << status.message();
    EXPECT_EQ(out, "");
    EXPECT_EQ(err, "");
    EXPECT_TRUE(factor.not_positive_definite());
    // The column of the factor where a pivot <= 0 was met; it holds S's column n / 2 or one
    // eliminated after it.
    const int bad = factor.bad_pivot_column();
    ASSERT_GE(bad, 0);
    ASSERT_LT(bad, n);
    EXPECT_EQ(factor.pivot_ratio(), 0.0);
    EXPECT_EQ(factor.smallest_pivot_column(), -1);
    EXPECT_EQ(factor.columns().n, 0);
    // No usable factor: no figure.
    EXPECT_TRUE(factor.Solve(rhs).array().isNaN().all());
    // New values on the same pattern: the factor is usable again.
    ASSERT_TRUE(factor.Factorize(upper).ok());
    EXPECT_FALSE(factor.not_positive_definite());
    EXPECT_EQ(factor.bad_pivot_column(), -1);
    const Eigen::MatrixXd expected = dense.llt().solve(rhs);
    EXPECT_LT(MaxAbs(factor.Solve(rhs) - expected), kDirectSolveAgreement * MaxAbs(expected));
  }
}

TEST(CholmodFactor, CholmodsOwnErrorsAreStatusAndNothingIsPrinted) {
  const int n = 12;
  const SparseMatrix upper = Upper(BandedSpd(n, 7));
  CholmodFactor factor(CholmodFactorForm::kSimplicialColumns);
  ::testing::internal::CaptureStdout();
  ::testing::internal::CaptureStderr();
  // Factorised before any analysis.
  const Status unanalysed = factor.Factorize(upper);
  // A "permutation" with a column twice: CHOLMOD refuses it (CHOLMOD_INVALID, through its error
  // handler).
  std::vector<int> twice(n);
  std::iota(twice.begin(), twice.end(), 0);
  twice[1] = 0;
  const Status invalid = factor.Analyze(upper, twice);
  // A matrix of another size than the one analysed.
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  const Status analysed = factor.Analyze(upper, order);
  const Status other_size = factor.Factorize(Upper(BandedSpd(n + 6, 7)));
  // Not compressed.
  SparseMatrix uncompressed = upper;
  uncompressed.uncompress();
  const Status not_compressed = factor.Analyze(uncompressed);
  const std::string out = ::testing::internal::GetCapturedStdout();
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_FALSE(unanalysed.ok());
  EXPECT_FALSE(invalid.ok());
  EXPECT_NE(invalid.message().find("CHOLMOD's analysis failed: invalid input"), std::string::npos)
      << invalid.message();
  EXPECT_TRUE(analysed.ok()) << analysed.message();
  EXPECT_FALSE(other_size.ok());
  EXPECT_FALSE(factor.not_positive_definite());
  EXPECT_FALSE(not_compressed.ok());
  EXPECT_FALSE(factor.analyzed());
  EXPECT_EQ(out, "");
  EXPECT_EQ(err, "");
  for (const Status* s : {&unanalysed, &invalid, &other_size, &not_compressed})
    EXPECT_EQ(s->message().find('\n'), std::string::npos) << s->message();  // one line each
}

TEST(CholmodFactor, RefactorisingOnTheAnalysedPatternEqualsAFreshAnalysis) {
  const int n = 48;
  const Eigen::MatrixXd first = BandedSpd(n, 8);
  // The same pattern, other values (as the next step of an adjustment brings).
  Eigen::MatrixXd second = BandedSpd(n, 9, 30.0);
  for (int c = 0; c < n; ++c)
    for (int r = 0; r < n; ++r)
      if (first(r, c) == 0.0) second(r, c) = 0.0;
  const SparseMatrix upper_first = Upper(first), upper_second = Upper(second);
  ASSERT_EQ(upper_first.nonZeros(), upper_second.nonZeros());
  const Eigen::MatrixXd rhs = RandomRhs(n, 2, 10);
  for (const CholmodFactorForm form : kForms) {
    SCOPED_TRACE(FormName(form));
    CholmodFactor reused(form), fresh(form);
    ASSERT_TRUE(reused.Analyze(upper_first).ok());
    ASSERT_TRUE(reused.Factorize(upper_first).ok());
    const Eigen::MatrixXd x_first = reused.Solve(rhs);
    ASSERT_TRUE(reused.Factorize(upper_second).ok());
    ASSERT_TRUE(fresh.Analyze(upper_second).ok());
    ASSERT_TRUE(fresh.Factorize(upper_second).ok());
    const Eigen::MatrixXd x_reused = reused.Solve(rhs), x_fresh = fresh.Solve(rhs);
    // The same analysis, the same arithmetic: bit for bit.
    for (int k = 0; k < x_fresh.size(); ++k) EXPECT_EQ(x_reused.data()[k], x_fresh.data()[k]);
    EXPECT_EQ(reused.pivot_ratio(), fresh.pivot_ratio());
    EXPECT_EQ(reused.permutation(), fresh.permutation());
    // And it is the second matrix's solution, not the first's.
    const Eigen::MatrixXd expected = second.llt().solve(rhs);
    EXPECT_LT(MaxAbs(x_reused - expected), kDirectSolveAgreement * MaxAbs(expected));
    EXPECT_GT(MaxAbs(x_reused - x_first), 1e-3 * MaxAbs(expected));
  }
}

TEST(CholmodFactor, GivenOrderAndTheFactorsColumns) {
  const int n = 36;
  const Eigen::MatrixXd dense = BandedSpd(n, 11);
  const SparseMatrix upper = Upper(dense);
  // AMD on the pattern of the matrix itself gives an order to hand back.
  std::vector<int> column_start = {0}, rows;
  for (int c = 0; c < n; ++c) {
    for (SparseMatrix::InnerIterator it(upper, c); it; ++it) rows.push_back(it.row());
    column_start.push_back(static_cast<int>(rows.size()));
  }
  CholmodFactor factor(CholmodFactorForm::kSimplicialColumns);
  std::vector<int> order;
  ASSERT_TRUE(factor.AmdOrder(n, column_start, rows, &order).ok());
  std::vector<int> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (int k = 0; k < n; ++k) ASSERT_EQ(sorted[k], k);
  // A reversed order, so that the given order is visibly kept (no postordering).
  std::reverse(order.begin(), order.end());
  ASSERT_TRUE(factor.Analyze(upper, order).ok());
  ASSERT_TRUE(factor.Factorize(upper).ok());
  EXPECT_EQ(factor.permutation(), order);
  // L from its columns: rows ascending, the diagonal first; L L^T = P S P^T.
  const CholmodFactor::Columns L = factor.columns();
  ASSERT_EQ(L.n, n);
  Eigen::MatrixXd L_dense = Eigen::MatrixXd::Zero(n, n);
  double smallest = std::numeric_limits<double>::infinity(), largest = 0.0;
  int smallest_column = -1;
  for (int j = 0; j < n; ++j) {
    ASSERT_LT(L.column_start[j], L.column_start[j + 1]);
    EXPECT_EQ(L.row[L.column_start[j]], j);
    EXPECT_TRUE(std::is_sorted(L.row + L.column_start[j], L.row + L.column_start[j + 1]));
    for (int t = L.column_start[j]; t < L.column_start[j + 1]; ++t)
      L_dense(L.row[t], j) = L.value[t];
    const double pivot = L_dense(j, j) * L_dense(j, j);
    if (pivot < smallest) {
      smallest = pivot;
      smallest_column = j;
    }
    largest = std::max(largest, pivot);
  }
  Eigen::MatrixXd permuted(n, n);
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) permuted(a, b) = dense(order[a], order[b]);
  EXPECT_LT(MaxAbs(L_dense * L_dense.transpose() - permuted), kFactorAgreement * MaxAbs(dense));
  EXPECT_EQ(factor.smallest_pivot_column(), smallest_column);
  EXPECT_NEAR(factor.pivot_ratio(), smallest / largest, 1e-14);
  // The supernodal form in the same order: the same pivots, read from its supernodes; no columns
  // to read.
  CholmodFactor supernodal(CholmodFactorForm::kSupernodal);
  ASSERT_TRUE(supernodal.Analyze(upper, order).ok());
  ASSERT_TRUE(supernodal.Factorize(upper).ok());
  EXPECT_EQ(supernodal.permutation(), order);
  EXPECT_EQ(supernodal.smallest_pivot_column(), smallest_column);
  EXPECT_NEAR(supernodal.pivot_ratio(), smallest / largest, 1e-14);
  EXPECT_EQ(supernodal.columns().n, 0);
}

TEST(CholmodFactor, EmptyMatrix) {
  const SparseMatrix empty(0, 0);
  CholmodFactor factor;
  const Status analysed = factor.Analyze(empty);
  ASSERT_TRUE(analysed.ok()) << analysed.message();
  ASSERT_TRUE(factor.Factorize(empty).ok());
  EXPECT_EQ(factor.pivot_ratio(), 1.0);
  EXPECT_EQ(factor.smallest_pivot_column(), -1);
  EXPECT_EQ(factor.Solve(Eigen::VectorXd()).size(), 0);
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose::internal
