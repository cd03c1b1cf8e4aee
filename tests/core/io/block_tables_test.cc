#include "core/io/block_tables.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "core/io/csv.h"
#include "core/simulation/synthetic_block.h"
#include "core/io/tables.h"
#include "tests/support/temp_dir.h"
#include "tests/test_data.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

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

// ------------------------------------------------------------------ reading: ReadBlock, AssembleBlock


// A digital camera (4.4 um pixels, 6000 x 4000), and a film camera with only the schema's required
// columns (no image size): its pixel marks cannot be turned into film, its film marks can.
BlockTables Tables() {
  BlockTables t;
  FrameCamera digital;
  digital.camera_id = "cam";
  digital.focal_length_um = 35000.0;
  digital.pixel_size_um = 4.4;
  digital.n_columns = 6000;
  digital.n_rows = 4000;
  FrameCamera film;
  film.camera_id = "film";
  film.focal_length_um = 152916.0;
  film.pixel_size_um = 1.0;
  t.cameras = {digital, film};
  GroundPoint a, b, c;
  a.point_id = "A";
  a.position = {100, 100, 0};
  a.accuracy_m = Eigen::Vector3d(0.02, 0.02, 0.05);
  a.line = 2;
  b.point_id = "B";
  b.position = {300, 120, 5};
  b.role = PointRole::kCheck;
  b.line = 3;
  c.point_id = "C";
  c.position = {180, 300, 2};
  c.role = PointRole::kTie;  // a row with approximate values only
  c.line = 4;
  t.points = {a, b, c};
  const auto mark = [](const std::string& raster, const std::string& point, int line,
                       std::optional<Eigen::Vector2d> pixels, std::optional<Eigen::Vector2d> film,
                       const std::string& camera = "") {
    ImageMark m;
    m.raster = raster;
    m.point_id = point;
    m.line = line;
    m.column_row = pixels;
    m.film_um = film;
    m.camera_id = camera;
    return m;
  };
  t.marks = {mark("img2", "A", 2, Eigen::Vector2d(1409.1, 3590.9), std::nullopt, "cam"),
             mark("img1", "B", 3, Eigen::Vector2d(10, 20), std::nullopt, "cam"),
             mark("img2", "X9", 4, Eigen::Vector2d(3000, 2000), std::nullopt),
             mark("photo", "A", 5, std::nullopt, Eigen::Vector2d(86421, -83977), "film")};
  t.marks[0].accuracy_px = 0.5;
  t.marks[3].accuracy_px = 3.0;  // um: the mark's own unit
  FrameRecord frame;
  frame.raster = "img3";
  frame.camera_id = "cam";
  frame.eo.set_center_in_ground({200, 200, 500});
  frame.eo.set_angles_seed_rad({0.01, -0.02, 0.3});
  frame.center_accuracy_m = Eigen::Vector3d(5, 5, 10);
  frame.attitude_accuracy_deg = Eigen::Vector3d(0.1, 0.1, 0.5);
  frame.line = 2;
  t.frames = {frame};
  t.cameras_file = "cameras.csv";
  t.points_file = "points.csv";
  t.marks_file = "marks.csv";
  t.frames_file = "frames.csv";
  return t;
}

