// Tests of the block model itself (core/block.h): the mark index, lookups by name and the
// structural checks. Reading a block from its tables is tested in tests/core/io/block_tables_test.cc.
#include "core/block.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// Two images, two points, three marks (one image sees both points, the other one).
Block TwoImageBlock() {
  Block block;
  BlockCamera camera;
  camera.camera_id = "cam";
  camera.model = CameraModelType::kSimplePinhole;
  camera.params.assign(CameraModelNumParams(camera.model), 0.0);
  camera.params[0] = 1000.0;
  block.cameras.push_back(camera);
  for (const char* name : {"a.jpg", "b.jpg"}) {
    BlockImage image;
    image.name = name;
    image.camera = 0;
    block.images.push_back(image);
  }
  for (const char* id : {"p1", "p2"}) {
    BlockPoint point;
    point.id = id;
    point.position_m = Eigen::Vector3d(1.0, 2.0, 3.0);
    block.points.push_back(point);
  }
  for (const auto& [image, point] : {std::pair{0, 0}, std::pair{0, 1}, std::pair{1, 1}}) {
    BlockMark mark;
    mark.image = image;
    mark.point = point;
    block.marks.push_back(mark);
  }
  block.BuildIndex();
  return block;
}

TEST(Block, IndexListsTheMarksOfEveryImageAndPointInMarksOrder) {
  const Block block = TwoImageBlock();
  ASSERT_EQ(block.marks_of_image.size(), 2u);
  ASSERT_EQ(block.marks_of_point.size(), 2u);
  EXPECT_EQ(block.marks_of_image[0], (std::vector<int>{0, 1}));
  EXPECT_EQ(block.marks_of_image[1], (std::vector<int>{2}));
  EXPECT_EQ(block.marks_of_point[0], (std::vector<int>{0}));
  EXPECT_EQ(block.marks_of_point[1], (std::vector<int>{1, 2}));
}

TEST(Block, APixelMarkIsMeasuredAndObservedInPixels) {
  const BlockMark mark = MakePixelMark(2, 5, Eigen::Vector2d(10.5, -3.25), 7);
  EXPECT_EQ(mark.image, 2);
  EXPECT_EQ(mark.point, 5);
  EXPECT_EQ(mark.unit, MarkUnit::kPixel);
  EXPECT_EQ(mark.measured, Eigen::Vector2d(10.5, -3.25));
  EXPECT_EQ(mark.observation, mark.measured);
  EXPECT_EQ(mark.observation_units_per_unit, 1.0);
  EXPECT_FALSE(mark.accuracy.has_value());
  EXPECT_EQ(mark.line, 7);
}

TEST(Block, FindsByNameOrMinusOne) {
  const Block block = TwoImageBlock();
  EXPECT_EQ(block.FindCamera("cam"), 0);
  EXPECT_EQ(block.FindImage("b.jpg"), 1);
  EXPECT_EQ(block.FindPoint("p2"), 1);
  EXPECT_EQ(block.FindImage("c.jpg"), -1);
  EXPECT_EQ(block.FindPoint("P2"), -1);  // names are exact
}

TEST(Block, CheckAcceptsAConsistentBlock) { EXPECT_TRUE(CheckBlock(TwoImageBlock()).ok()); }

TEST(Block, CheckNamesTheFirstOffence) {
  {
    Block block = TwoImageBlock();
    block.cameras[0].params.pop_back();
    const Status status = CheckBlock(block);
    ASSERT_FALSE(status.ok());
    EXPECT_NE(status.message().find("camera 'cam'"), std::string::npos) << status.message();
  }
  {
    Block block = TwoImageBlock();
    block.images[1].camera = 3;
    const Status status = CheckBlock(block);
    ASSERT_FALSE(status.ok());
    EXPECT_NE(status.message().find("image 'b.jpg' has no camera"), std::string::npos)
        << status.message();
  }
  {
    Block block = TwoImageBlock();
    block.points[0].position_m->x() = std::numeric_limits<double>::quiet_NaN();
    const Status status = CheckBlock(block);
    ASSERT_FALSE(status.ok());
    EXPECT_NE(status.message().find("point 'p1'"), std::string::npos) << status.message();
  }
  {
    Block block = TwoImageBlock();
    block.points[1].role = PointRole::kControl;  // control without surveyed coordinates
    const Status status = CheckBlock(block);
    ASSERT_FALSE(status.ok());
    EXPECT_NE(status.message().find("point 'p2' is a control or check point"), std::string::npos)
        << status.message();
  }
  {
    Block block = TwoImageBlock();
    block.marks[2].point = 7;
    const Status status = CheckBlock(block);
    ASSERT_FALSE(status.ok());
    EXPECT_NE(status.message().find("mark 3 names no image or point"), std::string::npos)
        << status.message();
  }
  {
    Block block = TwoImageBlock();
    block.marks[0].accuracy = 0.0;  // an accuracy must be positive
    const Status status = CheckBlock(block);
    ASSERT_FALSE(status.ok());
    EXPECT_NE(status.message().find("mark 1"), std::string::npos) << status.message();
  }
}

// A point's accuracy is positive on every axis or 0 on all three; only a control point with 0 is
// held fixed.
TEST(Block, AccuracyZeroOnEveryAxisHoldsAControlPointFixed) {
  EXPECT_EQ(InvalidPointAccuracyAxis(Eigen::Vector3d(0.01, 0.01, 0.02)), -1);
  EXPECT_EQ(InvalidPointAccuracyAxis(Eigen::Vector3d::Zero()), -1);
  EXPECT_EQ(InvalidPointAccuracyAxis(Eigen::Vector3d(0.0, 0.0, 0.02)), 2);
  EXPECT_EQ(InvalidPointAccuracyAxis(Eigen::Vector3d(0.01, 0.0, 0.0)), 1);
  EXPECT_EQ(InvalidPointAccuracyAxis(Eigen::Vector3d(-0.01, -0.01, -0.01)), 0);
  BlockPoint point;
  point.role = PointRole::kControl;
  point.surveyed_m = Eigen::Vector3d(1, 2, 3);
  EXPECT_FALSE(IsHeldFixed(point));  // no accuracy: the default one
  point.accuracy_m = Eigen::Vector3d(1e-9, 1e-9, 1e-9);
  EXPECT_FALSE(IsHeldFixed(point));
  point.accuracy_m = Eigen::Vector3d::Zero();
  EXPECT_TRUE(IsHeldFixed(point));
  point.role = PointRole::kCheck;
  EXPECT_FALSE(IsHeldFixed(point));  // only compared

  Block block = TwoImageBlock();
  for (BlockPoint& p : block.points) p.accuracy_m = Eigen::Vector3d::Zero();
  EXPECT_TRUE(CheckBlock(block).ok());
  block.points[0].accuracy_m = Eigen::Vector3d(0.0, 0.01, 0.0);
  const Status status = CheckBlock(block);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("point '" + block.points[0].id +
                                  "' has an accuracy that is neither positive"),
            std::string::npos)
      << status.message();
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
