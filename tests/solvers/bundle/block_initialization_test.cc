#include "solvers/bundle/block_initialization.h"

#include <gtest/gtest.h>

#include "core/simulation/synthetic_block.h"
#include "solvers/bundle/bundle_adjustment.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

SyntheticBlockOptions SmallBlock() {
  SyntheticBlockOptions o;
  o.seed = 11;
  o.num_lines = 3;
  o.images_per_line = 6;
  o.tie_point_start = false;  // every tie point to intersect
  return o;
}

TEST(BlockInitialization, OrientsImagesAndIntersectsTiePointsNearTheTruth) {
  Block block;
  SyntheticBlockTruth truth;
  ASSERT_TRUE(MakeSyntheticBlock(SmallBlock(), &block, &truth).ok());
  // Half the images without start values: they are resected from control points or from the tie
  // points the others let intersect.
  for (size_t i = 0; i < block.images.size(); i += 2) block.images[i].eo.reset();
  BlockInitializationSummary summary;
  ASSERT_TRUE(InitializeBlock(BlockInitializationOptions(), &block, &summary).ok());
  EXPECT_TRUE(summary.not_oriented.empty()) << summary.BriefReport();
  EXPECT_EQ(summary.images_given, 9);
  EXPECT_EQ(summary.images_resected, 9);
  EXPECT_GT(summary.points_triangulated, 0);
  for (size_t i = 0; i < block.images.size(); ++i)
    ASSERT_TRUE(block.images[i].eo.has_value()) << i;
  int tie = 0, positioned = 0;
  for (const BlockPoint& point : block.points) {
    if (point.role != PointRole::kTie) continue;
    ++tie;
    positioned += point.position_m.has_value();
  }
  EXPECT_EQ(positioned + summary.points_not_triangulated, tie);
  EXPECT_GT(positioned, tie * 9 / 10);

  // Initial values, not a solution (points intersected from start values metres off): what they
  // are for is a bundle adjustment that converges to the truth from them.
  BundleAdjustmentOptions options;
  options.solver.num_threads = 1;
  BundleAdjustmentResult result;
  ASSERT_TRUE(BundleAdjust(options, BundleAdjustmentConfig(), &block, &result).ok());
  ASSERT_TRUE(result.summary.IsSolutionUsable()) << result.summary.BriefReport();
  for (size_t i = 0; i < block.images.size(); ++i) {
    EXPECT_LT((block.images[i].eo->center_in_ground() - truth.eo[i].center_in_ground()).norm(),
              0.1)
        << block.images[i].name;
  }
}

TEST(BlockInitialization, AnImageWithNothingToOrientItFromIsNamedWithTheReason) {
  Block block;
  SyntheticBlockTruth truth;
  ASSERT_TRUE(MakeSyntheticBlock(SmallBlock(), &block, &truth).ok());
  for (BlockImage& image : block.images) image.eo.reset();
  // No control points: nothing to resect from.
  for (BlockPoint& point : block.points)
    if (point.role == PointRole::kControl) point.role = PointRole::kCheck;
  BlockInitializationSummary summary;
  ASSERT_TRUE(InitializeBlock(BlockInitializationOptions(), &block, &summary).ok());
  ASSERT_EQ(summary.not_oriented.size(), block.images.size());
  EXPECT_NE(summary.not_oriented[0].second.find("points with known coordinates"),
            std::string::npos)
      << summary.not_oriented[0].second;
  RemoveImages(summary.not_oriented, &block);
  EXPECT_TRUE(block.images.empty());
  EXPECT_TRUE(block.marks.empty());
}

// The brief report counts in words that agree with the count: "1 round", "2 rounds".
TEST(BlockInitialization, TheBriefReportSaysOneRoundNotOneRounds) {
  BlockInitializationSummary summary;
  summary.images_given = 1;
  summary.points_given = 1;
  summary.rounds = 1;
  EXPECT_EQ(summary.BriefReport(),
            "1 image with initial values, 0 resected, 0 not oriented; 1 tie point with "
            "coordinates, 0 intersected, 0 not; 1 round");
  summary.images_given = 12;
  summary.rounds = 2;
  EXPECT_NE(summary.BriefReport().find("12 images with initial values"), std::string::npos);
  EXPECT_NE(summary.BriefReport().find("; 2 rounds"), std::string::npos);
}

TEST(BlockInitialization, RefusesInvalidOptions) {
  Block block;
  BlockInitializationOptions options;
  options.min_marks_for_resection = 2;
  BlockInitializationSummary summary;
  EXPECT_FALSE(InitializeBlock(options, &block, &summary).ok());
  options = BlockInitializationOptions();
  options.max_ray_misfit_rad = 0.0;
  EXPECT_FALSE(InitializeBlock(options, &block, &summary).ok());
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
