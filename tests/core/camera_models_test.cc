#include "core/camera_models.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/camera.h"
#include "tests/support/ordered_draws.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// The inversions iterate to 1e-12 (normalised) and 1e-7 um (film); a round trip through both
// directions stays within a few times that.
constexpr double kNormalizedRoundTrip = 1e-10;
constexpr double kFilmRoundTripUm = 1e-6;
// Exact closed forms evaluated in double precision.
constexpr double kExact = 1e-9;

TEST(CameraModels, NamesRoundTrip) {
  for (CameraModelType type :
       {CameraModelType::kFrame, CameraModelType::kSimplePinhole, CameraModelType::kPinhole,
        CameraModelType::kSimpleRadial, CameraModelType::kRadial, CameraModelType::kOpenCv,
        CameraModelType::kFullOpenCv, CameraModelType::kOpenCvFisheye}) {
    const auto parsed = ParseEnum<CameraModelType>(EnumName(type));
    ASSERT_TRUE(parsed.has_value());
    EXPECT_EQ(*parsed, type);
    EXPECT_EQ(static_cast<int>(CameraModelParamNames(type).size()), CameraModelNumParams(type));
  }
  EXPECT_EQ(ParseEnum<CameraModelType>("simple_radial"), CameraModelType::kSimpleRadial);
  EXPECT_FALSE(ParseEnum<CameraModelType>("FISHEYE").has_value());
  EXPECT_EQ(CameraModelNumParams(CameraModelType::kFullOpenCv), kMaxCameraModelParams);
  EXPECT_EQ(CameraModelNumParams(CameraModelType::kFrame), kFrameNumParams);
}

TEST(CameraModels, SimpleRadialNominalCase) {
  // f = 1000 px, principal point (500, 400), k = 0.1. The ray (a, b) = (0.2, 0.1) in the seed's
  // image plane (y up) is COLMAP's (u, v) = (0.2, -0.1): r2 = 0.05, factor 1.005, pixel
  // (500 + 201, 400 - 100.5) = (701, 299.5).
  const double params[] = {1000.0, 500.0, 400.0, 0.1};
  const double ab[] = {0.2, 0.1};
  const double observed[] = {702.0, 300.0};
  double residual[2];
  CameraModelResidual(CameraModelType::kSimpleRadial, params, ab, observed, CameraModelData(),
                      residual);
  EXPECT_NEAR(residual[0], 1.0, kExact);
  EXPECT_NEAR(residual[1], 0.5, kExact);
}

TEST(CameraModels, FullOpenCvNominalCase) {
  // COLMAP's FULL_OPENCV, computed by hand: (a, b) = (0.2, 0.1) is (u, v) = (0.2, -0.1), r2 = 0.05.
  // k1 = 0.1, k2 = 0.2, k3 = 0.4, k4 = 0.2, k5 = k6 = 0: radial factor
  // (1 + 0.005 + 0.0005 + 0.00005) / (1 + 0.01) = 1.00555 / 1.01; p1 = 0.01, p2 = -0.02:
  // du = 2 p1 u v + p2 (r2 + 2 u^2) = -0.0004 - 0.0026 = -0.003,
  // dv = 2 p2 u v + p1 (r2 + 2 v^2) = 0.0008 + 0.0007 = 0.0015.
  // fx = 1000, fy = 1100, principal point (500, 400).
  const double params[] = {1000.0, 1100.0, 500.0, 400.0, 0.1, 0.2, 0.01, -0.02, 0.4, 0.2, 0.0, 0.0};
  const double ab[] = {0.2, 0.1};
  const double zero[] = {0.0, 0.0};
  double residual[2];
  CameraModelResidual(CameraModelType::kFullOpenCv, params, ab, zero, CameraModelData(), residual);
  const double factor = 1.00555 / 1.01;
  EXPECT_NEAR(-residual[0], 500.0 + 1000.0 * (0.2 * factor - 0.003), kExact);
  EXPECT_NEAR(-residual[1], 400.0 + 1100.0 * (-0.1 * factor + 0.0015), kExact);
}

