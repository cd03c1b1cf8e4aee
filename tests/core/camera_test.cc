#include "core/camera.h"
#include "tests/support/ordered_draws.h"

#include <gtest/gtest.h>

#include <random>

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// pixel -> film -> pixel must round-trip to 1e-9 um (the requirement); the arithmetic is a
// few multiplications, so rounding is ~1e-11 um at 50 mm from the centre.
constexpr double kRoundTripUm = 1e-9;

FrameCamera TestCamera(FilmCoordinateSystem fcs) {
  FrameCamera camera;
  camera.camera_id = "test";
  camera.focal_length_um = 35000.0;
  camera.principal_x_um = 15.0;
  camera.principal_y_um = -22.0;
  camera.pixel_size_um = 4.4;
  camera.n_columns = 7952;
  camera.n_rows = 5304;
  camera.film_coordinate_system = fcs;
  return camera;
}

TEST(Camera, FirstPixelCentreIsHalfAPixel) {
  FrameCamera camera = TestCamera(FilmCoordinateSystem::kXRightYUp);
  Eigen::Vector2d film;
  ASSERT_TRUE(FilmFromPixel(camera, {0.5, 0.5}, PixelOrigin::kCorner, &film).ok());
  EXPECT_NEAR(film.x(), (0.5 - 3976.0) * 4.4, 1e-9);
  EXPECT_NEAR(film.y(), (2652.0 - 0.5) * 4.4, 1e-9);  // y up
  Eigen::Vector2d same;
  ASSERT_TRUE(FilmFromPixel(camera, {0.0, 0.0}, PixelOrigin::kCenter, &same).ok());
  EXPECT_NEAR((same - film).norm(), 0.0, 1e-9);
  // The image centre is the film origin.
  ASSERT_TRUE(FilmFromPixel(camera, {3976.0, 2652.0}, PixelOrigin::kCorner, &film).ok());
  EXPECT_NEAR(film.norm(), 0.0, 1e-12);
}

TEST(Camera, FilmAxesFollowTheFilmCoordinateSystem) {
  // A pixel right of and above the centre.
  const Eigen::Vector2d right_up(3976.0 + 100.0, 2652.0 - 50.0);
  const struct {
    FilmCoordinateSystem fcs;
    Eigen::Vector2d expected_um;
  } cases[] = {{FilmCoordinateSystem::kXRightYUp, {440.0, 220.0}},
               {FilmCoordinateSystem::kXUpYLeft, {220.0, -440.0}},
               {FilmCoordinateSystem::kXLeftYDown, {-440.0, -220.0}},
               {FilmCoordinateSystem::kXDownYRight, {-220.0, 440.0}}};
  for (const auto& c : cases) {
    Eigen::Vector2d film;
    ASSERT_TRUE(FilmFromPixel(TestCamera(c.fcs), right_up, PixelOrigin::kCorner, &film).ok());
    EXPECT_NEAR((film - c.expected_um).norm(), 0.0, 1e-9) << static_cast<int>(c.fcs);
  }
}

TEST(Camera, PixelFilmRoundTripForAllFilmSystemsWithAndWithoutDistortion) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> col(0.0, 7952.0), row(0.0, 5304.0);
  for (int fcs = 1; fcs <= 4; ++fcs) {
    for (int distorted = 0; distorted < 2; ++distorted) {
      FrameCamera camera = TestCamera(static_cast<FilmCoordinateSystem>(fcs));
      if (distorted) {
        camera.radial_k = {1e-4, -2.1e-4, 3.0e-7, -1e-10};
        camera.tangential_p = {2e-6, -3e-6};
      }
      for (int i = 0; i < 500; ++i) {
        const Eigen::Vector2d pixel = DrawLastFirst<2>([&](int i) { return i == 0 ? col(rng) : row(rng); });
        Eigen::Vector2d film, back;
        ASSERT_TRUE(FilmFromPixel(camera, pixel, PixelOrigin::kCorner, &film).ok());
        ASSERT_TRUE(PixelFromFilm(camera, film, PixelOrigin::kCorner, &back).ok());
        Eigen::Vector2d film_again;
        ASSERT_TRUE(FilmFromPixel(camera, back, PixelOrigin::kCorner, &film_again).ok());
        EXPECT_LE((film_again - film).norm(), kRoundTripUm);
        // Through the image plane (distortion removed) and back: < 1e-6 px by the iteration.
        const Eigen::Vector2d ideal = ImagePlaneFromFilm(camera, film);
        Eigen::Vector2d film_from_ideal;
        ASSERT_TRUE(FilmFromImagePlane(camera, ideal, &film_from_ideal).ok());
        EXPECT_LE((film_from_ideal - film).norm(), 1e-6 * camera.pixel_size_um);
      }
    }
  }
}

