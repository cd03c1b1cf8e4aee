#include "core/io/tables.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/io/csv.h"
#include "core/io/fiducials_table.h"
#include "tests/test_data.h"
#include "tests/support/ordered_draws.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

namespace fs = std::filesystem;

// Numbers are written in their shortest round-trip form, so only the degree <-> radian conversions
// and the angle conversions of core/rotation.h (a few ulp each) separate a read from a write.
constexpr double kRoundTripTolerance = 1e-12;
// Central differences with a 1e-6 rad step reproduce a linear propagation to about 1e-10.
constexpr double kPropagationTolerance = 1e-8;

class TablesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::path(::testing::TempDir()) / "photopose_tables_XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Writes `contents` to a file `name` in the test folder and returns its path.
  std::string Write(const std::string& name, const std::string& contents) {
    const std::string path = Path(name);
    std::ofstream(path, std::ios::binary) << contents;
    return path;
  }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  static std::string Read(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }
  std::set<std::string> FilesInDir() const {
    std::set<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir_)) names.insert(entry.path().filename());
    return names;
  }

  fs::path dir_;
};

// ------------------------------------------------------------------ camera table

TEST_F(TablesTest, CameraTableSchemaExampleRows) {
  // The example of the ArcGIS cameras table schema, with the image sizes of the UltraCamXp
  // panchromatic (17310 x 11310) and multispectral (5770 x 3770) images that photopose needs to
  // place the fiducial centre.
  const std::string path = Write("cameras.csv",
                                 "ObjectID,CameraID,FocalLength,PrincipalX,PrincipalY,PixelSize,"
                                 "NColumns,NRows\n"
                                 "1,UltraCamXp_Pan,100500,-120,0,6,17310,11310\n"
                                 "2,UltraCamXp_MS,100500,0,0,18,5770,3770\n");
  std::vector<FrameCamera> cameras;
  const Status status = ReadCameraTable(path, &cameras);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(cameras.size(), 2u);
  const FrameCamera& pan = cameras[0];
  EXPECT_EQ(pan.object_id, 1);
  EXPECT_EQ(pan.camera_id, "UltraCamXp_Pan");
  EXPECT_EQ(pan.focal_length_um, 100500.0);
  EXPECT_EQ(pan.principal_x_um, -120.0);
  EXPECT_EQ(pan.principal_y_um, 0.0);
  EXPECT_EQ(pan.pixel_size_um, 6.0);
  EXPECT_EQ(pan.n_columns, 17310);
  EXPECT_EQ(pan.n_rows, 11310);
  // Schema defaults.
  EXPECT_FALSE(pan.has_affine);
  EXPECT_EQ(pan.film_coordinate_system, FilmCoordinateSystem::kXRightYUp);
  EXPECT_EQ(pan.distortion_type, DistortionType::kDistortionModel);
  EXPECT_EQ(pan.orientation_type, OrientationType::kOpk);
  EXPECT_EQ(pan.angle_direction, -1);
  EXPECT_EQ(pan.polarity, -1);
  EXPECT_EQ(pan.affine_direction, 1);
  EXPECT_FALSE(pan.apply_ecc);
  EXPECT_EQ(pan.earth_radius_m, 6378137.0);
  EXPECT_FALSE(pan.average_z_m.has_value());
  EXPECT_TRUE(pan.extra_columns.empty());
  const FrameCamera& ms = cameras[1];
  EXPECT_EQ(ms.object_id, 2);
  EXPECT_EQ(ms.camera_id, "UltraCamXp_MS");
  EXPECT_EQ(ms.principal_x_um, 0.0);
  EXPECT_EQ(ms.pixel_size_um, 18.0);
  EXPECT_EQ(ms.n_columns, 5770);
  EXPECT_EQ(ms.n_rows, 3770);
}

// The schema makes NRows and NColumns optional: a table without them is valid (film marks need
// neither); a pixel mark that needs them is refused at its own line (tests/core/block_test.cc).
TEST_F(TablesTest, CameraTableExampleWithoutImageSizeIsAccepted) {
  const std::string path = Write("cameras.csv",
                                 "ObjectID,CameraID,FocalLength,PrincipalX,PrincipalY,PixelSize\n"
                                 "1,UltraCamXp_Pan,100500,-120,0,6\n");
  std::vector<FrameCamera> cameras;
  ASSERT_TRUE(ReadCameraTable(path, &cameras).ok());
  ASSERT_EQ(cameras.size(), 1u);
  EXPECT_EQ(cameras[0].n_rows, 0);
  EXPECT_FALSE(cameras[0].HasPixelToFilm());
}

TEST_F(TablesTest, FramesTableAccuracyColumnsRoundTrip) {
  const std::string path = Write("frames.csv",
                                 "Raster,CameraID,PerspectiveX,PerspectiveY,PerspectiveZ,Omega,Phi,"
                                 "Kappa,AccuracyX,AccuracyY,AccuracyZ,AccuracyOmega,AccuracyPhi,"
                                 "AccuracyKappa\n"
                                 "a,c,1,2,3,0.1,0.2,0.3,0.05,0.05,0.1,0.01,0.01,0.05\n"
                                 "b,c,1,2,3,0.1,0.2,0.3,,,,,,\n");
  std::vector<FrameRecord> frames;
  ASSERT_TRUE(ReadFramesTable(path, FramesTableOptions(), &frames).ok());
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].center_accuracy_m, Eigen::Vector3d(0.05, 0.05, 0.1));
  EXPECT_EQ(frames[0].attitude_accuracy_deg, Eigen::Vector3d(0.01, 0.01, 0.05));
  EXPECT_EQ(frames[0].line, 2);
  EXPECT_FALSE(frames[1].center_accuracy_m.has_value());
  EXPECT_TRUE(frames[0].extra_columns.empty());
  const std::string out = Write("out.csv", "");
  ASSERT_TRUE(WriteFramesTable(out, FramesTableOptions(), frames).ok());
  std::vector<FrameRecord> back;
  ASSERT_TRUE(ReadFramesTable(out, FramesTableOptions(), &back).ok());
  EXPECT_EQ(back[0].center_accuracy_m, frames[0].center_accuracy_m);
  EXPECT_EQ(back[0].attitude_accuracy_deg, frames[0].attitude_accuracy_deg);
  // All three or none, each positive.
  const std::string partial = Write("partial.csv",
                                    "Raster,CameraID,PerspectiveX,PerspectiveY,PerspectiveZ,Omega,"
                                    "Phi,Kappa,AccuracyX,AccuracyY,AccuracyZ\n"
                                    "a,c,1,2,3,0,0,0,0.05,,0.1\n");
  EXPECT_EQ(ReadFramesTable(partial, FramesTableOptions(), &frames).message(),
            partial + ":2: AccuracyY: is empty; AccuracyX, AccuracyY, AccuracyZ are given together");
  const std::string negative = Write("negative.csv",
                                     "Raster,CameraID,PerspectiveX,PerspectiveY,PerspectiveZ,Omega,"
                                     "Phi,Kappa,AccuracyOmega,AccuracyPhi,AccuracyKappa\n"
                                     "a,c,1,2,3,0,0,0,0.1,-0.1,0.1\n");
  EXPECT_EQ(ReadFramesTable(negative, FramesTableOptions(), &frames).message(),
            negative + ":2: AccuracyPhi: '-0.1' must be positive");
}

TEST_F(TablesTest, CameraTableFullDistortionModelRow) {
  const std::string path = Write(
      "cameras.csv",
      "ObjectID,CameraID,FocalLength,PrincipalX,PrincipalY,PixelSize,NRows,NColumns,NBands,"
      "PixelType,BlockName,FilmCoordinateSystem,DistortionType,Radial,Tangential,OrientationType,"
      "AngleDirection,Polarity,AverageZ,ApplyECC,EarthRadius,SRS,FilmFiducials\n"
      "7,DMC,120000,12.5,-8.25,12,13824,7680,4,8_BIT_UNSIGNED,Block A,X_UP_Y_LEFT,"
      "\"Distortion Model\",0.0001;-3e-06;2e-10;-1e-14,1e-06 -2e-06,matrix,+1,1,250.5,YES,6371000,"
      "EPSG:32633,\"-82944 46080;82944 46080;82944 -46080;-82944 -46080\"\n");
  std::vector<FrameCamera> cameras;
  const Status status = ReadCameraTable(path, &cameras);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(cameras.size(), 1u);
  const FrameCamera& c = cameras[0];
  EXPECT_EQ(c.object_id, 7);
  EXPECT_EQ(c.camera_id, "DMC");
  EXPECT_EQ(c.focal_length_um, 120000.0);
  EXPECT_EQ(c.principal_x_um, 12.5);
  EXPECT_EQ(c.principal_y_um, -8.25);
  EXPECT_EQ(c.pixel_size_um, 12.0);
  EXPECT_EQ(c.n_rows, 13824);
  EXPECT_EQ(c.n_columns, 7680);
  EXPECT_EQ(c.n_bands, 4);
  EXPECT_EQ(c.pixel_type, "8_BIT_UNSIGNED");
  EXPECT_EQ(c.block_name, "Block A");
  EXPECT_EQ(c.film_coordinate_system, FilmCoordinateSystem::kXUpYLeft);
  EXPECT_EQ(c.distortion_type, DistortionType::kDistortionModel);
  EXPECT_EQ(c.radial_k, (std::array<double, 4>{1e-4, -3e-6, 2e-10, -1e-14}));
  EXPECT_EQ(c.tangential_p, (std::array<double, 2>{1e-6, -2e-6}));
  EXPECT_EQ(c.orientation_type, OrientationType::kMatrix);
  EXPECT_EQ(c.angle_direction, 1);
  EXPECT_EQ(c.polarity, 1);
  EXPECT_EQ(c.average_z_m, 250.5);
  EXPECT_TRUE(c.apply_ecc);
  EXPECT_EQ(c.earth_radius_m, 6371000.0);
  EXPECT_EQ(c.srs, "EPSG:32633");
  ASSERT_EQ(c.film_fiducials_um.size(), 4u);
  EXPECT_EQ(c.film_fiducials_um[0], Eigen::Vector2d(-82944, 46080));
  EXPECT_EQ(c.film_fiducials_um[3], Eigen::Vector2d(-82944, -46080));
}

TEST_F(TablesTest, CameraTableRadialWithThreeValuesMeansK1K2K3) {
  const std::string path = Write("cameras.csv",
                                 "CameraID,FocalLength,PixelSize,NRows,NColumns,Radial\n"
                                 "C,8800,2.41,3000,4000,1e-3 2e-6 -3e-9\n");
  std::vector<FrameCamera> cameras;
  ASSERT_TRUE(ReadCameraTable(path, &cameras).ok());
  EXPECT_EQ(cameras[0].radial_k, (std::array<double, 4>{0.0, 1e-3, 2e-6, -3e-9}));
}

TEST_F(TablesTest, CameraTableDistortionTableRow) {
  const std::string path = Write("cameras.csv",
                                 "CameraID,FocalLength,PixelSize,NRows,NColumns,DistortionType,"
                                 "RadialDistances,RadialDistortions\n"
                                 "RC30,153000,15,15000,15000,distortiontable,"
                                 "10000;20000;30000 40000,1.5;-2;2.5;3\n");
  std::vector<FrameCamera> cameras;
  const Status status = ReadCameraTable(path, &cameras);
  ASSERT_TRUE(status.ok()) << status.message();
  const FrameCamera& c = cameras[0];
  EXPECT_EQ(c.distortion_type, DistortionType::kDistortionTable);
  EXPECT_EQ(c.radial_distances_um, (std::vector<double>{10000, 20000, 30000, 40000}));
  EXPECT_EQ(c.radial_distortions_um, (std::vector<double>{1.5, -2, 2.5, 3}));
}