TEST(CameraModels, OpenCvFisheyeNominalCase) {
  // COLMAP's OPENCV_FISHEYE by hand: (u, v) = (0.3, -0.4), r = 0.5, theta = atan(0.5),
  // theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8), point (u, v) theta_d /
  // r.
  const double params[] = {800.0, 810.0, 320.0, 240.0, 0.05, -0.01, 0.002, -0.0005};
  const double ab[] = {0.3, 0.4};
  const double zero[] = {0.0, 0.0};
  double residual[2];
  CameraModelResidual(CameraModelType::kOpenCvFisheye, params, ab, zero, CameraModelData(),
                      residual);
  const double theta = std::atan(0.5), t2 = theta * theta;
  const double theta_d = theta * (1.0 + 0.05 * t2 - 0.01 * t2 * t2 + 0.002 * t2 * t2 * t2 -
                                  0.0005 * t2 * t2 * t2 * t2);
  EXPECT_NEAR(-residual[0], 320.0 + 800.0 * 0.3 * theta_d / 0.5, kExact);
  EXPECT_NEAR(-residual[1], 240.0 - 810.0 * 0.4 * theta_d / 0.5, kExact);
  // On the axis the model is the identity (no 0 / 0).
  const double centre[] = {0.0, 0.0};
  CameraModelResidual(CameraModelType::kOpenCvFisheye, params, centre, zero, CameraModelData(),
                      residual);
  EXPECT_EQ(-residual[0], 320.0);
  EXPECT_EQ(-residual[1], 240.0);
}

TEST(CameraModels, FrameNominalCase) {
  // c = 10000 um, principal point (10, -20) um, K1 = 1e-4 mm^-2, affinity 1e-3. Film (5010, -20):
  // x1 = 1.001 * 5010 = 5015.01, xb = 5.00501 mm, dx = xb^3 * 1e-4, ideal x = 1000 (xb - dx).
  double params[kFrameNumParams] = {10000.0, 10.0, -20.0, 0.0, 1e-4};
  params[kFrameAffinity] = 1e-3;
  const double film[] = {5010.0, -20.0};
  double ideal[2];
  FrameCorrectFilmPoint(params, film, CameraModelData(), ideal);
  const double xb = 5.00501;
  EXPECT_NEAR(ideal[0], 1000.0 * (xb - xb * xb * xb * 1e-4), kExact);
  EXPECT_NEAR(ideal[1], 0.0, kExact);
}

TEST(CameraModels, FrameMatchesTheCameraTableChain) {
  // Without affinity and skew the kFrame model is the camera table's ImagePlaneFromFilm.
  FrameCamera camera;
  camera.camera_id = "c";
  camera.focal_length_um = 8800.0;
  camera.principal_x_um = 12.0;
  camera.principal_y_um = -7.0;
  camera.radial_k = {1e-5, -1.2e-4, 2.0e-7, -1e-10};
  camera.tangential_p = {3.0e-6, -2.0e-6};
  camera.polarity = 1;
  const std::array<double, kFrameNumParams> params = FrameModelParams(camera);
  const Eigen::Vector2d film(4321.0, -2345.0);
  double ideal[2];
  FrameCorrectFilmPoint(params.data(), film.data(), FrameModelData(camera), ideal);
  const Eigen::Vector2d measured = film - Eigen::Vector2d(12.0, -7.0);
  const Eigen::Vector2d expected = -(measured - DistortionInMicrons(camera, measured));
  EXPECT_NEAR(ideal[0], expected.x(), kExact);
  EXPECT_NEAR(ideal[1], expected.y(), kExact);
}

