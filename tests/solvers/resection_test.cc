#include "solvers/resection.h"

#include <gtest/gtest.h>

#include <map>

#include "core/rotation.h"
#include "core/synthetic_scene.h"

#include <random>

namespace photopose {
namespace {

// Builds the resection inputs of every image of a synthetic scene (control points only).
std::vector<ResectionInput> InputsOf(const SyntheticScene& scene, bool with_approximate,
                                     std::vector<std::vector<char>>* outliers = nullptr) {
  std::map<std::string, const GroundPoint*> points;
  for (const auto& p : scene.points) points[p.point_id] = &p;
  std::vector<ResectionInput> inputs;
  std::map<std::string, size_t> index;
  const FrameCamera& camera = scene.cameras.front();
  for (size_t i = 0; i < scene.true_frames.size(); ++i) {
    ResectionInput input;
    input.raster = scene.true_frames[i].raster;
    input.focal_length_um = camera.focal_length_um;
    input.pixel_size_um = camera.pixel_size_um;
    if (with_approximate) input.approximate = scene.approximate_frames[i].eo;
    index[input.raster] = inputs.size();
    inputs.push_back(input);
    if (outliers) outliers->emplace_back();
  }
  for (size_t m = 0; m < scene.marks.size(); ++m) {
    const ImageMark& mark = scene.marks[m];
    const GroundPoint& point = *points.at(mark.point_id);
    if (point.role != PointRole::kControl) continue;
    ResectionInput& input = inputs[index.at(mark.raster)];
    Eigen::Vector2d xy;
    EXPECT_TRUE(ImagePlaneFromPixel(camera, *mark.column_row, PixelOrigin::kCorner, &xy).ok());
    input.image_plane_um.push_back(xy);
    input.points_in_ground.push_back(point.position);
    input.sigma_px.push_back(*mark.accuracy_px);
    if (outliers) (*outliers)[index.at(mark.raster)].push_back(scene.mark_is_outlier[m]);
  }
  return inputs;
}

// Pose difference with the angle differences wrapped to (-pi, pi].
Vector6d PoseError(const ExteriorOrientation& a, const ExteriorOrientation& b) {
  Vector6d e = a.parameters - b.parameters;
  for (int k = 3; k < 6; ++k) e[k] = WrapAngle(e[k]);
  return e;
}

SyntheticScene Scene(Scenario scenario, double noise_px, double outlier_fraction, uint64_t seed) {
  SyntheticSceneOptions options;
  options.scenario = scenario;
  options.noise_px = noise_px;
  options.outlier_fraction = outlier_fraction;
  options.seed = seed;
  SyntheticScene scene;
  EXPECT_TRUE(MakeSyntheticScene(options, &scene).ok());
  return scene;
}

TEST(Resection, NoiseFreeRecoversTheTruthOnEveryPathAndScenario) {
  for (Scenario scenario : {Scenario::kNadir, Scenario::kOblique, Scenario::kUavBlock}) {
    const SyntheticScene scene = Scene(scenario, 0.0, 0.0, 4);
    for (bool approximate : {true, false}) {
      const auto inputs = InputsOf(scene, approximate);
      for (PoseSolver solver : {PoseSolver::kCeres, PoseSolver::kTaylor}) {
        for (JacobianType jacobian : {JacobianType::kAnalytic, JacobianType::kAutodiff}) {
          ResectionOptions options;
          options.solver = solver;
          options.jacobian = jacobian;
          const auto results = ResectImages(options, inputs, 1);
          for (size_t i = 0; i < results.size(); ++i) {
            ASSERT_TRUE(results[i].success) << results[i].summary.message;
            const Vector6d error = PoseError(results[i].eo, scene.true_frames[i].eo);
            // Noise-free: only rounding remains (mm-scale scenes, 1e-6 m is generous).
            EXPECT_LT(error.head<3>().norm(), 1e-6) << ScenarioName(scenario);
            EXPECT_LT(error.tail<3>().norm(), 1e-9) << ScenarioName(scenario);
          }
        }
      }
    }
  }
}

TEST(Resection, TinySolverAndCeresProblemAgreeForEveryLoss) {
  const SyntheticScene scene = Scene(Scenario::kOblique, 1.0, 0.2, 8);
  const auto inputs = InputsOf(scene, true);
  for (LossType loss : {LossType::kNone, LossType::kHuber, LossType::kSoftL1, LossType::kCauchy,
                        LossType::kArctan, LossType::kTukey}) {
    ResectionOptions tiny, problem;
    tiny.loss = problem.loss = loss;
    tiny.loss_scale_px = problem.loss_scale_px = 3.0;
    problem.minimizer = CeresMinimizer::kProblem;
    const ResectionResult a = ResectImage(tiny, inputs[0]);
    const ResectionResult b = ResectImage(problem, inputs[0]);
    ASSERT_EQ(a.success, b.success) << LossTypeName(loss) << a.summary.message << b.summary.message;
    if (!a.success) continue;  // plain least squares may legitimately fail with 20% gross errors
    // The same minimum: IRLS stops at 1e-9 relative, ceres::Solve at its own tolerances.
    EXPECT_LT((a.eo.parameters - b.eo.parameters).head<3>().norm(), 1e-4) << LossTypeName(loss);
    EXPECT_LT((a.eo.parameters - b.eo.parameters).tail<3>().norm(), 1e-7) << LossTypeName(loss);
  }
}

TEST(Resection, RobustLossBeatsPlainLeastSquaresWithOutliers) {
  const SyntheticScene scene = Scene(Scenario::kNadir, 0.5, 0.2, 12);
  const auto inputs = InputsOf(scene, true);  // from approximate values: no RANSAC to clean up
  ResectionOptions plain, robust;
  plain.loss = LossType::kNone;
  plain.ransac_threshold_px = robust.ransac_threshold_px = 1e6;  // keep every observation
  robust.loss = LossType::kCauchy;
  const ResectionResult a = ResectImage(plain, inputs[0]);
  const ResectionResult b = ResectImage(robust, inputs[0]);
  ASSERT_TRUE(b.success) << b.summary.message;
  const double error_robust = (b.eo.center_in_ground() - scene.true_frames[0].eo.center_in_ground()).norm();
  EXPECT_LT(error_robust, 0.5);
  // Plain least squares either fails outright or lands far off.
  if (a.success) {
    const double error_plain = (a.eo.center_in_ground() - scene.true_frames[0].eo.center_in_ground()).norm();
    EXPECT_GT(error_plain, 5.0 * error_robust);
  }
}

TEST(Resection, RansacFlagsTheGrossErrors) {
  std::vector<std::vector<char>> outliers;
  const SyntheticScene scene = Scene(Scenario::kUavBlock, 0.5, 0.4, 21);
  const auto inputs = InputsOf(scene, false, &outliers);
  ResectionOptions options;
  const auto results = ResectImages(options, inputs, 2);
  for (size_t i = 0; i < results.size(); ++i) {
    ASSERT_TRUE(results[i].success) << results[i].summary.message;
    EXPECT_GT(results[i].summary.ransac_trials, 0);
    int wrong = 0;
    for (size_t k = 0; k < outliers[i].size(); ++k)
      wrong += (results[i].inliers[k] == 0) != (outliers[i][k] != 0);
    EXPECT_LE(wrong, 1) << inputs[i].raster;  // a 20 px error near the edge may pass, rarely
    EXPECT_NEAR(results[i].sigma0, 1.0, 0.4);
  }
}

TEST(Resection, ParallelResultsEqualSerialInInputOrder) {
  const SyntheticScene scene = Scene(Scenario::kUavBlock, 0.5, 0.1, 5);
  const auto inputs = InputsOf(scene, false);
  ResectionOptions options;
  const auto serial = ResectImages(options, inputs, 1);
  const auto parallel = ResectImages(options, inputs, 0);
  ASSERT_EQ(serial.size(), parallel.size());
  for (size_t i = 0; i < serial.size(); ++i) {
    EXPECT_EQ(serial[i].eo.parameters, parallel[i].eo.parameters);
    EXPECT_EQ(serial[i].inliers, parallel[i].inliers);
  }
}

TEST(Resection, CovarianceMatchesTheMonteCarloScatter) {
  // 150 noisy trials of one nadir pose: the mean NEES of the position and angles is near 6.
  double nees_sum = 0.0;
  constexpr int kTrials = 150;
  for (int t = 0; t < kTrials; ++t) {
    // The same geometry every trial (seed 77, noise-free marks) with fresh noise added here.
    SyntheticSceneOptions options;
    options.seed = 77;
    options.noise_px = 0.0;
    SyntheticScene clean;
    ASSERT_TRUE(MakeSyntheticScene(options, &clean).ok());
    std::mt19937_64 rng(1000 + t);
    std::normal_distribution<double> n(0.0, 0.5);
    for (auto& mark : clean.marks) *mark.column_row += Eigen::Vector2d(n(rng), n(rng));
    for (auto& mark : clean.marks) mark.accuracy_px = 0.5;
    const auto inputs = InputsOf(clean, true);
    const ResectionResult r = ResectImage(ResectionOptions(), inputs[0]);
    ASSERT_TRUE(r.success);
    const Vector6d e = PoseError(r.eo, clean.true_frames[0].eo);
    // The covariance scaled by sigma0^2; with known sigma use the a-priori one for NEES.
    const Matrix6d prior = r.covariance / (r.sigma0 * r.sigma0);
    nees_sum += e.dot(prior.ldlt().solve(e));
  }
  const double mean_nees = nees_sum / kTrials;
  // Mean of 150 chi^2_6: sd = sqrt(2*6/150) = 0.28; 99% interval about 6 +- 0.75 (Huber with a 2 px
  // scale at 0.5 px noise is practically least squares).
  EXPECT_NEAR(mean_nees, 6.0, 0.8);
}

TEST(Resection, DegenerateConfigurationsFailWithAReason) {
  ResectionInput input;
  input.focal_length_um = 8800;
  input.pixel_size_um = 2.4;
  input.image_plane_um = {{0, 0}, {100, 100}};
  input.points_in_ground = {{0, 0, 0}, {1, 1, 0}};
  input.sigma_px = {1, 1};
  ResectionResult r = ResectImage(ResectionOptions(), input);
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.summary.message.find("at least three"), std::string::npos);
  input.image_plane_um = {{0, 0}, {100, 100}, {200, 200}, {300, 300}};
  input.points_in_ground = {{0, 0, 0}, {1, 1, 0}, {2, 2, 0}, {3, 3, 0}};
  input.sigma_px = {1, 1, 1, 1};
  r = ResectImage(ResectionOptions(), input);
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.summary.message.find("one line"), std::string::npos);
  input.sigma_px[0] = 0.0;
  EXPECT_FALSE(ResectImage(ResectionOptions(), input).success);
  ResectionOptions bad;
  bad.loss_scale_px = -1;
  std::string why;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_FALSE(why.empty());
}

TEST(Resection, ParsersRoundTripNames) {
  for (const char* name : {"ceres", "taylor", "taylor_as_printed"})
    EXPECT_STREQ(PoseSolverName(*ParsePoseSolver(name)), name);
  for (const char* name : {"none", "huber", "softl1", "cauchy", "arctan", "tukey"})
    EXPECT_STREQ(LossTypeName(*ParseLossType(name)), name);
  for (const char* name : {"tiny_solver", "problem"})
    EXPECT_STREQ(CeresMinimizerName(*ParseCeresMinimizer(name)), name);
  EXPECT_FALSE(ParsePoseSolver("lm").has_value());
}

}  // namespace
}  // namespace photopose
