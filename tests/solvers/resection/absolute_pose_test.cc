#include "core/io/block_tables.h"
#include "solvers/resection/absolute_pose.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "core/camera.h"
#include "core/collinearity.h"
#include "core/rotation.h"
#include "core/simulation/synthetic_scene.h"
#include "core/types.h"
#include "solvers/resection/resection.h"
#include "tests/support/ordered_draws.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// ------------------------------------------------------------------ tolerances
// The pose from noisy data is checked against the truth per parameter in units of its predicted
// standard deviation: sigma_k = sqrt((J^T J)^-1_kk) * noise, J the collinearity partials of the
// true inliers at the true pose. A least-squares estimate is within 5 sigma per parameter with
// probability 1 - 6e-7; the RANSAC pose (least squares on its own inlier set) adds well under a
// sigma. For the scenes below sigma is ~1-3 cm and ~1-5 arcsec: the nadir geometry correlates the
// horizontal position with the tilts, so neither is known better than that from 0.5 px marks.
constexpr double kSigmas = 5.0;
// Fraction of correspondences whose inlier flag must equal the truth (the brief's 99 %). Outliers
// are >= 20 px off, far beyond the threshold; only inliers beyond ~3.5 sigma can be misclassified.
constexpr double kMinMaskAgreement = 0.99;
// Inlier threshold for 0.5 px (3 um) noise: 4 sigma of a 2-D residual norm keeps 99.97 % of
// inliers.
constexpr double kThresholdUm = 12.0;
// Noise-free data: the solution is exact to rounding; 1e-9 (relative to the flying height for the
// centre, rad for the angles) leaves orders of margin.
constexpr double kNoiseFreeTolerance = 1e-9;
// Normal equations from the folded closed form against those built from ProjectWithJacobians:
// the same formulas evaluated in a different order, so rounding only.
constexpr double kSameFormulaRelativeTolerance = 1e-12;

struct Correspondences {
  std::vector<Eigen::Vector2d> image_plane_um;
  std::vector<Eigen::Vector3d> points_in_ground;
  std::vector<char> is_outlier;
  ExteriorOrientation truth;
  double focal_um = 0.0;
  double noise_um = 0.0;  // one sigma per image coordinate
};

// 500 correspondences of one frame of the shared synthetic scene generator: 0.5 px noise and gross
// errors of 20-200 px on the given fraction of the marks.
Correspondences FromSyntheticScene(Scenario scenario, double outlier_fraction, uint64_t seed) {
  SyntheticSceneOptions options;
  options.scenario = scenario;
  options.seed = seed;
  options.noise_px = 0.5;
  options.outlier_fraction = outlier_fraction;
  options.outlier_min_px = 20.0;
  options.outlier_max_px = 200.0;
  options.num_control_points = 500;
  options.num_check_points = 0;
  SyntheticScene scene;
  const Status status = MakeSyntheticScene(options, &scene);
  EXPECT_TRUE(status.ok()) << status.message();
  Correspondences c;
  if (!status.ok()) return c;
  // The library's one assembly: the scene's tables into a block, its image into a resection input.
  Block block;
  ResectionInput input;
  std::vector<int> marks;
  const Status assembled = AssembleBlock(SceneBlockTables(scene), &block);
  EXPECT_TRUE(assembled.ok()) << assembled.message();
  EXPECT_TRUE(MakeResectionInput(block, 0, ResectionInputOptions(), &input, &marks).ok());
  c.image_plane_um = input.image_plane;
  c.points_in_ground = input.points_in_ground;
  for (const int m : marks) c.is_outlier.push_back(scene.mark_is_outlier[m] ? 1 : 0);
  const FrameCamera& camera = scene.cameras.front();
  c.truth = scene.true_frames.front().eo;
  c.focal_um = camera.focal_length_um;
  c.noise_um = options.noise_px * camera.pixel_size_um;
  return c;
}