TEST(BlockAssembly, AssemblesMarksPointsImagesAndFrames) {
  Block block;
  const Status status = AssembleBlock(Tables(), &block);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_TRUE(CheckBlock(block).ok());
  // Images in the order of their first mark, then the frames row without marks.
  ASSERT_EQ(block.images.size(), 4u);
  EXPECT_EQ(block.images[0].name, "img2");
  EXPECT_EQ(block.images[1].name, "img1");
  EXPECT_EQ(block.images[2].name, "photo");
  EXPECT_EQ(block.images[3].name, "img3");
  EXPECT_EQ(block.cameras[block.images[2].camera].camera_id, "film");
  // The points of the table, then the tie point only a mark names.
  ASSERT_EQ(block.points.size(), 4u);
  EXPECT_EQ(block.points[0].role, PointRole::kControl);
  EXPECT_EQ(block.points[0].surveyed_m, Eigen::Vector3d(100, 100, 0));
  EXPECT_EQ(block.points[0].accuracy_m, Eigen::Vector3d(0.02, 0.02, 0.05));
  EXPECT_EQ(block.points[1].role, PointRole::kCheck);
  EXPECT_EQ(block.points[2].role, PointRole::kTie);
  EXPECT_FALSE(block.points[2].surveyed_m.has_value());
  EXPECT_EQ(block.points[2].position_m, Eigen::Vector3d(180, 300, 2));
  EXPECT_EQ(block.points[3].id, "X9");
  EXPECT_EQ(block.points[3].role, PointRole::kTie);
  EXPECT_FALSE(block.points[3].position_m.has_value());
  // A pixel mark: film through the camera table, um per pixel, accuracy kept in pixels.
  const BlockMark& pixel = block.marks[0];
  EXPECT_EQ(pixel.unit, MarkUnit::kPixel);
  EXPECT_EQ(pixel.measured, Eigen::Vector2d(1409.1, 3590.9));
  EXPECT_NEAR(pixel.observation.x(), (1409.1 - 3000.0) * 4.4, 1e-9);
  EXPECT_NEAR(pixel.observation.y(), (2000.0 - 3590.9) * 4.4, 1e-9);
  EXPECT_NEAR(pixel.observation_units_per_unit, 4.4, 1e-12);
  EXPECT_EQ(pixel.accuracy, 0.5);
  EXPECT_EQ(pixel.line, 2);
  // A film mark: as it is, accuracy in um.
  const BlockMark& film = block.marks[3];
  EXPECT_EQ(film.unit, MarkUnit::kFilm);
  EXPECT_EQ(film.observation, Eigen::Vector2d(86421, -83977));
  EXPECT_EQ(film.observation_units_per_unit, 1.0);
  EXPECT_EQ(film.accuracy, 3.0);
  // The frames row: initial pose and measured centre and attitude with their accuracies.
  const BlockImage& framed = block.images[3];
  ASSERT_TRUE(framed.eo.has_value());
  EXPECT_EQ(framed.measured_center_m, Eigen::Vector3d(200, 200, 500));
  EXPECT_EQ(framed.center_accuracy_m, Eigen::Vector3d(5, 5, 10));
  ASSERT_TRUE(framed.attitude_accuracy_rad.has_value());
  // rxryrz with AngleDirection -1: the file's angles are the seed angles, sigmas unchanged.
  EXPECT_NEAR((*framed.attitude_accuracy_rad)[0], DegreesToRadians(0.1), 1e-9);
  EXPECT_NEAR((*framed.attitude_accuracy_rad)[2], DegreesToRadians(0.5), 1e-9);
  EXPECT_EQ(framed.line, 2);
  EXPECT_EQ(block.marks_of_image[0].size(), 2u);
  EXPECT_EQ(block.marks_of_point[0].size(), 2u);
}

TEST(BlockAssembly, ErrorsNameTheFileLineAndColumn) {
  BlockTables t = Tables();
  t.marks[1].camera_id = "nocam";
  Block block;
  EXPECT_EQ(AssembleBlock(t, &block).message(), "marks.csv:3: CameraID: unknown camera 'nocam'");
  t = Tables();
  t.marks[2].camera_id = "film";
  EXPECT_EQ(AssembleBlock(t, &block).message(),
            "marks.csv:4: CameraID: image 'img2' has marks of two cameras ('cam' and 'film')");
  t = Tables();
  t.marks[1].camera_id.clear();
  EXPECT_EQ(AssembleBlock(t, &block).message(),
            "marks.csv:3: CameraID: image 'img1' names no camera and the camera table has several");
  // A pixel mark of the film camera, which has no image size: refused at that mark.
  t = Tables();
  t.marks[3].film_um.reset();
  t.marks[3].column_row = Eigen::Vector2d(10, 10);
  const std::string message = AssembleBlock(t, &block).message();
  EXPECT_EQ(message.rfind("marks.csv:5: Column: camera 'film' has no NRows and NColumns", 0), 0u)
      << message;
  // 20 000 px outside a 6000 x 4000 image.
  t = Tables();
  t.marks[1].column_row = Eigen::Vector2d(26000, 20);
  EXPECT_EQ(AssembleBlock(t, &block).message(),
            "marks.csv:3: Column: the mark of point '" + t.marks[1].point_id +
                "' in image 'img1' lies 20000 pixels outside the 6000 x 4000 image of camera '" +
                t.cameras[0].camera_id + "' (at most 5% of the image size is allowed)");
  // The frames row names another camera than the marks.
  t = Tables();
  t.frames[0].raster = "img1";
  t.frames[0].camera_id = "film";
  EXPECT_EQ(AssembleBlock(t, &block).message().rfind("frames.csv:2: CameraID:", 0), 0u);
}