TEST_F(TablesTest, CameraTableAffineRowNeedsNoPixelSize) {
  const std::string path = Write("cameras.csv",
                                 "CameraID,FocalLength,A0,A1,A2,B0,B1,B2,AffineDirection,"
                                 "FilmCoordinateSystem\n"
                                 "RMK,152000,-115000,12,0.01,115000,-0.02,-12,-1,4\n");
  std::vector<FrameCamera> cameras;
  const Status status = ReadCameraTable(path, &cameras);
  ASSERT_TRUE(status.ok()) << status.message();
  const FrameCamera& c = cameras[0];
  EXPECT_TRUE(c.has_affine);
  EXPECT_EQ(c.affine_a, (std::array<double, 3>{-115000, 12, 0.01}));
  EXPECT_EQ(c.affine_b, (std::array<double, 3>{115000, -0.02, -12}));
  EXPECT_EQ(c.affine_direction, -1);
  EXPECT_EQ(c.film_coordinate_system, FilmCoordinateSystem::kXDownYRight);
  EXPECT_EQ(c.pixel_size_um, 0.0);
}

FrameCamera FullCamera() {
  FrameCamera c;
  c.object_id = 3;
  c.camera_id = "Cam, \"main\"";  // needs quoting
  c.focal_length_um = 100500.123456789;
  c.principal_x_um = -120.25;
  c.principal_y_um = 1.0 / 3.0;
  c.pixel_size_um = 6.0;
  c.n_rows = 11310;
  c.n_columns = 17310;
  c.n_bands = 1;
  c.pixel_type = "16_BIT_UNSIGNED";
  c.block_name = " block ";
  c.film_coordinate_system = FilmCoordinateSystem::kXLeftYDown;
  c.has_affine = true;
  c.affine_a = {-51930.0, 6.0, 1e-7};
  c.affine_b = {33930.0, -2e-7, -6.0};
  c.affine_direction = 1;
  c.distortion_type = DistortionType::kDistortionTable;
  c.radial_k = {1e-5, -2e-9, 3e-13, 0.1};
  c.tangential_p = {1e-7, 2e-7};
  c.radial_distances_um = {0.0, 1e4, 2e4, 5e4};
  c.radial_distortions_um = {0.0, 0.5, -0.7, 1.0 / 7.0};
  c.film_fiducials_um = {{-106000.0, 106000.0}, {106000.0, 106000.0}, {0.1, -106000.0}};
  c.orientation_type = OrientationType::kMatrix;
  c.angle_direction = 1;
  c.polarity = 1;
  c.average_z_m = 312.75;
  c.apply_ecc = true;
  c.earth_radius_m = 6371008.8;
  c.srs = "+proj=utm +zone=33 +datum=WGS84";
  c.extra_columns = {{"Owner", "Survey, Inc."}, {"Calibrated", "2021-04-01"}};
  return c;
}

void ExpectSameCamera(const FrameCamera& a, const FrameCamera& b) {
  EXPECT_EQ(a.object_id, b.object_id);
  EXPECT_EQ(a.camera_id, b.camera_id);
  EXPECT_EQ(a.focal_length_um, b.focal_length_um);
  EXPECT_EQ(a.principal_x_um, b.principal_x_um);
  EXPECT_EQ(a.principal_y_um, b.principal_y_um);
  EXPECT_EQ(a.pixel_size_um, b.pixel_size_um);
  EXPECT_EQ(a.n_rows, b.n_rows);
  EXPECT_EQ(a.n_columns, b.n_columns);
  EXPECT_EQ(a.n_bands, b.n_bands);
  EXPECT_EQ(a.pixel_type, b.pixel_type);
  EXPECT_EQ(a.block_name, b.block_name);
  EXPECT_EQ(a.film_coordinate_system, b.film_coordinate_system);
  EXPECT_EQ(a.has_affine, b.has_affine);
  if (a.has_affine) {
    EXPECT_EQ(a.affine_a, b.affine_a);
    EXPECT_EQ(a.affine_b, b.affine_b);
  }
  EXPECT_EQ(a.affine_direction, b.affine_direction);
  EXPECT_EQ(a.distortion_type, b.distortion_type);
  EXPECT_EQ(a.radial_k, b.radial_k);
  EXPECT_EQ(a.tangential_p, b.tangential_p);
  EXPECT_EQ(a.radial_distances_um, b.radial_distances_um);
  EXPECT_EQ(a.radial_distortions_um, b.radial_distortions_um);
  EXPECT_EQ(a.film_fiducials_um, b.film_fiducials_um);
  EXPECT_EQ(a.orientation_type, b.orientation_type);
  EXPECT_EQ(a.angle_direction, b.angle_direction);
  EXPECT_EQ(a.polarity, b.polarity);
  EXPECT_EQ(a.average_z_m, b.average_z_m);
  EXPECT_EQ(a.apply_ecc, b.apply_ecc);
  EXPECT_EQ(a.earth_radius_m, b.earth_radius_m);
  EXPECT_EQ(a.srs, b.srs);
  EXPECT_EQ(a.extra_columns, b.extra_columns);
}

TEST_F(TablesTest, CameraTableRoundTripKeepsEveryFieldAndUnknownColumns) {
  FrameCamera plain;
  plain.camera_id = "Plain";
  plain.focal_length_um = 8800.0;
  plain.pixel_size_um = 2.41;
  plain.n_rows = 3000;
  plain.n_columns = 4000;
  plain.extra_columns = {{"Calibrated", "2020"}};  // a subset of the other camera's extras
  const std::vector<FrameCamera> cameras = {FullCamera(), plain};
  const std::string path = Path("cameras_out.csv");
  const Status written = WriteCameraTable(path, cameras);
  ASSERT_TRUE(written.ok()) << written.message();

  std::vector<FrameCamera> back;
  const Status read = ReadCameraTable(path, &back);
  ASSERT_TRUE(read.ok()) << read.message() << "\n" << Read(path);
  ASSERT_EQ(back.size(), 2u);
  ExpectSameCamera(back[0], cameras[0]);
  // The union of the extra columns is written; a camera without one gets an empty field.
  FrameCamera expected_plain = plain;
  expected_plain.extra_columns = {{"Owner", ""}, {"Calibrated", "2020"}};
  ExpectSameCamera(back[1], expected_plain);
}

TEST_F(TablesTest, CameraTableReadsUnknownColumnsAndTolerantHeaders) {
  const std::string path = Write("cameras.csv",
                                 "camera_id,Focal Length,pixelsize,NROWS,n_columns,Lens Serial\n"
                                 "C1,8800,2.41,3000,4000,SN-123\n");
  std::vector<FrameCamera> cameras;
  const Status status = ReadCameraTable(path, &cameras);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(cameras[0].camera_id, "C1");
  EXPECT_EQ(cameras[0].n_columns, 4000);
  ASSERT_EQ(cameras[0].extra_columns.size(), 1u);
  EXPECT_EQ(cameras[0].extra_columns[0],
            (std::pair<std::string, std::string>{"Lens Serial", "SN-123"}));
}

// One header line and one data row (line 2) of a camera table, for the error cases.
struct CameraErrorCase {
  std::string header;
  std::string row;
  std::string expected;  // after "path:"
};

TEST_F(TablesTest, CameraTableErrorsNameFileLineAndColumn) {
  const std::string base = "CameraID,FocalLength,PixelSize,NRows,NColumns";
  const std::vector<CameraErrorCase> cases = {
      {"FocalLength,PixelSize", "1,2", "1: CameraID: required column is missing"},
      {"CameraID,PixelSize", "C,2", "1: FocalLength: required column is missing"},
      {"CameraID,FocalLength,NRows", "C,1,2", "1: PixelSize: required column is missing"},
      {base, "C,abc,6,10,10", "2: FocalLength: 'abc' is not a number"},
      {base, "C,NaN,6,10,10", "2: FocalLength: 'NaN' is not a finite number"},
      {base, "C,100,inf,10,10", "2: PixelSize: 'inf' is not a finite number"},
      {base, ",100,6,10,10", "2: CameraID: is empty"},
      {base, "C,,6,10,10", "2: FocalLength: is empty"},
      {base, "C,-100,6,10,10", "2: FocalLength: '-100' is outside [1, 100000000] um"},
      {base, "C,100,6,10.5,10", "2: NRows: '10.5' is not a whole number"},
      {base, "C,100,6,-10,10", "2: NRows: '-10' must be a positive whole number"},
      {base + ",Radial", "C,100,6,10,10,1;2",
       "2: Radial: has 2 numbers, expected K0;K1;K2;K3 (4) or "
       "K1;K2;K3 (3)"},
      {base + ",Radial", "C,100,6,10,10,1;x;3", "2: Radial: item 2: 'x' is not a number"},
      {base + ",Tangential", "C,100,6,10,10,1 2 3",
       "2: Tangential: has 3 numbers, expected P1;P2 (2)"},
      {base + ",FilmCoordinateSystem", "C,100,6,10,10,5",
       "2: FilmCoordinateSystem: '5' is not 1, 2, 3, 4, X_RIGHT_Y_UP, X_UP_Y_LEFT, X_LEFT_Y_DOWN "
       "or X_DOWN_Y_RIGHT"},
      {base + ",DistortionType", "C,100,6,10,10,Polynomial",
       "2: DistortionType: 'Polynomial' is not DistortionModel or DistortionTable"},
      {base + ",OrientationType", "C,100,6,10,10,PhiOmegaKappa",
       "2: OrientationType: 'PhiOmegaKappa' is not OPK or Matrix"},
      {base + ",AngleDirection", "C,100,6,10,10,0", "2: AngleDirection: '0' must be -1 or +1"},
      {base + ",Polarity", "C,100,6,10,10,2", "2: Polarity: '2' must be -1 or +1"},
      {base + ",AffineDirection", "C,100,6,10,10,x", "2: AffineDirection: 'x' is not a number"},
      {base + ",ApplyECC", "C,100,6,10,10,maybe",
       "2: ApplyECC: 'maybe' is not true, false, 1, 0, yes or no"},
      {base + ",A0,A1,A2,B0,B1,B2", "C,100,6,10,10,1,2,3,4,,6",
       "2: B1: is empty; A0, A1, A2, B0, B1, B2 are given together"},
      {base + ",DistortionType", "C,100,6,10,10,DistortionTable",
       "2: RadialDistances: is empty; DistortionTable needs RadialDistances and RadialDistortions"},
      {base + ",RadialDistances,RadialDistortions", "C,100,6,10,10,1;2;3,0;0",
       "2: RadialDistortions: has 2 numbers but RadialDistances has 3"},
      {base + ",RadialDistances,RadialDistortions", "C,100,6,10,10,1;3;2,0;0;0",
       "2: RadialDistances: must increase: item 3 (2) is not larger than item 2 (3)"},
      {base + ",FilmFiducials", "C,100,6,10,10,1 2;3",
       "2: FilmFiducials: item 2 '3' has 1 numbers, expected 2 separated by spaces"},
      {base + ",EarthRadius", "C,100,6,10,10,-1",
       "2: EarthRadius: '-1' is outside (0, 100000000] m"},
  };
  for (const CameraErrorCase& c : cases) {
    const std::string path = Write("cameras.csv", c.header + "\n" + c.row + "\n");
    std::vector<FrameCamera> cameras;
    EXPECT_EQ(ReadCameraTable(path, &cameras).message(), path + ":" + c.expected) << c.row;
  }
}

TEST_F(TablesTest, CameraTableDuplicateIdNamesBothLines) {
  const std::string path = Write("cameras.csv",
                                 "CameraID,FocalLength,PixelSize,NRows,NColumns\n"
                                 "A,100,6,10,10\n"
                                 "# a comment\n"
                                 "A,100,6,10,10\n");
  std::vector<FrameCamera> cameras;
  EXPECT_EQ(ReadCameraTable(path, &cameras).message(),
            path + ":4: CameraID: duplicate camera 'A' (first on line 2)");
}

TEST_F(TablesTest, MissingFileSaysSo) {
  const std::string path = Path("points.csv");
  std::vector<GroundPoint> points;
  EXPECT_EQ(ReadGroundPoints(path, &points).message(),
            path + ": cannot open: No such file or directory");
  std::vector<FrameCamera> cameras;
  EXPECT_EQ(ReadCameraTable(path, &cameras).message(),
            path + ": cannot open: No such file or directory");
  GcpList gcp;
  EXPECT_EQ(ReadGcpList(path, &gcp).message(), path + ": cannot open: No such file or directory");
}