// A frame at 800 m over +-15 m terrain with the UltraCam-like 100.5 mm lens and n points, exact
// image coordinates (plus Gaussian noise of noise_um).
Correspondences SimpleScene(uint64_t seed, int n, const Eigen::Vector3d& angles, double noise_um) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::normal_distribution<double> gaussian(0.0, 1.0);
  Correspondences c;
  c.focal_um = 100500.0;
  c.noise_um = noise_um;
  c.truth.set_center_in_ground(Eigen::Vector3d(5000.0, 6000.0, 850.0));
  c.truth.set_angles_seed_rad(angles);
  const Eigen::Matrix3d R = RotationFromAngles(RotationConvention::kSeed, angles);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d ray =
        R.transpose() * DrawLastFirst<3>([&](int i) { return i == 2 ? -c.focal_um : (i == 0 ? 45000.0 : 30000.0) * unit(rng); });
    const double height = 50.0 + 15.0 * unit(rng);
    const Eigen::Vector3d X =
        c.truth.center_in_ground() + (height - c.truth.center_in_ground().z()) / ray.z() * ray;
    double xy[2];
    EXPECT_TRUE(ProjectToImagePlane(c.truth.data(), X.data(), c.focal_um, xy));
    c.points_in_ground.push_back(X);
    const Eigen::Vector2d noise = noise_um * DrawLastFirst<2>([&](int) { return gaussian(rng); });
    c.image_plane_um.emplace_back(xy[0] + noise[0], xy[1] + noise[1]);
    c.is_outlier.push_back(0);
  }
  return c;
}

// Predicted standard deviations of (X0, Y0, Z0, omega, phi, kappa) of the least-squares pose from
// the true inliers.
Vector6d PredictedSigmas(const Correspondences& c) {
  Matrix6d normal = Matrix6d::Zero();
  for (size_t i = 0; i < c.points_in_ground.size(); ++i) {
    if (c.is_outlier[i]) continue;
    double xy[2];
    Eigen::Matrix<double, 2, 6, Eigen::RowMajor> J;
    if (!ProjectWithJacobians(c.truth.data(), c.points_in_ground[i].data(), c.focal_um, xy,
                              J.data(), nullptr, nullptr))
      continue;
    normal += J.transpose() * J;
  }
  return (normal.inverse().diagonal().cwiseSqrt() * c.noise_um).eval();
}

Vector6d PoseError(const ExteriorOrientation& estimate, const ExteriorOrientation& truth) {
  Vector6d error = estimate.parameters - truth.parameters;
  for (int k = 3; k < 6; ++k) error[k] = WrapAngle(error[k]);
  return error;
}

double MaskAgreement(const std::vector<char>& mask, const std::vector<char>& is_outlier) {
  int agree = 0;
  for (size_t i = 0; i < mask.size(); ++i) agree += (mask[i] != 0) == (is_outlier[i] == 0);
  return static_cast<double>(agree) / static_cast<double>(mask.size());
}

AbsolutePoseRansacOptions Options(uint64_t seed) {
  AbsolutePoseRansacOptions options;
  options.ransac.seed = seed;
  options.inlier_threshold = kThresholdUm;
  return options;
}

// ------------------------------------------------------------------ the estimator

TEST(AbsolutePoseEstimatorTest, NormalEquationsMatchProjectWithJacobians) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const double zero_eo[6] = {0, 0, 0, 0, 0, 0};
  for (double focal : {8800.0, 100500.0}) {
    for (int k = 0; k < 200; ++k) {
      // Wide-angle and oblique rays (up to 45 deg off axis), depths 50-1500 m.
      const double depth = 775.0 + 725.0 * unit(rng);
      const Eigen::Vector3d point = DrawLastFirst<3>([&](int i) { return i == 2 ? -depth : depth * unit(rng); });
      const double observed[2] = {focal * 0.4 * unit(rng), focal * 0.4 * unit(rng)};
      double xy[2];
      Eigen::Matrix<double, 2, 6, Eigen::RowMajor> J;
      ASSERT_TRUE(
          ProjectWithJacobians(zero_eo, point.data(), focal, xy, J.data(), nullptr, nullptr));
      const Eigen::Matrix<double, 2, 6> Jn = J / focal;
      const Eigen::Vector2d rn =
          (Eigen::Vector2d(observed[0], observed[1]) - Eigen::Vector2d(xy[0], xy[1])) / focal;
      const Matrix6d expected_normal = Jn.transpose() * Jn;
      const Vector6d expected_gradient = Jn.transpose() * rn;

      double normal[21] = {};
      double gradient[6] = {};
      ASSERT_TRUE(internal::AddGaussNewtonTerms(point, observed[0] / focal, observed[1] / focal,
                                                normal, gradient));
      const double scale = expected_normal.cwiseAbs().maxCoeff();
      for (int r = 0, i = 0; r < 6; ++r)
        for (int col = r; col < 6; ++col, ++i)
          EXPECT_NEAR(normal[i], expected_normal(r, col), kSameFormulaRelativeTolerance * scale)
              << "(" << r << ", " << col << ")";
      const double gradient_scale = expected_gradient.cwiseAbs().maxCoeff();
      for (int r = 0; r < 6; ++r)
        EXPECT_NEAR(gradient[r], expected_gradient[r],
                    kSameFormulaRelativeTolerance * gradient_scale)
            << r;
    }
  }
  // A point behind the camera contributes nothing.
  double normal[21] = {};
  double gradient[6] = {};
  EXPECT_FALSE(internal::AddGaussNewtonTerms(Eigen::Vector3d(1, 2, 3), 0, 0, normal, gradient));
  for (double v : normal) EXPECT_EQ(v, 0.0);
}