// ApplyECC lowers points below the tangent plane of a map frame; a ground frame that PROJ knows as
// geographic (degrees) or geocentric (ECEF) is refused, naming the camera and where the CRS is named.
TEST(BlockAssembly, EarthCurvatureIsRefusedInAGeographicOrGeocentricFrame) {
  Block block;
  BlockTables t = Tables();
  t.cameras[0].apply_ecc = true;
  t.crs = "EPSG:4326";  // a gcp_list header
  EXPECT_EQ(AssembleBlock(t, &block).message(),
            "cameras.csv: ApplyECC: camera 'cam': the earth-curvature correction needs a projected or local "
            "map frame, and the ground frame is geographic (EPSG:4326, points.csv: header)");
  t.crs.clear();
  t.cameras[0].srs = "EPSG:4978";
  EXPECT_EQ(AssembleBlock(t, &block).message(),
            "cameras.csv: ApplyECC: camera 'cam': the earth-curvature correction needs a projected or local "
            "map frame, and the ground frame is geocentric (EPSG:4978, cameras.csv: SRS)");
  t.cameras[0].srs.clear();
  t.frames[0].srs = "EPSG:4979";
  EXPECT_EQ(AssembleBlock(t, &block).message(),
            "cameras.csv: ApplyECC: camera 'cam': the earth-curvature correction needs a projected or local "
            "map frame, and the ground frame is geographic (EPSG:4979, frames.csv:2: SRS)");
  // A projected grid, a text PROJ does not know (SRS is free text), or no ApplyECC: assembled.
  for (const char* srs : {"EPSG:32632", "site grid 1987"}) {
    t.frames[0].srs = srs;
    const Status status = AssembleBlock(t, &block);
    EXPECT_TRUE(status.ok()) << srs << ": " << status.message();
    EXPECT_GT(block.cameras[0].earth_curvature_radius_m(), 0.0);
  }
  t.frames[0].srs = "EPSG:4326";
  t.cameras[0].apply_ecc = false;
  EXPECT_TRUE(AssembleBlock(t, &block).ok());
  // The film camera's ApplyECC is checked against its own frames rows, not those of 'cam'.
  t.cameras[1].apply_ecc = true;
  EXPECT_TRUE(AssembleBlock(t, &block).ok());
}

TEST(BlockAssembly, ReadsTheFilesAndKeepsTheCoordinateSystemOfAGcpList) {
  const std::filesystem::path dir = testing::ScratchRoot();
  std::filesystem::create_directories(dir);
  const std::string cameras = (dir / "block_cameras.csv").string();
  std::ofstream(cameras) << "CameraID,FocalLength,PixelSize,NColumns,NRows\n"
                            "SX260HS,4500,1.5495867768595042,4000,3000\n";
  BlockFiles files;
  files.cameras = cameras;
  files.gcp_list = testing::SharedDataPath("odm_br/gcp_list.txt");
  Block block;
  const Status status = ReadBlock(files, &block);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(block.crs, "+proj=utm +zone=22 +south +datum=WGS84 +units=m +no_defs");
  EXPECT_EQ(block.images.size(), 10u);
  EXPECT_EQ(block.marks.size(), 25u);
  EXPECT_EQ(block.marks_source, files.gcp_list);
  EXPECT_EQ(block.marks[0].line, 2);
}