TEST_F(TablesTest, CameraWriterRefusesWhatCouldNotBeReadBack) {
  FrameCamera camera = FullCamera();
  camera.focal_length_um = std::nan("");
  const std::string path = Path("cameras.csv");
  EXPECT_FALSE(WriteCameraTable(path, {camera}).ok());
  camera = FullCamera();
  camera.extra_columns = {{"focal length", "1"}};
  EXPECT_EQ(WriteCameraTable(path, {camera}).message(),
            path + ": extra column 'focal length' is a standard column");
  EXPECT_FALSE(fs::exists(path));
}

// ------------------------------------------------------------------ frames table

FrameCamera SimpleCamera(const std::string& id, int angle_direction,
                         OrientationType orientation = OrientationType::kOpk) {
  FrameCamera c;
  c.camera_id = id;
  c.focal_length_um = 100000.0;
  c.pixel_size_um = 6.0;
  c.n_rows = 1000;
  c.n_columns = 1000;
  c.angle_direction = angle_direction;
  c.orientation_type = orientation;
  return c;
}

double MaxAngleDifference(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  double worst = 0.0;
  for (int i = 0; i < 3; ++i) worst = std::max(worst, std::abs(WrapAngle(a[i] - b[i])));
  return worst;
}

TEST_F(TablesTest, FramesRoundTripEveryConventionAndAngleDirection) {
  std::mt19937 rng(20240611);
  std::uniform_real_distribution<double> any_angle(-kPi, kPi);
  std::uniform_real_distribution<double> phi_angle(DegreesToRadians(-80), DegreesToRadians(80));
  std::uniform_real_distribution<double> coordinate(-1e4, 1e4);
  const std::vector<FrameCamera> cameras = {SimpleCamera("clockwise", -1),
                                            SimpleCamera("counterclockwise", +1)};
  std::vector<FrameRecord> frames;
  for (int i = 0; i < 40; ++i) {
    FrameRecord f;
    f.raster = "IMG_" + std::to_string(i);
    f.camera_id = cameras[i % 2].camera_id;
    f.eo.parameters << 500000 + coordinate(rng), 4e6 + coordinate(rng), 800 + coordinate(rng) / 10,
        any_angle(rng), phi_angle(rng), any_angle(rng);
    frames.push_back(f);
  }
  for (const RotationConvention convention :
       {RotationConvention::kSeed, RotationConvention::kOpk, RotationConvention::kPok}) {
    SCOPED_TRACE(EnumName(convention));
    FramesTableOptions options;
    options.convention = convention;
    options.cameras = &cameras;
    const std::string path = Path(std::string("frames_") + EnumName(convention));
    const Status written = WriteFramesTable(path, options, frames);
    ASSERT_TRUE(written.ok()) << written.message();
    std::vector<FrameRecord> back;
    const Status read = ReadFramesTable(path, options, &back);
    ASSERT_TRUE(read.ok()) << read.message();
    ASSERT_EQ(back.size(), frames.size());
    for (size_t i = 0; i < frames.size(); ++i) {
      EXPECT_EQ(back[i].raster, frames[i].raster);
      EXPECT_EQ(back[i].camera_id, frames[i].camera_id);
      EXPECT_EQ(back[i].eo.center_in_ground(), frames[i].eo.center_in_ground());
      EXPECT_LT(MaxAngleDifference(back[i].eo.angles_seed_rad(), frames[i].eo.angles_seed_rad()),
                kRoundTripTolerance)
          << i;
      EXPECT_FALSE(back[i].covariance.has_value());
    }
  }
}

TEST_F(TablesTest, FramesAnglesAreConvertedFromTheFileConvention) {
  const std::string path = Write("frames.csv",
                                 "Raster,CameraID,PerspectiveX,PerspectiveY,PerspectiveZ,Omega,Phi,"
                                 "Kappa,SRS\n"
                                 "a.tif,cw,100,200,300,10,20,30,EPSG:2056\n"
                                 "b.tif,ccw,100,200,300,10,20,30,\n");
  const Eigen::Vector3d angles_rad = Eigen::Vector3d(10, 20, 30) / kDegreesPerRadian;
  const std::vector<FrameCamera> cameras = {SimpleCamera("cw", -1), SimpleCamera("ccw", +1)};
  for (const RotationConvention convention :
       {RotationConvention::kSeed, RotationConvention::kOpk, RotationConvention::kPok}) {
    SCOPED_TRACE(EnumName(convention));
    FramesTableOptions options;
    options.convention = convention;
    options.cameras = &cameras;
    std::vector<FrameRecord> frames;
    const Status status = ReadFramesTable(path, options, &frames);
    ASSERT_TRUE(status.ok()) << status.message();
    ASSERT_EQ(frames.size(), 2u);
    EXPECT_EQ(frames[0].eo.center_in_ground(), Eigen::Vector3d(100, 200, 300));
    EXPECT_EQ(frames[0].srs, "EPSG:2056");
    // R_camera_from_ground of the file's convention, AngleDirection -1: angles as written.
    const Eigen::Matrix3d R_cw = RotationFromAngles(convention, angles_rad);
    EXPECT_LT((RotationFromAngles(RotationConvention::kSeed, frames[0].eo.angles_seed_rad()) - R_cw)
                  .cwiseAbs()
                  .maxCoeff(),
              kRoundTripTolerance);
    // AngleDirection +1: the angles are negated.
    const Eigen::Matrix3d R_ccw = RotationFromAngles(convention, -angles_rad);
    EXPECT_LT(
        (RotationFromAngles(RotationConvention::kSeed, frames[1].eo.angles_seed_rad()) - R_ccw)
            .cwiseAbs()
            .maxCoeff(),
        kRoundTripTolerance);
  }
  // Seed convention, no cameras: the angles are the seed angles (AngleDirection -1).
  std::vector<FrameRecord> frames;
  ASSERT_TRUE(ReadFramesTable(path, FramesTableOptions(), &frames).ok());
  EXPECT_LT(MaxAngleDifference(frames[1].eo.angles_seed_rad(), angles_rad), kRoundTripTolerance);
}

TEST_F(TablesTest, FramesMatrixColumn) {
  const Eigen::Vector3d seed(0.1, -0.2, 2.5);
  const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> R =
      RotationFromAngles(RotationConvention::kSeed, seed);
  std::string matrix;
  for (int i = 0; i < 9; ++i)
    matrix += (i % 3 == 0 && i > 0 ? ";" : " ") + FormatNumber(R.data()[i]);
  const std::string path = Write("frames.csv",
                                 "Raster,CameraID,PerspectiveX,PerspectiveY,PerspectiveZ,Matrix\n"
                                 "m.tif,M,1,2,3," +
                                     matrix + "\n");
  // Without cameras, the Matrix column is used because there are no angles; the matrix is
  // R_camera_from_ground whatever the convention and AngleDirection.
  for (const RotationConvention convention :
       {RotationConvention::kSeed, RotationConvention::kOpk, RotationConvention::kPok}) {
    FramesTableOptions options;
    options.convention = convention;
    std::vector<FrameRecord> frames;
    const Status status = ReadFramesTable(path, options, &frames);
    ASSERT_TRUE(status.ok()) << status.message();
    EXPECT_LT(MaxAngleDifference(frames[0].eo.angles_seed_rad(), seed), kRoundTripTolerance);
  }
  // A camera with OrientationType Matrix: the writer adds the Matrix column and the reader uses it.
  const std::vector<FrameCamera> cameras = {SimpleCamera("M", +1, OrientationType::kMatrix)};
  FramesTableOptions options;
  options.convention = RotationConvention::kOpk;
  options.cameras = &cameras;
  std::vector<FrameRecord> frames;
  ASSERT_TRUE(ReadFramesTable(path, options, &frames).ok());
  EXPECT_LT(MaxAngleDifference(frames[0].eo.angles_seed_rad(), seed), kRoundTripTolerance);
  const std::string out = Path("frames_out.csv");
  ASSERT_TRUE(WriteFramesTable(out, options, frames).ok());
  CsvTable table;
  ASSERT_TRUE(CsvTable::Read(out, CsvOptions(), &table).ok());
  ASSERT_TRUE(table.HasColumn("Matrix"));
  ASSERT_TRUE(table.HasColumn("Omega"));
  std::vector<FrameRecord> back;
  ASSERT_TRUE(ReadFramesTable(out, options, &back).ok());
  EXPECT_LT(MaxAngleDifference(back[0].eo.angles_seed_rad(), seed), kRoundTripTolerance);
}

TEST_F(TablesTest, FramesCameraTypeMatrixNeedsTheMatrix) {
  const std::string path = Write("frames.csv",
                                 "Raster,CameraID,PerspectiveX,PerspectiveY,PerspectiveZ,Omega,Phi,"
                                 "Kappa\n"
                                 "a,M,1,2,3,0,0,0\n");
  const std::vector<FrameCamera> cameras = {SimpleCamera("M", -1, OrientationType::kMatrix)};
  FramesTableOptions options;
  options.cameras = &cameras;
  std::vector<FrameRecord> frames;
  EXPECT_EQ(ReadFramesTable(path, options, &frames).message(), path + ":2: Matrix: is empty");
}

TEST_F(TablesTest, FramesErrors) {
  const std::string header =
      "Raster,CameraID,PerspectiveX,PerspectiveY,PerspectiveZ,Omega,Phi,Kappa,Matrix";
  struct Case {
    std::string header;
    std::string rows;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {"Raster,PerspectiveX,PerspectiveY,PerspectiveZ,Omega,Phi,Kappa", "",
       "1: CameraID: required column is missing"},
      {"Raster,CameraID,PerspectiveX,PerspectiveY,PerspectiveZ", "",
       "1: Omega: required column is missing (give Omega, Phi, Kappa or Matrix)"},
      {"Raster,CameraID,PerspectiveX,PerspectiveY,PerspectiveZ,Omega,Kappa", "",
       "1: Phi: required column is missing"},
      {header + ",SigmaX", "", "1: SigmaY: required column is missing"},
      {header, "a,C,1,2,x,0,0,0,\n", "2: PerspectiveZ: 'x' is not a number"},
      {header, "a,C,1,2,3,0,nan,0,\n", "2: Phi: 'nan' is not a finite number"},
      {header, "a,C,1,2,3,0,,0,\n", "2: Phi: is empty"},
      {header, ",C,1,2,3,0,0,0,\n", "2: Raster: is empty"},
      {header, "a,C,1,2,3,0,0,0,\nb,C,1,2,3,0,0,0,\na,C,1,2,3,0,0,0,\n",
       "4: Raster: duplicate raster 'a' (first on line 2)"},
      {header, "a,C,1,2,3,,,,1 0 0;0 1 0;0 0 2\n",
       "2: Matrix: rotation matrix is not orthonormal (max |R R^T - I| = 3)"},
      {header, "a,C,1,2,3,,,,1 0 0;0 1 0;0 0 -1\n",
       "2: Matrix: rotation matrix has determinant -1 (a reflection)"},
      {header, "a,C,1,2,3,,,,1 0 0;0 1 0;0 0\n",
       "2: Matrix: has 8 numbers, expected 9 (a 3x3 matrix, row by row)"},
      {header + ",SigmaX,SigmaY,SigmaZ,SigmaOmega,SigmaPhi,SigmaKappa",
       "a,C,1,2,3,0,0,0,,1,1,1,1,,1\n",
       "2: SigmaPhi: is empty; SigmaX, SigmaY, SigmaZ, SigmaOmega, SigmaPhi, SigmaKappa are given "
       "together"},
      {header + ",SigmaX,SigmaY,SigmaZ,SigmaOmega,SigmaPhi,SigmaKappa",
       "a,C,1,2,3,0,0,0,,1,-1,1,1,1,1\n", "2: SigmaY: '-1' is negative"},
  };
  for (const Case& c : cases) {
    const std::string path = Write("frames.csv", c.header + "\n" + c.rows);
    std::vector<FrameRecord> frames;
    EXPECT_EQ(ReadFramesTable(path, FramesTableOptions(), &frames).message(),
              path + ":" + c.expected)
        << c.rows;
  }
  // An unknown camera when cameras are given.
  const std::string path = Write("frames.csv", header + "\na,Nope,1,2,3,0,0,0,\n");
  const std::vector<FrameCamera> cameras = {SimpleCamera("C", -1)};
  FramesTableOptions options;
  options.cameras = &cameras;
  std::vector<FrameRecord> frames;
  EXPECT_EQ(ReadFramesTable(path, options, &frames).message(),
            path + ":2: CameraID: unknown camera 'Nope'");
}