TEST(AbsolutePoseEstimatorTest, ScoresInliersAndEarlyExit) {
  const Correspondences c =
      SimpleScene(2, 200, Eigen::Vector3d(0.02, -0.01, 0.5), /*noise_um=*/0.0);
  const AbsolutePoseEstimator estimator(c.image_plane_um, c.points_in_ground, c.focal_um,
                                        kThresholdUm);
  ASSERT_EQ(estimator.num_data(), 200);
  PoseCandidate truth;
  truth.R_camera_from_ground =
      RotationFromAngles(RotationConvention::kSeed, c.truth.angles_seed_rad());
  truth.center_in_ground = c.truth.center_in_ground();
  // Exact data: zero cost (rounding of um-sized residuals only), every point an inlier.
  EXPECT_LT(estimator.ScoreModel(truth, std::numeric_limits<double>::infinity()), 1e-12);
  std::vector<char> mask;
  EXPECT_EQ(estimator.Inliers(truth, &mask), 200);
  // The camera turned upside down sees every point behind it: all capped at threshold^2.
  PoseCandidate flipped = truth;
  flipped.R_camera_from_ground = RotationX(kPi) * truth.R_camera_from_ground;
  EXPECT_NEAR(estimator.ScoreModel(flipped, std::numeric_limits<double>::infinity()),
              200 * kThresholdUm * kThresholdUm, 1e-6);
  EXPECT_EQ(estimator.Inliers(flipped, &mask), 0);
  // A model that cannot beat the best returns at least the best.
  EXPECT_GE(estimator.ScoreModel(flipped, 10.0), 10.0);
  PoseCandidate shifted = truth;
  shifted.center_in_ground.x() += 50.0;
  EXPECT_GE(estimator.ScoreModel(shifted, 1.0), 1.0);
  // The bearings are unit vectors along (x, y, -c).
  const Eigen::Vector3d b = estimator.bearing(7);
  EXPECT_NEAR(b.norm(), 1.0, 1e-15);
  EXPECT_NEAR(b.x() / -b.z() * c.focal_um, c.image_plane_um[7].x(), 1e-9);
}

TEST(AbsolutePoseEstimatorTest, MemosGiveWhatAFreshEstimatorGives) {
  // ScoreModel keeps its sequential test's logarithms for the last best score, RefineModel its DLT
  // start for the last inlier set. Interleaving scores and sets on one estimator must give, bit
  // for bit, what a fresh estimator gives for each call alone.
  const Correspondences c = SimpleScene(5, 40, Eigen::Vector3d(0.02, -0.01, 0.5), 3.0);
  const auto fresh = [&c]() {
    return AbsolutePoseEstimator(c.image_plane_um, c.points_in_ground, c.focal_um, kThresholdUm);
  };
  const AbsolutePoseEstimator reused = fresh();
  PoseCandidate start;
  start.R_camera_from_ground =
      RotationX(0.02) * RotationFromAngles(RotationConvention::kSeed, c.truth.angles_seed_rad());
  // Far enough that two Gauss-Newton iterations from here do not converge: the DLT start wins, so
  // a DLT of the wrong set would show.
  start.center_in_ground = c.truth.center_in_ground() + Eigen::Vector3d(20.0, -15.0, 10.0);
  std::vector<int> first, second;
  for (int i = 0; i < 40; ++i) (i % 3 == 0 ? second : first).push_back(i);
  for (const std::vector<int>* set : {&first, &second, &first, &first, &second}) {
    PoseCandidate a = start, b = start;
    reused.RefineModel(*set, &a);
    fresh().RefineModel(*set, &b);
    EXPECT_EQ(a.R_camera_from_ground, b.R_camera_from_ground);
    EXPECT_EQ(a.center_in_ground, b.center_in_ground);
    EXPECT_NE(a.center_in_ground, start.center_in_ground);  // it did refine
  }
  // Best scores that switch the sequential test on and off (infinity: off), repeated.
  const double inf = std::numeric_limits<double>::infinity();
  const double exact = fresh().ScoreModel(start, inf);
  for (const double best : {inf, 0.5 * exact, inf, 2.0 * exact, 0.5 * exact, 0.5 * exact}) {
    const double a = reused.ScoreModel(start, best);
    const double b = fresh().ScoreModel(start, best);
    EXPECT_EQ(a, b) << best;
  }
}