// A scan of 11500 x 11500 pixels of 20 um, the film centre at pixel (5750, 5750), film y up: four
// measured fiducials and the mark of film point (60000, 40000) um, Row counted as `rows` says.
BlockTables ScannedFilmTables(PixelRows rows) {
  BlockTables t;
  FrameCamera rc30;
  rc30.camera_id = "RC30";
  rc30.focal_length_um = 153012.0;
  rc30.n_rows = 11500;
  rc30.n_columns = 11500;
  rc30.film_fiducials_um = {{-106000, -106000}, {106000, -106000}, {106000, 106000},
                            {-106000, 106000}};
  t.cameras = {rc30};
  // Row 5750 - y / 20 counted down, 11500 minus that counted up.
  const auto pixel = [&](const Eigen::Vector2d& film) {
    const double row = 5750.0 - film.y() / 20.0;
    return Eigen::Vector2d(5750.0 + film.x() / 20.0, rows == PixelRows::kUp ? 11500.0 - row : row);
  };
  ImageMark mark;
  mark.raster = "scan_1";
  mark.point_id = "P";
  mark.column_row = pixel({60000, 40000});
  mark.line = 2;
  t.marks = {mark};
  for (int k = 0; k < 4; ++k) {
    MeasuredFiducial f;
    f.raster = "scan_1";
    f.fiducial_id = k + 1;
    f.column_row = pixel(rc30.film_fiducials_um[k]);
    f.line = k + 2;
    t.fiducials.push_back(f);
  }
  t.pixel_rows = rows;
  t.marks_file = "marks.csv";
  t.fiducials_file = "fiducials.csv";
  return t;
}

TEST(BlockAssembly, ScannedFilmUsesEachImagesFiducialAffine) {
  BlockTables t = ScannedFilmTables(PixelRows::kDown);
  Block block;
  const Status status = AssembleBlock(t, &block);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_TRUE(block.images[0].fiducial_fit.has_value());
  EXPECT_EQ(block.images[0].fiducial_fit->redundancy, 2);
  EXPECT_LT((block.marks[0].observation - Eigen::Vector2d(60000, 40000)).norm(), 1e-6);
  EXPECT_NEAR(block.marks[0].observation_units_per_unit, 20.0, 1e-9);
  EXPECT_TRUE(PixelToFilmCamera(block, 0).has_affine);
  // Fiducials of an image the block does not have.
  t.fiducials[0].raster = "scan_9";
  EXPECT_EQ(AssembleBlock(t, &block).message(),
            "fiducials.csv:2: Raster: image 'scan_9' has no marks and no frames row");
}

// Rows counted up (Row 0 at the bottom edge) are counted down at the reader: the same marks
// written either way give the same block, with the corner and the centre origin, with and without
// A0-B2 (stated in the file's row convention).
TEST(BlockAssembly, RowsCountedUpGiveTheBlockOfRowsCountedDown) {
  for (const PixelOrigin origin : {PixelOrigin::kCorner, PixelOrigin::kCenter}) {
    for (const bool affine : {false, true}) {
      SCOPED_TRACE(EnumName(origin) + std::string(affine ? " with A0-B2" : ""));
      BlockTables down = Tables();
      down.pixel_origin = origin;
      if (affine) {
        // 4.4 um pixels, the film centre at (3000, 2000), turned by 0.01 / 4.4 rad.
        down.cameras[0].has_affine = true;
        down.cameras[0].affine_a = {-13200.0, 4.4, 0.01};
        down.cameras[0].affine_b = {8800.0, 0.01, -4.4};
      }
      BlockTables up = down;
      up.pixel_rows = PixelRows::kUp;
      if (affine) {
        // By hand, Row counted up = 4000 - Row counted down (corner coordinates):
        // x = -13200 + 4.4 c + 0.01 (4000 - r') = -13160 + 4.4 c - 0.01 r',
        // y = 8800 + 0.01 c - 4.4 (4000 - r') = -8800 + 0.01 c + 4.4 r'.
        up.cameras[0].affine_a = {-13160.0, 4.4, -0.01};
        up.cameras[0].affine_b = {-8800.0, 0.01, 4.4};
      }
      const double last_row = origin == PixelOrigin::kCorner ? 4000.0 : 3999.0;
      for (ImageMark& mark : up.marks)
        if (mark.column_row) mark.column_row->y() = last_row - mark.column_row->y();
      Block from_down, from_up;
      ASSERT_TRUE(AssembleBlock(down, &from_down).ok());
      const Status status = AssembleBlock(up, &from_up);
      ASSERT_TRUE(status.ok()) << status.message();
      ASSERT_EQ(from_up.marks.size(), from_down.marks.size());
      for (size_t m = 0; m < from_up.marks.size(); ++m) {
        // 4000 - (4000 - r) is r to an ulp of 4000.
        EXPECT_NEAR((from_up.marks[m].measured - from_down.marks[m].measured).norm(), 0.0, 1e-12);
        EXPECT_NEAR((from_up.marks[m].observation - from_down.marks[m].observation).norm(), 0.0,
                    1e-9);
        EXPECT_NEAR(from_up.marks[m].observation_units_per_unit,
                    from_down.marks[m].observation_units_per_unit, 1e-12);
      }
      // The film camera has no NRows: its film mark needs none.
      EXPECT_EQ(from_up.marks[3].unit, MarkUnit::kFilm);
      EXPECT_EQ(from_up.cameras[0].table.affine_a, from_down.cameras[0].table.affine_a);
      for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(from_up.cameras[0].table.affine_b[k], from_down.cameras[0].table.affine_b[k],
                    1e-9);
    }
  }
}

