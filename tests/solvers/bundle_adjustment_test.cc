#include "solvers/bundle_adjustment.h"

#include <gtest/gtest.h>

#include <random>

#include "core/collinearity.h"
#include "core/rotation.h"

namespace photopose {
namespace {

// A small nadir block built in memory: rows x cols images of a 24 mm / 4 um / 6000 x 4000 frame
// camera at 100 m, tie points on a jittered grid, control and check points, GNSS centres.
struct SmallBlockOptions {
  int rows = 3;
  int cols = 4;
  double forward_m = 20.0;
  double side_m = 30.0;
  int tie_grid = 12;  // tie points per side of the ground grid
  double noise_px = 0.5;
  double gnss_noise_m = 0.03;
  bool gnss = true;
  std::vector<Eigen::Vector2d> control_xy = {{-10, -10}, {70, -10}, {-10, 70}, {70, 70}};
  double control_z = 1.0;
  double control_noise_m = 0.005;  // surveying error of the control points (their stated accuracy)
  std::vector<Eigen::Vector2d> check_xy = {{30, 30}, {10, 50}};
  double start_position_error_m = 2.0;
  double start_angle_error_deg = 1.0;
  double start_point_error_m = 1.0;
  uint64_t seed = 1;
};

struct SmallBlock {
  Block block;
  std::vector<ExteriorOrientation> true_eo;
  std::vector<Eigen::Vector3d> true_points;
};

SmallBlock MakeSmallBlock(const SmallBlockOptions& o) {
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  SmallBlock out;
  Block& block = out.block;
  BlockCamera camera;
  camera.camera_id = "cam";
  camera.model = CameraModelType::kFrame;
  camera.table.camera_id = "cam";
  camera.table.focal_length_um = 24000.0;
  camera.table.pixel_size_um = 4.0;
  camera.table.n_columns = 6000;
  camera.table.n_rows = 4000;
  camera.table.radial_k = {0.0, -2e-5, 0.0, 0.0};
  const auto params = FrameModelParams(camera.table);
  camera.params.assign(params.begin(), params.end());
  block.cameras.push_back(camera);

  for (int r = 0; r < o.rows; ++r) {
    for (int c = 0; c < o.cols; ++c) {
      ExteriorOrientation eo;
      eo.set_center_in_ground({c * o.forward_m, r * o.side_m, 100.0 + 0.5 * uniform(rng)});
      eo.set_angles_seed_rad({DegreesToRadians(2.0 * uniform(rng)),
                              DegreesToRadians(2.0 * uniform(rng)),
                              DegreesToRadians(3.0 * uniform(rng))});
      out.true_eo.push_back(eo);
      BlockImage image;
      image.name = "img_" + std::to_string(r) + "_" + std::to_string(c);
      image.camera = 0;
      ExteriorOrientation start = eo;
      for (int k = 0; k < 3; ++k) {
        start.parameters[k] += o.start_position_error_m * uniform(rng);
        start.parameters[3 + k] += DegreesToRadians(o.start_angle_error_deg) * uniform(rng);
      }
      image.eo = start;
      if (o.gnss) {
        image.measured_center_m = eo.center_in_ground() +
                                  o.gnss_noise_m * Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng));
        image.center_accuracy_m = Eigen::Vector3d::Constant(o.gnss_noise_m);
      }
      block.images.push_back(image);
    }
  }
  auto add_point = [&](const Eigen::Vector3d& X, PointRole role, const std::string& id) {
    BlockPoint point;
    point.id = id;
    point.role = role;
    if (role == PointRole::kTie) {
      point.position_m = X + o.start_point_error_m * Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng));
    } else {
      // Surveyed with the stated accuracy.
      point.surveyed_m = X + o.control_noise_m * Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng));
      point.accuracy_m = Eigen::Vector3d::Constant(0.005);
    }
    block.points.push_back(point);
    out.true_points.push_back(X);
  };
  const double x_min = -25.0, x_max = (o.cols - 1) * o.forward_m + 25.0;
  const double y_min = -25.0, y_max = (o.rows - 1) * o.side_m + 25.0;
  for (int i = 0; i < o.tie_grid; ++i) {
    for (int j = 0; j < o.tie_grid; ++j) {
      const double x = x_min + (x_max - x_min) * (i + 0.5 + 0.3 * uniform(rng)) / o.tie_grid;
      const double y = y_min + (y_max - y_min) * (j + 0.5 + 0.3 * uniform(rng)) / o.tie_grid;
      add_point({x, y, 5.0 * uniform(rng)}, PointRole::kTie, "T" + std::to_string(i * 100 + j));
    }
  }
  for (size_t k = 0; k < o.control_xy.size(); ++k)
    add_point({o.control_xy[k].x(), o.control_xy[k].y(), o.control_z}, PointRole::kControl,
              "C" + std::to_string(k));
  for (size_t k = 0; k < o.check_xy.size(); ++k)
    add_point({o.check_xy[k].x(), o.check_xy[k].y(), 2.0 * uniform(rng)}, PointRole::kCheck,
              "K" + std::to_string(k));

  const BlockCamera& cam = block.cameras[0];
  for (size_t i = 0; i < block.images.size(); ++i) {
    for (size_t p = 0; p < block.points.size(); ++p) {
      double ab[2];
      if (!ProjectToNormalized(out.true_eo[i].data(), out.true_points[p].data(), ab)) continue;
      Eigen::Vector2d film;
      if (!ObservationFromNormalized(cam.model, cam.params.data(), cam.data(), {ab[0], ab[1]}, &film).ok())
        continue;
      Eigen::Vector2d pixel;
      if (!PixelFromFilm(cam.table, film, PixelOrigin::kCorner, &pixel).ok()) continue;
      if (pixel.x() < 0 || pixel.y() < 0 || pixel.x() > 6000 || pixel.y() > 4000) continue;
      pixel += o.noise_px * Eigen::Vector2d(gauss(rng), gauss(rng));
      BlockMark mark;
      mark.image = static_cast<int>(i);
      mark.point = static_cast<int>(p);
      mark.unit = MarkUnit::kPixel;
      mark.measured = pixel;
      mark.accuracy = o.noise_px > 0.0 ? o.noise_px : 0.5;
      EXPECT_TRUE(FilmFromPixel(cam.table, pixel, PixelOrigin::kCorner, &mark.observation).ok());
      mark.observation_units_per_unit = cam.table.pixel_size_um;
      block.marks.push_back(mark);
    }
  }
  block.BuildIndex();
  return out;
}