TEST(AbsolutePoseEstimatorTest, GaussNewtonConvergesEvenAtGimbalLock) {
  // phi = 90 deg is the seed angles' singularity; the refinement works on a local rotation
  // increment and must not care.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const double focal = 100500.0;
  const Eigen::Vector3d center(5000.0, 6000.0, 850.0);
  for (const Eigen::Vector3d& angles :
       {Eigen::Vector3d(0.03, -0.02, 1.0), Eigen::Vector3d(0.3, kPi / 2, -0.4)}) {
    // Points in front of the camera whatever its attitude: along rays of the format at 400-1200 m.
    const Eigen::Matrix3d R_true = RotationFromAngles(RotationConvention::kSeed, angles);
    std::vector<Eigen::Vector2d> image;
    std::vector<Eigen::Vector3d> ground;
    for (int i = 0; i < 60; ++i) {
      const Eigen::Vector2d xy = DrawLastFirst<2>([&](int i) { return (i == 0 ? 45000.0 : 30000.0) * unit(rng); });
      const double depth = 800.0 + 400.0 * unit(rng);
      ground.push_back(center + R_true.transpose() *
                                    (depth * Eigen::Vector3d(xy.x(), xy.y(), -focal).normalized()));
      image.push_back(xy);
    }
    const AbsolutePoseEstimator estimator(image, ground, focal, kThresholdUm);
    std::vector<int> all(60);
    for (int i = 0; i < 60; ++i) all[i] = i;
    PoseCandidate pose;
    pose.R_camera_from_ground = RotationX(0.002) * RotationZ(-0.003) * R_true;
    pose.center_in_ground = center + Eigen::Vector3d(2.0, -1.5, 1.0);
    estimator.Polish(all, 10, &pose);
    EXPECT_LT((pose.R_camera_from_ground - R_true).norm(), kNoiseFreeTolerance);
    EXPECT_LT((pose.center_in_ground - center).norm() / 800.0, kNoiseFreeTolerance);
  }
}

// ------------------------------------------------------------------ robust resection

class AbsolutePoseRansacTest : public ::testing::TestWithParam<std::tuple<Scenario, double>> {};

TEST_P(AbsolutePoseRansacTest, RecoversPoseAndOutliers) {
  const Scenario scenario = std::get<0>(GetParam());
  const double outlier_fraction = std::get<1>(GetParam());
  const Correspondences c = FromSyntheticScene(scenario, outlier_fraction, /*seed=*/11);
  ASSERT_EQ(c.points_in_ground.size(), 500u);
  ExteriorOrientation eo;
  std::vector<char> mask;
  RansacSummary summary;
  const Status status = EstimateAbsolutePoseRansac(Options(3), c.image_plane_um, c.points_in_ground,
                                                   c.focal_um, &eo, &mask, &summary);
  ASSERT_TRUE(status.ok()) << status.message();
  ASSERT_TRUE(summary.success) << summary.BriefReport();
  ASSERT_EQ(mask.size(), c.points_in_ground.size());
  EXPECT_EQ(summary.num_inliers, std::count(mask.begin(), mask.end(), 1));
  EXPECT_GE(MaskAgreement(mask, c.is_outlier), kMinMaskAgreement);

  const Vector6d sigma = PredictedSigmas(c);
  const Vector6d error = PoseError(eo, c.truth);
  for (int k = 0; k < 6; ++k)
    EXPECT_LE(std::abs(error[k]), kSigmas * sigma[k]) << "parameter " << k;
  std::printf("[ RANSAC ] %s, %.0f %% outliers: %s\n", EnumName(scenario),
              100 * outlier_fraction, summary.BriefReport().c_str());
  std::printf(
      "[ RANSAC ] centre error %.3f m (sigma %.3f), angle errors %.2f %.2f %.2f arcsec "
      "(sigma %.2f %.2f %.2f)\n",
      error.head<3>().norm(), sigma.head<3>().norm(), error[3] * kArcSecondsPerRadian,
      error[4] * kArcSecondsPerRadian, error[5] * kArcSecondsPerRadian,
      sigma[3] * kArcSecondsPerRadian, sigma[4] * kArcSecondsPerRadian,
      sigma[5] * kArcSecondsPerRadian);
  // The adaptive stop: at inlier ratio w the budget is log(1e-4) / log(1 - w^3), 22 trials at 70 %
  // and 140 at 40 % inliers; the estimated ratio is a little lower than the true one.
  EXPECT_LE(summary.num_trials, outlier_fraction < 0.5 ? 40 : 250);
}

