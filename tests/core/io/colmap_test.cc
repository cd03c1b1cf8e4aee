#include "core/io/colmap.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "core/collinearity.h"
#include "core/io/csv.h"
#include "core/io/output_files.h"
#include "core/rotation.h"
#include "tests/support/block_expect.h"
#include "tests/support/ordered_draws.h"
#include "tests/support/temp_dir.h"
#include "tests/test_data.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

using testing::ScopedTempDir;

// Closed forms in double precision (a projection of O(1000) px through a handful of operations).
constexpr double kExactPx = 1e-9;
// A read -> write -> read round trip of a pose goes through the quaternion and the seed angles;
// both conversions are exact up to a few ulp of O(1) numbers (the brief asks 1e-12).
constexpr double kPoseRoundTrip = 1e-12;
// colmap_ar7 prints poses, points and the focal length with 6 significant digits: rounding them
// moves a projection by up to about 0.01 px (1e-6 rad of attitude at f = 2882 px is 0.003 px,
// 5e-6 of a 5-unit depth 0.003 px, 0.005 px of f at the image edge 0.004 px), so a point's mean
// reprojection error recomputed from the file agrees with its ERROR column to that.
constexpr double kAr7PointErrorPx = 0.02;
// The mean over all 9896 observations averages the rounding out: agreement to 1e-4 of its 1 px.
constexpr double kAr7MeanErrorRelative = 1e-4;

// COLMAP's OPENCV projection, written here from COLMAP's documentation as an independent check.
Eigen::Vector2d ColmapOpenCvPixel(const Eigen::Quaterniond& q, const Eigen::Vector3d& t,
                                  const double* p, const Eigen::Vector3d& X) {
  const Eigen::Vector3d x_cam = q.toRotationMatrix() * X + t;
  const double u = x_cam.x() / x_cam.z(), v = x_cam.y() / x_cam.z();
  const double u2 = u * u, v2 = v * v, uv = u * v, r2 = u2 + v2;
  const double radial = p[4] * r2 + p[5] * r2 * r2;
  const double du = u * radial + 2.0 * p[6] * uv + p[7] * (r2 + 2.0 * u2);
  const double dv = v * radial + 2.0 * p[7] * uv + p[6] * (r2 + 2.0 * v2);
  return {p[0] * (u + du) + p[2], p[1] * (v + dv) + p[3]};
}

std::string Ar7() { return testing::SharedDataPath("colmap_ar7"); }

TEST(ColmapIo, NominalPoseAndProjection) {
  // Identity pose: COLMAP's camera at the origin looking along +Z with y down. In the seed frame
  // (u, v, w) = (x, -y, -z): R_camera_from_ground = diag(1, -1, -1) = Rx(pi), centre 0. The point
  // (1, 2, 10) lands at (100 * 0.1 + 50, 100 * 0.2 + 40) = (60, 60) px.
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  dir.Write("cameras.txt", "1 SIMPLE_PINHOLE 100 80 100 50 40\n");
  dir.Write("images.txt", "# comment\n7 1 0 0 0 0 0 0 1 a.jpg\n60 60 3\n");
  dir.Write("points3D.txt", "3 1 2 10 10 20 30 0 7 0\n");
  Block block;
  ColmapModelExtras extras;
  const Status status = ReadColmapModel(dir.path(), &block, &extras);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(block.images.size(), 1u);
  ASSERT_TRUE(block.images[0].eo.has_value());
  EXPECT_NEAR(block.images[0].eo->center_in_ground().norm(), 0.0, kExactPx);
  const Eigen::Matrix3d R =
      RotationFromAngles(RotationConvention::kSeed, block.images[0].eo->angles_seed_rad());
  EXPECT_LT((R - Eigen::Matrix3d(Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal())).norm(), kExactPx);
  EXPECT_NEAR(std::abs(block.images[0].eo->angles_seed_rad()[0]), kPi, kExactPx);
  ASSERT_EQ(block.marks.size(), 1u);
  EXPECT_EQ(block.points[0].id, "3");
  EXPECT_EQ(block.points[0].role, PointRole::kTie);
  EXPECT_EQ(extras.image_ids, std::vector<long long>{7});
  EXPECT_EQ(extras.point_rgb[0][2], 30);
  std::vector<double> errors;
  MarkReprojectionErrors(block, &errors);
  EXPECT_NEAR(errors[0], 0.0, kExactPx);
}

