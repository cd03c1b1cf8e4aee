// The Taylor bundle's per-mark and per-point storage (solvers/bundle/internal/taylor_normals.h):
// IndexLists against a vector of vectors built from the same entries, a mark's W and g_p part
// made from its rows (MarkW, MarkGp) against the products written out by hand, the rows made
// again (MarkRowsAt) against those of the first linearisation after the state has moved, a small
// block's kept W (LinearizationPoint::kept_W) against W made again, and BuildLayout's image order
// and mark lists against the same things made the plain way.
#include <gtest/gtest.h>

#include <Eigen/OrderingMethods>
#include <random>
#include <vector>

#include "core/simulation/synthetic_block.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/bundle/internal/taylor_normals.h"
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

// A block linearised as the Taylor adjustment's first round linearises it (its plan, frame,
// layout and normal equations at the generator's perturbed start), on two threads. Made in place:
// the normal equations point into the block, plan and frame.
struct Linearised {
  Block block;
  Plan plan;
  Frame frame;
  State state;
  Layout layout;
  Normal normal;
};

void Linearise(const TaylorBundleOptions& options, const std::vector<std::string>& calibrate,
               Linearised* out) {
  SyntheticBlockTruth truth;
  ASSERT_TRUE(MakeSyntheticBlock(SolverBenchmarkBlockOptions(3, 6, 250), &out->block, &truth).ok());
  out->block.BuildIndex();
  BundleAdjustmentConfig config;
  if (!calibrate.empty())
    ASSERT_TRUE(BundleAdjustmentConfig::FromCalibrationNames(out->block, calibrate, &config).ok());
  ASSERT_TRUE(MakePlan(options, config, out->block, &out->plan).ok());
  out->frame = MakeFrame(config, out->block, out->plan, &out->state);
  BuildLayout(out->block, out->plan, &out->layout);
  ASSERT_TRUE(Linearize(options.partials, out->block, out->plan, out->layout, out->frame,
                        out->state, /*num_threads=*/2, &out->normal, nullptr));
}

// The points eliminated and the reduced system solved, undamped: (d_e, d_p).
void SolveOnce(const Plan& plan, Layout* layout, const Normal& normal, Eigen::VectorXd* d_e,
               std::vector<Eigen::Vector3d>* d_p) {
  Reduction reduction;
  reduction.num_threads = 2;
  ASSERT_EQ(Reduce(normal, *layout, &reduction), -1);
  ASSERT_EQ(WriteScaled(plan, layout, &reduction), -1);
  ASSERT_TRUE(Factorize(1e-14, *layout, &reduction));
  SolveCorrections(plan, *layout, normal, reduction, d_e, d_p);
}

void ExpectSameRows(const MarkRows& a, const MarkRows& b, int m) {
  EXPECT_EQ(a.A_e, b.A_e) << "mark " << m;
  EXPECT_EQ(a.f, b.f) << "mark " << m;
  EXPECT_EQ(a.weight, b.weight) << "mark " << m;
  EXPECT_EQ(a.cost, b.cost) << "mark " << m;
  ASSERT_EQ(a.num_calibration, b.num_calibration) << "mark " << m;
  for (int j = 0; j < a.num_calibration; ++j) {
    EXPECT_EQ(a.calib_u[j], b.calib_u[j]) << "mark " << m << ", parameter " << j;
    EXPECT_EQ(a.calib_v[j], b.calib_v[j]) << "mark " << m << ", parameter " << j;
  }
}

