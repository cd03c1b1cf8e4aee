#include "tests/support/dbat_data.h"

#include <gtest/gtest.h>

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "core/collinearity.h"
#include "core/rotation.h"
#include "tests/test_data.h"
#include "tests/support/ordered_draws.h"

namespace photopose::testing {
namespace PHOTOPOSE_UNITY_ID {

// Closed forms in double precision (film coordinates of O(1e4) um).
constexpr double kExactUm = 1e-8;
// The report prints sigma0 with four decimals and "Last error" (the norm of the weighted residual
// vector) with five digits; the published IO and EO have 16 digits, so a reproduction without
// any adjustment must land within that rounding.
constexpr double kSigma0Rounding = 0.5e-4;
constexpr double kLastErrorRounding = 0.5e-3;
// Pixel figures of the report are printed to 1e-3 px.
constexpr double kReportPxRounding = 0.5e-3 + 1e-9;
// Angles of the report are printed to 1e-6 deg.
constexpr double kReportAngleRoundingDeg = 0.5e-6 + 1e-12;
// The report's DBAT figures for c4040z (result_report.txt), beyond what ReadDbatReport parses.
constexpr double kPublishedLastError = 98.556;

DbatDataset Files() { return DbatDataset::C4040z(); }
std::string Published(const std::string& name) {
  return SharedDataPath("dbat_c4040z/" + name);
}

// DBAT's model-3 residual written in DBAT's own terms (mm), as docs/dbat.md states it from
// DBAT's code: independent of the conversion under test.
Eigen::Vector2d DbatResidualMm(const DbatCamera& c, const DbatStation& station,
                               const Eigen::Vector3d& X, const Eigen::Vector2d& xy_px) {
  const Eigen::Matrix3d M = RotationX(station.angles_rad[0]) * RotationY(station.angles_rad[1]) *
                            RotationZ(station.angles_rad[2]);
  const Eigen::Vector3d Q = M.transpose() * (X - station.center_m);
  const Eigen::Vector2d projected = -c.cc_mm * Eigen::Vector2d(Q.x() / Q.z(), Q.y() / Q.z());
  const double ps = c.pixel_mm(), as = c.as();
  const Eigen::Vector2d d((1.0 + as) * (ps * xy_px.x() - c.pp_mm.x()), -(ps * xy_px.y() - c.pp_mm.y()));
  const double r2 = d.squaredNorm();
  const double radial = c.K[0] * r2 + c.K[1] * r2 * r2 + c.K[2] * r2 * r2 * r2;
  const Eigen::Vector2d tangential(c.P[0] * (r2 + 2 * d.x() * d.x()) + 2 * c.P[1] * d.x() * d.y(),
                                   2 * c.P[0] * d.x() * d.y() + c.P[1] * (r2 + 2 * d.y() * d.y()));
  const Eigen::Vector2d corrected = d + d * radial + tangential;
  return projected - corrected;
}

// The residual of core/camera_models.h (um) for a film observation.
Eigen::Vector2d PhotoposeResidualUm(const BlockCamera& camera, const ExteriorOrientation& eo,
                                    const Eigen::Vector3d& X, const Eigen::Vector2d& film_um) {
  double ab[2], r[2];
  EXPECT_TRUE(ProjectToNormalized(eo.data(), X.data(), ab));
  CameraModelResidual(camera.model, camera.params.data(), ab, film_um.data(), camera.data(), r);
  return {r[0], r[1]};
}

TEST(DbatData, ReadsTheC4040zProject) {
  DbatCamera camera;
  ASSERT_TRUE(ReadDbatCameraXml(Files().camera_xml, &camera).ok());
  EXPECT_EQ(camera.model, 3);
  EXPECT_EQ(camera.sensor_width_mm, 0.0);  // "auto"
  EXPECT_EQ(camera.sensor_height_mm, 5.43764);
  EXPECT_EQ(camera.image_width_px, 2272);
  EXPECT_EQ(camera.focal_mm, 7.5);
  Block block;
  const Status status = ReadDbatBlock(Files(), DbatDefaultCamera(camera), &block);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_TRUE(CheckBlock(block).ok());
  EXPECT_EQ(block.images.size(), 21u);
  EXPECT_EQ(block.images[0].name, "P8250021.JPG");
  EXPECT_EQ(block.points.size(), 100u);  // 4 control + 96 object points
  EXPECT_EQ(block.marks.size(), 2074u);  // the report's 4148 image observations
  int control = 0;
  for (const BlockPoint& p : block.points) control += p.role == PointRole::kControl;
  EXPECT_EQ(control, 4);
  EXPECT_EQ(*block.points[0].surveyed_m, Eigen::Vector3d(0, 1, 0));
  EXPECT_FALSE(block.points[0].accuracy_m.has_value());  // fixed
  EXPECT_EQ(block.marks[0].accuracy, 0.1);
  // DBAT's default camera: c = 7.5 mm, principal point at the sensor centre = film (0, 0).
  const std::vector<double>& p = block.cameras[0].params;
  EXPECT_EQ(p[kFrameFocal], 7500.0);
  EXPECT_NEAR(p[kFramePrincipalX], 0.0, kExactUm);
  EXPECT_NEAR(p[kFramePrincipalY], 0.0, kExactUm);
  EXPECT_NEAR(block.cameras[0].table.pixel_size_um, 5437.64 / 1704.0, 1e-12);
}

TEST(DbatData, WeightedControlKeepsItsAccuracy) {
  DbatDataset files = Files();
  files.control = Published("reference_camcal-weighted.txt");
  DbatCamera camera;
  ASSERT_TRUE(ReadDbatCameraXml(files.camera_xml, &camera).ok());
  Block block;
  ASSERT_TRUE(ReadDbatBlock(files, DbatDefaultCamera(camera), &block).ok());
  EXPECT_EQ(*block.points[3].accuracy_m, Eigen::Vector3d::Constant(0.001));
}

TEST(DbatData, ConversionRoundTripsAndMatchesDbatsResidual) {
  DbatCamera dbat;
  ASSERT_TRUE(ReadDbatCameraXml(Published("result_c4040z.xml"), &dbat).ok());
  EXPECT_NEAR(dbat.cc_mm, 7.45699532273933752, 1e-15);
  BlockCamera camera;
  ASSERT_TRUE(BlockCameraFromDbat(dbat, &camera).ok());
  // The inverse gives DBAT's numbers back.
  DbatCamera back;
  ASSERT_TRUE(DbatFromBlockCamera(camera, dbat, &back).ok());
  EXPECT_NEAR(back.cc_mm, dbat.cc_mm, 1e-15);
  EXPECT_NEAR((back.pp_mm - dbat.pp_mm).norm(), 0.0, 1e-14);
  EXPECT_NEAR(back.aspect, dbat.aspect, 1e-16);
  EXPECT_EQ(back.K, dbat.K);
  EXPECT_EQ(back.P, dbat.P);
  // For random marks and points the two residuals are one vector: photopose's (um) is -1000
  // times DBAT's (mm).
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  DbatStation station;
  station.center_m = {0.4, 0.8, 1.9};
  station.angles_rad = {-0.15, 0.02, 3.1};
  const ExteriorOrientation eo = EoFromDbat(station.center_m, station.angles_rad);
  for (int k = 0; k < 50; ++k) {
    const Eigen::Vector2d xy = DrawLastFirst<2>([&](int i) { return i == 0 ? 1136 + 1100 * unit(rng) : 852 + 820 * unit(rng); });
    const Eigen::Vector3d X = DrawLastFirst<3>([&](int i) { return i == 2 ? 0.05 * unit(rng) : 0.5 + 0.5 * unit(rng); });
    Eigen::Vector2d film;
    ASSERT_TRUE(FilmFromPixel(camera.table, xy, PixelOrigin::kCorner, &film).ok());
    const Eigen::Vector2d mine = PhotoposeResidualUm(camera, eo, X, film);
    const Eigen::Vector2d theirs = DbatResidualMm(dbat, station, X, xy);
    EXPECT_NEAR(mine.x(), -1000.0 * theirs.x(), kExactUm);
    EXPECT_NEAR(mine.y(), -1000.0 * theirs.y(), kExactUm);
  }
}

TEST(DbatData, ReportAgreesWithTheCalibratedCameraXml) {
  DbatReport report;
  ASSERT_TRUE(ReadDbatReport(Published("result_report.txt"), &report).ok());
  EXPECT_EQ(report.redundancy, 3725);
  EXPECT_EQ(report.num_observations, 4148);
  DbatCamera dbat;
  ASSERT_TRUE(ReadDbatCameraXml(Published("result_c4040z.xml"), &dbat).ok());
  const std::map<std::string, double> xml = {
      {"cc", dbat.cc_mm}, {"px", dbat.pp_mm.x()}, {"py", dbat.pp_mm.y()}, {"K1", dbat.K[0]},
      {"K2", dbat.K[1]},  {"K3", dbat.K[2]},      {"P1", dbat.P[0]},      {"P2", dbat.P[1]},
      {"as", dbat.as()}};
  ASSERT_EQ(report.camera.size(), xml.size());
  for (const auto& [name, value_sigma] : report.camera) {
    // The report prints six significant digits.
    EXPECT_NEAR(value_sigma.x(), xml.at(name), 5e-6 * std::abs(xml.at(name))) << name;
    EXPECT_GT(value_sigma.y(), 0.0) << name;
  }
  // Photo 1: "Xc ... Deviation: 0.000155 ou", "Kappa ... Deviation: 0.00275 deg".
  EXPECT_EQ(report.photos[0].name, "P8250021.JPG");
  EXPECT_EQ(report.photos[0].center_sigma_m.x(), 0.000155);
  EXPECT_EQ(report.photos[0].angle_sigma_deg.z(), 0.00275);
}

TEST(DbatData, SkewAndOtherModelsAreRefused) {
  DbatCamera dbat;
  ASSERT_TRUE(ReadDbatCameraXml(Published("result_c4040z.xml"), &dbat).ok());
  BlockCamera camera;
  dbat.skew = 1e-4;
  EXPECT_FALSE(BlockCameraFromDbat(dbat, &camera).ok());
  dbat.skew = 0.0;
  dbat.model = 1;
  EXPECT_FALSE(BlockCameraFromDbat(dbat, &camera).ok());
}

// One point's marks for the triangulation: the residual of core/camera_models.h over the mark's
// accuracy, with the orientation and camera fixed.
struct RayResidual {
  RayResidual(const BlockCamera& camera, const ExteriorOrientation& eo, const BlockMark& mark)
      : camera(camera), eo(eo), mark(mark) {}
  template <typename T>
  bool operator()(const T* X, T* residual) const {
    T eo_t[6], params[kFrameNumParams], ab[2];
    for (int k = 0; k < 6; ++k) eo_t[k] = T(eo.parameters[k]);
    for (int k = 0; k < kFrameNumParams; ++k) params[k] = T(camera.params[k]);
    if (!ProjectToNormalized(eo_t, X, ab)) return false;
    CameraModelResidual(camera.model, params, ab, mark.observation.data(), camera.data(), residual);
    const double sigma_um = *mark.accuracy * mark.observation_units_per_unit;
    residual[0] /= sigma_um;
    residual[1] /= sigma_um;
    return true;
  }
  const BlockCamera& camera;
  const ExteriorOrientation& eo;
  const BlockMark& mark;
};

TEST(DbatData, PublishedAdjustmentReproducedWithoutAdjusting) {
  // DBAT's published IO and EO, converted; every object point triangulated from the published
  // stations (multi-ray least squares, kFrame model); the control points at their fixed
  // coordinates. The residuals must be DBAT's: its sigma0, its last error, its per-point and
  // per-photo figures.
  DbatCamera dbat;
  ASSERT_TRUE(ReadDbatCameraXml(Published("result_c4040z.xml"), &dbat).ok());
  Block block;
  ASSERT_TRUE(ReadDbatBlock(Files(), dbat, &block).ok());
  std::vector<DbatStation> stations;
  ASSERT_TRUE(ReadDbatCameraStations(Published("result_camera_stations.txt"), &stations).ok());
  ASSERT_EQ(stations.size(), block.images.size());
  DbatReport report;
  ASSERT_TRUE(ReadDbatReport(Published("result_report.txt"), &report).ok());
  ASSERT_EQ(report.photos.size(), stations.size());
  for (size_t i = 0; i < stations.size(); ++i) {
    ASSERT_EQ(stations[i].label, block.images[i].name);
    block.images[i].eo = EoFromDbat(stations[i].center_m, stations[i].angles_rad);
    // The stations file's angles are radians (its header says degrees): the report's degrees.
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(RadiansToDegrees(stations[i].angles_rad[k]), report.photos[i].angles_deg[k],
                  kReportAngleRoundingDeg);
    }
  }
  const BlockCamera& camera = block.cameras[0];