TEST_F(TablesTest, FramesExtraColumnsAndSigma0PassThrough) {
  const std::string path = Write("frames.csv",
                                 "Raster,CameraID,PerspectiveX,PerspectiveY,PerspectiveZ,Omega,Phi,"
                                 "Kappa,NumObservations,Sigma0,Note\n"
                                 "a,C,1,2,3,0,0,0,12,0.75,\"first, best\"\n");
  std::vector<FrameRecord> frames;
  ASSERT_TRUE(ReadFramesTable(path, FramesTableOptions(), &frames).ok());
  EXPECT_EQ(frames[0].sigma0, 0.75);
  const std::vector<std::pair<std::string, std::string>> extra = {{"NumObservations", "12"},
                                                                  {"Note", "first, best"}};
  EXPECT_EQ(frames[0].extra_columns, extra);
  const std::string out = Path("out.csv");
  ASSERT_TRUE(WriteFramesTable(out, FramesTableOptions(), frames).ok());
  EXPECT_EQ(Read(out),
            "Raster,CameraID,PerspectiveX,PerspectiveY,PerspectiveZ,Omega,Phi,Kappa,SRS,Sigma0,"
            "NumObservations,Note\n"
            "a,C,1,2,3,0,0,0,,0.75,12,\"first, best\"\n");
  std::vector<FrameRecord> back;
  ASSERT_TRUE(ReadFramesTable(out, FramesTableOptions(), &back).ok());
  EXPECT_EQ(back[0].sigma0, 0.75);
  EXPECT_EQ(back[0].extra_columns, extra);
}

// A symmetric positive definite 6x6 covariance with correlations: X0, Y0, Z0 in m^2, angles in
// rad^2 (standard deviations of about 0.05 m and 1e-3 rad).
Matrix6d TestCovariance() {
  Matrix6d A;
  A << 5, 1, 0, 0, 2, 0,          //
      0, 4, 1, 0, 0, 1,           //
      1, 0, 6, 1, 0, 0,           //
      0, 0, 0, 0.1, 0.02, 0,      //
      0, 0, 0, 0.01, 0.08, 0.03,  //
      0, 0, 0, 0, 0.02, 0.12;
  A.topRows<3>() *= 0.01;
  A.bottomRows<3>() *= 0.01;
  return A * A.transpose();
}

// The six written standard deviations of the first frame of a frames file.
Vector6d WrittenSigmas(const std::string& path) {
  CsvTable table;
  EXPECT_TRUE(CsvTable::Read(path, CsvOptions(), &table).ok());
  const CsvRowReader row(table, table.rows().at(0));
  Vector6d sigmas;
  const char* names[6] = {"SigmaX", "SigmaY", "SigmaZ", "SigmaOmega", "SigmaPhi", "SigmaKappa"};
  for (int i = 0; i < 6; ++i) EXPECT_TRUE(row.RequiredNumber(names[i], &sigmas[i]).ok());
  return sigmas;
}

TEST_F(TablesTest, FramesCovarianceInSeedConventionIsTheDiagonal) {
  FrameRecord frame;
  frame.raster = "a";
  frame.camera_id = "C";
  frame.eo.parameters << 1000, 2000, 300, 0.3, -0.4, 2.9;
  frame.covariance = TestCovariance();
  frame.sigma0 = 1.5;
  const Vector6d expected = [&] {
    Vector6d s = frame.covariance->diagonal().cwiseSqrt();
    s.tail<3>() *= kDegreesPerRadian;
    return s;
  }();
  // Seed convention: the angles are the parameters themselves (AngleDirection -1) or their
  // negatives (+1): the standard deviations are sqrt(diag), in degrees for the angles.
  for (const int direction : {-1, +1}) {
    const std::vector<FrameCamera> cameras = {SimpleCamera("C", direction)};
    FramesTableOptions options;
    options.cameras = &cameras;
    const std::string path = Path("frames.csv");
    ASSERT_TRUE(WriteFramesTable(path, options, {frame}).ok());
    const Vector6d sigmas = WrittenSigmas(path);
    for (int i = 0; i < 6; ++i) EXPECT_NEAR(sigmas[i] / expected[i], 1.0, kPropagationTolerance);
    // Read back: a covariance with the same diagonal.
    std::vector<FrameRecord> back;
    ASSERT_TRUE(ReadFramesTable(path, options, &back).ok());
    ASSERT_TRUE(back[0].covariance.has_value());
    for (int i = 0; i < 6; ++i) {
      EXPECT_NEAR((*back[0].covariance)(i, i) / (*frame.covariance)(i, i), 1.0,
                  kPropagationTolerance);
    }
    EXPECT_EQ(back[0].sigma0, 1.5);
  }
}

TEST_F(TablesTest, FramesCovarianceNearIdentityIsTheDiagonalInEveryConvention) {
  // At zero angles every convention's angles are +-(the seed's) to first order (opk: -omega, -phi,
  // -kappa; pok: -omega, phi, -kappa), so the variances are unchanged.
  FrameRecord frame;
  frame.raster = "a";
  frame.camera_id = "C";
  frame.covariance = TestCovariance();
  for (const RotationConvention convention : {RotationConvention::kOpk, RotationConvention::kPok}) {
    FramesTableOptions options;
    options.convention = convention;
    const std::string path = Path("frames.csv");
    ASSERT_TRUE(WriteFramesTable(path, options, {frame}).ok());
    const Vector6d sigmas = WrittenSigmas(path);
    for (int i = 0; i < 6; ++i) {
      const double expected =
          std::sqrt((*frame.covariance)(i, i)) * (i < 3 ? 1.0 : kDegreesPerRadian);
      EXPECT_NEAR(sigmas[i] / expected, 1.0, kPropagationTolerance) << i;
    }
  }
}

TEST_F(TablesTest, FramesCovarianceMatchesMonteCarloInOpk) {
  // Propagation checked against sampling: draw seed parameters from N(eo, Sigma), convert each
  // draw to opk angles and compare the sample standard deviations with the written ones.
  FrameRecord frame;
  frame.raster = "a";
  frame.camera_id = "C";
  frame.eo.parameters << 0, 0, 0, 0.5, -0.7, 2.0;
  frame.covariance = TestCovariance();
  FramesTableOptions options;
  options.convention = RotationConvention::kOpk;
  const std::string path = Path("frames.csv");
  ASSERT_TRUE(WriteFramesTable(path, options, {frame}).ok());
  const Vector6d sigmas = WrittenSigmas(path);

  const Eigen::Matrix3d L = frame.covariance->bottomRightCorner<3, 3>().llt().matrixL();
  const Eigen::Vector3d mean_seed = frame.eo.angles_seed_rad();
  const Eigen::Vector3d mean_opk = AnglesFromRotation(
      RotationConvention::kOpk, RotationFromAngles(RotationConvention::kSeed, mean_seed));
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  constexpr int kSamples = 40000;
  Eigen::Vector3d sum_squares = Eigen::Vector3d::Zero();
  for (int s = 0; s < kSamples; ++s) {
    const Eigen::Vector3d z = DrawLastFirst<3>([&](int) { return normal(rng); });
    const Eigen::Vector3d opk = AnglesFromRotation(
        RotationConvention::kOpk, RotationFromAngles(RotationConvention::kSeed, mean_seed + L * z));
    for (int i = 0; i < 3; ++i) sum_squares[i] += std::pow(WrapAngle(opk[i] - mean_opk[i]), 2);
  }
  // The standard deviation of a sample standard deviation is about sigma / sqrt(2 n) = 0.35 %.
  constexpr double kMonteCarloTolerance = 0.02;
  for (int i = 0; i < 3; ++i) {
    const double sampled_deg = std::sqrt(sum_squares[i] / kSamples) * kDegreesPerRadian;
    EXPECT_NEAR(sigmas[3 + i] / sampled_deg, 1.0, kMonteCarloTolerance) << i;
  }
}

TEST_F(TablesTest, FramesSigmasRoundTripInEveryConvention) {
  FrameRecord frame;
  frame.raster = "a";
  frame.camera_id = "C";
  frame.eo.parameters << 10, 20, 30, -1.0, 0.6, -2.4;
  frame.covariance = TestCovariance();
  FrameRecord without = frame;
  without.raster = "b";
  without.covariance.reset();
  for (const RotationConvention convention :
       {RotationConvention::kSeed, RotationConvention::kOpk, RotationConvention::kPok}) {
    FramesTableOptions options;
    options.convention = convention;
    const std::string first = Path("first.csv"), second = Path("second.csv");
    ASSERT_TRUE(WriteFramesTable(first, options, {frame, without}).ok());
    std::vector<FrameRecord> back;
    ASSERT_TRUE(ReadFramesTable(first, options, &back).ok());
    EXPECT_TRUE(back[0].covariance.has_value());
    EXPECT_FALSE(back[1].covariance.has_value());
    ASSERT_TRUE(WriteFramesTable(second, options, back).ok());
    const Vector6d a = WrittenSigmas(first), b = WrittenSigmas(second);
    for (int i = 0; i < 6; ++i) EXPECT_NEAR(b[i] / a[i], 1.0, kPropagationTolerance);
  }
}

// ------------------------------------------------------------------ ground points

TEST_F(TablesTest, GroundPointsReadAndRoundTrip) {
  const std::string path = Write("points.csv",
                                 "PointID,X,Y,Z,AccuracyX,AccuracyY,AccuracyZ,Role\n"
                                 "P1,2600000.5,1200000.25,450.125,0.02,0.02,0.05,\n"
                                 "P2,2600100,1200100,455,,,,CHECK\n"
                                 "P3,2600200,1200200,460,,,,Control\n");
  std::vector<GroundPoint> points;
  const Status status = ReadGroundPoints(path, &points);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(points.size(), 3u);
  EXPECT_EQ(points[0].point_id, "P1");
  EXPECT_EQ(points[0].position, Eigen::Vector3d(2600000.5, 1200000.25, 450.125));
  ASSERT_TRUE(points[0].accuracy_m.has_value());
  EXPECT_EQ(*points[0].accuracy_m, Eigen::Vector3d(0.02, 0.02, 0.05));
  EXPECT_EQ(points[0].role, PointRole::kControl);
  EXPECT_EQ(points[0].line, 2);
  EXPECT_FALSE(points[1].accuracy_m.has_value());
  EXPECT_EQ(points[1].role, PointRole::kCheck);
  EXPECT_EQ(points[2].role, PointRole::kControl);
  EXPECT_EQ(points[2].line, 4);

  const std::string out = Path("points_out.csv");
  ASSERT_TRUE(WriteGroundPoints(out, points).ok());
  std::vector<GroundPoint> back;
  ASSERT_TRUE(ReadGroundPoints(out, &back).ok());
  ASSERT_EQ(back.size(), points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(back[i].point_id, points[i].point_id);
    EXPECT_EQ(back[i].position, points[i].position);
    EXPECT_EQ(back[i].accuracy_m, points[i].accuracy_m);
    EXPECT_EQ(back[i].role, points[i].role);
  }
}

