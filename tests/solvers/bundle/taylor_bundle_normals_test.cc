// The Taylor bundle's per-mark and per-point storage (solvers/bundle/internal/taylor_normals.h):
// IndexLists against a vector of vectors built from the same entries, a mark's W and g_p part
// made from its stored rows (MarkW, MarkGp) against the products written out by hand.
#include "solvers/bundle/internal/taylor_normals.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace photopose::internal::taylor {
namespace {

TEST(IndexLists, HoldWhatAVectorPerListHolds) {
  std::mt19937 rng(23);
  std::uniform_int_distribution<int> list_of(0, 6);  // list 7 of 8 gets nothing
  std::vector<std::pair<int, int>> entries;          // (list, item) in the order added
  for (int item = 0; item < 200; ++item) entries.emplace_back(list_of(rng), item);
  std::vector<std::vector<int>> expected(8);
  for (const auto& [list, item] : entries) expected[list].push_back(item);

  IndexLists lists;
  lists.Reset(expected.size());
  for (const auto& entry : entries) lists.Count(entry.first);
  lists.Allocate();
  for (const auto& [list, item] : entries) lists.Add(list, item);
  lists.Finish();

  ASSERT_EQ(lists.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) {
    const IndexLists::List list = lists[i];
    ASSERT_EQ(list.size(), expected[i].size()) << "list " << i;
    EXPECT_EQ(std::vector<int>(list.begin(), list.end()), expected[i]) << "list " << i;
    for (size_t k = 0; k < list.size(); ++k) EXPECT_EQ(list[k], expected[i][k]);
  }
  EXPECT_EQ(lists[7].size(), 0u);
}

TEST(IndexLists, EntriesWrittenInPlace) {
  IndexLists lists;
  lists.Reset(3);
  lists.Count(0, 3);
  lists.Count(2, 1);
  lists.Allocate();
  lists.Finish();
  int* first = lists.Entries(0);
  first[0] = 5;
  first[1] = 6;
  first[2] = 7;
  lists.Entries(2)[0] = 9;
  EXPECT_EQ(std::vector<int>(lists[0].begin(), lists[0].end()), (std::vector<int>{5, 6, 7}));
  EXPECT_EQ(lists[1].size(), 0u);
  EXPECT_EQ(std::vector<int>(lists[2].begin(), lists[2].end()), (std::vector<int>{9}));
}

// A mark's W = w A_e^T A_p and g_p = w A_p^T F, with A_p = -(A_e's first three columns) (dF/dX =
// -dF/dX0), written out entry by entry. Rounding only: a few units of the last place of entries
// of order 10.
constexpr double kProductAgreement = 1e-13;

TEST(MarkRows, WAndGradientPartAreTheHandWrittenProducts) {
  MarkRows rows;
  rows.A_e << 1.5, -2.0, 0.25, 3.0, -1.0, 0.5,  //
      -0.75, 1.25, 2.5, -0.5, 4.0, -3.0;
  rows.f = Eigen::Vector2d(0.3, -1.7);
  rows.weight = 2.5;
  const Matrix63 W = MarkW(rows);
  const Eigen::Vector3d gp = MarkGp(rows);
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 3; ++c) {
      const double expected = rows.weight * (rows.A_e(0, r) * -rows.A_e(0, c) +
                                             rows.A_e(1, r) * -rows.A_e(1, c));
      EXPECT_NEAR(W(r, c), expected, kProductAgreement) << r << ", " << c;
    }
  }
  for (int c = 0; c < 3; ++c) {
    const double expected =
        rows.weight * (-rows.A_e(0, c) * rows.f[0] + -rows.A_e(1, c) * rows.f[1]);
    EXPECT_NEAR(gp[c], expected, kProductAgreement) << c;
  }
  // V's part: the top of -W is w A_p^T A_p, symmetric with a positive diagonal.
  const Eigen::Matrix3d V = -W.topRows<3>();
  EXPECT_NEAR((V - V.transpose()).cwiseAbs().maxCoeff(), 0.0, kProductAgreement);
  EXPECT_GT(V.diagonal().minCoeff(), 0.0);
}

}  // namespace
}  // namespace photopose::internal::taylor