BundleAdjustmentOptions QuietOptions() {
  BundleAdjustmentOptions options;
  options.num_threads = 1;
  return options;
}

TEST(BundleAdjustment, NoiseFreeBlockReachesTheTruth) {
  SmallBlockOptions o;
  o.noise_px = 0.0;
  o.gnss_noise_m = 1e-9;
  o.control_noise_m = 0.0;
  SmallBlock data = MakeSmallBlock(o);
  BundleAdjustmentResult result;
  ASSERT_TRUE(BundleAdjust(QuietOptions(), BundleAdjustmentConfig(), &data.block, &result).ok());
  ASSERT_TRUE(result.summary.IsSolutionUsable()) << result.summary.BriefReport();
  for (size_t i = 0; i < data.true_eo.size(); ++i) {
    EXPECT_LT((data.block.images[i].eo->center_in_ground() - data.true_eo[i].center_in_ground()).norm(), 1e-6);
  }
  EXPECT_LT(result.check_rmse_total_m, 1e-6);
}

TEST(BundleAdjustment, NoisyBlockHasSigma0NearOneAndHonestGroups) {
  SmallBlock data = MakeSmallBlock(SmallBlockOptions());
  BundleAdjustmentResult result;
  ASSERT_TRUE(BundleAdjust(QuietOptions(), BundleAdjustmentConfig(), &data.block, &result).ok());
  ASSERT_TRUE(result.summary.IsSolutionUsable()) << result.summary.BriefReport();
  EXPECT_NEAR(result.summary.sigma0, 1.0, 0.15) << result.FullReport(data.block);
  EXPECT_EQ(result.summary.num_rejected_marks, 0);
  // Redundancy shares sum to the redundancy.
  double total = 0.0;
  for (const BundleGroupStatistics& g : result.groups) {
    ASSERT_TRUE(std::isfinite(g.redundancy_share)) << g.name;
    total += g.redundancy_share * g.count * g.num_axes;
  }
  EXPECT_NEAR(total, result.summary.redundancy, 1e-6 * result.summary.redundancy);
  EXPECT_GT(result.num_check_points, 0);
}

