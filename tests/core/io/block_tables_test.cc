#include "core/io/block_tables.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "core/io/csv.h"
#include "core/simulation/synthetic_block.h"
#include "core/io/tables.h"
#include "tests/support/temp_dir.h"

namespace photopose {
namespace {

using testing::ScopedTempDir;

// Numbers are written in their shortest round-trip form; angles go through degrees and the seed
// convention (a few ulp).
constexpr double kAngleRoundTripRad = 1e-14;

SyntheticBlockOptions Options() {
  SyntheticBlockOptions o;
  o.num_lines = 2;
  o.images_per_line = 5;
  o.num_tie_points = 200;
  o.attitude = true;
  o.camera_params = {24050.0, 10.0, -6.0, 0.0, -1e-4, 0.0, 0.0, 0.0, 0.0, 1e-4, 0.0};
  return o;
}

TEST(BlockTables, WritesWhatTheTableReadersReadBack) {
  Block block;
  SyntheticBlockTruth truth;
  ASSERT_TRUE(MakeSyntheticBlock(Options(), &block, &truth).ok());
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  const BlockTableFiles files{dir.Path("cameras.csv"), dir.Path("points.csv"),
                              dir.Path("marks.csv"), dir.Path("frames.csv")};
  const Status status = WriteBlockTables(block, files);
  ASSERT_TRUE(status.ok()) << status.message();

  std::vector<FrameCamera> cameras;
  ASSERT_TRUE(ReadCameraTable(files.cameras, &cameras).ok());
  ASSERT_EQ(cameras.size(), 1u);
  EXPECT_EQ(cameras[0].focal_length_um, 24050.0);
  EXPECT_EQ(cameras[0].radial_k[1], -1e-4);
  // The affinity is folded into A0-B2: film x = (1 + b1) (column - 3000) 4 um.
  ASSERT_TRUE(cameras[0].has_affine);
  EXPECT_NEAR(cameras[0].affine_a[1], 4.0 * (1.0 + 1e-4), 1e-12);
  EXPECT_NEAR(cameras[0].affine_a[0], -3000.0 * 4.0 * (1.0 + 1e-4), 1e-9);

  std::vector<GroundPoint> points;
  ASSERT_TRUE(ReadGroundPoints(files.points, &points).ok());
  ASSERT_EQ(points.size(), block.points.size());
  for (size_t p = 0; p < points.size(); ++p) {
    EXPECT_EQ(points[p].point_id, block.points[p].id);
    EXPECT_EQ(points[p].role, block.points[p].role);
    const Eigen::Vector3d expected = block.points[p].role == PointRole::kTie
                                         ? *block.points[p].position_m
                                         : *block.points[p].surveyed_m;
    EXPECT_EQ(points[p].position, expected);
  }

  std::vector<ImageMark> marks;
  ASSERT_TRUE(ReadImageMarks(files.marks, &marks).ok());
  ASSERT_EQ(marks.size(), block.marks.size());
  for (size_t m = 0; m < marks.size(); ++m) {
    EXPECT_EQ(marks[m].raster, block.images[block.marks[m].image].name);
    EXPECT_EQ(marks[m].point_id, block.points[block.marks[m].point].id);
    ASSERT_TRUE(marks[m].column_row.has_value());
    EXPECT_EQ(*marks[m].column_row, block.marks[m].measured);
    EXPECT_EQ(marks[m].accuracy_px, block.marks[m].accuracy);
    EXPECT_EQ(marks[m].camera_id, "SyntheticCamera");
  }

  std::vector<FrameRecord> frames;
  ASSERT_TRUE(ReadFramesTable(files.frames, FramesTableOptions(), &frames).ok());
  ASSERT_EQ(frames.size(), block.images.size());
  for (size_t i = 0; i < frames.size(); ++i) {
    const BlockImage& image = block.images[i];
    EXPECT_EQ(frames[i].raster, image.name);
    // Perspective = the GNSS centre, angles = the measured attitude.
    EXPECT_EQ(frames[i].eo.center_in_ground(), *image.measured_center_m);
    EXPECT_LT((frames[i].eo.angles_seed_rad() - *image.measured_angles_rad).norm(),
              kAngleRoundTripRad);
    ASSERT_TRUE(frames[i].center_accuracy_m.has_value());
    EXPECT_EQ((*frames[i].center_accuracy_m)[2], (*image.center_accuracy_m)[2]);
    ASSERT_TRUE(frames[i].attitude_accuracy_deg.has_value());
    EXPECT_NEAR((*frames[i].attitude_accuracy_deg)[0], 0.01, 1e-12);
  }
}

TEST(BlockTables, WithoutMeasurementsTheStartIsWritten) {
  SyntheticBlockOptions o = Options();
  o.gnss = false;
  o.attitude = false;
  Block block;
  ASSERT_TRUE(MakeSyntheticBlock(o, &block, nullptr).ok());
  BlockTableRecords records;
  BlockTableWriteOptions options;
  options.write_tie_points = false;
  ASSERT_TRUE(BlockToTableRecords(block, options, &records).ok());
  ASSERT_EQ(records.frames.size(), block.images.size());
  EXPECT_EQ(records.frames[0].eo.parameters, block.images[0].eo->parameters);
  EXPECT_TRUE(records.frames[0].extra_columns.empty());
  EXPECT_EQ(records.points.size(),
            static_cast<size_t>(o.num_control_points + o.num_check_points));
}

TEST(BlockTables, ColmapCameraIsRefusedAndNothingWritten) {
  SyntheticBlockOptions o = Options();
  o.camera_model = CameraModelType::kPinhole;
  o.camera_params.clear();
  Block block;
  ASSERT_TRUE(MakeSyntheticBlock(o, &block, nullptr).ok());
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  const Status status = WriteBlockTables(
      block, {dir.Path("c.csv"), dir.Path("p.csv"), dir.Path("m.csv"), dir.Path("f.csv")});
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.message(),
            "camera 'SyntheticCamera' is a PINHOLE camera: the camera table holds frame cameras "
            "only (write the block as a COLMAP model instead)");
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(BlockTables, AttitudeAccuracyNeedsTheSeedConvention) {
  Block block;
  ASSERT_TRUE(MakeSyntheticBlock(Options(), &block, nullptr).ok());
  BlockTableWriteOptions options;
  options.rotation = RotationConvention::kOpk;
  BlockTableRecords records;
  const Status status = BlockToTableRecords(block, options, &records);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("attitude accuracies are per seed angle"), std::string::npos);
}

}  // namespace
}  // namespace photopose
