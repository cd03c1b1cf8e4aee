// The Taylor bundle's per-mark and per-point storage (solvers/bundle/internal/taylor_normals.h):
// IndexLists against a vector of vectors built from the same entries, a mark's W and g_p part
// made from its stored rows (MarkW, MarkGp) against the products written out by hand, and
// BuildLayout's image order and mark lists against the same things made the plain way.
#include "solvers/bundle/internal/taylor_normals.h"

#include <gtest/gtest.h>

#include <Eigen/OrderingMethods>
#include <random>
#include <vector>

#include "core/simulation/synthetic_block.h"
#include "tests/support/exact_block.h"

namespace photopose::internal::taylor {
namespace PHOTOPOSE_UNITY_ID {

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

// A plan for BuildLayout alone: every mark used but every fifth, the first image and the control
// points held constant, no priors, no calibration.
Plan LayoutPlan(const Block& block) {
  Plan plan;
  plan.mark_used.assign(block.marks.size(), 1);
  for (size_t m = 0; m < block.marks.size(); m += 5) plan.mark_used[m] = 0;
  plan.point_in_problem.assign(block.points.size(), 1);
  plan.point_constant.assign(block.points.size(), 0);
  for (size_t p = 0; p < block.points.size(); ++p)
    plan.point_constant[p] = block.points[p].role == PointRole::kControl;
  plan.point_prior.assign(block.points.size(), 0);
  plan.image_constant.assign(block.images.size(), 0);
  plan.image_constant[0] = 1;
  plan.image_fixed.assign(block.images.size(), std::array<bool, 6>{});
  plan.image_prior.assign(block.images.size(), 0);
  plan.image_prior_height.assign(block.images.size(), 1);
  plan.image_attitude.assign(block.images.size(), 0);
  plan.calibrated.assign(block.cameras.size(), {});
  return plan;
}

TEST(BuildLayout, ImageOrderAndMarkListsAsMadeThePlainWay) {
  SyntheticBlockOptions options;
  options.num_lines = 3;
  options.images_per_line = 6;
  options.num_tie_points = 150;
  Block block = photopose::testing::MakeExactBlock(options).block;
  block.BuildIndex();
  const Plan plan = LayoutPlan(block);
  Layout layout;
  BuildLayout(block, plan, &layout);

  // The fill-reducing order: AMD on the graph with an entry for every two images of every free
  // point (each pair as often as points share it), as it was built before it was built pair by
  // pair.
  std::vector<int> free_images, block_of(block.images.size(), -1);
  for (size_t i = 0; i < block.images.size(); ++i) {
    if (plan.image_constant[i]) continue;
    block_of[i] = static_cast<int>(free_images.size());
    free_images.push_back(static_cast<int>(i));
  }
  const int num_blocks = static_cast<int>(free_images.size());
  std::vector<Eigen::Triplet<double, int>> entries;
  for (size_t p = 0; p < block.points.size(); ++p) {
    if (plan.point_constant[p]) continue;
    std::vector<int> seen;
    for (const int m : block.marks_of_point[p])
      if (plan.mark_used[m] && block_of[block.marks[m].image] >= 0)
        seen.push_back(block_of[block.marks[m].image]);
    for (const int b1 : seen)
      for (const int b2 : seen) entries.emplace_back(b1, b2, 1.0);
  }
  for (int b = 0; b < num_blocks; ++b) entries.emplace_back(b, b, 1.0);
  SparseMatrix graph(num_blocks, num_blocks);
  graph.setFromTriplets(entries.begin(), entries.end());
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> order;
  Eigen::AMDOrdering<int>()(graph, order);
  std::vector<int> expected_order(num_blocks);
  for (int k = 0; k < num_blocks; ++k) expected_order[k] = free_images[order.indices()[k]];
  ASSERT_GT(num_blocks, 10);
  EXPECT_EQ(layout.free_images, expected_order);

  // The mark lists: positions in layout.marks, in mark order.
  ASSERT_EQ(layout.image_marks.size(), block.images.size());
  ASSERT_EQ(layout.point_marks.size(), layout.free_points.size());
  std::vector<std::vector<int>> image_marks(block.images.size());
  std::vector<std::vector<int>> point_marks(layout.free_points.size());
  std::vector<std::vector<int>> point_all_marks(layout.free_points.size());
  int k = 0;
  for (size_t m = 0; m < block.marks.size(); ++m) {
    if (!plan.mark_used[m]) continue;
    ASSERT_EQ(layout.marks[k], static_cast<int>(m));
    const int q = layout.point_block[block.marks[m].point];
    image_marks[block.marks[m].image].push_back(k);
    if (q >= 0) point_all_marks[q].push_back(k);
    if (q >= 0 && layout.image_block[block.marks[m].image] >= 0) point_marks[q].push_back(k);
    ++k;
  }
  ASSERT_EQ(static_cast<size_t>(k), layout.marks.size());
  const auto as_vector = [](IndexLists::List list) { return std::vector<int>(list.begin(), list.end()); };
  for (size_t i = 0; i < block.images.size(); ++i)
    EXPECT_EQ(as_vector(layout.image_marks[i]), image_marks[i]) << "image " << i;
  for (size_t q = 0; q < layout.free_points.size(); ++q) {
    EXPECT_EQ(as_vector(layout.point_marks[q]), point_marks[q]) << "point " << q;
    EXPECT_EQ(as_vector(layout.point_all_marks[q]), point_all_marks[q]) << "point " << q;
    const size_t n = point_marks[q].size();
    EXPECT_EQ(layout.point_pairs[q].size(), n * (n + 1) / 2) << "point " << q;
  }
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose::internal::taylor
