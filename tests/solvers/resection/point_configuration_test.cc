#include "solvers/resection/point_configuration.h"

#include <gtest/gtest.h>

#include <cmath>

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

TEST(PointConfiguration, ExtentsOfAHandComputedCloud) {
  // Four points on a 200 x 100 m rectangle at large map coordinates: RMS extents 100 and 50 m
  // along its sides, none across it.
  const Eigen::Vector3d o(500000.0, 4100000.0, 90.0);
  const std::vector<Eigen::Vector3d> points = {o + Eigen::Vector3d(-100, -50, 0),
                                               o + Eigen::Vector3d(100, -50, 0),
                                               o + Eigen::Vector3d(100, 50, 0),
                                               o + Eigen::Vector3d(-100, 50, 0)};
  const PointSpread spread = ComputePointSpread(points);
  EXPECT_LT((spread.centroid - o).norm(), 1e-9);
  EXPECT_NEAR(spread.extents_m[2], 100.0, 1e-9);
  EXPECT_NEAR(spread.extents_m[1], 50.0, 1e-9);
  EXPECT_LT(spread.extents_m[0], 1e-6);
  EXPECT_FALSE(spread.collinear());
  EXPECT_TRUE(spread.coplanar());
  EXPECT_TRUE(CheckControlConfiguration(points).ok());
}

TEST(PointConfiguration, CollinearCoincidentFewAndNonFiniteAreRefusedWithTheReason) {
  std::vector<Eigen::Vector3d> line;
  for (int i = 0; i < 5; ++i) line.push_back(Eigen::Vector3d(300000.0 + 10 * i, 4e6 + 5 * i, 20 + i));
  EXPECT_TRUE(ComputePointSpread(line).collinear());
  EXPECT_NE(CheckControlConfiguration(line).message().find("one line"), std::string::npos);
  // 1 mm off the line over 40 m is 2.5e-5 of the extent: a real (if weak) configuration.
  line[2].x() += 1e-3;
  EXPECT_FALSE(ComputePointSpread(line).collinear());
  const std::vector<Eigen::Vector3d> same(4, Eigen::Vector3d(1, 2, 3));
  EXPECT_NE(CheckControlConfiguration(same).message().find("one line"), std::string::npos);
  EXPECT_NE(CheckControlConfiguration({{0, 0, 0}, {1, 0, 0}}).message().find("at least three"),
            std::string::npos);
  EXPECT_NE(CheckControlConfiguration({{0, 0, 0}, {1, 0, 0}, {0, NAN, 0}}).message().find("non-finite"),
            std::string::npos);
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