TEST(Camera, AffineBothDirectionsAgreeWithPixelSize) {
  FrameCamera plain = TestCamera(FilmCoordinateSystem::kXRightYUp);
  FrameCamera affine = plain;
  affine.has_affine = true;
  affine.affine_a = {-3976.0 * 4.4, 4.4, 0.0};
  affine.affine_b = {2652.0 * 4.4, 0.0, -4.4};
  FrameCamera inverse = plain;
  inverse.has_affine = true;
  inverse.affine_direction = -1;
  inverse.affine_a = {3976.0, 1.0 / 4.4, 0.0};
  inverse.affine_b = {2652.0, 0.0, -1.0 / 4.4};
  const Eigen::Vector2d pixel(1234.5, 987.25);
  Eigen::Vector2d a, b, c;
  ASSERT_TRUE(FilmFromPixel(plain, pixel, PixelOrigin::kCorner, &a).ok());
  ASSERT_TRUE(FilmFromPixel(affine, pixel, PixelOrigin::kCorner, &b).ok());
  ASSERT_TRUE(FilmFromPixel(inverse, pixel, PixelOrigin::kCorner, &c).ok());
  EXPECT_LE((a - b).norm(), 1e-9);
  EXPECT_LE((a - c).norm(), 1e-9);
  Eigen::Vector2d back;
  ASSERT_TRUE(PixelFromFilm(inverse, c, PixelOrigin::kCorner, &back).ok());
  EXPECT_LE((back - pixel).norm(), 1e-9);
  EXPECT_NEAR(affine.MeanPixelSizeUm(), 4.4, 1e-12);
  EXPECT_NEAR(inverse.MeanPixelSizeUm(), 4.4, 1e-12);
}

TEST(Camera, DistortionModelHandComputed) {
  FrameCamera camera = TestCamera(FilmCoordinateSystem::kXRightYUp);
  camera.radial_k = {0.0, 1e-4, 0.0, 0.0};  // mm^-2
  // At (10 mm, 0): dx = 10 * 1e-4 * 100 = 0.1 mm = 100 um.
  const Eigen::Vector2d d = DistortionInMicrons(camera, {10000.0, 0.0});
  EXPECT_NEAR(d.x(), 100.0, 1e-9);
  EXPECT_NEAR(d.y(), 0.0, 1e-12);
  camera.radial_k = {0.0, 0.0, 0.0, 0.0};
  camera.tangential_p = {1e-5, 0.0};  // mm^-1: dx = P1 (r^2 + 2 x^2) = 1e-5 * 300 mm = 3 um
  EXPECT_NEAR(DistortionInMicrons(camera, {10000.0, 0.0}).x(), 3.0, 1e-9);
}

TEST(Camera, DistortionTableInterpolates) {
  FrameCamera camera = TestCamera(FilmCoordinateSystem::kXRightYUp);
  camera.distortion_type = DistortionType::kDistortionTable;
  camera.radial_distances_um = {10000.0, 20000.0};
  camera.radial_distortions_um = {2.0, 6.0};
  // d(0) = 0 is implied; at 5 mm half of 2 um; at 15 mm the mean 4 um; at 30 mm extrapolated 10 um.
  EXPECT_NEAR(DistortionInMicrons(camera, {5000.0, 0.0}).x(), 1.0, 1e-12);
  EXPECT_NEAR(DistortionInMicrons(camera, {0.0, 15000.0}).y(), 4.0, 1e-12);
  EXPECT_NEAR(DistortionInMicrons(camera, {30000.0, 0.0}).x(), 10.0, 1e-12);
}