INSTANTIATE_TEST_SUITE_P(Scenes, AbsolutePoseRansacTest,
                         ::testing::Combine(::testing::Values(Scenario::kNadir, Scenario::kOblique),
                                            ::testing::Values(0.3, 0.6)),
                         [](const ::testing::TestParamInfo<std::tuple<Scenario, double>>& info) {
                           return std::string(EnumName(std::get<0>(info.param))) + "_" +
                                  std::to_string(static_cast<int>(
                                      std::lround(100 * std::get<1>(info.param)))) +
                                  "pct_outliers";
                         });

TEST(AbsolutePoseRansacTest, SameSeedIdenticalDifferentSeedsBothSucceed) {
  const Correspondences c = FromSyntheticScene(Scenario::kNadir, 0.4, /*seed=*/21);
  ExteriorOrientation first, second, third;
  std::vector<char> first_mask, second_mask, third_mask;
  RansacSummary a, b, d;
  ASSERT_TRUE(EstimateAbsolutePoseRansac(Options(5), c.image_plane_um, c.points_in_ground,
                                         c.focal_um, &first, &first_mask, &a)
                  .ok());
  ASSERT_TRUE(EstimateAbsolutePoseRansac(Options(5), c.image_plane_um, c.points_in_ground,
                                         c.focal_um, &second, &second_mask, &b)
                  .ok());
  EXPECT_EQ(first.parameters, second.parameters);  // bit for bit
  EXPECT_EQ(first_mask, second_mask);
  EXPECT_EQ(a.num_trials, b.num_trials);
  EXPECT_EQ(a.num_models, b.num_models);
  EXPECT_EQ(a.score, b.score);

  ASSERT_TRUE(EstimateAbsolutePoseRansac(Options(6), c.image_plane_um, c.points_in_ground,
                                         c.focal_um, &third, &third_mask, &d)
                  .ok());
  const Vector6d sigma = PredictedSigmas(c);
  const Vector6d error = PoseError(third, c.truth);
  for (int k = 0; k < 6; ++k)
    EXPECT_LE(std::abs(error[k]), kSigmas * sigma[k]) << "parameter " << k;
  EXPECT_GE(MaskAgreement(third_mask, c.is_outlier), kMinMaskAgreement);
}

TEST(AbsolutePoseRansacTest, NoiseFreeIsExactAndOptionalOutputsMayBeNull) {
  const Correspondences c = SimpleScene(4, 100, Eigen::Vector3d(0.4, -0.2, 2.5), 0.0);
  ExteriorOrientation eo;
  ASSERT_TRUE(EstimateAbsolutePoseRansac(Options(1), c.image_plane_um, c.points_in_ground,
                                         c.focal_um, &eo, nullptr, nullptr)
                  .ok());
  const Vector6d error = PoseError(eo, c.truth);
  EXPECT_LT(error.head<3>().norm() / 800.0, kNoiseFreeTolerance);
  EXPECT_LT(error.tail<3>().norm(), kNoiseFreeTolerance);
}

TEST(AbsolutePoseRansacTest, ExactlyThreePoints) {
  // The minimum: the pose is one of P3P's, and it reproduces the three marks.
  const Correspondences c = SimpleScene(5, 3, Eigen::Vector3d(0.01, 0.02, -0.7), 0.0);
  ExteriorOrientation eo;
  std::vector<char> mask;
  RansacSummary summary;
  const Status status = EstimateAbsolutePoseRansac(Options(1), c.image_plane_um, c.points_in_ground,
                                                   c.focal_um, &eo, &mask, &summary);
  ASSERT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(summary.num_inliers, 3);
  for (int i = 0; i < 3; ++i) {
    double xy[2];
    ASSERT_TRUE(ProjectToImagePlane(eo.data(), c.points_in_ground[i].data(), c.focal_um, xy));
    EXPECT_NEAR(xy[0], c.image_plane_um[i].x(), 1e-6);
    EXPECT_NEAR(xy[1], c.image_plane_um[i].y(), 1e-6);
  }
}