  // Triangulation: linear intersection of the rays, then Gauss-Newton (Ceres) on the residuals.
  for (size_t p = 0; p < block.points.size(); ++p) {
    BlockPoint& point = block.points[p];
    if (point.role == PointRole::kControl) continue;
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    for (const int m : block.marks_of_point[p]) {
      const ExteriorOrientation& eo = *block.images[block.marks[m].image].eo;
      Eigen::Vector2d ab;
      ASSERT_TRUE(NormalizedFromObservation(camera.model, camera.params.data(), camera.data(),
                                            block.marks[m].observation, &ab)
                      .ok());
      const Eigen::Vector3d direction =
          (RotationFromAngles(RotationConvention::kSeed, eo.angles_seed_rad()).transpose() *
           Eigen::Vector3d(ab.x(), ab.y(), -1.0))
              .normalized();
      const Eigen::Matrix3d across = Eigen::Matrix3d::Identity() - direction * direction.transpose();
      A += across;
      b += across * eo.center_in_ground();
    }
    Eigen::Vector3d X = A.ldlt().solve(b);
    ceres::Problem problem;
    for (const int m : block.marks_of_point[p]) {
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<RayResidual, 2, 3>(
              new RayResidual(camera, *block.images[block.marks[m].image].eo, block.marks[m])),
          nullptr, X.data());
    }
    ceres::Solver::Options options;
    options.function_tolerance = 1e-14;
    options.gradient_tolerance = 1e-14;
    options.parameter_tolerance = 1e-14;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
    ASSERT_TRUE(summary.IsSolutionUsable()) << point.id;
    point.position_m = X;
  }