TEST(Camera, PolarityFlipsTheImagePlane) {
  FrameCamera camera = TestCamera(FilmCoordinateSystem::kXRightYUp);
  const Eigen::Vector2d negative = ImagePlaneFromFilm(camera, {1000.0, 500.0});
  camera.polarity = +1;
  const Eigen::Vector2d positive = ImagePlaneFromFilm(camera, {1000.0, 500.0});
  EXPECT_LE((negative + positive).norm(), 1e-12);
}

TEST(Camera, ComputerVisionConversionAsTheSchemaStates) {
  std::array<double, 4> k;
  std::array<double, 2> p;
  DistortionFromComputerVision(0.1, 0.01, 0.001, 0.002, 0.003, 10.0, &k, &p);
  EXPECT_DOUBLE_EQ(k[0], 0.0);
  EXPECT_DOUBLE_EQ(k[1], 0.1 / 100.0);
  EXPECT_DOUBLE_EQ(k[2], 0.01 / 1e4);
  EXPECT_DOUBLE_EQ(k[3], 0.001 / 1e6);
  EXPECT_DOUBLE_EQ(p[0], -0.002 / 10.0);
  EXPECT_DOUBLE_EQ(p[1], -0.003 / 10.0);
}

TEST(Camera, FiducialAffineRecoversThePixelSize) {
  FrameCamera camera = TestCamera(FilmCoordinateSystem::kXRightYUp);
  camera.film_fiducials_um = {{106003.0, -106000.0}, {-105997.0, -106001.0},
                              {-106002.0, 105998.0}, {105999.0, 106000.0}};
  std::vector<Eigen::Vector2d> measured;
  for (const auto& f : camera.film_fiducials_um) {
    Eigen::Vector2d pixel;
    ASSERT_TRUE(PixelFromFilm(camera, f, PixelOrigin::kCorner, &pixel).ok());
    measured.push_back(pixel);
  }
  FrameCamera calibrated;
  ASSERT_TRUE(FitAffineFromFiducials(camera, measured, PixelOrigin::kCorner, &calibrated).ok());
  EXPECT_NEAR(calibrated.MeanPixelSizeUm(), 4.4, 1e-9);
  measured.resize(2);
  camera.film_fiducials_um.resize(2);
  EXPECT_FALSE(FitAffineFromFiducials(camera, measured, PixelOrigin::kCorner, &calibrated).ok());
}

TEST(Camera, IsValidNamesTheProblem) {
  FrameCamera camera = TestCamera(FilmCoordinateSystem::kXRightYUp);
  EXPECT_TRUE(camera.IsValid().ok());
  camera.focal_length_um = -1.0;
  EXPECT_NE(camera.IsValid().message().find("FocalLength"), std::string::npos);
  // Without the image size the camera still serves film marks (the schema makes NRows and
  // NColumns optional); pixel marks are refused where they need it, naming what is missing.
  camera = TestCamera(FilmCoordinateSystem::kXRightYUp);
  camera.n_rows = 0;
  EXPECT_TRUE(camera.IsValid().ok());
  EXPECT_FALSE(camera.HasPixelToFilm());
  EXPECT_NE(camera.PixelToFilmStatus().message().find("NRows and NColumns"), std::string::npos);
  Eigen::Vector2d film;
  EXPECT_FALSE(FilmFromPixel(camera, {10, 10}, PixelOrigin::kCorner, &film).ok());
  camera.pixel_size_um = -1.0;
  EXPECT_NE(camera.IsValid().message().find("PixelSize"), std::string::npos);
  camera = TestCamera(FilmCoordinateSystem::kXRightYUp);
  camera.polarity = 0;
  EXPECT_FALSE(camera.IsValid().ok());
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