TEST(ColmapIo, ResidualsEqualColmapsOwnProjection) {
  // Random poses, points in front and an OPENCV camera: the residual of the read block through
  // core/camera_models.h vanishes at the pixel COLMAP's own formula gives.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const double params[] = {1500.0, 1480.0, 960.0, 540.0, -0.12, 0.03, 4e-4, -2e-4};
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  std::string cameras = "3 OPENCV 1920 1080";
  for (const double p : params) cameras += " " + FormatNumber(p);
  dir.Write("cameras.txt", cameras + "\n");
  std::string images, points;
  std::vector<Eigen::Vector2d> expected;
  const int kImages = 5;
  for (int i = 0; i < kImages; ++i) {
    // The axis drawn before the angle (tests/support/ordered_draws.h).
    const Eigen::Vector3d axis = DrawLastFirst<3>([&](int) { return unit(rng); }).normalized();
    const Eigen::Quaterniond q(Eigen::AngleAxisd(0.5 * unit(rng), axis));
    const Eigen::Vector3d t = DrawLastFirst<3>([&](int k) { return (k == 2 ? 8.0 : 0.0) + unit(rng); });
    const Eigen::Vector3d X = DrawLastFirst<3>([&](int) { return unit(rng); });
    const Eigen::Vector2d pixel = ColmapOpenCvPixel(q, t, params, X);
    expected.push_back(pixel);
    images += std::to_string(i + 1);
    for (const double v : {q.w(), q.x(), q.y(), q.z(), t.x(), t.y(), t.z()})
      images += " " + FormatNumber(v);
    images += " 3 img" + std::to_string(i) + ".png\n";
    images += FormatNumber(pixel.x()) + " " + FormatNumber(pixel.y()) + " " +
              std::to_string(100 + i) + "\n";
    points += std::to_string(100 + i) + " " + FormatNumber(X.x()) + " " + FormatNumber(X.y()) +
              " " + FormatNumber(X.z()) + " 0 0 0 0.5 " + std::to_string(i + 1) + " 0\n";
  }
  dir.Write("images.txt", images);
  dir.Write("points3D.txt", points);
  Block block;
  const Status status = ReadColmapModel(dir.path(), &block);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(block.marks.size(), static_cast<size_t>(kImages));
  const CameraModelData data;
  for (const BlockMark& mark : block.marks) {
    double ab[2], residual[2];
    ASSERT_TRUE(ProjectToNormalized(block.images[mark.image].eo->data(),
                                    block.points[mark.point].position_m->data(), ab));
    CameraModelResidual(CameraModelType::kOpenCv, block.cameras[0].params.data(), ab,
                        mark.observation.data(), data, residual);
    EXPECT_NEAR(residual[0], 0.0, kExactPx);
    EXPECT_NEAR(residual[1], 0.0, kExactPx);
    EXPECT_EQ(mark.observation, expected[mark.image]);
  }
}

