#include "core/collinearity.h"

#include <gtest/gtest.h>

#include <random>

namespace photopose {
namespace {

FrameCamera UavCamera() {
  FrameCamera camera;
  camera.camera_id = "uav";
  camera.focal_length_um = 8800.0;
  camera.pixel_size_um = 2.41;
  camera.n_columns = 5472;
  camera.n_rows = 3648;
  camera.principal_x_um = 12.0;
  camera.principal_y_um = -7.0;
  camera.radial_k = {0.0, -1.2e-4, 2.0e-7, 0.0};
  return camera;
}

TEST(Collinearity, NadirHandComputed) {
  // 1000 m above the origin, looking down, c = 100 mm: a point 100 m east lands 10 mm right.
  ExteriorOrientation eo;
  eo.set_center_in_ground({0.0, 0.0, 1000.0});
  const double point[3] = {100.0, -50.0, 0.0};
  double xy[2];
  ASSERT_TRUE(ProjectToImagePlane(eo.data(), point, 100000.0, xy));
  EXPECT_NEAR(xy[0], 10000.0, 1e-9);
  EXPECT_NEAR(xy[1], -5000.0, 1e-9);
  const double above[3] = {0.0, 0.0, 1200.0};
  EXPECT_FALSE(ProjectToImagePlane(eo.data(), above, 100000.0, xy));
}

TEST(Collinearity, ClosedFormPartialsMatchCentralDifferences) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    double eo[6] = {50 * u(rng), 50 * u(rng), 500 + 50 * u(rng), 0.8 * u(rng), 0.5 * u(rng), kPi * u(rng)};
    const Eigen::Matrix3d R = RotationFromAngles(RotationConvention::kSeed, {eo[3], eo[4], eo[5]});
    const Eigen::Vector3d ray(0.5 * u(rng), 0.5 * u(rng), -1.0);
    const Eigen::Vector3d p = Eigen::Vector3d(eo[0], eo[1], eo[2]) + R.transpose() * (600.0 * ray);
    double point[3] = {p.x(), p.y(), p.z()};
    double xy[2], d_eo[12], d_point[6], d_focal[2];
    ASSERT_TRUE(ProjectWithJacobians(eo, point, 8800.0, xy, d_eo, d_point, d_focal));
    // Central differences; h balances truncation (h^2) and rounding (eps / h).
    for (int k = 0; k < 6; ++k) {
      const double h = k < 3 ? 1e-4 : 1e-7;
      double plus[6], minus[6], xp[2], xm[2];
      std::copy(eo, eo + 6, plus);
      std::copy(eo, eo + 6, minus);
      plus[k] += h;
      minus[k] -= h;
      ASSERT_TRUE(ProjectToImagePlane(plus, point, 8800.0, xp));
      ASSERT_TRUE(ProjectToImagePlane(minus, point, 8800.0, xm));
      for (int r = 0; r < 2; ++r) {
        const double numeric = (xp[r] - xm[r]) / (2 * h);
        EXPECT_NEAR(d_eo[r * 6 + k], numeric, 1e-5 * std::max(1.0, std::abs(numeric))) << k << r;
      }
    }
    for (int k = 0; k < 3; ++k) {
      double plus[3] = {point[0], point[1], point[2]}, minus[3] = {point[0], point[1], point[2]};
      plus[k] += 1e-4;
      minus[k] -= 1e-4;
      double xp[2], xm[2];
      ASSERT_TRUE(ProjectToImagePlane(eo, plus, 8800.0, xp));
      ASSERT_TRUE(ProjectToImagePlane(eo, minus, 8800.0, xm));
      for (int r = 0; r < 2; ++r)
        EXPECT_NEAR(d_point[r * 3 + k], (xp[r] - xm[r]) / 2e-4, 1e-6 * std::max(1.0, std::abs(d_point[r * 3 + k])));
    }
    EXPECT_NEAR(d_focal[0], xy[0] / 8800.0, 1e-12);
  }
}

TEST(Collinearity, ProjectAndIntersectRoundTrip) {
  const FrameCamera camera = UavCamera();
  ExteriorOrientation eo;
  eo.set_center_in_ground({300000.0, 4100000.0, 120.0});
  eo.set_angles_seed_rad({0.03, -0.02, 2.0});
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> col(0.0, 5472.0), row(0.0, 3648.0);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector2d pixel(col(rng), row(rng));
    Eigen::Vector3d ground;
    ASSERT_TRUE(IntersectRayWithPlane(camera, eo, pixel, PixelOrigin::kCorner, 20.0, &ground).ok());
    EXPECT_NEAR(ground.z(), 20.0, 1e-12);
    Eigen::Vector2d back;
    ASSERT_TRUE(ProjectGroundPoint(camera, eo, ground, PixelOrigin::kCorner, &back).ok());
    EXPECT_LE((back - pixel).norm(), 1e-6);
  }
}

TEST(Collinearity, EarthCurvatureLowersDistantPoints) {
  FrameCamera camera = UavCamera();
  camera.radial_k = {0.0, 0.0, 0.0, 0.0};
  ExteriorOrientation eo;
  eo.set_center_in_ground({0.0, 0.0, 1000.0});
  const Eigen::Vector2d pixel(5000.0, 1824.0);
  Eigen::Vector3d flat, curved;
  ASSERT_TRUE(IntersectRayWithPlane(camera, eo, pixel, PixelOrigin::kCorner, 0.0, &flat).ok());
  camera.apply_ecc = true;
  ASSERT_TRUE(IntersectRayWithPlane(camera, eo, pixel, PixelOrigin::kCorner, 0.0, &curved).ok());
  // The surface drops by D^2 / 2R, so the ray meets it farther out.
  EXPECT_GT(curved.head<2>().norm(), flat.head<2>().norm());
  const double drop = curved.head<2>().squaredNorm() / (2.0 * camera.earth_radius_m);
  const double expected_extra = drop * flat.head<2>().norm() / 1000.0;  // similar triangles
  EXPECT_NEAR(curved.head<2>().norm() - flat.head<2>().norm(), expected_extra, 1e-3 * expected_extra);
  Eigen::Vector2d back;
  ASSERT_TRUE(ProjectGroundPoint(camera, eo, curved, PixelOrigin::kCorner, &back).ok());
  EXPECT_LE((back - pixel).norm(), 1e-6);
}

TEST(Collinearity, RayAwayFromThePlaneFails) {
  const FrameCamera camera = UavCamera();
  ExteriorOrientation eo;
  eo.set_center_in_ground({0.0, 0.0, 100.0});
  Eigen::Vector3d ground;
  EXPECT_FALSE(IntersectRayWithPlane(camera, eo, {100.0, 100.0}, PixelOrigin::kCorner, 200.0, &ground).ok());
}

}  // namespace
}  // namespace photopose
