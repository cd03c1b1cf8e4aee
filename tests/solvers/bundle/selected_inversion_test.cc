#include "solvers/bundle/internal/selected_inversion.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>
#include <vector>

namespace photopose::internal {
namespace PHOTOPOSE_UNITY_ID {

// Selected and dense inverses agree to this, relative to sqrt(C_ii C_jj) (the correlation
// scale): both are exact up to rounding of a well-conditioned matrix.
constexpr double kRelative = 1e-10;

struct BlockMatrix {
  SelectedInverse::SparseMatrix upper;
  Eigen::MatrixXd dense;
  std::vector<int> block_start;
  std::vector<std::vector<char>> coupled;  // per pair of blocks: a nonzero block of S
};

// A random symmetric positive definite matrix of blocks of 6, 3 and 9 columns coupled along a
// band and at a few random places (a block's "neighbours"), with each block's columns in units
// `unit[b]` apart (as um and mm^-6 are).
BlockMatrix RandomBlockMatrix(int num_blocks, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  BlockMatrix m;
  m.block_start.push_back(0);
  std::vector<double> unit;
  for (int b = 0; b < num_blocks; ++b) {
    const int size = b % 7 == 3 ? 9 : (b % 5 == 1 ? 3 : 6);
    m.block_start.push_back(m.block_start.back() + size);
    unit.push_back(std::pow(10.0, 6.0 * uniform(rng)));
  }
  const int n = m.block_start.back();
  // S = J^T J + identity-ish, J with rows touching two or three blocks.
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(n, n);
  m.coupled.assign(num_blocks, std::vector<char>(num_blocks, 0));
  std::uniform_int_distribution<int> pick(0, num_blocks - 1);
  for (int r = 0; r < 8 * num_blocks; ++r) {
    std::vector<int> blocks = {r % num_blocks, (r % num_blocks + 1 + r % 3) % num_blocks};
    if (r % 4 == 0) blocks.push_back(pick(rng));
    Eigen::VectorXd row = Eigen::VectorXd::Zero(n);
    for (const int b : blocks)
      for (int c = m.block_start[b]; c < m.block_start[b + 1]; ++c) row[c] = uniform(rng);
    S += row * row.transpose();
    for (const int a : blocks)
      for (const int b : blocks) m.coupled[a][b] = 1;
  }
  S += 0.1 * Eigen::MatrixXd::Identity(n, n);
  for (int b = 0; b < num_blocks; ++b) {
    for (int c = m.block_start[b]; c < m.block_start[b + 1]; ++c) {
      S.row(c) *= unit[b];
      S.col(c) *= unit[b];
    }
  }
  m.dense = S;
  std::vector<Eigen::Triplet<double, int>> entries;
  for (int a = 0; a < num_blocks; ++a)
    for (int b = a; b < num_blocks; ++b)
      if (m.coupled[a][b])
        for (int r = m.block_start[a]; r < m.block_start[a + 1]; ++r)
          for (int c = m.block_start[b]; c < m.block_start[b + 1]; ++c)
            entries.emplace_back(r, c, S(r, c));
  m.upper.resize(n, n);
  m.upper.setFromTriplets(entries.begin(), entries.end());
  return m;
}

// The dense inverse, through the Jacobi-scaled matrix (the units would cost the plain inverse its
// digits).
Eigen::MatrixXd Oracle(const Eigen::MatrixXd& S) {
  const Eigen::VectorXd d = S.diagonal().cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd A = d.asDiagonal() * S * d.asDiagonal();
  return d.asDiagonal() * A.ldlt().solve(Eigen::MatrixXd::Identity(S.rows(), S.cols())) *
         d.asDiagonal();
}

// The upper triangle of [a b; b c].
SelectedInverse::SparseMatrix TwoByTwo(double a, double b, double c) {
  SelectedInverse::SparseMatrix S(2, 2);
  S.insert(0, 0) = a;
  S.insert(0, 1) = b;
  S.insert(1, 1) = c;
  return S;
}

TEST(SelectedInversion, HandComputedTwoByTwo) {
  // S = [4 2; 2 3], S^-1 = [3 -2; -2 4] / 8, as two blocks of one column.
  const SelectedInverse::SparseMatrix S = TwoByTwo(4.0, 2.0, 3.0);
  SelectedInverse C;
  ASSERT_TRUE(C.Compute(S, {0, 1, 2}, SelectedInversionOptions()).ok());
  Eigen::MatrixXd block;
  ASSERT_TRUE(C.Block(0, 0, &block));
  EXPECT_NEAR(block(0, 0), 3.0 / 8.0, 1e-15);
  ASSERT_TRUE(C.Block(1, 0, &block));
  EXPECT_NEAR(block(0, 0), -2.0 / 8.0, 1e-15);
  ASSERT_TRUE(C.Block(0, 1, &block));
  EXPECT_NEAR(block(0, 0), -2.0 / 8.0, 1e-15);
  ASSERT_TRUE(C.Block(1, 1, &block));
  EXPECT_NEAR(block(0, 0), 4.0 / 8.0, 1e-15);
}

TEST(SelectedInversion, EveryBlockOfSEqualsTheDenseInverse) {
  for (const uint32_t seed : {1u, 2u, 3u}) {
    const BlockMatrix m = RandomBlockMatrix(60, seed);
    const Eigen::MatrixXd oracle = Oracle(m.dense);
    SelectedInverse C;
    const Status status = C.Compute(m.upper, m.block_start, SelectedInversionOptions());
    ASSERT_TRUE(status.ok()) << status.message();
    const int num_blocks = static_cast<int>(m.block_start.size()) - 1;
    int compared = 0, beyond = 0;
    Eigen::MatrixXd block;
    for (int a = 0; a < num_blocks; ++a) {
      for (int b = 0; b < num_blocks; ++b) {
        const bool known = C.Block(a, b, &block);
        // What the statistics need, the pattern of S, is always known.
        if (m.coupled[a][b]) ASSERT_TRUE(known) << a << " " << b;
        if (!known) continue;
        beyond += !m.coupled[a][b];  // the fill-in is exact too
        for (int r = 0; r < block.rows(); ++r) {
          for (int c = 0; c < block.cols(); ++c) {
            const int i = m.block_start[a] + r, j = m.block_start[b] + c;
            const double yardstick = std::sqrt(oracle(i, i) * oracle(j, j));
            EXPECT_NEAR(block(r, c), oracle(i, j), kRelative * yardstick) << i << " " << j;
            ++compared;
          }
        }
      }
    }
    EXPECT_GT(compared, 0);
    EXPECT_GT(beyond, 0);  // the band's fill reaches beyond S's pattern
    EXPECT_LT(C.num_entries(), m.dense.size() / 2);  // and is not the dense inverse
    // Off the pattern, through the factor.
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(m.dense.rows(), 2);
    rhs(0, 0) = 1.0;
    rhs(m.dense.rows() - 1, 1) = 2.0;
    const Eigen::MatrixXd solved = C.Solve(rhs);
    const Eigen::MatrixXd expected = oracle * rhs;
    const int last = static_cast<int>(rhs.rows()) - 1;
    for (int r = 0; r < rhs.rows(); ++r) {
      EXPECT_NEAR(solved(r, 0), expected(r, 0), kRelative * std::sqrt(oracle(r, r) * oracle(0, 0)));
      EXPECT_NEAR(solved(r, 1), expected(r, 1),
                  kRelative * 2.0 * std::sqrt(oracle(r, r) * oracle(last, last)));
    }
  }
}

TEST(SelectedInversion, DenseOracleModeGivesEveryEntry) {
  const BlockMatrix m = RandomBlockMatrix(20, 7);
  SelectedInversionOptions options;
  options.dense = true;
  SelectedInverse C;
  ASSERT_TRUE(C.Compute(m.upper, m.block_start, options).ok());
  const Eigen::MatrixXd oracle = Oracle(m.dense);
  Eigen::MatrixXd block;
  ASSERT_TRUE(C.Block(0, 19, &block));
  const int i = 0, j = m.block_start[19];
  EXPECT_NEAR(block(0, 0), oracle(i, j), kRelative * std::sqrt(oracle(i, i) * oracle(j, j)));
  EXPECT_EQ(C.num_entries(), m.dense.size());
}

TEST(SelectedInversion, SingularMatrixIsAnErrorNotAnAbort) {
  // Rank 1: [1 1; 1 1] (in blocks of one), then a column without weight.
  const SelectedInverse::SparseMatrix S = TwoByTwo(1.0, 1.0, 1.0);
  SelectedInverse C;
  EXPECT_FALSE(C.Compute(S, {0, 1, 2}, SelectedInversionOptions()).ok());
  SelectedInversionOptions dense;
  dense.dense = true;
  EXPECT_FALSE(C.Compute(S, {0, 1, 2}, dense).ok());
  SelectedInverse::SparseMatrix T(2, 2);
  T.insert(0, 0) = 1.0;
  EXPECT_FALSE(C.Compute(T, {0, 2}, SelectedInversionOptions()).ok());
  // Blocks that do not partition the matrix.
  EXPECT_FALSE(C.Compute(S, {0, 1}, SelectedInversionOptions()).ok());
}

TEST(SelectedInversion, ASingularMatrixNamesAColumnOfItsDefect) {
  // S = J^T J over blocks {0, 1}, {2, 3}, {4} with column 3 = column 0 + 2 column 1: the null
  // vector (1, 2, 0, -1, 0). A Cholesky meets the defect at the last of columns 0, 1, 3 in its
  // order: 3 in the blocks' own order (the dense path), one of the three in the sparse factor's.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::MatrixXd J(12, 5);
  for (int r = 0; r < J.rows(); ++r)
    for (int c = 0; c < J.cols(); ++c) J(r, c) = uniform(rng);
  J.col(3) = J.col(0) + 2.0 * J.col(1);
  const Eigen::MatrixXd S = J.transpose() * J;
  SelectedInverse::SparseMatrix upper(5, 5);
  for (int c = 0; c < 5; ++c)
    for (int r = 0; r <= c; ++r) upper.insert(r, c) = S(r, c);
  const std::vector<int> blocks = {0, 2, 4, 5};
  SelectedInverse C;
  EXPECT_FALSE(C.Compute(upper, blocks, SelectedInversionOptions()).ok());
  EXPECT_TRUE(C.singular());
  EXPECT_TRUE(C.singular_column() == 0 || C.singular_column() == 1 || C.singular_column() == 3)
      << C.singular_column();
  SelectedInversionOptions dense;
  dense.dense = true;
  EXPECT_FALSE(C.Compute(upper, blocks, dense).ok());
  EXPECT_TRUE(C.singular());
  EXPECT_EQ(C.singular_column(), 3);
  // Factorising only finds it too.
  SelectedInversionOptions factor_only;
  factor_only.factor_only = true;
  EXPECT_FALSE(C.Compute(upper, blocks, factor_only).ok());
  EXPECT_TRUE(C.singular());
  // A column without weight is named as such; a regular matrix is not singular, and factorising
  // only keeps no entry of the inverse.
  SelectedInverse::SparseMatrix T(2, 2);
  T.insert(0, 0) = 1.0;
  EXPECT_FALSE(C.Compute(T, {0, 1, 2}, SelectedInversionOptions()).ok());
  EXPECT_EQ(C.singular_column(), 1);
  ASSERT_TRUE(C.Compute(TwoByTwo(4.0, 2.0, 3.0), {0, 1, 2}, factor_only).ok());
  EXPECT_FALSE(C.singular());
  EXPECT_EQ(C.singular_column(), -1);
  Eigen::MatrixXd block;
  EXPECT_FALSE(C.Block(0, 0, &block));
  EXPECT_TRUE(C.Solve(Eigen::MatrixXd::Ones(2, 1)).hasNaN());
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose::internal