TEST(ColmapIo, ReadsAr7AndItsErrorColumnAgrees) {
  Block block;
  ColmapModelExtras extras;
  const Status status = ReadColmapModel(Ar7(), &block, &extras);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(block.cameras.size(), 1u);
  EXPECT_EQ(block.cameras[0].model, CameraModelType::kSimpleRadial);
  EXPECT_EQ(block.cameras[0].table.n_columns, 4032);
  EXPECT_EQ(block.cameras[0].table.n_rows, 3024);
  EXPECT_EQ(block.cameras[0].params, (std::vector<double>{2881.59, 2016, 1512, -0.0210311}));
  EXPECT_EQ(block.images.size(), 7u);
  EXPECT_EQ(block.points.size(), 2707u);
  EXPECT_EQ(block.marks.size(), 9896u);
  EXPECT_EQ(block.images[0].name, "image1.JPG");
  // Every POINTS2D entry is kept: the matched ones as marks, the others apart.
  long long keypoints = 0;
  for (const int n : extras.num_keypoints) keypoints += n;
  EXPECT_EQ(keypoints, static_cast<long long>(block.marks.size() + extras.unmatched.size()));
  EXPECT_GT(extras.unmatched.size(), 0u);

  std::vector<double> errors;
  MeanReprojectionErrors(block, &errors);
  double worst = 0.0, mine = 0.0, colmap = 0.0;
  for (size_t p = 0; p < block.points.size(); ++p) {
    ASSERT_GE(errors[p], 0.0) << block.points[p].id;
    worst = std::max(worst, std::abs(errors[p] - extras.point_error_px[p]));
    const double track = static_cast<double>(block.marks_of_point[p].size());
    mine += errors[p] * track;
    colmap += extras.point_error_px[p] * track;
  }
  mine /= block.marks.size();
  colmap /= block.marks.size();
  EXPECT_LT(worst, kAr7PointErrorPx);
  EXPECT_NEAR(mine, colmap, kAr7MeanErrorRelative * colmap);
  std::printf("colmap_ar7: mean reprojection error %.6f px (COLMAP's ERROR column: %.6f px), "
              "largest per-point difference %.2e px\n",
              mine, colmap, worst);
}

// Blocks equal as the COLMAP round trip promises: everything exact but the poses (1e-12).
void ExpectSameBlock(const Block& a, const Block& b) {
  ASSERT_EQ(a.cameras.size(), b.cameras.size());
  for (size_t c = 0; c < a.cameras.size(); ++c) {
    EXPECT_EQ(a.cameras[c].camera_id, b.cameras[c].camera_id);
    EXPECT_EQ(a.cameras[c].model, b.cameras[c].model);
    EXPECT_EQ(a.cameras[c].params, b.cameras[c].params);
  }
  ASSERT_EQ(a.images.size(), b.images.size());
  for (size_t i = 0; i < a.images.size(); ++i) {
    EXPECT_EQ(a.images[i].name, b.images[i].name);
    EXPECT_EQ(a.images[i].camera, b.images[i].camera);
    const Eigen::Matrix3d Ra =
        RotationFromAngles(RotationConvention::kSeed, a.images[i].eo->angles_seed_rad());
    const Eigen::Matrix3d Rb =
        RotationFromAngles(RotationConvention::kSeed, b.images[i].eo->angles_seed_rad());
    EXPECT_LT((Ra - Rb).cwiseAbs().maxCoeff(), kPoseRoundTrip);
    const Eigen::Vector3d ca = a.images[i].eo->center_in_ground();
    EXPECT_LT((ca - b.images[i].eo->center_in_ground()).norm(),
              kPoseRoundTrip * std::max(1.0, ca.norm()));
  }
  EXPECT_TRUE(testing::SamePointsAndMarks(a, b));
}

TEST(ColmapIo, Ar7WritesBackAndReadsIdentically) {
  Block block, again;
  ColmapModelExtras extras, extras_again;
  ASSERT_TRUE(ReadColmapModel(Ar7(), &block, &extras).ok());
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  const std::string out = dir.Path("model");
  Status status = WriteColmapModel(out, block, &extras);
  ASSERT_TRUE(status.ok()) << status.message();
  status = ReadColmapModel(out, &again, &extras_again);
  ASSERT_TRUE(status.ok()) << status.message();
  ExpectSameBlock(block, again);
  EXPECT_EQ(extras.image_ids, extras_again.image_ids);
  EXPECT_EQ(extras.mark_keypoint_index, extras_again.mark_keypoint_index);
  EXPECT_EQ(extras.num_keypoints, extras_again.num_keypoints);
  EXPECT_EQ(extras.point_rgb, extras_again.point_rgb);
  ASSERT_EQ(extras.unmatched.size(), extras_again.unmatched.size());
  for (size_t k = 0; k < extras.unmatched.size(); ++k) {
    EXPECT_EQ(extras.unmatched[k].image, extras_again.unmatched[k].image);
    EXPECT_EQ(extras.unmatched[k].index, extras_again.unmatched[k].index);
    EXPECT_EQ(extras.unmatched[k].xy, extras_again.unmatched[k].xy);
  }
  // ERROR is written from the block: it reads back as what the block gives.
  std::vector<double> errors;
  MeanReprojectionErrors(block, &errors);
  for (size_t p = 0; p < errors.size(); ++p)
    EXPECT_NEAR(extras_again.point_error_px[p], errors[p], 1e-9 * std::max(1.0, errors[p]));
}