TEST(BundleAdjustment, AnalyticAndAutodiffGiveTheSameAdjustment) {
  SmallBlock a = MakeSmallBlock(SmallBlockOptions());
  SmallBlock b = a;
  BundleAdjustmentOptions options = QuietOptions();
  BundleAdjustmentResult ra, rb;
  ASSERT_TRUE(BundleAdjust(options, BundleAdjustmentConfig(), &a.block, &ra).ok());
  options.jacobian = JacobianType::kAutodiff;
  ASSERT_TRUE(BundleAdjust(options, BundleAdjustmentConfig(), &b.block, &rb).ok());
  ASSERT_TRUE(ra.summary.IsSolutionUsable() && rb.summary.IsSolutionUsable());
  for (size_t i = 0; i < a.block.images.size(); ++i)
    EXPECT_LT((a.block.images[i].eo->parameters - b.block.images[i].eo->parameters).norm(), 1e-7);
}

const BundleGroupStatistics* FindGroup(const BundleAdjustmentResult& result,
                                       const std::string& name) {
  for (const BundleGroupStatistics& g : result.groups)
    if (g.name == name) return &g;
  return nullptr;
}

TEST(BundleAdjustment, FewTiePointsFlagTheCameraPositionsAsOverfitted) {
  // The seed note's warning: with a few dozen tie marks the solution bends to the GNSS positions;
  // with a dense tie grid the same positions are checked by the block.
  for (const int grid : {3, 20}) {
    SmallBlockOptions o;
    o.tie_grid = grid;
    o.gnss_noise_m = 0.05;
    SmallBlock data = MakeSmallBlock(o);
    BundleAdjustmentResult result;
    ASSERT_TRUE(BundleAdjust(QuietOptions(), BundleAdjustmentConfig(), &data.block, &result).ok());
    ASSERT_TRUE(result.summary.IsSolutionUsable()) << result.summary.BriefReport();
    const BundleGroupStatistics* cameras = FindGroup(result, "camera_positions");
    ASSERT_NE(cameras, nullptr);
    EXPECT_EQ(cameras->overfit, grid == 3) << result.FullReport(data.block);
    EXPECT_EQ(cameras->message.empty(), grid != 3);
  }
}

TEST(BundleAdjustment, SelfCalibrationRecoversFocalLengthAndRadialDistortion) {
  SmallBlockOptions o;
  o.tie_grid = 20;
  SmallBlock data = MakeSmallBlock(o);
  const double true_focal = data.block.cameras[0].params[kFrameFocal];
  const double true_k1 = data.block.cameras[0].params[kFrameK1];
  data.block.cameras[0].params[kFrameFocal] *= 1.002;
  data.block.cameras[0].params[kFrameK1] = 0.0;
  BundleAdjustmentConfig config;
  ASSERT_TRUE(BundleAdjustmentConfig::FromCalibrationNames(data.block, {"FocalLength", "K1"}, &config).ok());
  BundleAdjustmentResult result;
  ASSERT_TRUE(BundleAdjust(QuietOptions(), config, &data.block, &result).ok());
  ASSERT_TRUE(result.summary.IsSolutionUsable()) << result.summary.BriefReport();
  ASSERT_EQ(result.calibration.size(), 1u);
  const BundleCalibrationResult& c = result.calibration[0];
  ASSERT_EQ(c.names, (std::vector<std::string>{"FocalLength", "K1"}));
  ASSERT_EQ(c.sigmas.size(), 2u);
  // Within four standard deviations of the truth (a 1 in 16000 chance to fail by noise alone).
  EXPECT_LT(std::abs(c.values[0] - true_focal), 4.0 * c.sigmas[0]) << result.FullReport(data.block);
  EXPECT_LT(std::abs(c.values[1] - true_k1), 4.0 * c.sigmas[1]) << result.FullReport(data.block);
  EXPECT_NEAR(c.correlation(0, 0), 1.0, 1e-12);
}