TEST(CameraModels, InversionsRoundTripForEveryModel) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const std::vector<double> table_r = {2000.0, 5000.0, 9000.0}, table_d = {3.0, -4.0, 12.0};
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector2d ab = DrawLastFirst<2>([&](int i) { return (i == 0 ? 0.4 : 0.3) * u(rng); });
    struct Case {
      CameraModelType type;
      std::vector<double> params;
      CameraModelData data;
    };
    double frame[kFrameNumParams] = {8800.0, 12.0, -7.0, 1e-5, -1.2e-4, 2e-7, -1e-10, 3e-6, -2e-6,
                                     4e-4, -3e-4};
    CameraModelData table;
    table.polarity_sign = -1.0;
    table.table_radius_um = table_r.data();
    table.table_distortion_um = table_d.data();
    table.table_size = 3;
    const std::vector<Case> cases = {
        {CameraModelType::kFrame, std::vector<double>(frame, frame + kFrameNumParams), {}},
        {CameraModelType::kFrame, std::vector<double>(frame, frame + kFrameNumParams), table},
        {CameraModelType::kSimplePinhole, {3000.0, 2000.0, 1500.0}, {}},
        {CameraModelType::kPinhole, {3000.0, 3010.0, 2000.0, 1500.0}, {}},
        {CameraModelType::kSimpleRadial, {3000.0, 2000.0, 1500.0, -0.08}, {}},
        {CameraModelType::kRadial, {3000.0, 2000.0, 1500.0, -0.08, 0.01}, {}},
        {CameraModelType::kOpenCv, {3000.0, 3010.0, 2000.0, 1500.0, -0.08, 0.01, 1e-3, -2e-3}, {}},
        {CameraModelType::kFullOpenCv,
         {3000.0, 3010.0, 2000.0, 1500.0, -0.08, 0.01, 1e-3, -2e-3, 0.002, 0.01, -0.003, 0.0005},
         {}},
        {CameraModelType::kOpenCvFisheye,
         {3000.0, 3010.0, 2000.0, 1500.0, 0.03, -0.01, 0.002, -0.0003},
         {}},
    };
    for (const Case& c : cases) {
      SCOPED_TRACE(EnumName(c.type));
      Eigen::Vector2d observation, back;
      ASSERT_TRUE(ObservationFromNormalized(c.type, c.params.data(), c.data, ab, &observation).ok());
      // The observation reproduces the ray: zero residual.
      double residual[2];
      CameraModelResidual(c.type, c.params.data(), ab.data(), observation.data(), c.data,
                          residual);
      EXPECT_LE(Eigen::Vector2d(residual[0], residual[1]).norm(), kFilmRoundTripUm);
      ASSERT_TRUE(NormalizedFromObservation(c.type, c.params.data(), c.data, observation, &back).ok());
      EXPECT_LE((back - ab).norm(), kNormalizedRoundTrip);
    }
  }
}

TEST(CameraModels, AffinityAndSkewFoldExactlyIntoTheTableAffine) {
  // A camera table row without an affine: PixelSize, image size, FilmCoordinateSystem 1.
  FrameCamera camera;
  camera.camera_id = "c";
  camera.focal_length_um = 7457.0;
  camera.pixel_size_um = 3.1911;
  camera.n_columns = 2272;
  camera.n_rows = 1704;
  camera.radial_k = {0.0, -4.5e-3, 4.5e-5, 2e-6};
  std::array<double, kFrameNumParams> params = FrameModelParams(camera);
  params[kFrameAffinity] = 3.9e-4;
  params[kFrameSkew] = -2e-4;
  params[kFramePrincipalX] = -11.0;
  FrameCamera written = camera;
  ASSERT_TRUE(SetFrameModelParams(params.data(), &written).ok());
  ASSERT_TRUE(written.has_affine);
  // The written table, read as a plain camera (no affinity), corrects a pixel exactly as the model
  // with affinity and skew corrects the original table's film point.
  for (const Eigen::Vector2d pixel : {Eigen::Vector2d(10.5, 20.5), Eigen::Vector2d(2000.0, 1600.0),
                                      Eigen::Vector2d(1136.0, 852.0)}) {
    Eigen::Vector2d film, film_written;
    ASSERT_TRUE(FilmFromPixel(camera, pixel, PixelOrigin::kCorner, &film).ok());
    ASSERT_TRUE(FilmFromPixel(written, pixel, PixelOrigin::kCorner, &film_written).ok());
    double with_affinity[2];
    FrameCorrectFilmPoint(params.data(), film.data(), FrameModelData(camera), with_affinity);
    const Eigen::Vector2d plain = ImagePlaneFromFilm(written, film_written);
    EXPECT_NEAR(plain.x(), with_affinity[0], kExact);
    EXPECT_NEAR(plain.y(), with_affinity[1], kExact);
  }
}

