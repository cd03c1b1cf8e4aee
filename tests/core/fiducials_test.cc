#include "core/fiducials.h"

#include <gtest/gtest.h>

#include <cmath>

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// A Wild RC-30 style film camera: 153 mm lens, four corner and four mid-side fiducials with
// calibrated film coordinates (um, the numbers of the camera-table example of docs/formats.md).
FrameCamera Rc30() {
  FrameCamera camera;
  camera.camera_id = "RC30";
  camera.focal_length_um = 153012.0;
  camera.film_fiducials_um = {{-105997.0, -106001.0}, {106003.0, -106000.0},
                              {105999.0, 106000.0},   {-106002.0, 105998.0},
                              {-0.2, -110000.5},      {110001.0, -0.5},
                              {0.3, 110002.0},        {-109998.0, 0.4}};
  return camera;
}

// A scan of it: 20 um pixels, the film turned by 0.25 deg and shifted in the scanner, rows down.
// pixel = S (film) + t, its inverse gives the true affine.
Eigen::Vector2d ScanPixel(const Eigen::Vector2d& film_um) {
  const double angle = 0.25 * 3.14159265358979 / 180.0;
  Eigen::Matrix2d R;
  R << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
  const Eigen::Vector2d rotated = R * film_um / 20.0;
  return Eigen::Vector2d(5750.0 + 12.5 + rotated.x(), 5750.0 - 7.25 - rotated.y());
}

std::vector<MeasuredFiducial> Measure(const FrameCamera& camera, double noise_um = 0.0) {
  std::vector<MeasuredFiducial> measured;
  for (size_t k = 0; k < camera.film_fiducials_um.size(); ++k) {
    MeasuredFiducial f;
    f.raster = "scan_017.tif";
    f.fiducial_id = static_cast<int>(k + 1);
    // A deterministic +-noise pattern (um on the film).
    const double e = noise_um * ((k % 3) - 1.0);
    f.column_row = ScanPixel(camera.film_fiducials_um[k] + Eigen::Vector2d(e, -e));
    f.line = static_cast<int>(k + 2);
    measured.push_back(f);
  }
  return measured;
}

TEST(Fiducials, ExactScanFitsToRoundingAndMapsPixelsBackToFilm) {
  const FrameCamera camera = Rc30();
  FiducialFit fit;
  const Status status = FitFiducials(camera, Measure(camera), FiducialFitOptions(), "f.csv", &fit);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(fit.residuals.size(), 8u);
  EXPECT_EQ(fit.redundancy, 10);
  EXPECT_LT(fit.max_um, 1e-6);
  // The fitted map takes any scan pixel to its film point.
  const FrameCamera scanned = WithFiducialAffine(camera, fit);
  const Eigen::Vector2d film(-61234.5, 40211.25);
  Eigen::Vector2d back;
  ASSERT_TRUE(FilmFromPixel(scanned, ScanPixel(film), PixelOrigin::kCorner, &back).ok());
  EXPECT_LT((back - film).norm(), 1e-6);
  double um_per_pixel = 0.0;
  ASSERT_TRUE(FilmUmPerPixel(scanned, ScanPixel(film), PixelOrigin::kCorner, &um_per_pixel).ok());
  EXPECT_NEAR(um_per_pixel, 20.0, 1e-9);
}

TEST(Fiducials, ResidualsAreReportedAndAPoorFitIsRefusedAtItsLine) {
  const FrameCamera camera = Rc30();
  FiducialFit fit;
  ASSERT_TRUE(FitFiducials(camera, Measure(camera, 3.0), FiducialFitOptions(), "f.csv", &fit).ok());
  EXPECT_GT(fit.rms_um, 0.5);
  EXPECT_LT(fit.max_um, 6.0);
  // Fiducials 2 and 3 swapped by the operator: 212 mm off, named with the line of the worst.
  std::vector<MeasuredFiducial> swapped = Measure(camera);
  std::swap(swapped[1].column_row, swapped[2].column_row);
  const Status status = FitFiducials(camera, swapped, FiducialFitOptions(), "f.csv", &fit);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.message().rfind("f.csv:", 0), 0u) << status.message();
  EXPECT_NE(status.message().find("misnumbered or mismeasured"), std::string::npos);
  EXPECT_NE(status.message().find("limit 30.0 um"), std::string::npos) << status.message();
}

TEST(Fiducials, BadInputIsNamed) {
  FrameCamera camera = Rc30();
  FiducialFit fit;
  std::vector<MeasuredFiducial> measured = Measure(camera);
  measured[0].fiducial_id = 9;
  EXPECT_NE(FitFiducials(camera, measured, FiducialFitOptions(), "f.csv", &fit)
                .message()
                .find("f.csv:2: FiducialID: 9 is not a fiducial of camera 'RC30' (it has 8)"),
            std::string::npos);
  measured = Measure(camera);
  measured.resize(2);
  EXPECT_NE(FitFiducials(camera, measured, FiducialFitOptions(), "f.csv", &fit)
                .message()
                .find("at least three"),
            std::string::npos);
  camera.film_fiducials_um.clear();
  EXPECT_NE(FitFiducials(camera, Measure(Rc30()), FiducialFitOptions(), "f.csv", &fit)
                .message()
                .find("has no FilmFiducials"),
            std::string::npos);
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