// A two-image block in memory with a frame camera (pinhole: no distortion).
Block FramePinholeBlock() {
  Block block;
  BlockCamera camera;
  camera.camera_id = "frame";
  camera.model = CameraModelType::kFrame;
  camera.table.camera_id = "frame";
  camera.table.focal_length_um = 24000.0;
  camera.table.principal_x_um = 12.0;
  camera.table.principal_y_um = -8.0;
  camera.table.pixel_size_um = 4.0;
  camera.table.n_columns = 6000;
  camera.table.n_rows = 4000;
  const auto params = FrameModelParams(camera.table);
  camera.params.assign(params.begin(), params.end());
  block.cameras.push_back(camera);
  for (int i = 0; i < 2; ++i) {
    BlockImage image;
    image.name = "img " + std::to_string(i);  // a space in the name survives
    image.camera = 0;
    ExteriorOrientation eo;
    eo.set_center_in_ground({500000.0 + 30.0 * i, 4100000.0, 120.0});
    eo.set_angles_seed_rad({0.01, -0.02, 0.3 + i});
    image.eo = eo;
    block.images.push_back(image);
  }
  for (int p = 0; p < 3; ++p) {
    BlockPoint point;
    point.id = "T" + std::to_string(p);
    point.position_m = Eigen::Vector3d(500010.0 + 5.0 * p, 4100004.0 - 3.0 * p, 20.0 + p);
    block.points.push_back(point);
  }
  for (int i = 0; i < 2; ++i) {
    for (int p = 0; p < 3; ++p) {
      BlockMark mark;
      mark.image = i;
      mark.point = p;
      double ab[2];
      ProjectToNormalized(block.images[i].eo->data(), block.points[p].position_m->data(), ab);
      Eigen::Vector2d film;
      EXPECT_TRUE(ObservationFromNormalized(CameraModelType::kFrame,
                                            block.cameras[0].params.data(),
                                            block.cameras[0].data(), {ab[0], ab[1]}, &film)
                      .ok());
      mark.unit = MarkUnit::kFilm;
      mark.measured = film + Eigen::Vector2d(0.3, -0.2);  // 0.09 px of error
      mark.observation = mark.measured;
      block.marks.push_back(mark);
    }
  }
  block.BuildIndex();
  return block;
}

TEST(ColmapIo, FramePinholeCameraBecomesSimplePinhole) {
  // c = 24 mm with 4 um pixels is f = 6000 px; the principal point (12, -8) um from the centre of
  // the 6000 x 4000 image is (3000 + 3, 2000 + 2) px (film y up, Row down).
  const Block block = FramePinholeBlock();
  CameraModelType model;
  std::vector<double> params;
  ASSERT_TRUE(ColmapCameraFromBlockCamera(block.cameras[0], &model, &params).ok());
  EXPECT_EQ(model, CameraModelType::kSimplePinhole);
  ASSERT_EQ(params.size(), 3u);
  EXPECT_NEAR(params[0], 6000.0, kExactPx);
  EXPECT_NEAR(params[1], 3003.0, kExactPx);
  EXPECT_NEAR(params[2], 2002.0, kExactPx);

  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  const Status status = WriteColmapModel(dir.path(), block);
  ASSERT_TRUE(status.ok()) << status.message();
  Block again;
  ASSERT_TRUE(ReadColmapModel(dir.path(), &again).ok());
  EXPECT_EQ(again.cameras[0].camera_id, "1");  // "frame" is no COLMAP id: numbered
  EXPECT_EQ(again.points[2].id, "3");
  EXPECT_EQ(again.images[1].name, "img 1");
  // The same reprojection errors in pixels before and after.
  std::vector<double> before, after;
  MarkReprojectionErrors(block, &before);
  MarkReprojectionErrors(again, &after);
  ASSERT_EQ(before.size(), after.size());
  for (size_t m = 0; m < before.size(); ++m) {
    EXPECT_NEAR(before[m], std::hypot(0.3, 0.2) / 4.0, 1e-6);
    EXPECT_NEAR(after[m], before[m], 1e-6);
  }
}