// AccuracyX = AccuracyY = AccuracyZ = 0: a control point held fixed (error-free), a check point
// compared as usual; read, written and read back as 0.
TEST_F(TablesTest, GroundPointsWithAccuracyZeroAreHeldFixedControl) {
  const std::string path = Write("points.csv",
                                 "PointID,X,Y,Z,AccuracyX,AccuracyY,AccuracyZ,Role\n"
                                 "F1,10,20,30,0,0,0,control\n"
                                 "K1,11,21,31,0,0,0,check\n"
                                 "W1,12,22,32,0.01,0.01,0.02,control\n");
  std::vector<GroundPoint> points;
  const Status status = ReadGroundPoints(path, &points);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(points.size(), 3u);
  ASSERT_TRUE(points[0].accuracy_m.has_value());
  EXPECT_EQ(*points[0].accuracy_m, Eigen::Vector3d::Zero());
  EXPECT_EQ(*points[1].accuracy_m, Eigen::Vector3d::Zero());
  std::string text;
  ASSERT_TRUE(FormatGroundPoints(points, "out.csv", &text).ok());
  EXPECT_NE(text.find("F1,10,20,30,0,0,0,control\n"), std::string::npos) << text;
  std::vector<GroundPoint> back;
  ASSERT_TRUE(ParseGroundPoints(text, "out.csv", &back).ok());
  for (size_t i = 0; i < points.size(); ++i) EXPECT_EQ(back[i].accuracy_m, points[i].accuracy_m);
  // The writer refuses what the reader refuses.
  points[2].accuracy_m = Eigen::Vector3d(0.0, 0.01, 0.01);
  EXPECT_EQ(FormatGroundPoints(points, "out.csv", &text).message(),
            "out.csv: point 'W1': AccuracyY: 0.01 beside AccuracyX 0: AccuracyX, AccuracyY, "
            "AccuracyZ are all positive, or all 0 (the point held fixed)");
}

TEST_F(TablesTest, GroundPointsMinimalColumns) {
  const std::string path = Write("points.csv", "pointid,x,y,z\nA,1,2,3\n");
  std::vector<GroundPoint> points;
  ASSERT_TRUE(ReadGroundPoints(path, &points).ok());
  EXPECT_EQ(points[0].position, Eigen::Vector3d(1, 2, 3));
  EXPECT_FALSE(points[0].accuracy_m.has_value());
}

TEST_F(TablesTest, GroundPointsErrors) {
  const std::string full = "PointID,X,Y,Z,AccuracyX,AccuracyY,AccuracyZ,Role";
  struct Case {
    std::string header;
    std::string rows;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {"PointID,X,Y", "", "1: Z: required column is missing"},
      {"PointID,X,Y,Z,AccuracyZ", "", "1: AccuracyX: required column is missing"},
      {full,
       "P1,1,2,3,,,,\nP2,1,2,3,,,,\nP3,1,2,3,,,,\nP4,1,2,3,,,,\nP5,1,2,3,,,,\nP6,1,2,abc,,,,\n",
       "7: Z: 'abc' is not a number"},
      {full, "P1,1,2,3,0.1,,0.1,\n",
       "2: AccuracyY: is empty; AccuracyX, AccuracyY, AccuracyZ are given together"},
      {full, "P1,1,2,3,0.1,0.1,-1,\n", "2: AccuracyZ: '-1' is outside [0, 100000000] m"},
      // All three 0 hold a control point fixed; a mix is refused at the first axis that breaks it.
      {full, "P1,1,2,3,0.1,0,0.1,\n",
       "2: AccuracyY: 0 beside AccuracyX 0.1: AccuracyX, AccuracyY, AccuracyZ are all positive, or "
       "all 0 (the point held fixed)"},
      {full, "P1,1,2,3,0,0,0,control\nP2,1,2,3,0,0,0.02,control\n",
       "3: AccuracyZ: 0.02 beside AccuracyX 0: AccuracyX, AccuracyY, AccuracyZ are all positive, or "
       "all 0 (the point held fixed)"},
      {full, "P1,1,2,3,0.01,0,0,check\n",
       "2: AccuracyY: 0 beside AccuracyX 0.01: AccuracyX, AccuracyY, AccuracyZ are all positive, or "
       "all 0 (the point held fixed)"},
      {full, "P1,1,2,3,,,,tied\n", "2: Role: 'tied' is not control, check or tie"},
      {full, "P1,1,2,3,,,,\nP1,4,5,6,,,,\n", "3: PointID: duplicate point 'P1' (first on line 2)"},
      {full, ",1,2,3,,,,\n", "2: PointID: is empty"},
  };
  for (const Case& c : cases) {
    const std::string path = Write("points.csv", c.header + "\n" + c.rows);
    std::vector<GroundPoint> points;
    EXPECT_EQ(ReadGroundPoints(path, &points).message(), path + ":" + c.expected) << c.rows;
  }
}

// ------------------------------------------------------------------ image marks

TEST_F(TablesTest, ImageMarksReadAndRoundTrip) {
  const std::string path = Write("marks.csv",
                                 "Raster,PointID,Column,Row,FilmX,FilmY,Accuracy,CameraID\n"
                                 "IMG_1.JPG,P1,1024.5,768.25,,,0.5,C1\n"
                                 "IMG_1.JPG,P2,,,-1234.5,2345.75,,\n"
                                 "IMG_2.JPG,P1,10,20,,,,\n");
  std::vector<ImageMark> marks;
  const Status status = ReadImageMarks(path, &marks);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(marks.size(), 3u);
  EXPECT_EQ(marks[0].raster, "IMG_1.JPG");
  EXPECT_EQ(marks[0].point_id, "P1");
  ASSERT_TRUE(marks[0].column_row.has_value());
  EXPECT_EQ(*marks[0].column_row, Eigen::Vector2d(1024.5, 768.25));
  EXPECT_FALSE(marks[0].film_um.has_value());
  EXPECT_EQ(marks[0].accuracy_px, 0.5);
  EXPECT_EQ(marks[0].camera_id, "C1");
  EXPECT_EQ(marks[0].line, 2);
  EXPECT_FALSE(marks[1].column_row.has_value());
  ASSERT_TRUE(marks[1].film_um.has_value());
  EXPECT_EQ(*marks[1].film_um, Eigen::Vector2d(-1234.5, 2345.75));
  EXPECT_FALSE(marks[1].accuracy_px.has_value());
  EXPECT_EQ(marks[2].line, 4);

  const std::string out = Path("marks_out.csv");
  ASSERT_TRUE(WriteImageMarks(out, marks).ok());
  std::vector<ImageMark> back;
  ASSERT_TRUE(ReadImageMarks(out, &back).ok());
  ASSERT_EQ(back.size(), marks.size());
  for (size_t i = 0; i < marks.size(); ++i) {
    EXPECT_EQ(back[i].raster, marks[i].raster);
    EXPECT_EQ(back[i].point_id, marks[i].point_id);
    EXPECT_EQ(back[i].column_row, marks[i].column_row);
    EXPECT_EQ(back[i].film_um, marks[i].film_um);
    EXPECT_EQ(back[i].accuracy_px, marks[i].accuracy_px);
    EXPECT_EQ(back[i].camera_id, marks[i].camera_id);
  }
}

TEST_F(TablesTest, ImageMarksErrors) {
  const std::string full = "Raster,PointID,Column,Row,FilmX,FilmY,Accuracy";
  struct Case {
    std::string header;
    std::string rows;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {"Raster,Column,Row", "", "1: PointID: required column is missing"},
      {"Raster,PointID,Accuracy", "",
       "1: Column: required column is missing (give Column and Row, or FilmX and FilmY)"},
      {"Raster,PointID,Column", "", "1: Row: required column is missing (Column is given)"},
      {"Raster,PointID,Column,Row,FilmY", "",
       "1: FilmX: required column is missing (FilmY is given)"},
      {full, "I,P,1,2,3,4,\n", "2: FilmX: give either Column/Row or FilmX/FilmY, not both"},
      {full, "I,P,,,,,\n",
       "2: Column: is empty; give Column and Row (pixels) or FilmX and FilmY (um)"},
      {full, "I,P,1,,,,\n", "2: Row: is empty"},
      {full, "I,P,1,x,,,\n", "2: Row: 'x' is not a number"},
      {full, "I,P,1,2,,,0\n", "2: Accuracy: '0' is outside (0, 100000000] px"},
      {full, "I,P,1,2,,,\nI,Q,1,2,,,\n\nI,P,3,4,,,\n",
       "5: PointID: duplicate mark of point 'P' in image 'I' (first on line 2)"},
      // The first problem in the file wins: a duplicate before a bad row, a bad row before a
      // duplicate, the earliest of two duplicates of different points.
      {full, "I,P,1,2,,,\nI,P,3,4,,,\nI,Q,x,2,,,\n",
       "3: PointID: duplicate mark of point 'P' in image 'I' (first on line 2)"},
      {full, "I,P,1,2,,,\nI,Q,x,2,,,\nI,P,3,4,,,\n", "3: Column: 'x' is not a number"},
      {full, "A,P,1,2,,,\nB,Q,1,2,,,\nB,Q,1,2,,,\nA,P,1,2,,,\n",
       "4: PointID: duplicate mark of point 'Q' in image 'B' (first on line 3)"},
      {full, "I,P,1,2,,,\nI,P,1,2,,,\nI,P,1,2,,,\n",
       "3: PointID: duplicate mark of point 'P' in image 'I' (first on line 2)"},
      // A bad number in the last row without a line end; CRLF line ends.
      {full, "I,P,1,2,,,\nI,Q,1,2e,,,", "3: Row: '2e' is not a number"},
      {full, "I,P,1,2,,,\r\nI,Q,1,x,,,\r\n", "3: Row: 'x' is not a number"},
      {full, "I,P,1,2,,,\r\nI,P,1,2,,,\r\n",
       "3: PointID: duplicate mark of point 'P' in image 'I' (first on line 2)"},
      // Quoted names are the same names; one with "" is unescaped (kept apart from the text).
      {full, "\"I\",P,1,2,,,\nI,\"P\",3,4,,,\n",
       "3: PointID: duplicate mark of point 'P' in image 'I' (first on line 2)"},
      {full, "\"I\"\"x\",P,1,2,,,\nI,P,1,2,,,\n\"I\"\"x\",P,3,4,,,\n",
       "4: PointID: duplicate mark of point 'P' in image 'I\"x' (first on line 2)"},
      {full, "\"I\nJ\",P,1,2,,,\n\"I\r\nJ\",P,3,4,,,\n",
       "4: PointID: duplicate mark of point 'P' in image 'I\\nJ' (first on line 2)"},
  };
  for (const Case& c : cases) {
    const std::string path = Write("marks.csv", c.header + "\n" + c.rows);
    std::vector<ImageMark> marks;
    EXPECT_EQ(ReadImageMarks(path, &marks).message(), path + ":" + c.expected) << c.rows;
  }
}

TEST_F(TablesTest, ImageMarksReadCrLfQuotedAndUnterminatedRows) {
  const std::string path = Write("marks.csv",
                                 "raster,POINT ID,column,Row,Accuracy\r\n"
                                 "\"IMG \"\"1\"\".JPG\",P1,1,2,0.5\r\n"
                                 "# a comment\r\n"
                                 "IMG_2.JPG , \"P,2\" ,3,4,");
  std::vector<ImageMark> marks;
  const Status status = ReadImageMarks(path, &marks);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_EQ(marks.size(), 2u);
  EXPECT_EQ(marks[0].raster, "IMG \"1\".JPG");
  EXPECT_EQ(marks[0].point_id, "P1");
  EXPECT_EQ(marks[0].accuracy_px, 0.5);
  EXPECT_EQ(marks[1].raster, "IMG_2.JPG");
  EXPECT_EQ(marks[1].point_id, "P,2");
  EXPECT_EQ(*marks[1].column_row, Eigen::Vector2d(3, 4));
  EXPECT_FALSE(marks[1].accuracy_px.has_value());
  EXPECT_EQ(marks[1].line, 4);
}