  // The residuals, weighted by the marks' sxy, and DBAT's statistics of them.
  const double pixel_um = camera.table.pixel_size_um;
  double ssr = 0.0, ssr_px = 0.0;
  std::map<std::string, std::pair<double, int>> per_point;  // sum of squared px, count
  std::vector<std::pair<double, int>> per_photo(block.images.size(), {0.0, 0});
  double worst_px = 0.0;
  std::string worst_where;
  for (const BlockMark& mark : block.marks) {
    const Eigen::Vector2d r = PhotoposeResidualUm(camera, *block.images[mark.image].eo,
                                                  *block.points[mark.point].position_m,
                                                  mark.observation);
    ssr += r.squaredNorm() / std::pow(*mark.accuracy * pixel_um, 2);
    const double px2 = r.squaredNorm() / (pixel_um * pixel_um);
    ssr_px += px2;
    per_point[block.points[mark.point].id].first += px2;
    ++per_point[block.points[mark.point].id].second;
    per_photo[mark.image].first += px2;
    ++per_photo[mark.image].second;
    if (std::sqrt(px2) > worst_px) {
      worst_px = std::sqrt(px2);
      worst_where = block.points[mark.point].id + " on photo " + std::to_string(mark.image + 1);
    }
  }
  const double sigma0 = std::sqrt(ssr / report.redundancy);
  const int object_unknowns = 3 * static_cast<int>(block.points.size() - 4);
  const int redundancy_points_only = 2 * static_cast<int>(block.marks.size()) - object_unknowns;
  std::printf(
      "DBAT c4040z reproduced without adjustment: sigma0 %.5f (DBAT %.4f, redundancy %d; with the "
      "IO and EO held fixed, redundancy %d: %.5f); weighted residual norm %.4f (DBAT's last error "
      "%.3f); RMS of the mark residuals %.4f px (DBAT %.3f); largest %.4f px (%s)\n",
      sigma0, report.sigma0, report.redundancy, redundancy_points_only,
      std::sqrt(ssr / redundancy_points_only), std::sqrt(ssr), kPublishedLastError,
      std::sqrt(ssr_px / block.marks.size()), report.overall_rms_px, worst_px,
      worst_where.c_str());
  EXPECT_EQ(report.num_observations, 2 * static_cast<int>(block.marks.size()));
  EXPECT_NEAR(sigma0, report.sigma0, kSigma0Rounding);
  EXPECT_NEAR(report.sigma0_px, report.sigma0 * 0.1, 1e-12);  // sxy = 0.1 px
  EXPECT_NEAR(std::sqrt(ssr), kPublishedLastError, kLastErrorRounding);
  EXPECT_NEAR(std::sqrt(ssr_px / block.marks.size()), report.overall_rms_px, kReportPxRounding);
  // "Mark point residuals: Maximum: 0.955 pixels (OP 1003 on photo 5)".
  EXPECT_NEAR(worst_px, 0.955, kReportPxRounding);
  EXPECT_EQ(worst_where, "1003 on photo 5");
  // "Object point residuals: Minimum: 0.095 pixels (OP 65 over 21 images), Maximum: 0.553
  // pixels (OP 1004 over 21 images)": the control points reproject as DBAT reports them.
  const auto rms = [](const std::pair<double, int>& s) { return std::sqrt(s.first / s.second); };
  EXPECT_NEAR(rms(per_point["65"]), 0.095, kReportPxRounding);
  EXPECT_NEAR(rms(per_point["1004"]), 0.553, kReportPxRounding);
  for (const auto& [id, sum] : per_point) {
    EXPECT_GE(rms(sum), 0.095 - kReportPxRounding) << id;
    EXPECT_LE(rms(sum), 0.553 + kReportPxRounding) << id;
  }
  for (const char* id : {"1001", "1002", "1003"})
    std::printf("  control point %s: RMS %.4f px over %d images\n", id, rms(per_point[id]),
                per_point[id].second);
  // "Photo residuals: Minimum: 0.153 pixels (photo 4 over 97 points), Maximum: 0.281 pixels
  // (photo 11 over 100 points)".
  EXPECT_NEAR(rms(per_photo[3]), 0.153, kReportPxRounding);
  EXPECT_EQ(per_photo[3].second, 97);
  EXPECT_NEAR(rms(per_photo[10]), 0.281, kReportPxRounding);
  EXPECT_EQ(per_photo[10].second, 100);
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose::testing