// A model of 600 000 marks (ar7's images 60 times over), whose images file is
// several pieces long (core/io/output_files.h TextPieces) in either format: written in pieces, the
// files are the bytes FormatColmapModel formats whole.
TEST(ColmapIo, ALargeModelIsWrittenInPiecesAsItIsFormattedWhole) {
  Block ar7;
  ASSERT_TRUE(ReadColmapModel(Ar7(), &ar7).ok());
  Block block = ar7;
  const int num_images = static_cast<int>(ar7.images.size());
  for (int copy = 1; copy < 60; ++copy) {
    for (const BlockImage& image : ar7.images) {
      block.images.push_back(image);
      block.images.back().name = std::to_string(copy) + "_" + image.name;
    }
    for (BlockMark mark : ar7.marks) {
      mark.image += copy * num_images;
      block.marks.push_back(mark);
    }
  }
  block.BuildIndex();
  for (const ColmapFormat format : {ColmapFormat::kText, ColmapFormat::kBinary}) {
    ColmapWriteOptions options;
    options.format = format;
    ColmapModelFiles whole;
    ASSERT_TRUE(FormatColmapModel(block, nullptr, options, &whole).ok());
    EXPECT_GT(whole.images.size(), 2 * TextPieces::kPieceBytes);
    ScopedTempDir dir;
    ASSERT_TRUE(dir.ok());
    const Status written = WriteColmapModel(dir.path(), block, nullptr, options);
    ASSERT_TRUE(written.ok()) << written.message();
    const std::array<const char*, 3> names = ColmapFileNames(format);
    const std::string* expected[] = {&whole.cameras, &whole.images, &whole.points3D};
    for (int k = 0; k < 3; ++k) {
      std::string bytes;
      ASSERT_TRUE(ReadTextFile(dir.Path(names[k]), &bytes).ok());
      EXPECT_TRUE(bytes == *expected[k]) << names[k] << ": " << bytes.size() << " bytes written, "
                                         << expected[k]->size() << " formatted";
    }
  }
}

TEST(ColmapIo, FrameCameraWithDistortionIsRefusedAndNothingWritten) {
  Block block = FramePinholeBlock();
  block.cameras[0].params[kFrameK1] = 1e-5;
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  const Status status = WriteColmapModel(dir.Path("out"), block);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("camera 'frame' has K1"), std::string::npos)
      << status.message();
  EXPECT_FALSE(std::filesystem::exists(dir.Path("out")));
}

TEST(ColmapIo, PointWithoutPositionIsWrittenAsUnmatched) {
  Block block = FramePinholeBlock();
  block.points[1].position_m.reset();
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  ASSERT_TRUE(WriteColmapModel(dir.path(), block).ok());
  Block again;
  ColmapModelExtras extras;
  ASSERT_TRUE(ReadColmapModel(dir.path(), &again, &extras).ok());
  EXPECT_EQ(again.points.size(), 2u);
  EXPECT_EQ(again.marks.size(), 4u);
  EXPECT_EQ(extras.unmatched.size(), 2u);
}