TEST_F(TablesTest, ImageMarksWriterNamesTheFirstProblemInMarkOrder) {
  const auto mark = [](const std::string& raster, const std::string& point, double column,
                       int line) {
    ImageMark m;
    m.raster = raster;
    m.point_id = point;
    m.column_row = Eigen::Vector2d(column, 2.0);
    m.line = line;
    return m;
  };
  const double kNan = std::numeric_limits<double>::quiet_NaN();
  std::string text;
  // A duplicate before a bad mark, a bad mark before a duplicate, the earliest of two duplicates.
  EXPECT_EQ(FormatImageMarks({mark("I", "P", 1, 7), mark("I", "P", 1, 9), mark("I", "Q", kNan, 11)},
                             "m.csv", &text)
                .message(),
            "m.csv: mark of point 'P' in image 'I': PointID: the point is marked twice in the "
            "image (source lines 7 and 9)");
  EXPECT_EQ(FormatImageMarks({mark("I", "P", 1, 7), mark("I", "Q", kNan, 9), mark("I", "P", 1, 11)},
                             "m.csv", &text)
                .message(),
            "m.csv: mark of point 'Q' in image 'I': Column: value is not finite");
  EXPECT_EQ(FormatImageMarks({mark("A", "P", 1, 2), mark("B", "Q", 1, 3), mark("B", "Q", 1, 4),
                              mark("A", "P", 1, 5)},
                             "m.csv", &text)
                .message(),
            "m.csv: mark of point 'Q' in image 'B': PointID: the point is marked twice in the "
            "image (source lines 3 and 4)");
  EXPECT_EQ(FormatImageMarks({mark("I", "P", 2e8, 7)}, "m.csv", &text).message(),
            "m.csv: mark of point 'P' in image 'I': Column: 200000000 is outside [-100000000, "
            "100000000] px");
  // Good marks: one line each, numbers in their shortest positional form, fields quoted as needed.
  ImageMark film = mark("I,1", " P", 0, 3);
  film.column_row.reset();
  film.film_um = Eigen::Vector2d(-1234.5, 0.125);
  film.accuracy_px = 1.5;
  film.camera_id = "C";
  ASSERT_TRUE(FormatImageMarks({mark("I", "P", 1024.5, 2), film}, "m.csv", &text).ok());
  EXPECT_EQ(text,
            "Raster,PointID,Column,Row,FilmX,FilmY,Accuracy,CameraID\n"
            "I,P,1024.5,2,,,,\n"
            "\"I,1\",\" P\",,,-1234.5,0.125,1.5,C\n");
}

TEST_F(TablesTest, TablesAreReadFromStandardInputAndRegularFilesOnly) {
  std::vector<ImageMark> marks;
  EXPECT_EQ(ReadImageMarks(dir_.string(), &marks).message(),
            dir_.string() +
                ": is a folder, not a regular file; photopose reads regular files, or standard "
                "input for '-'");
  const std::string fifo = Path("fifo.csv");
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  // A FIFO without a writer is refused at once, not waited on.
  EXPECT_EQ(ReadImageMarks(fifo, &marks).message(),
            fifo + ": is a FIFO (named pipe), not a regular file; photopose reads regular files, "
                   "or standard input for '-'");
  const std::string empty = Write("empty.csv", "");
  EXPECT_EQ(ReadImageMarks(empty, &marks).message(), empty + ": no header line");
}

TEST_F(TablesTest, CheckMarksNamesTheUnknownPoint) {
  const std::string path = Write("marks.csv",
                                 "Raster,PointID,Column,Row\n"
                                 "I,P1,1,2\nI,P2,1,2\nI,P3,1,2\nI,P4,1,2\nI,P5,1,2\nI,P6,1,2\n"
                                 "J,P1,1,2\nJ,P2,1,2\nJ,P3,1,2\nJ,P4,1,2\nJ,P7,1,2\n");
  std::vector<ImageMark> marks;
  ASSERT_TRUE(ReadImageMarks(path, &marks).ok());
  std::vector<GroundPoint> points(6);
  for (int i = 0; i < 6; ++i) points[i].point_id = "P" + std::to_string(i + 1);
  EXPECT_EQ(CheckMarks("marks.csv", marks, points).message(),
            "marks.csv:12: PointID: unknown point 'P7'");
  points.emplace_back();
  points.back().point_id = "P7";
  EXPECT_TRUE(CheckMarks("marks.csv", marks, points).ok());
}

// ------------------------------------------------------------------ OpenDroneMap gcp_list.txt

TEST_F(TablesTest, GcpListFloatFileOfTheOdmDataset) {
  // README.txt beside the file: 82 observations at 0.1 px in 10 images of 19 targets HV01..HV19.
  GcpList gcp;
  const Status status =
      ReadGcpList(testing::SharedDataPath("odm_br/odm_gcp_br_gcp_list_floatxy_raw.txt"), &gcp);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(gcp.crs, "+proj=utm +zone=22 +south +datum=WGS84 +units=m +no_defs");
  EXPECT_EQ(gcp.marks.size(), 82u);
  EXPECT_EQ(gcp.points.size(), 19u);
  std::set<std::string> images, names;
  for (const ImageMark& m : gcp.marks) images.insert(m.raster);
  for (const GroundPoint& p : gcp.points) names.insert(p.point_id);
  EXPECT_EQ(images.size(), 10u);
  EXPECT_EQ(*names.begin(), "HV01");
  EXPECT_EQ(*names.rbegin(), "HV19");
  // First data line: 658528.361 7167002.098 890.636 2460.6 233.9 IMG_5349.JPG HV01
  EXPECT_EQ(gcp.points[0].point_id, "HV01");
  EXPECT_EQ(gcp.points[0].position, Eigen::Vector3d(658528.361, 7167002.098, 890.636));
  EXPECT_EQ(gcp.points[0].line, 2);
  EXPECT_EQ(gcp.marks[0].raster, "IMG_5349.JPG");
  EXPECT_EQ(gcp.marks[0].point_id, "HV01");
  ASSERT_TRUE(gcp.marks[0].column_row.has_value());
  EXPECT_EQ(*gcp.marks[0].column_row, Eigen::Vector2d(2460.6, 233.9));
  EXPECT_EQ(gcp.marks[0].line, 2);
  EXPECT_TRUE(CheckMarks("gcp", gcp.marks, gcp.points).ok());
  // The file marks HV11 twice in IMG_5352.JPG (lines 51 and 52, 640 px apart): both are kept, and
  // a marks table refuses them.
  std::vector<int> hv11_lines;
  for (const ImageMark& m : gcp.marks)
    if (m.raster == "IMG_5352.JPG" && m.point_id == "HV11") hv11_lines.push_back(m.line);
  EXPECT_EQ(hv11_lines, (std::vector<int>{51, 52}));
  const std::string marks_path = Path("marks.csv");
  EXPECT_EQ(WriteImageMarks(marks_path, gcp.marks).message(),
            marks_path +
                ": mark of point 'HV11' in image 'IMG_5352.JPG': PointID: the point is "
                "marked twice in the image (source lines 51 and 52)");
  EXPECT_FALSE(fs::exists(marks_path));
}

TEST_F(TablesTest, GcpListIntegerFileOfTheOdmDataset) {
  GcpList gcp;
  const Status status = ReadGcpList(testing::SharedDataPath("odm_br/gcp_list.txt"), &gcp);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(gcp.crs, "+proj=utm +zone=22 +south +datum=WGS84 +units=m +no_defs");
  EXPECT_EQ(gcp.marks.size(), 25u);
  EXPECT_EQ(gcp.points.size(), 6u);
  EXPECT_EQ(*gcp.marks[0].column_row, Eigen::Vector2d(2461, 234));
}

TEST_F(TablesTest, GcpListUnnamedPointsAndCrsForms) {
  const std::string path = Write("gcp_list.txt",
                                 "EPSG:32722\n"
                                 "\n"
                                 "100.5 200 10 1 2 a.jpg\n"
                                 "100.50 200.0 10 3 4 b.jpg\r\n"
                                 "101 200 10 5 6\tc.jpg  G1\n");
  GcpList gcp;
  const Status status = ReadGcpList(path, &gcp);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(gcp.crs, "EPSG:32722");
  ASSERT_EQ(gcp.points.size(), 2u);
  EXPECT_EQ(gcp.points[0].point_id, "100.5_200_10");
  EXPECT_EQ(gcp.points[1].point_id, "G1");
  ASSERT_EQ(gcp.marks.size(), 3u);
  EXPECT_EQ(gcp.marks[1].point_id, "100.5_200_10");
  EXPECT_EQ(gcp.marks[1].line, 4);
  EXPECT_EQ(gcp.marks[2].raster, "c.jpg");

  for (const std::string crs : {"WGS84 UTM 22S", "+proj=utm +zone=22 +south"}) {
    const std::string other = Write("crs.txt", crs + "\n1 2 3 4 5 a.jpg\n");
    ASSERT_TRUE(ReadGcpList(other, &gcp).ok()) << crs;
    EXPECT_EQ(gcp.crs, crs);
  }
}

TEST_F(TablesTest, GcpListErrors) {
  struct Case {
    std::string text;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {"",
       "1: CRS: the first line must name the coordinate system (EPSG:<code>, WGS84 UTM "
       "<zone><N|S>, or a +proj=... string), got ''"},
      {"1 2 3 4 5 a.jpg\n",
       "1: CRS: the first line must name the coordinate system (EPSG:<code>, WGS84 UTM "
       "<zone><N|S>, or a +proj=... string), got '1 2 3 4 5 a.jpg'"},
      {"EPSG:\n",
       "1: CRS: the first line must name the coordinate system (EPSG:<code>, WGS84 UTM "
       "<zone><N|S>, or a +proj=... string), got 'EPSG:'"},
      {"EPSG:32722\n1 2 3 4 5\n", "2: expected 'X Y Z px py image [name]', got 5 fields"},
      {"EPSG:32722\n1 2 3 4 5 a\n\n1 2 z 4 5 a\n", "4: Z: 'z' is not a number"},
      {"EPSG:32722\n1 2 3 4 nan a\n", "2: py: 'nan' is not a finite number"},
      {"EPSG:32722\n1 2 3 4 5 a P\n1 2 4 4 5 b P\n",
       "3: name: point 'P' has other coordinates on line 2 (1 2 3)"},
      {"EPSG:32722\n1 -1e308 3 4 5 a\n", "2: Y: '-1e308' is outside [-100000000, 100000000] m"},
      {"EPSG:32722\n1 2 3 4 2e8 a\n", "2: py: '2e8' is outside [-100000000, 100000000] px"},
      {std::string("EPSG:32722\n1 2 3 4 5 a\0b\n", 25),
       "2: character 12: NUL byte: photopose reads UTF-8 text (is this a binary file, or UTF-16 "
       "without a byte order mark?)"},
  };
  for (const Case& c : cases) {
    const std::string path = Write("gcp_list.txt", c.text);
    GcpList gcp;
    EXPECT_EQ(ReadGcpList(path, &gcp).message(), path + ":" + c.expected) << c.text;
  }
}

TEST_F(TablesTest, GcpListExtraFieldsAfterTheNameAreOdmsExtrasAndNotRead) {
  const std::string path = Write("gcp_list.txt", "WGS84 UTM 32N\n1 2 3 4 5 a.jpg P extra1 extra2\n");
  GcpList gcp;
  ASSERT_TRUE(ReadGcpList(path, &gcp).ok());
  ASSERT_EQ(gcp.points.size(), 1u);
  EXPECT_EQ(gcp.points[0].point_id, "P");
  EXPECT_EQ(gcp.crs, "WGS84 UTM 32N");
}

TEST_F(TablesTest, GeoTxtReadsPositionsAttitudesAndAccuracies) {
  const std::string path = Write("geo.txt",
                                 "EPSG:4326\n"
                                 "a.jpg 11.5 48.1 520.25\n"
                                 "# comment\n"
                                 "b.jpg 11.6 48.2 521 10 -2 3\n"
                                 "c.jpg 11.7 48.3 522 10 -2 3 0.02 0.05 extra\n");
  GeoTxt geo;
  ASSERT_TRUE(ReadGeoTxt(path, &geo).ok());
  EXPECT_EQ(geo.crs, "EPSG:4326");
  ASSERT_EQ(geo.records.size(), 3u);
  EXPECT_EQ(geo.records[0].image, "a.jpg");
  EXPECT_EQ(geo.records[0].position, Eigen::Vector3d(11.5, 48.1, 520.25));
  EXPECT_FALSE(geo.records[0].yaw_pitch_roll_deg.has_value());
  EXPECT_FALSE(geo.records[0].horizontal_accuracy_m.has_value());
  ASSERT_TRUE(geo.records[1].yaw_pitch_roll_deg.has_value());
  EXPECT_EQ(*geo.records[1].yaw_pitch_roll_deg, Eigen::Vector3d(10, -2, 3));
  EXPECT_EQ(geo.records[1].line, 4);
  ASSERT_TRUE(geo.records[2].vertical_accuracy_m.has_value());
  EXPECT_EQ(*geo.records[2].horizontal_accuracy_m, 0.02);
  EXPECT_EQ(*geo.records[2].vertical_accuracy_m, 0.05);
}