// The rows are not kept per mark but made again where they are needed (MarkRowsAt). Made again
// after the caller's state has moved (a step taken or tried, as the rounds do), they are the
// rows of the first linearisation bit for bit, and so are the elimination and the
// back-substitution that read them; the points' sums Linearize made are sums of those same rows.
// With a robust tie loss (the weight depends on F) and with self-calibration (the Jet with the
// calibration's derivatives, whose rows enter the global columns).
TEST(MarkRowsAt, MadeAgainEqualTheFirstLinearisationBitForBit) {
  struct Case {
    const char* name;
    LossType tie_loss;
    std::vector<std::string> calibrate;
  };
  for (const Case& c : {Case{"Cauchy tie loss", LossType::kCauchy, {}},
                        Case{"self-calibrated c, K1", LossType::kNone, {"FocalLength", "K1"}}}) {
    SCOPED_TRACE(c.name);
    TaylorBundleOptions options;
    options.tie_loss = c.tie_loss;
    Linearised data;
    Linearise(options, c.calibrate, &data);
    ASSERT_FALSE(::testing::Test::HasFatalFailure());
    const Layout& layout = data.layout;
    const Normal& normal = data.normal;
    ASSERT_EQ(layout.num_global > 0, !c.calibrate.empty());

    std::vector<MarkRows> first(layout.marks.size());
    for (size_t k = 0; k < layout.marks.size(); ++k)
      ASSERT_TRUE(MarkRowsAt(normal.at, MarkInputOf(data.block, data.plan, layout.marks[k]),
                             data.block.marks[layout.marks[k]].point, &first[k]));
    int weighted_down = 0;  // tie marks whose loss lowered their weight
    for (size_t k = 0; k < layout.marks.size(); ++k) {
      const int m = layout.marks[k];
      weighted_down += first[k].weight < 1.0 / (data.plan.mark_sigma[m] * data.plan.mark_sigma[m]);
    }
    EXPECT_EQ(weighted_down > 0, c.tie_loss != LossType::kNone);
    // The points' sums of the linearisation (points without a prior: a control point's prior is
    // added after its marks).
    int checked = 0;
    for (size_t q = 0; q < layout.free_points.size(); ++q) {
      if (data.plan.point_prior[layout.free_points[q]]) continue;
      Eigen::Matrix3d V = Eigen::Matrix3d::Zero();
      Eigen::Vector3d gp = Eigen::Vector3d::Zero();
      for (const int k : layout.point_all_marks[q]) {
        V -= MarkW(first[k]).topRows<3>();
        gp += MarkGp(first[k]);
      }
      EXPECT_EQ(normal.V[q], V) << "point " << q;
      EXPECT_EQ(normal.gp[q], gp) << "point " << q;
      ++checked;
    }
    EXPECT_GT(checked, 200);
    Eigen::VectorXd d_e;
    std::vector<Eigen::Vector3d> d_p;
    SolveOnce(data.plan, &data.layout, normal, &d_e, &d_p);
    ASSERT_FALSE(::testing::Test::HasFatalFailure());

    // The caller's state moved: the step applied, and the calibration changed.
    for (size_t b = 0; b < layout.free_images.size(); ++b)
      data.state.eo[layout.free_images[b]] -= d_e.segment<6>(6 * b);
    for (size_t q = 0; q < layout.free_points.size(); ++q)
      data.state.points[layout.free_points[q]] -= d_p[q];
    for (std::vector<double>& camera : data.state.cameras) camera[0] *= 1.01;
    for (size_t k = 0; k < layout.marks.size(); ++k) {
      MarkRows again;
      ASSERT_TRUE(MarkRowsAt(normal.at, MarkInputOf(data.block, data.plan, layout.marks[k]),
                             data.block.marks[layout.marks[k]].point, &again));
      ExpectSameRows(again, first[k], layout.marks[k]);
    }
    Eigen::VectorXd d_e_again;
    std::vector<Eigen::Vector3d> d_p_again;
    SolveOnce(data.plan, &data.layout, normal, &d_e_again, &d_p_again);
    EXPECT_EQ(d_e_again, d_e);
    EXPECT_EQ(d_p_again, d_p);
  }
}