TEST(ColmapIo, MarksLeftOutBecomeKeypointsAndTheirPointsGoWhenTooFewStay) {
  // Three points seen by both images; leave out the mark of T0 in image 0 (T0 keeps one mark:
  // it goes, its other mark a keypoint too) and none of T1, T2.
  const Block block = FramePinholeBlock();
  ColmapWriteOptions options;
  options.marks_left_out.assign(block.marks.size(), 0);
  options.marks_left_out[0] = 1;  // image 0, T0
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  const Status status = WriteColmapModel(dir.path(), block, nullptr, options);
  ASSERT_TRUE(status.ok()) << status.message();
  Block again;
  ColmapModelExtras extras;
  ASSERT_TRUE(ReadColmapModel(dir.path(), &again, &extras).ok());
  ASSERT_EQ(again.points.size(), 2u);
  EXPECT_EQ(again.points[0].id, "2");  // T1 (ids 1..n of the block's points)
  EXPECT_EQ(again.marks.size(), 4u);
  // Every keypoint stays, at its index: mark 0 (T0) was keypoint 0 of image 0.
  EXPECT_EQ(extras.num_keypoints, (std::vector<int>{3, 3}));
  ASSERT_EQ(extras.unmatched.size(), 2u);
  EXPECT_EQ(extras.unmatched[0].image, 0);
  EXPECT_EQ(extras.unmatched[0].index, 0);
  EXPECT_EQ(extras.unmatched[1].image, 1);
  EXPECT_EQ(extras.unmatched[1].index, 0);

  options.marks_left_out.pop_back();
  EXPECT_EQ(WriteColmapModel(dir.path(), block, nullptr, options).message(),
            "ColmapWriteOptions::marks_left_out has 5 entries for 6 marks");
}

TEST(ColmapIo, ErrorColumnLeavesTheMarksLeftOutOut) {
  Block block = FramePinholeBlock();
  block.marks[3].observation += Eigen::Vector2d(80.0, 0.0);  // image 1, T0: 20 px off
  block.marks[3].measured = block.marks[3].observation;
  ColmapWriteOptions options;
  options.marks_left_out.assign(block.marks.size(), 0);
  ColmapModelFiles with, without;
  ASSERT_TRUE(FormatColmapModel(block, nullptr, options, &with).ok());
  options.marks_left_out[3] = 1;
  ASSERT_TRUE(FormatColmapModel(block, nullptr, options, &without).ok());
  ColmapModelExtras with_extras, without_extras;
  Block read;
  ASSERT_TRUE(ParseColmapModel(with, "m", &read, &with_extras).ok());
  ASSERT_TRUE(ParseColmapModel(without, "m", &read, &without_extras).ok());
  // T0 went (one mark left); T1 and T2 keep their 0.09 px.
  EXPECT_GT(with_extras.point_error_px[0], 10.0);
  ASSERT_EQ(without_extras.point_error_px.size(), 2u);
  EXPECT_NEAR(without_extras.point_error_px[0], std::hypot(0.3, 0.2) / 4.0, 1e-6);
}

TEST(ColmapIo, CalibratingAFrameCamerasDistortionIsRefusedForAColmapOutput) {
  const Block block = FramePinholeBlock();
  EXPECT_TRUE(CheckColmapCamerasWritable(block, {}).ok());
  EXPECT_TRUE(CheckColmapCamerasWritable(block, {{kFrameFocal, kFramePrincipalX}}).ok());
  EXPECT_EQ(CheckColmapCamerasWritable(block, {{kFrameFocal, kFrameK1}}).message(),
            "camera 'frame': calibrating K1 would make it no COLMAP pinhole camera (a frame "
            "camera is written to COLMAP without distortion, affinity and skew)");
  EXPECT_FALSE(CheckColmapCamerasWritable(block, {{kFrameSkew}}).ok());
}

struct BadModel {
  const char* name;
  const char* cameras;
  const char* images;
  const char* points;
  const char* message;  // after the folder
};

class ColmapIoBadInput : public ::testing::TestWithParam<BadModel> {};

TEST_P(ColmapIoBadInput, ClearMessage) {
  const BadModel& bad = GetParam();
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  dir.Write("cameras.txt", bad.cameras);
  dir.Write("images.txt", bad.images);
  dir.Write("points3D.txt", bad.points);
  Block block;
  const Status status = ReadColmapModel(dir.path(), &block);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.message(), dir.path() + "/" + bad.message);
}