TEST(CameraModels, CalibrationNamesPerModel) {
  std::vector<int> indices;
  ASSERT_TRUE(CalibrationParamIndices(CameraModelType::kFrame, "affinity", &indices).ok());
  EXPECT_EQ(indices, std::vector<int>{kFrameAffinity});
  ASSERT_TRUE(CalibrationParamIndices(CameraModelType::kOpenCv, "FocalLength", &indices).ok());
  EXPECT_EQ(indices, (std::vector<int>{0, 1}));
  ASSERT_TRUE(CalibrationParamIndices(CameraModelType::kSimpleRadial, "K1", &indices).ok());
  EXPECT_EQ(indices, std::vector<int>{3});
  ASSERT_TRUE(CalibrationParamIndices(CameraModelType::kOpenCv, "P2", &indices).ok());
  EXPECT_EQ(indices, std::vector<int>{7});
  ASSERT_TRUE(CalibrationParamIndices(CameraModelType::kFullOpenCv, "K3", &indices).ok());
  EXPECT_EQ(indices, std::vector<int>{8});
  ASSERT_TRUE(CalibrationParamIndices(CameraModelType::kOpenCvFisheye, "k3", &indices).ok());
  EXPECT_EQ(indices, std::vector<int>{6});
  ASSERT_TRUE(
      CalibrationParamIndices(CameraModelType::kOpenCvFisheye, "PrincipalY", &indices).ok());
  EXPECT_EQ(indices, std::vector<int>{3});
  EXPECT_FALSE(CalibrationParamIndices(CameraModelType::kOpenCvFisheye, "P1", &indices).ok());
  ASSERT_TRUE(CalibrationParamIndices(CameraModelType::kFullOpenCv, "k5", &indices).ok());
  EXPECT_EQ(indices, std::vector<int>{10});
  ASSERT_TRUE(CalibrationParamIndices(CameraModelType::kRadial, "f", &indices).ok());
  EXPECT_EQ(indices, std::vector<int>{0});
  EXPECT_FALSE(CalibrationParamIndices(CameraModelType::kOpenCv, "K3", &indices).ok());
  const Status missing = CalibrationParamIndices(CameraModelType::kSimpleRadial, "K2", &indices);
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.message(), "the SIMPLE_RADIAL camera model has no parameter 'K2'");
  EXPECT_FALSE(CalibrationParamIndices(CameraModelType::kPinhole, "Affinity", &indices).ok());
  EXPECT_FALSE(CalibrationParamIndices(CameraModelType::kFrame, "k", &indices).ok());
}

TEST(CameraModels, CalibrationTakesColmapsOwnParameterNames) {
  // COLMAP's names of each model's parameters (CameraModelParamNames), any case; f is both focal
  // lengths of the models that have two.
  struct Case {
    CameraModelType model;
    const char* name;
    std::vector<int> indices;
  };
  const Case cases[] = {{CameraModelType::kSimpleRadial, "f", {0}},
                        {CameraModelType::kSimpleRadial, "K", {3}},
                        {CameraModelType::kSimplePinhole, "cy", {2}},
                        {CameraModelType::kRadial, "k2", {4}},
                        {CameraModelType::kPinhole, "F", {0, 1}},
                        {CameraModelType::kPinhole, "fy", {1}},
                        {CameraModelType::kOpenCv, "fx", {0}},
                        {CameraModelType::kOpenCv, "cx", {2}},
                        {CameraModelType::kOpenCv, "p1", {6}}};
  for (const Case& c : cases) {
    std::vector<int> indices;
    const Status status = CalibrationParamIndices(c.model, c.name, &indices);
    ASSERT_TRUE(status.ok()) << EnumName(c.model) << " " << c.name << ": " << status.message();
    EXPECT_EQ(indices, c.indices) << EnumName(c.model) << " " << c.name;
  }
  std::vector<int> indices;
  EXPECT_EQ(CalibrationParamIndices(CameraModelType::kRadial, "k", &indices).message(),
            "the RADIAL camera model has no parameter 'k'");
  EXPECT_EQ(CalibrationParamIndices(CameraModelType::kSimplePinhole, "fx", &indices).message(),
            "the SIMPLE_PINHOLE camera model has no parameter 'fx'");
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