// ODM's z is optional: "image x y" is a horizontal position, its z NaN (never a height), while
// "image x y z" beside it keeps its height.
TEST_F(TablesTest, GeoTxtLineWithoutZIsAPositionWithoutHeight) {
  const std::string path = Write("geo.txt",
                                 "WGS84 UTM 32N\n"
                                 "a.jpg 500100.5 5300200.25\n"
                                 "b.jpg 500110 5300210 512.5\n");
  GeoTxt geo;
  const Status read = ReadGeoTxt(path, &geo);
  ASSERT_TRUE(read.ok()) << read.message();
  ASSERT_EQ(geo.records.size(), 2u);
  EXPECT_FALSE(geo.records[0].has_height);
  EXPECT_EQ(geo.records[0].position.head<2>(), Eigen::Vector2d(500100.5, 5300200.25));
  EXPECT_TRUE(std::isnan(geo.records[0].position.z()));
  EXPECT_FALSE(geo.records[0].yaw_pitch_roll_deg.has_value());
  EXPECT_FALSE(geo.records[0].horizontal_accuracy_m.has_value());
  EXPECT_EQ(geo.records[0].line, 2);
  EXPECT_TRUE(geo.records[1].has_height);
  EXPECT_EQ(geo.records[1].position, Eigen::Vector3d(500110, 5300210, 512.5));
}

TEST_F(TablesTest, GeoTxtWithMissingOrBrokenFieldsIsRefusedAtItsLine) {
  struct Case {
    std::string text;
    std::string expected;
  };
  const std::vector<Case> cases = {
      {"a.jpg 1 2 3\n",
       "1: CRS: the first line must name the coordinate system (EPSG:<code>, WGS84 UTM "
       "<zone><N|S>, or a +proj=... string), got 'a.jpg 1 2 3'"},
      {"EPSG:4326\na.jpg 1\n",
       "2: y: missing: expected 'image x y [z [yaw pitch roll [horizontal_accuracy "
       "vertical_accuracy]]]', got 1 number"},
      // x y and two accuracies read positionally as z and yaw: refused, not taken as accuracies.
      {"EPSG:4326\na.jpg 1 2 0.05 0.1\n",
       "2: pitch: missing: expected 'image x y [z [yaw pitch roll [horizontal_accuracy "
       "vertical_accuracy]]]', got 4 numbers (x y z and yaw: yaw pitch roll come as three; the "
       "fields are positional, so a line without z cannot give accuracies)"},
      {"EPSG:4326\na.jpg 1 2 3 4 5\n",
       "2: roll: missing: expected 'image x y [z [yaw pitch roll [horizontal_accuracy "
       "vertical_accuracy]]]', got 5 numbers (x y z and yaw pitch: yaw pitch roll come as three; "
       "the fields are positional, so a line without z cannot give accuracies)"},
      {"EPSG:4326\na.jpg 1 2 3 4 5 6 7\n",
       "2: vertical_accuracy: missing: expected 'image x y [z [yaw pitch roll "
       "[horizontal_accuracy vertical_accuracy]]]', got 7 numbers (the accuracies come as two: "
       "horizontal vertical)"},
      {"EPSG:4326\na.jpg 1 1e30\n", "2: y: '1e30' is outside [-100000000, 100000000] m"},
      {"EPSG:4326\na.jpg 1 2 x\n", "2: z: 'x' is not a number"},
      {"EPSG:4326\na.jpg 1 2 3 4 5 6 0 1\n",
       "2: horizontal_accuracy: '0' must be a positive accuracy in metres (at most 1e6)"},
      {"EPSG:4326\na.jpg 1 2 3\na.jpg 1 2 3\n", "3: image: 'a.jpg' is already on line 2"},
  };
  for (const Case& c : cases) {
    const std::string path = Write("geo.txt", c.text);
    GeoTxt geo;
    EXPECT_EQ(ReadGeoTxt(path, &geo).message(), path + ":" + c.expected) << c.text;
  }
}

// What FormatGcpList and FormatGeoTxt write reads back as the same points, marks and positions
// (FormatNumber's shortest exact text: equal doubles), and what cannot be read back is refused.
TEST_F(TablesTest, GcpListAndGeoTxtWrittenReadBackAsTheyWere) {
  GcpList gcp;
  gcp.crs = "EPSG:32632";
  GroundPoint a, b;
  a.point_id = "GCP_1";
  a.position = Eigen::Vector3d(667123.123456789, 5296000.0000001, 512.3);
  b.point_id = "GCP_2";
  b.position = Eigen::Vector3d(667200.5, 5296100.25, 498.0625);
  gcp.points = {a, b};
  ImageMark m1, m2, m3;
  m1.raster = "IMG_1.JPG", m1.point_id = "GCP_1", m1.column_row = Eigen::Vector2d(1024.123456789, 77.5);
  m2.raster = "IMG_2.JPG", m2.point_id = "GCP_1", m2.column_row = Eigen::Vector2d(12.0, 3999.875);
  m3.raster = "IMG_2.JPG", m3.point_id = "GCP_2", m3.column_row = Eigen::Vector2d(0.1, 0.2);
  gcp.marks = {m1, m2, m3};
  std::string text;
  ASSERT_TRUE(FormatGcpList(gcp, "gcp_list.txt", &text).ok());
  GcpList read;
  ASSERT_TRUE(ReadGcpList(Write("gcp_list.txt", text), &read).ok()) << text;
  EXPECT_EQ(read.crs, gcp.crs);
  ASSERT_EQ(read.points.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(read.points[i].point_id, gcp.points[i].point_id);
    EXPECT_EQ(read.points[i].position, gcp.points[i].position);
  }
  ASSERT_EQ(read.marks.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(read.marks[i].raster, gcp.marks[i].raster);
    EXPECT_EQ(read.marks[i].point_id, gcp.marks[i].point_id);
    EXPECT_EQ(*read.marks[i].column_row, *gcp.marks[i].column_row);
  }

  GeoTxt geo;
  geo.crs = "EPSG:4326";
  GeoTxtRecord full, plain, flat, no_height;
  full.image = "IMG_1.JPG", full.position = Eigen::Vector3d(11.200000012345, 47.8000000098765, 612.25);
  full.yaw_pitch_roll_deg = Eigen::Vector3d(92.5, -1.5, 0.25);
  full.horizontal_accuracy_m = 0.03, full.vertical_accuracy_m = 0.06;
  plain.image = "IMG_2.JPG", plain.position = Eigen::Vector3d(11.21, 47.81, 600.0);
  flat.image = "IMG_3.JPG", flat.position = Eigen::Vector3d(11.22, 47.82, 601.0);
  flat.horizontal_accuracy_m = 0.5, flat.vertical_accuracy_m = 1.0;  // written after ODM's "0 0 0"
  no_height.image = "IMG_4.JPG", no_height.position = Eigen::Vector3d(11.23, 47.83, std::nan(""));
  no_height.has_height = false;
  geo.records = {full, plain, flat, no_height};
  ASSERT_TRUE(FormatGeoTxt(geo, "geo.txt", &text).ok());
  GeoTxt geo_read;
  ASSERT_TRUE(ReadGeoTxt(Write("geo.txt", text), &geo_read).ok()) << text;
  EXPECT_EQ(geo_read.crs, geo.crs);
  ASSERT_EQ(geo_read.records.size(), 4u);
  for (size_t i = 0; i < 4; ++i) {
    const GeoTxtRecord& r = geo_read.records[i];
    const GeoTxtRecord& w = geo.records[i];
    EXPECT_EQ(r.image, w.image);
    EXPECT_EQ(r.has_height, w.has_height) << w.image;
    EXPECT_EQ(r.position.head<2>(), w.position.head<2>()) << w.image;
    if (w.has_height) EXPECT_EQ(r.position.z(), w.position.z()) << w.image;
    EXPECT_EQ(r.horizontal_accuracy_m, w.horizontal_accuracy_m) << w.image;
    EXPECT_EQ(r.vertical_accuracy_m, w.vertical_accuracy_m) << w.image;
  }
  EXPECT_EQ(*geo_read.records[0].yaw_pitch_roll_deg, *full.yaw_pitch_roll_deg);
  EXPECT_EQ(*geo_read.records[2].yaw_pitch_roll_deg, Eigen::Vector3d::Zero());  // ODM's "not available"
  EXPECT_FALSE(geo_read.records[1].yaw_pitch_roll_deg.has_value());

  // What would not read back is refused, naming the file and the record.
  GcpList bad = gcp;
  bad.marks[0].point_id = "GCP 1";
  EXPECT_EQ(FormatGcpList(bad, "g.txt", &text).message(),
            "g.txt: mark of point 'GCP 1' in image 'IMG_1.JPG': names must be one word (the fields of a line are "
            "separated by white space)");
  bad = gcp;
  bad.marks[2].point_id = "GCP_9";
  EXPECT_EQ(FormatGcpList(bad, "g.txt", &text).message(),
            "g.txt: mark of point 'GCP_9' in image 'IMG_2.JPG': the point is not in the list");
  bad = gcp;
  bad.crs = "UTM 32";
  EXPECT_NE(FormatGcpList(bad, "g.txt", &text).message().find("g.txt: CRS: 'UTM 32' cannot be written"), std::string::npos);
  GeoTxt bad_geo = geo;
  bad_geo.records[3].horizontal_accuracy_m = 1.0;
  bad_geo.records[3].vertical_accuracy_m = 1.0;
  EXPECT_EQ(FormatGeoTxt(bad_geo, "geo.txt", &text).message(),
            "geo.txt: image 'IMG_4.JPG': a line without height cannot give attitudes or accuracies (the fields are "
            "positional)");
  bad_geo = geo;
  bad_geo.records[1].vertical_accuracy_m = 0.1;
  EXPECT_EQ(FormatGeoTxt(bad_geo, "geo.txt", &text).message(),
            "geo.txt: image 'IMG_2.JPG': the accuracies come as two (horizontal vertical)");
  bad_geo = geo;
  bad_geo.records[1].position.x() = std::numeric_limits<double>::infinity();
  EXPECT_EQ(FormatGeoTxt(bad_geo, "geo.txt", &text).message(), "geo.txt: image 'IMG_2.JPG': a coordinate is not a finite number");
}

// ------------------------------------------------------------------ physical ranges