const char kCamera[] = "# c\n1 SIMPLE_RADIAL 100 80 100 50 40 0.01\n";
const char kImage[] = "1 1 0 0 0 0 0 0 1 a.jpg\n60 60 3 10 10 -1\n";
const char kPoint[] = "3 1 2 10 10 20 30 0.5 1 0\n";

INSTANTIATE_TEST_SUITE_P(
    Cases, ColmapIoBadInput,
    ::testing::Values(
        BadModel{"Fisheye", "# c\n# c\n\n4 FISHEYE 100 80 100 50 40 0.1\n", kImage, kPoint,
                 "cameras.txt:4: MODEL: camera model 'FISHEYE' is not supported (supported: "
                 "SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV, OPENCV_FISHEYE, "
                 "FULL_OPENCV)"},
        BadModel{"MissingParameter", "1 RADIAL 100 80 100 50 40 0.1\n", kImage, kPoint,
                 "cameras.txt:1: PARAMS k2: is missing"},
        BadModel{"NotANumber", kCamera, "1 1 0 abc 0 0 0 0 1 a.jpg\n\n", kPoint,
                 "images.txt:1: QY: 'abc' is not a number"},
        BadModel{"UnknownCamera", kCamera, "1 1 0 0 0 0 0 0 2 a.jpg\n\n", kPoint,
                 "images.txt:1: CAMERA_ID: camera 2 is not in cameras.txt"},
        BadModel{"UnknownPoint", kCamera, "1 1 0 0 0 0 0 0 1 a.jpg\n60 60 4\n", kPoint,
                 "images.txt:2: POINTS2D POINT3D_ID: point 4 is not in points3D.txt"},
        BadModel{"NoName", kCamera, "1 1 0 0 0 0 0 0 1\n\n", kPoint,
                 "images.txt:1: NAME: is missing"},
        BadModel{"DuplicateImage", kCamera, "1 1 0 0 0 0 0 0 1 a.jpg\n60 60 3\n1 1 0 0 0 0 0 0 1 b\n\n",
                 kPoint, "images.txt:3: IMAGE_ID: image 1 is listed twice"},
        BadModel{"TrackNamesOtherEntry", kCamera, kImage, "3 1 2 10 10 20 30 0.5 1 1\n",
                 "points3D.txt:1: TRACK: entry (1, 1): that POINTS2D entry does not name this "
                 "point"},
        BadModel{"TrackMissesObservation", kCamera, kImage, "3 1 2 10 10 20 30 0.5\n",
                 "points3D.txt:1: TRACK: point 3 is observed in image 'a.jpg' but that is not in "
                 "its track"},
        BadModel{"ColourOutOfRange", kCamera, kImage, "3 1 2 10 300 20 30 0.5 1 0\n",
                 "points3D.txt:1: R: 300 is out of range [0, 255]"},
        BadModel{"ZeroQuaternion", kCamera, "1 0 0 0 0 0 0 0 1 a.jpg\n\n", kPoint,
                 "images.txt:1: QW: the quaternion (QW, QX, QY, QZ) is zero"},
        // Absurd values: refused at their line, before any work (issue 20).
        BadModel{"HugeQuaternion", kCamera, "1 1e300 0 0 0 0 0 0 1 a.jpg\n\n", kPoint,
                 "images.txt:1: QW: the quaternion (QW, QX, QY, QZ) has norm 1e+300; COLMAP's is "
                 "a unit quaternion (one with a norm between 1e-12 and 1000000000000 is "
                 "normalised)"},
        BadModel{"NegativeFocalLength", "1 SIMPLE_RADIAL 100 80 -6000 50 40 0.01\n", kImage,
                 kPoint, "cameras.txt:1: PARAMS f: -6000 is no focal length: it must be at least "
                 "0.001 px"},
        BadModel{"HugeFocalLength", "1 PINHOLE 100 80 100 1e300 50 40\n", kImage, kPoint,
                 "cameras.txt:1: PARAMS fy: 1e+300 is outside [-100000000, 100000000] px"},
        BadModel{"HugePrincipalPoint", "1 PINHOLE 100 80 100 100 50 -4e8\n", kImage, kPoint,
                 "cameras.txt:1: PARAMS cy: -400000000 is outside [-100000000, 100000000] px"},
        BadModel{"HugeTranslation", kCamera, "1 1 0 0 0 0 1e300 0 1 a.jpg\n\n", kPoint,
                 "images.txt:1: TY: 1e+300 is outside [-100000000, 100000000] m"},
        BadModel{"HugeKeypoint", kCamera, "1 1 0 0 0 0 0 0 1 a.jpg\n60 1e10 3\n", kPoint,
                 "images.txt:2: POINTS2D Y: 10000000000 is outside [-100000000, 100000000] px"},
        BadModel{"HugePoint", kCamera, kImage, "3 1 2e300 10 10 20 30 0.5 1 0\n",
                 "points3D.txt:1: Y: 2e+300 is outside [-100000000, 100000000] m"},
        // A long token is echoed cut, and escaped.
        BadModel{"LongModelName",
                 "1 \x1b[2J_ABCDEFGHIJKLMNOPQRSTUVWXYZ_ABCDEFGHIJKLMNOPQRSTUVWXYZ 100 80 1 2 3\n",
                 kImage, kPoint,
                 "cameras.txt:1: MODEL: camera model '\\x1B[2J_ABCDEFGHIJKLMNOPQRSTUVWXYZ_ABCDEFGH"
                 "\u2026(58 bytes)' is not supported (supported: SIMPLE_PINHOLE, PINHOLE, "
                 "SIMPLE_RADIAL, RADIAL, OPENCV, OPENCV_FISHEYE, FULL_OPENCV)"}),
    [](const ::testing::TestParamInfo<BadModel>& info) { return std::string(info.param.name); });