TEST(BlockAssembly, RowsCountedUpNeedNRows) {
  Block block;
  // A pixel mark of a camera without NRows, refused at its line and field.
  BlockTables t = Tables();
  t.pixel_rows = PixelRows::kUp;
  t.marks[3].film_um.reset();
  t.marks[3].column_row = Eigen::Vector2d(10, 10);
  EXPECT_EQ(AssembleBlock(t, &block).message(),
            "marks.csv:5: Row: rows counted up need NRows in the camera table (camera 'film' has "
            "none)");
  // A0-B2 of a camera without NRows cannot be turned: refused at the camera table.
  t = Tables();
  t.pixel_rows = PixelRows::kUp;
  t.cameras[1].has_affine = true;
  t.cameras[1].affine_a = {0.0, 1.0, 0.0};
  t.cameras[1].affine_b = {0.0, 0.0, -1.0};
  EXPECT_EQ(AssembleBlock(t, &block).message(),
            "cameras.csv: NRows: camera 'film': rows counted up need NRows in the camera table (to "
            "turn A0-B2 to rows counted down)");
  // A gcp_list counts rows down by its definition.
  ScopedTempDir dir;
  ASSERT_TRUE(dir.ok());
  ASSERT_TRUE(WriteCameraTable(dir.Path("cameras.csv"), Tables().cameras).ok());
  {
    std::ofstream(dir.Path("gcp_list.txt")) << "EPSG:32632\n100 100 0 10 20 img1.jpg A\n";
  }
  BlockFiles files;
  files.cameras = dir.Path("cameras.csv");
  files.gcp_list = dir.Path("gcp_list.txt");
  files.pixel_rows = PixelRows::kUp;
  const std::string message = ReadBlock(files, &block).message();
  EXPECT_NE(message.find("gcp_list.txt: rows counted up apply to a marks table"), std::string::npos)
      << message;
}

// Scanned film with rows counted up: the measured fiducials' and the marks' Row counted down with
// NRows before the fit; a fiducial of a camera without NRows is refused at its line.
TEST(BlockAssembly, ScannedFilmWithRowsCountedUp) {
  BlockTables t = ScannedFilmTables(PixelRows::kUp);
  Block block;
  const Status status = AssembleBlock(t, &block);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_LT((block.marks[0].observation - Eigen::Vector2d(60000, 40000)).norm(), 1e-6);
  EXPECT_EQ(block.marks[0].measured, Eigen::Vector2d(8750, 3750));  // counted down
  EXPECT_LT(block.images[0].fiducial_fit->max_um, 1e-6);
  t.cameras[0].n_rows = 0;
  EXPECT_EQ(AssembleBlock(t, &block).message(),
            "fiducials.csv:2: Row: rows counted up need NRows in the camera table (camera 'RC30' "
            "has none)");
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