TEST_F(TablesTest, CameraTableValuesOutsideTheirPhysicalRangeAreRefusedAtTheirLine) {
  const std::string base = "CameraID,FocalLength,PixelSize,NRows,NColumns";
  const std::string uav = "C,8800,2.41,3648,5472";
  const std::vector<CameraErrorCase> cases = {
      {base, "C,8800,0.0001,3648,5472", "2: PixelSize: '0.0001' is outside (0.001, 1000) um"},
      {base, "C,8800,1000,3648,5472", "2: PixelSize: '1000' is outside (0.001, 1000) um"},
      {base, "C,8800,0,3648,5472", "2: PixelSize: '0' is outside (0.001, 1000) um"},
      {base, "C,1e9,2.41,3648,5472", "2: FocalLength: '1e9' is outside [1, 100000000] um"},
      {base, "C,1e-300,2.41,3648,5472",
       "2: FocalLength: '1e-300' is outside [1, 100000000] um"},
      {base, "C,8800,2.41,1,1", "2: NRows: 1 is outside [2, 1000000] pixels"},
      {base, "C,8800,2.41,3648,1", "2: NColumns: 1 is outside [2, 1000000] pixels"},
      {base, "C,8800,2.41,3648,2000000", "2: NColumns: 2000000 is outside [2, 1000000] pixels"},
      {base + ",PrincipalX", uav + ",-2e8",
       "2: PrincipalX: '-2e8' is outside [-100000000, 100000000] um"},
      {base + ",AverageZ", uav + ",1e308",
       "2: AverageZ: '1e308' is outside [-100000000, 100000000] m"},
      {base + ",FilmFiducials", uav + ",1 2;3 1e9",
       "2: FilmFiducials: item 2: '1000000000' is outside [-100000000, 100000000] um"},
      // The seed's example K1 = -1 mm^-2: the corner of a 1-inch sensor would move 500 mm.
      {base + ",Radial", uav + ",0;-1;0;0",
       "2: Radial: the distortion correction scales the radius by 3.028 at 1.424 mm from the "
       "principal point; inside the image (7.925 mm to its farthest corner) it may change it by a "
       "factor of 3 at most"},
      {base + ",Radial", uav + ",0;1;0;0",
       "2: Radial: the distortion folds the image: the corrected radius stops increasing at 0.619 "
       "mm from the principal point, inside the image (7.925 mm to its farthest corner)"},
      {base + ",Tangential", uav + ",0.5;0",
       "2: Tangential: the distortion folds the image: the corrected radius stops increasing at "
       "0.371 mm from the principal point, inside the image (7.925 mm to its farthest corner)"},
      {base + ",DistortionType,RadialDistances,RadialDistortions",
       uav + ",DistortionTable,1000;2000,0;1500",
       "2: RadialDistortions: the distortion folds the image: the corrected radius stops "
       "increasing at 1.022 mm from the principal point, inside the image (7.925 mm to its "
       "farthest corner)"},
      // Affine: a denormal A1 makes the rows parallel; the pixel size must be physical too.
      {"CameraID,FocalLength,A0,A1,A2,B0,B1,B2", "C,152000,0,4.9e-324,0,0,0,-12",
       "2: A1: the affine is singular: A1 B2 - A2 B1 = -6e-323 is negligible against its "
       "coefficients (up to 12); the rows of A and B must not be parallel"},
      {"CameraID,FocalLength,A0,A1,A2,B0,B1,B2", "C,152000,0,12,24,0,6,12",
       "2: A1: the affine is singular: A1 B2 - A2 B1 = 0 is negligible against its coefficients "
       "(up to 24); the rows of A and B must not be parallel"},
      {"CameraID,FocalLength,A0,A1,A2,B0,B1,B2", "C,152000,0,12000,0,0,0,-12000",
       "2: A1: the affine gives pixels of 12000 um (sqrt |A1 B2 - A2 B1|), outside (0.001, 1000) "
       "um"},
      {"CameraID,FocalLength,A0,A1,A2,B0,B1,B2,AffineDirection", "C,152000,0,12000,0,0,0,-12000,-1",
       "2: A1: the affine gives pixels of 8.333333333333333e-05 um (sqrt |A1 B2 - A2 B1|, "
       "inverted for AffineDirection -1), outside (0.001, 1000) um"},
  };
  for (const CameraErrorCase& c : cases) {
    const std::string path = Write("cameras.csv", c.header + "\n" + c.row + "\n");
    std::vector<FrameCamera> cameras;
    EXPECT_EQ(ReadCameraTable(path, &cameras).message(), path + ":" + c.expected) << c.row;
  }
  // The same camera with a real lens reads, and a film camera without image size is checked
  // over its fiducials.
  const std::string path = Write("cameras.csv", base + ",Radial\n" + uav + ",0;-1.2e-4;2e-7;0\n");
  std::vector<FrameCamera> cameras;
  EXPECT_TRUE(ReadCameraTable(path, &cameras).ok());
  const std::string film =
      Write("film.csv",
            "CameraID,FocalLength,A0,A1,A2,B0,B1,B2,FilmFiducials,Radial\n"
            "RMK,152000,-115000,12,0,115000,0,-12,\"-106000 106000;106000 -106000\",0;1e-4;0;0\n");
  EXPECT_EQ(ReadCameraTable(film, &cameras).message(),
            film +
                ":2: Radial: the distortion folds the image: the corrected radius stops "
                "increasing at 58.557 mm from the principal point, inside the image (149.907 "
                "mm to its farthest corner)");
}

TEST_F(TablesTest, CoordinatesBeyondTheRangeAreRefusedInEveryTable) {
  std::vector<GroundPoint> points;
  std::string path = Write("points.csv", "PointID,X,Y,Z\nP1,1,2,3\nP2,1e308,2,3\n");
  EXPECT_EQ(ReadGroundPoints(path, &points).message(),
            path + ":3: X: '1e308' is outside [-100000000, 100000000] m");
  path = Write("points.csv", "PointID,X,Y,Z,AccuracyX,AccuracyY,AccuracyZ\nP1,1,2,3,1,1,1e9\n");
  EXPECT_EQ(ReadGroundPoints(path, &points).message(),
            path + ":2: AccuracyZ: '1e9' is outside [0, 100000000] m");
  std::vector<FrameRecord> frames;
  path = Write("frames.csv",
               "Raster,CameraID,PerspectiveX,PerspectiveY,PerspectiveZ,Omega,Phi,Kappa\n"
               "a,C,1,2,-1e300,0,0,0\n");
  EXPECT_EQ(ReadFramesTable(path, {}, &frames).message(),
            path + ":2: PerspectiveZ: '-1e300' is outside [-100000000, 100000000] m");
  path = Write("frames.csv",
               "Raster,CameraID,PerspectiveX,PerspectiveY,PerspectiveZ,Omega,Phi,Kappa\n"
               "a,C,1,2,3,0,0,1e6\n");
  EXPECT_EQ(ReadFramesTable(path, {}, &frames).message(),
            path + ":2: Kappa: '1e6' is outside [-360, 360] degrees");
  std::vector<ImageMark> marks;
  path = Write("marks.csv", "Raster,PointID,Column,Row\na,P,1,-1e300\n");
  EXPECT_EQ(ReadImageMarks(path, &marks).message(),
            path + ":2: Row: '-1e300' is outside [-100000000, 100000000] px");
  path = Write("marks.csv", "Raster,PointID,FilmX,FilmY,Accuracy\na,P,1e9,1,1\n");
  EXPECT_EQ(ReadImageMarks(path, &marks).message(),
            path + ":2: FilmX: '1e9' is outside [-100000000, 100000000] um");
  // Writers refuse what the readers would.
  GroundPoint far;
  far.point_id = "P";
  far.position.x() = 1e9;
  EXPECT_EQ(WriteGroundPoints(Path("out.csv"), {far}).message(),
            Path("out.csv") + ": point 'P': X: 1000000000 is outside [-100000000, 100000000] m");
  EXPECT_FALSE(fs::exists(Path("out.csv")));
}

TEST_F(TablesTest, MarksFarOutsideTheirImageAreRefusedWithTheirLine) {
  FrameCamera camera;
  camera.camera_id = "UAV";
  camera.focal_length_um = 8800.0;
  camera.pixel_size_um = 2.41;
  camera.n_columns = 5472;
  camera.n_rows = 3648;
  ImageMark mark;
  mark.raster = "a.jpg";
  mark.point_id = "P3";
  mark.line = 7;
  // Inside, on the border and within 5% of the size outside are fine.
  for (const Eigen::Vector2d& pixel :
       {Eigen::Vector2d(2736, 1824), Eigen::Vector2d(0, 3648), Eigen::Vector2d(-273, 3648 + 182)}) {
    mark.column_row = pixel;
    EXPECT_TRUE(CheckMarkInsideImage("marks.csv", mark, camera, PixelOrigin::kCorner).ok());
  }
  mark.column_row = Eigen::Vector2d(5472 + 20000, 100);
  EXPECT_EQ(CheckMarkInsideImage("marks.csv", mark, camera, PixelOrigin::kCorner).message(),
            "marks.csv:7: Column: the mark of point 'P3' in image 'a.jpg' lies 20000 pixels "
            "outside the 5472 x 3648 image of camera 'UAV' (at most 5% of the image size is "
            "allowed)");
  mark.column_row = Eigen::Vector2d(100, -500);
  EXPECT_EQ(CheckMarkInsideImage("marks.csv", mark, camera, PixelOrigin::kCenter).message(),
            "marks.csv:7: Row: the mark of point 'P3' in image 'a.jpg' lies 500 pixels outside "
            "the 5472 x 3648 image of camera 'UAV' (at most 5% of the image size is allowed)");
  // Film marks are converted to pixels: 2.41 um per pixel, FilmCoordinateSystem 1 (y up).
  mark.column_row.reset();
  mark.film_um = Eigen::Vector2d(0.0, 2.41 * (1824 + 1000));
  EXPECT_EQ(CheckMarkInsideImage("marks.csv", mark, camera, PixelOrigin::kCorner).message(),
            "marks.csv:7: FilmY: the mark of point 'P3' in image 'a.jpg' lies 1000 pixels outside "
            "the 5472 x 3648 image of camera 'UAV' (at most 5% of the image size is allowed)");
  // Without an image size there is nothing to check against.
  camera.n_columns = camera.n_rows = 0;
  EXPECT_TRUE(CheckMarkInsideImage("marks.csv", mark, camera, PixelOrigin::kCorner).ok());
}

// ------------------------------------------------------------------ documentation

TEST_F(TablesTest, EveryExampleOfTheFormatsPageReads) {
  const std::string doc = Read(testing::SourcePath("docs/formats.md"));
  ASSERT_FALSE(doc.empty());
  int examples = 0;
  size_t pos = 0;
  while ((pos = doc.find("```", pos)) != std::string::npos) {
    const size_t language_end = doc.find('\n', pos);
    const size_t close = doc.find("```", language_end);
    ASSERT_NE(close, std::string::npos);
    const std::string language = doc.substr(pos + 3, language_end - pos - 3);
    const std::string body = doc.substr(language_end + 1, close - language_end - 1);
    pos = close + 3;
    if (language == "json") continue;  // the resect report's layout, not a table
    if (language == "console") continue;  // messages a command prints, not a table
    const std::string path = Write("example_" + std::to_string(++examples), body);
    const std::string header = body.substr(0, body.find('\n'));
    Status status;
    if (language == "text") {
      // gcp_list.txt lines start with a coordinate, geo.txt lines with an image name.
      const std::string second = body.substr(body.find('\n') + 1);
      double number = 0.0;
      std::string why;
      if (ParseFiniteNumber(second.substr(0, second.find(' ')), &number, &why)) {
        GcpList gcp;
        status = ReadGcpList(path, &gcp);
      } else {
        GeoTxt geo;
        status = ReadGeoTxt(path, &geo);
      }
    } else if (header.find("CameraID,FocalLength") != std::string::npos) {
      std::vector<FrameCamera> cameras;
      status = ReadCameraTable(path, &cameras);
    } else if (header.find("PerspectiveX") != std::string::npos) {
      std::vector<FrameRecord> frames;
      status = ReadFramesTable(path, FramesTableOptions(), &frames);
    } else if (header.rfind("PointID,", 0) == 0) {
      std::vector<GroundPoint> points;
      status = ReadGroundPoints(path, &points);
    } else if (header.rfind("Raster,PointID,", 0) == 0) {
      std::vector<ImageMark> marks;
      status = ReadImageMarks(path, &marks);
    } else if (header.rfind("Raster,FiducialID,", 0) == 0) {
      std::vector<MeasuredFiducial> fiducials;
      status = ReadMeasuredFiducials(path, &fiducials);
    } else {
      ADD_FAILURE() << "an example of an unknown kind: " << header;
    }
    EXPECT_TRUE(status.ok()) << status.message() << "\n" << body;
  }
  EXPECT_EQ(examples, 10);
}

TEST_F(TablesTest, FailedTableWriteLeavesNoFile) {
  const std::string path = Path("missing/points.csv");
  GroundPoint point;
  point.point_id = "P";
  EXPECT_FALSE(WriteGroundPoints(path, {point}).ok());
  point.position.x() = std::nan("");
  EXPECT_EQ(WriteGroundPoints(Path("points.csv"), {point}).message(),
            Path("points.csv") + ": point 'P': X: value is not finite");
  EXPECT_TRUE(FilesInDir().empty());
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