TEST(ColmapIo, AFifoOrAFileOverTheLimitIsRefusedWithoutWaitingOrReading) {
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  dir.Write("cameras.txt", kCamera);
  dir.Write("points3D.txt", kPoint);
  ASSERT_EQ(mkfifo(dir.Path("images.txt").c_str(), 0644), 0);
  Block block;
  EXPECT_EQ(ReadColmapModel(dir.path(), &block).message(),
            dir.Path("images.txt") +
                ": is a FIFO (named pipe), not a regular file; photopose reads regular files, or "
                "standard input for '-'");
  std::filesystem::remove(dir.Path("images.txt"));
  dir.Write("images.txt", kImage);
  std::filesystem::resize_file(dir.Path("points3D.txt"), kMaxInputBytes + 1);  // sparse
  EXPECT_EQ(ReadColmapModel(dir.path(), &block).message(),
            dir.Path("points3D.txt") +
                ": is larger than 268435456 bytes, the largest input photopose reads");
}

TEST(ColmapIo, ParseColmapModelReadsTheTextsAsReadColmapModelReadsTheFiles) {
  ColmapModelFiles text{ColmapFormat::kText, kCamera, kImage, kPoint};
  Block block;
  ASSERT_TRUE(ParseColmapModel(text, "m", &block).ok());
  EXPECT_EQ(block.images.size(), 1u);
  EXPECT_EQ(block.marks.size(), 1u);
  text.points3D = "3 1 2 10 10 20 30 0.5\n";
  EXPECT_EQ(ParseColmapModel(text, "m", &block).message(),
            "m/points3D.txt:1: TRACK: point 3 is observed in image 'a.jpg' but that is not in its "
            "track");
}

TEST(ColmapIo, MissingFileIsAnError) {
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  Block block;
  const Status status = ReadColmapModel(dir.path(), &block);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.message(), dir.path() +
                                  ": no complete COLMAP model (cameras, images and points3D, all "
                                  ".bin or all .txt): cameras.txt, images.txt, points3D.txt "
                                  "missing");
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