TEST(BundleAdjustment, CameraPositionCovarianceIsHonest) {
  // Mean NEES of the adjusted camera centres against the truth, over seeds: for an honest
  // covariance each is chi-square with 3 degrees of freedom. 10 seeds x 12 images: the mean of
  // 120 has standard deviation sqrt(6 / 120) = 0.22 if independent; images of one block are
  // correlated, so the band is +-0.6 (about 2.7 standard deviations).
  constexpr double kNeesBand = 0.6;
  double sum = 0.0;
  int count = 0;
  for (uint64_t seed = 1; seed <= 10; ++seed) {
    SmallBlockOptions o;
    o.seed = seed;
    SmallBlock data = MakeSmallBlock(o);
    BundleAdjustmentResult result;
    ASSERT_TRUE(BundleAdjust(QuietOptions(), BundleAdjustmentConfig(), &data.block, &result).ok());
    ASSERT_TRUE(result.summary.IsSolutionUsable());
    for (size_t i = 0; i < data.true_eo.size(); ++i) {
      ASSERT_TRUE(result.images[i].has_covariance);
      const Eigen::Vector3d e =
          data.block.images[i].eo->center_in_ground() - data.true_eo[i].center_in_ground();
      const Eigen::Matrix3d C = result.images[i].covariance.topLeftCorner<3, 3>();
      sum += e.dot(C.ldlt().solve(e));
      ++count;
    }
  }
  EXPECT_NEAR(sum / count, 3.0, kNeesBand);
}

TEST(BundleAdjustment, RelativeBlockUsesColmapsGauge) {
  SmallBlockOptions o;
  o.gnss = false;
  o.control_xy.clear();
  o.check_xy.clear();
  SmallBlock data = MakeSmallBlock(o);
  BundleAdjustmentResult result;
  ASSERT_TRUE(BundleAdjust(QuietOptions(), BundleAdjustmentConfig(), &data.block, &result).ok());
  ASSERT_TRUE(result.summary.IsSolutionUsable()) << result.summary.BriefReport();
  EXPECT_EQ(result.summary.datum, BundleDatum::kRelative);
  EXPECT_NEAR(result.summary.sigma0, 1.0, 0.2);
}

TEST(BundleAdjustment, RefusesBlocksItCannotAdjust) {
  {
    SmallBlockOptions o;
    o.gnss = false;
    o.control_xy = {{0, 0}, {30, 30}, {60, 60}};  // on one line (and at one height)
    SmallBlock data = MakeSmallBlock(o);
    BundleAdjustmentResult result;
    const Status status = BundleAdjust(QuietOptions(), BundleAdjustmentConfig(), &data.block, &result);
    ASSERT_FALSE(status.ok());
    EXPECT_NE(status.message().find("no datum"), std::string::npos) << status.message();
  }
  {
    SmallBlock data = MakeSmallBlock(SmallBlockOptions());
    data.block.images[0].eo.reset();
    BundleAdjustmentResult result;
    EXPECT_FALSE(BundleAdjust(QuietOptions(), BundleAdjustmentConfig(), &data.block, &result).ok());
  }
}

}  // namespace
}  // namespace photopose
