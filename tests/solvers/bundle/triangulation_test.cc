#include "solvers/bundle/triangulation.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <vector>

#include "tests/support/exact_block.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

using testing::ExactBlock;
using testing::MakeExactBlock;

// Noise-free marks from the true orientations: the intersection is the true point to the
// Gauss-Newton stop (1e-9 of the distance, 0.1 um at 100 m) and the rounding of the film points.
constexpr double kExactPointM = 1e-6;

int FirstPointWithRays(const Block& block, size_t at_least) {
  for (size_t p = 0; p < block.points.size(); ++p)
    if (block.marks_of_point[p].size() >= at_least) return static_cast<int>(p);
  return -1;
}

TEST(Triangulation, NoiseFreeRaysMeetAtTheTruePoint) {
  const ExactBlock data = MakeExactBlock();
  const int p = FirstPointWithRays(data.block, 3);
  ASSERT_GE(p, 0);
  const std::vector<RayObservation> rays = PointRays(data.block, p, MarkSigmaDefaults());
  ASSERT_EQ(rays.size(), data.block.marks_of_point[p].size());
  // The fixture states 0.5 px on 4 um pixels: 2 um on the film (core/mark_weight.h).
  for (const RayObservation& ray : rays) EXPECT_NEAR(ray.sigma, 2.0, 1e-12);
  TriangulationResult result;
  ASSERT_TRUE(TriangulatePoint(TriangulationOptions(), rays, &result).ok());
  EXPECT_LT((result.point_m - data.truth.points_m[p]).norm(), kExactPointM);
  EXPECT_LT(result.rms_whitened, 1e-3);
  EXPECT_GT(result.max_intersection_angle_rad, TriangulationOptions().min_intersection_angle_rad);
  // A-priori covariance: symmetric, positive, and depth (Z) the weakest axis of a vertical block.
  EXPECT_TRUE(result.covariance.isApprox(result.covariance.transpose(), 1e-12));
  EXPECT_GT(result.covariance(0, 0), 0.0);
  EXPECT_GT(result.covariance(2, 2), result.covariance(0, 0));
}

// Noise-free marks generated with the earth-curvature drop (EarthCurvatureBlockOptions): every
// tie point with three or more rays is intersected at the truth through the camera's ApplyECC
// (CreateRayCost); with ApplyECC off the same rays meet lower, by up to their largest drop.
TEST(Triangulation, RaysOfACameraWithApplyEccMeetAtTheTruePointThroughTheCorrection) {
  ExactBlock data = MakeExactBlock(EarthCurvatureBlockOptions());
  double largest_miss_m = 0.0, largest_plain_miss_m = 0.0;
  int intersected = 0;
  for (size_t p = 0; p < data.block.points.size(); ++p) {
    if (data.block.points[p].role != PointRole::kTie || data.block.marks_of_point[p].size() < 3)
      continue;
    data.block.cameras[0].table.apply_ecc = true;
    std::vector<RayObservation> rays = PointRays(data.block, static_cast<int>(p), MarkSigmaDefaults());
    TriangulationResult corrected, plain;
    ASSERT_TRUE(TriangulatePoint(TriangulationOptions(), rays, &corrected).ok());
    data.block.cameras[0].table.apply_ecc = false;
    rays = PointRays(data.block, static_cast<int>(p), MarkSigmaDefaults());
    ASSERT_TRUE(TriangulatePoint(TriangulationOptions(), rays, &plain).ok());
    largest_miss_m = std::max(largest_miss_m, (corrected.point_m - data.truth.points_m[p]).norm());
    largest_plain_miss_m =
        std::max(largest_plain_miss_m, (plain.point_m - data.truth.points_m[p]).norm());
    EXPECT_LT(plain.point_m.z(), data.truth.points_m[p].z()) << data.block.points[p].id;
    ++intersected;
  }
  std::printf("  %d tie points: largest miss %.2g m with the correction, %.3f m without\n",
              intersected, largest_miss_m, largest_plain_miss_m);
  EXPECT_GT(intersected, 100);
  EXPECT_LT(largest_miss_m, kExactPointM);
  EXPECT_GT(largest_plain_miss_m, 0.02);
}

TEST(Triangulation, PointRaysLeaveOutSkippedMarksAndImagesWithoutOrientation) {
  ExactBlock data = MakeExactBlock();
  const int p = FirstPointWithRays(data.block, 3);
  ASSERT_GE(p, 0);
  const std::vector<int>& marks = data.block.marks_of_point[p];
  std::vector<char> skip(data.block.marks.size(), 0);
  skip[marks[0]] = 1;
  EXPECT_EQ(PointRays(data.block, p, MarkSigmaDefaults(), &skip).size(), marks.size() - 1);
  data.block.images[data.block.marks[marks[1]].image].eo.reset();
  EXPECT_EQ(PointRays(data.block, p, MarkSigmaDefaults()).size(), marks.size() - 1);
  EXPECT_EQ(PointRays(data.block, p, MarkSigmaDefaults(), &skip).size(), marks.size() - 2);
  EXPECT_TRUE(PointRays(data.block, -1, MarkSigmaDefaults()).empty());
}

TEST(Triangulation, FailsCleanlyWithTooFewOrParallelRays) {
  const ExactBlock data = MakeExactBlock();
  const int p = FirstPointWithRays(data.block, 2);
  ASSERT_GE(p, 0);
  std::vector<RayObservation> rays = PointRays(data.block, p, MarkSigmaDefaults());
  TriangulationResult result;
  const std::vector<RayObservation> one(rays.begin(), rays.begin() + 1);
  Status status = TriangulatePoint(TriangulationOptions(), one, &result);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("at least two rays"), std::string::npos) << status.message();
  // The same ray twice: they meet at 0 deg.
  const std::vector<RayObservation> twice = {rays[0], rays[0]};
  status = TriangulatePoint(TriangulationOptions(), twice, &result);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("depth is not determined"), std::string::npos)
      << status.message();
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
