#include "core/camera_models.h"

#include <gtest/gtest.h>

#include <random>

#include "core/camera.h"

namespace photopose {
namespace {

// The inversions iterate to 1e-12 (normalised) and 1e-7 um (film); a round trip through both
// directions stays within a few times that.
constexpr double kNormalizedRoundTrip = 1e-10;
constexpr double kFilmRoundTripUm = 1e-6;
// Exact closed forms evaluated in double precision.
constexpr double kExact = 1e-9;

TEST(CameraModels, NamesRoundTrip) {
  for (CameraModelType type :
       {CameraModelType::kFrame, CameraModelType::kSimplePinhole, CameraModelType::kPinhole,
        CameraModelType::kSimpleRadial, CameraModelType::kRadial, CameraModelType::kOpenCv}) {
    const auto parsed = ParseEnum<CameraModelType>(EnumName(type));
    ASSERT_TRUE(parsed.has_value());
    EXPECT_EQ(*parsed, type);
    EXPECT_EQ(static_cast<int>(CameraModelParamNames(type).size()), CameraModelNumParams(type));
  }
  EXPECT_EQ(ParseEnum<CameraModelType>("simple_radial"), CameraModelType::kSimpleRadial);
  EXPECT_FALSE(ParseEnum<CameraModelType>("FISHEYE").has_value());
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
    const Eigen::Vector2d ab(0.4 * u(rng), 0.3 * u(rng));
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

}  // namespace
}  // namespace photopose
