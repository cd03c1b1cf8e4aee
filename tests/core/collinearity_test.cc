#include "core/collinearity.h"
#include "tests/support/ordered_draws.h"

#include <gtest/gtest.h>

#include <random>

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

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

// The partials d_eo (2 x 6) and d_point (2 x 3), row-major, of project(eo, point, xy) against
// central differences; h balances truncation (h^2) and rounding (eps / h): 1e-4 m for
// coordinates, 1e-7 rad for angles. Tolerance 1e-5 relative (at least 1e-5 absolute).
template <typename Project>
void ExpectCentralDifferences(const Project& project, const double* eo, const double* point,
                              const double* d_eo, const double* d_point) {
  for (int k = 0; k < 9; ++k) {
    const bool of_eo = k < 6;
    const double h = of_eo ? (k < 3 ? 1e-4 : 1e-7) : 1e-4;
    double eo_plus[6], eo_minus[6], point_plus[3], point_minus[3], xp[2], xm[2];
    std::copy(eo, eo + 6, eo_plus);
    std::copy(eo, eo + 6, eo_minus);
    std::copy(point, point + 3, point_plus);
    std::copy(point, point + 3, point_minus);
    (of_eo ? eo_plus[k] : point_plus[k - 6]) += h;
    (of_eo ? eo_minus[k] : point_minus[k - 6]) -= h;
    ASSERT_TRUE(project(eo_plus, point_plus, xp));
    ASSERT_TRUE(project(eo_minus, point_minus, xm));
    for (int r = 0; r < 2; ++r) {
      const double numeric = (xp[r] - xm[r]) / (2 * h);
      const double analytic = of_eo ? d_eo[r * 6 + k] : d_point[r * 3 + k - 6];
      EXPECT_NEAR(analytic, numeric, 1e-5 * std::max(1.0, std::abs(numeric))) << k << r;
    }
  }
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
    const Eigen::Vector3d ray = DrawLastFirst<3>([&](int i) { return i == 2 ? -1.0 : 0.5 * u(rng); });
    const Eigen::Vector3d p = Eigen::Vector3d(eo[0], eo[1], eo[2]) + R.transpose() * (600.0 * ray);
    double point[3] = {p.x(), p.y(), p.z()};
    double xy[2], d_eo[12], d_point[6], d_focal[2];
    ASSERT_TRUE(ProjectWithJacobians(eo, point, 8800.0, xy, d_eo, d_point, d_focal));
    ExpectCentralDifferences(
        [](const double* e, const double* p, double* out) {
          return ProjectToImagePlane(e, p, 8800.0, out);
        },
        eo, point, d_eo, d_point);
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
    const Eigen::Vector2d pixel = DrawLastFirst<2>([&](int i) { return i == 0 ? col(rng) : row(rng); });
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

TEST(Collinearity, EarthCurvatureDropHandComputed) {
  // 1 km east and 1 km north of the centre: D^2 = 2e6 m^2, drop = 2e6 / (2 * 6378137) = 0.1568 m.
  const double center[6] = {1000.0, 2000.0, 800.0, 0.0, 0.0, 0.0};
  const double point[3] = {2000.0, 3000.0, 50.0};
  double lowered[3];
  LowerByEarthCurvature(center, point, 6378137.0, lowered);
  EXPECT_EQ(lowered[0], point[0]);
  EXPECT_EQ(lowered[1], point[1]);
  // 1e-14 m: the subtraction from Z = 50 m rounds at 50 * 2^-52.
  EXPECT_NEAR(point[2] - lowered[2], 2e6 / (2.0 * 6378137.0), 1e-14);
  EXPECT_NEAR(point[2] - lowered[2], 0.15678, 1e-5);
  // The Eigen form is the same rule, bit for bit.
  EXPECT_EQ(EarthCurvatureDrop({1000.0, 2000.0, 800.0}, {2000.0, 3000.0, 50.0}, 6378137.0),
            EarthCurvatureDropOf(center, point, 6378137.0));
}

// The projection with the earth-curvature correction and its chained partials: the value is the
// plain projection of the lowered point; every partial (centre, angles, point) matches central
// differences of that value, with the drop recomputed at each perturbed centre and point. R is
// shrunk to 50 km so that the chain-rule terms are large enough for the differences to resolve.
TEST(Collinearity, EarthCurvaturePartialsMatchCentralDifferences) {
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  constexpr double kRadius = 50000.0;
  constexpr double kFocal = 8800.0;
  auto project = [&](const double* eo, const double* point, double* xy) {
    double lowered[3];
    LowerByEarthCurvature(eo, point, kRadius, lowered);
    return ProjectToImagePlane(eo, lowered, kFocal, xy);
  };
  for (int trial = 0; trial < 200; ++trial) {
    double eo[6] = {50 * u(rng), 50 * u(rng), 800 + 50 * u(rng), 0.6 * u(rng), 0.4 * u(rng), kPi * u(rng)};
    const Eigen::Matrix3d R = RotationFromAngles(RotationConvention::kSeed, {eo[3], eo[4], eo[5]});
    const Eigen::Vector3d ray = DrawLastFirst<3>([&](int i) { return i == 2 ? -1.0 : 0.6 * u(rng); });
    const Eigen::Vector3d p = Eigen::Vector3d(eo[0], eo[1], eo[2]) + R.transpose() * (900.0 * ray);
    const double point[3] = {p.x(), p.y(), p.z()};
    double xy[2], d_eo[12], d_point[6], d_focal[2];
    ASSERT_TRUE(ProjectWithJacobiansEarthCurvature(eo, point, kFocal, kRadius, xy, d_eo, d_point, d_focal));
    double expected[2];
    ASSERT_TRUE(project(eo, point, expected));
    // The same value by another order of rounding (SeedProjector against the template).
    EXPECT_NEAR(xy[0], expected[0], 1e-12 * std::max(1.0, std::abs(expected[0])));
    EXPECT_NEAR(xy[1], expected[1], 1e-12 * std::max(1.0, std::abs(expected[1])));
    ExpectCentralDifferences(project, eo, point, d_eo, d_point);
    EXPECT_NEAR(d_focal[0], xy[0] / kFocal, 1e-12);
    // Only the centre's partials alone (the point's taken internally) give the same d_eo.
    double xy_only[2], d_eo_only[12];
    ASSERT_TRUE(ProjectWithJacobiansEarthCurvature(eo, point, kFocal, kRadius, xy_only, d_eo_only,
                                                   nullptr, nullptr));
    for (int k = 0; k < 12; ++k) EXPECT_EQ(d_eo_only[k], d_eo[k]);
  }
}

TEST(Collinearity, RayAwayFromThePlaneFails) {
  const FrameCamera camera = UavCamera();
  ExteriorOrientation eo;
  eo.set_center_in_ground({0.0, 0.0, 100.0});
  Eigen::Vector3d ground;
  EXPECT_FALSE(IntersectRayWithPlane(camera, eo, {100.0, 100.0}, PixelOrigin::kCorner, 200.0, &ground).ok());
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