TEST(AbsolutePoseRansacTest, WithoutFinalPolish) {
  const Correspondences c = FromSyntheticScene(Scenario::kOblique, 0.3, /*seed=*/31);
  AbsolutePoseRansacOptions options = Options(2);
  options.final_gauss_newton_iterations = 0;
  ExteriorOrientation eo;
  std::vector<char> mask;
  ASSERT_TRUE(EstimateAbsolutePoseRansac(options, c.image_plane_um, c.points_in_ground, c.focal_um,
                                         &eo, &mask, nullptr)
                  .ok());
  // Local optimisation fits at most 96 inliers: about sqrt(350 / 96) ~ 2x the full-set sigma.
  const Vector6d sigma = PredictedSigmas(c);
  const Vector6d error = PoseError(eo, c.truth);
  for (int k = 0; k < 6; ++k)
    EXPECT_LE(std::abs(error[k]), 2.0 * kSigmas * sigma[k]) << "parameter " << k;
  EXPECT_GE(MaskAgreement(mask, c.is_outlier), kMinMaskAgreement);
}

TEST(AbsolutePoseRansacTest, FailsCleanly) {
  const Correspondences c = SimpleScene(6, 50, Eigen::Vector3d(0.01, 0.02, 0.3), 3.0);
  ExteriorOrientation eo;
  eo.set_center_in_ground(Eigen::Vector3d(1, 2, 3));
  const ExteriorOrientation untouched = eo;
  std::vector<char> mask;
  RansacSummary summary;
  auto expect_failure = [&](const Status& status, const std::string& fragment) {
    EXPECT_FALSE(status.ok());
    EXPECT_NE(status.message().find(fragment), std::string::npos) << status.message();
    EXPECT_FALSE(summary.success);
    EXPECT_FALSE(summary.message.empty());
    EXPECT_EQ(eo.parameters, untouched.parameters);
  };

  // Two points.
  const std::vector<Eigen::Vector2d> two_xy(c.image_plane_um.begin(), c.image_plane_um.begin() + 2);
  const std::vector<Eigen::Vector3d> two_X(c.points_in_ground.begin(),
                                           c.points_in_ground.begin() + 2);
  expect_failure(
      EstimateAbsolutePoseRansac(Options(1), two_xy, two_X, c.focal_um, &eo, &mask, &summary),
      "at least 3");

  // All ground points on one line (a road centre line, say), seen consistently.
  Correspondences line = c;
  for (size_t i = 0; i < line.points_in_ground.size(); ++i) {
    line.points_in_ground[i] = Eigen::Vector3d(4800.0 + 8.0 * i, 5900.0 + 3.0 * i, 50.0);
    double xy[2];
    ASSERT_TRUE(
        ProjectToImagePlane(c.truth.data(), line.points_in_ground[i].data(), c.focal_um, xy));
    line.image_plane_um[i] = Eigen::Vector2d(xy[0], xy[1]);
  }
  expect_failure(EstimateAbsolutePoseRansac(Options(1), line.image_plane_um, line.points_in_ground,
                                            c.focal_um, &eo, &mask, &summary),
                 "collinear");

  // Mismatched sizes, a bad principal distance, non-finite data, invalid options.
  expect_failure(EstimateAbsolutePoseRansac(Options(1), two_xy, c.points_in_ground, c.focal_um, &eo,
                                            &mask, &summary),
                 "image points");
  expect_failure(EstimateAbsolutePoseRansac(Options(1), c.image_plane_um, c.points_in_ground, 0.0,
                                            &eo, &mask, &summary),
                 "principal distance");
  Correspondences nan = c;
  nan.image_plane_um[10].y() = std::numeric_limits<double>::quiet_NaN();
  expect_failure(EstimateAbsolutePoseRansac(Options(1), nan.image_plane_um, nan.points_in_ground,
                                            c.focal_um, &eo, &mask, &summary),
                 "not finite");
  AbsolutePoseRansacOptions bad = Options(1);
  bad.inlier_threshold = 0.0;
  expect_failure(EstimateAbsolutePoseRansac(bad, c.image_plane_um, c.points_in_ground, c.focal_um,
                                            &eo, &mask, &summary),
                 "inlier_threshold");
  bad = Options(1);
  bad.ransac.confidence = 1.5;
  expect_failure(EstimateAbsolutePoseRansac(bad, c.image_plane_um, c.points_in_ground, c.focal_um,
                                            &eo, &mask, &summary),
                 "confidence");
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