// A small block's marks' W and g_p shares kept by Linearize (LinearizationPoint::kept_W,
// kept_gp), read by the points' sums, the elimination and the back-substitution instead of rows
// made again: after a step and a second linearisation into the same normal equations, each kept W
// and g_p share is that of the mark's rows made again at the second linearisation point bit for
// bit (none of the first's left), each point's V and g_p the sum of those, and the step
// solved from the kept W is the step solved from the rows made again, bit for bit.
TEST(KeptW, IsEachMarksWOfTheLatestLinearisationBitForBit) {
  const TaylorBundleOptions options;
  Linearised data;
  Linearise(options, {}, &data);
  ASSERT_FALSE(::testing::Test::HasFatalFailure());
  Layout& layout = data.layout;
  ASSERT_TRUE(KeepsMarkW(layout.point_mark_inputs.size()));
  ASSERT_EQ(data.normal.at.kept_W.size(), layout.point_mark_inputs.size());
  Eigen::VectorXd d_e;
  std::vector<Eigen::Vector3d> d_p;
  SolveOnce(data.plan, &layout, data.normal, &d_e, &d_p);
  ASSERT_FALSE(::testing::Test::HasFatalFailure());
  for (size_t b = 0; b < layout.free_images.size(); ++b)
    data.state.eo[layout.free_images[b]] -= d_e.segment<6>(6 * b);
  for (size_t q = 0; q < layout.free_points.size(); ++q)
    data.state.points[layout.free_points[q]] -= d_p[q];
  ASSERT_TRUE(Linearize(options.partials, data.block, data.plan, layout, data.frame, data.state,
                        /*num_threads=*/2, &data.normal, nullptr));
  const Normal& normal = data.normal;
  ASSERT_EQ(normal.at.kept_W.size(), layout.point_mark_inputs.size());
  ASSERT_EQ(normal.at.kept_gp.size(), layout.point_mark_inputs.size());
  // The same linearisation with nothing kept (the layout without the image pass's positions):
  // its points' sums made from the rows made again.
  Layout keeps_nothing = layout;
  keeps_nothing.point_position.clear();
  Normal summed_again;
  ASSERT_TRUE(Linearize(options.partials, data.block, data.plan, keeps_nothing, data.frame,
                        data.state, /*num_threads=*/2, &summed_again, nullptr));
  ASSERT_TRUE(summed_again.at.kept_W.empty());
  ASSERT_TRUE(summed_again.at.kept_gp.empty());
  size_t checked = 0;
  for (size_t q = 0; q < layout.free_points.size(); ++q) {
    // The points' sums read from what the image pass kept: the sums of the rows made again.
    EXPECT_EQ(normal.V[q], summed_again.V[q]) << "point " << q;
    EXPECT_EQ(normal.gp[q], summed_again.gp[q]) << "point " << q;
    for (size_t j = 0; j < layout.point_all_marks[q].size(); ++j) {
      const size_t position = layout.point_all_marks.Offset(q) + j;
      MarkRows rows;
      ASSERT_TRUE(
          MarkRowsAt(normal.at, layout.point_mark_inputs[position], layout.free_points[q], &rows));
      EXPECT_EQ(normal.at.kept_W[position], MarkW(rows)) << "point " << q << ", mark " << j;
      EXPECT_EQ(normal.at.kept_gp[position], MarkGp(rows)) << "point " << q << ", mark " << j;
      ++checked;
    }
  }
  EXPECT_EQ(checked, layout.point_mark_inputs.size());
  Normal made_again = normal;
  made_again.at.kept_W.clear();
  made_again.at.kept_gp.clear();
  Eigen::VectorXd d_e_kept, d_e_again;
  std::vector<Eigen::Vector3d> d_p_kept, d_p_again;
  SolveOnce(data.plan, &layout, normal, &d_e_kept, &d_p_kept);
  SolveOnce(data.plan, &layout, made_again, &d_e_again, &d_p_again);
  ASSERT_FALSE(::testing::Test::HasFatalFailure());
  EXPECT_EQ(d_e_kept, d_e_again);
  EXPECT_EQ(d_p_kept, d_p_again);
}

// The budget: the 60- and 150-image benchmark blocks (10 444 and 37 564 marks) keep their W and
// g_p shares, the 1000-image block (1 713 495) does not; the limit itself is kept.
TEST(KeptW, KeptUpToTheBudget) {
  const size_t limit = kKeptWBudgetBytes / kKeptBytesPerMark;
  EXPECT_EQ(limit, 49932u);
  EXPECT_TRUE(KeepsMarkW(10444));
  EXPECT_TRUE(KeepsMarkW(37564));
  EXPECT_TRUE(KeepsMarkW(limit));
  EXPECT_FALSE(KeepsMarkW(limit + 1));
  EXPECT_FALSE(KeepsMarkW(1713495));
}

// A plan for BuildLayout alone: every mark used but every fifth, the first image and the control
// points held constant, no priors, no calibration.
Plan LayoutPlan(const Block& block) {
  Plan plan;
  plan.mark_used.assign(block.marks.size(), 1);
  for (size_t m = 0; m < block.marks.size(); m += 5) plan.mark_used[m] = 0;
  plan.mark_sigma.assign(block.marks.size(), 1.0);
  plan.ideal_um.assign(block.marks.size(), Eigen::Vector2d::Zero());
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
    // Each of its marks' inputs beside its entry, in the list's order.
    for (size_t j = 0; j < point_all_marks[q].size(); ++j) {
      const MarkInput& input = layout.point_mark_inputs[layout.point_all_marks.Offset(q) + j];
      const int m = layout.marks[point_all_marks[q][j]];
      EXPECT_EQ(input.m, m) << "point " << q;
      EXPECT_EQ(input.image, block.marks[m].image) << "point " << q;
    }
    const size_t n = point_marks[q].size();
    EXPECT_EQ(layout.point_pairs[q].size(), n * (n + 1) / 2) << "point " << q;
  }
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose::internal::taylor
