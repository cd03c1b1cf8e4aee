#include "cost_functions/collinearity_cost.h"

#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include <memory>
#include <random>

#include "core/rotation.h"
#include "tests/support/ordered_draws.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// Analytic and autodiff evaluate the same model in double precision; they may differ only by
// rounding. 1e-9 relative to the Jacobian's largest element (the requirement).
constexpr double kAgreementTolerance = 1e-9;
constexpr int kNumRandomPoses = 1000;
// Two paths through the same functions: only the order of rounding may differ.
constexpr double kSameArithmetic = 1e-14;

struct RandomView {
  double eo[6];
  double point[3];
  double focal_um;
  double frame_params[kFrameNumParams];
  Eigen::Vector2d film_um;
  Eigen::Vector2d observed_um;
};

// A camera 100-1000 m from a point it sees at up to 60 deg off nadir, kappa anywhere on the circle.
RandomView MakeRandomView(std::mt19937_64* rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  RandomView view;
  const double omega = DegreesToRadians(60.0) * u(*rng);
  const double phi = DegreesToRadians(60.0) * u(*rng) * 0.5;
  const double kappa = kPi * u(*rng);
  const Eigen::Matrix3d R = RotationFromAngles(RotationConvention::kSeed, {omega, phi, kappa});
  const Eigen::Vector3d center = DrawLastFirst<3>([&](int i) { return i == 2 ? 300.0 + 200 * u(*rng) : 1000.0 * u(*rng) + (i == 0 ? 5e5 : 4e6); });
  // A ray inside a +-35 deg field of view, 100-1000 m long, in front of the camera (w < 0).
  const Eigen::Vector3d ray_camera = DrawLastFirst<3>([&](int i) { return i == 2 ? -1.0 : 0.7 * u(*rng); }).normalized();
  const double range = 550.0 + 450.0 * u(*rng);
  const Eigen::Vector3d point = center + R.transpose() * (range * ray_camera);
  view.eo[0] = center.x();
  view.eo[1] = center.y();
  view.eo[2] = center.z();
  view.eo[3] = omega;
  view.eo[4] = phi;
  view.eo[5] = kappa;
  for (int i = 0; i < 3; ++i) view.point[i] = point[i];
  view.focal_um = 8800.0 * (1.0 + 0.2 * u(*rng));
  double* p = view.frame_params;
  p[kFrameFocal] = view.focal_um;
  p[kFramePrincipalX] = 30.0 * u(*rng);
  p[kFramePrincipalY] = 30.0 * u(*rng);
  p[kFrameK0] = 1e-4 * u(*rng);
  p[kFrameK1] = 1e-4 * u(*rng);
  p[kFrameK2] = 1e-7 * u(*rng);
  p[kFrameK3] = 1e-10 * u(*rng);
  p[kFrameP1] = 1e-5 * u(*rng);
  p[kFrameP2] = 1e-5 * u(*rng);
  p[kFrameAffinity] = 1e-3 * u(*rng);
  p[kFrameSkew] = 1e-3 * u(*rng);
  view.film_um = DrawLastFirst<2>([&](int i) { return (i == 0 ? 6000.0 : 4000.0) * u(*rng); });
  view.observed_um = DrawLastFirst<2>([&](int i) { return (i == 0 ? 6000.0 : 4000.0) * u(*rng); });
  return view;
}

// Evaluates a cost and returns residuals and Jacobians as one flat vector per block.
bool Evaluate(const ceres::CostFunction& cost, const std::vector<const double*>& parameters,
              Eigen::Vector2d* residual, std::vector<Eigen::VectorXd>* jacobians) {
  const auto& sizes = cost.parameter_block_sizes();
  jacobians->clear();
  std::vector<double*> pointers;
  for (int size : sizes) jacobians->emplace_back(Eigen::VectorXd::Zero(2 * size));
  for (auto& j : *jacobians) pointers.push_back(j.data());
  return cost.Evaluate(parameters.data(), residual->data(), pointers.data());
}

void ExpectAgreement(const ceres::CostFunction& analytic, const ceres::CostFunction& autodiff,
                     const std::vector<const double*>& parameters) {
  Eigen::Vector2d r_analytic, r_autodiff;
  std::vector<Eigen::VectorXd> j_analytic, j_autodiff;
  ASSERT_TRUE(Evaluate(analytic, parameters, &r_analytic, &j_analytic));
  ASSERT_TRUE(Evaluate(autodiff, parameters, &r_autodiff, &j_autodiff));
  const double r_scale = std::max(1.0, r_autodiff.cwiseAbs().maxCoeff());
  EXPECT_LE((r_analytic - r_autodiff).cwiseAbs().maxCoeff(), kAgreementTolerance * r_scale);
  for (size_t b = 0; b < j_analytic.size(); ++b) {
    const double scale = std::max(1e-300, j_autodiff[b].cwiseAbs().maxCoeff());
    EXPECT_LE((j_analytic[b] - j_autodiff[b]).cwiseAbs().maxCoeff(), kAgreementTolerance * scale)
        << "block " << b;
  }
}

TEST(PoseCost, NominalNadirResidualIsHandComputable) {
  // Camera 1000 m above the origin looking straight down; a point 100 m east: x = c * 100/1000.
  const double eo[6] = {0.0, 0.0, 1000.0, 0.0, 0.0, 0.0};
  PoseCostFunctor data(Eigen::Vector2d(10000.0, 0.0), Eigen::Vector3d(100.0, 0.0, 0.0), 100000.0,
                       1.0);
  PoseCostAnalytic cost(data);
  const double* parameters[] = {eo};
  double residual[2];
  ASSERT_TRUE(cost.Evaluate(parameters, residual, nullptr));
  EXPECT_NEAR(residual[0], 0.0, 1e-9);
  EXPECT_NEAR(residual[1], 0.0, 1e-9);
}

TEST(PoseCost, AnalyticMatchesAutodiffOverRandomPoses) {
  std::mt19937_64 rng(42);
  for (int i = 0; i < kNumRandomPoses; ++i) {
    const RandomView view = MakeRandomView(&rng);
    const PoseCostFunctor data(view.observed_um, Eigen::Map<const Eigen::Vector3d>(view.point),
                               view.focal_um, 1.0 / 2.4);
    std::unique_ptr<ceres::CostFunction> analytic(CreatePoseCost(JacobianType::kAnalytic, data));
    std::unique_ptr<ceres::CostFunction> autodiff(CreatePoseCost(JacobianType::kAutodiff, data));
    ExpectAgreement(*analytic, *autodiff, {view.eo});
  }
}

// Parameters of each camera model around a 4000 x 3000 px camera with f = 3000 px (COLMAP models)
// or the random frame camera of the view; observations in the model's unit near the projection.
struct ModelCase {
  CameraModelType type;
  std::vector<double> params;
  CameraModelData data;
  Eigen::Vector2d observation;
};

std::vector<ModelCase> ModelCases(const RandomView& view, std::mt19937_64* rng,
                                  const std::vector<double>* table_r = nullptr,
                                  const std::vector<double>* table_d = nullptr) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<ModelCase> cases;
  const double f = 3000.0 * (1.0 + 0.1 * u(*rng));
  const double cx = 2000.0 + 20.0 * u(*rng), cy = 1500.0 + 20.0 * u(*rng);
  const Eigen::Vector2d pixel = DrawLastFirst<2>([&](int i) { return i == 0 ? 2000.0 + 1500.0 * u(*rng) : 1500.0 + 1000.0 * u(*rng); });
  cases.push_back({CameraModelType::kSimplePinhole, {f, cx, cy}, {}, pixel});
  cases.push_back({CameraModelType::kPinhole, {f, f * 1.01, cx, cy}, {}, pixel});
  cases.push_back({CameraModelType::kSimpleRadial, {f, cx, cy, 0.05 * u(*rng)}, {}, pixel});
  cases.push_back({CameraModelType::kRadial, {f, cx, cy, 0.05 * u(*rng), 0.01 * u(*rng)}, {}, pixel});
  cases.push_back({CameraModelType::kOpenCv,
                   {f, f * 0.99, cx, cy, 0.05 * u(*rng), 0.01 * u(*rng), 1e-3 * u(*rng),
                    1e-3 * u(*rng)},
                   {},
                   pixel});
  CameraModelData frame_data;
  frame_data.polarity_sign = u(*rng) > 0.0 ? 1.0 : -1.0;
  cases.push_back({CameraModelType::kFrame,
                   std::vector<double>(view.frame_params, view.frame_params + kFrameNumParams),
                   frame_data, view.film_um});
  if (table_r != nullptr) {
    CameraModelData table_data = frame_data;
    table_data.table_radius_um = table_r->data();
    table_data.table_distortion_um = table_d->data();
    table_data.table_size = static_cast<int>(table_r->size());
    cases.push_back({CameraModelType::kFrame, cases.back().params, table_data, view.film_um});
  }
  cases.push_back({CameraModelType::kFullOpenCv,
                   {f, f * 0.99, cx, cy, 0.05 * u(*rng), 0.01 * u(*rng), 1e-3 * u(*rng),
                    1e-3 * u(*rng), 1e-3 * u(*rng), 0.01 * u(*rng), 1e-3 * u(*rng), 1e-4 * u(*rng)},
                   {},
                   pixel});
  cases.push_back(
      {CameraModelType::kOpenCvFisheye,
       {f, f * 1.01, cx, cy, 0.05 * u(*rng), 0.01 * u(*rng), 1e-3 * u(*rng), 1e-4 * u(*rng)},
       {},
       pixel});
  return cases;
}

TEST(CollinearityCost, AnalyticMatchesAutodiffForEveryCameraModel) {
  std::mt19937_64 rng(7);
  const std::vector<double> table_r = {1000.0, 3000.0, 6000.0}, table_d = {1.5, -2.0, 4.0};
  for (int i = 0; i < kNumRandomPoses / 4; ++i) {
    RandomView view = MakeRandomView(&rng);
    for (ModelCase& model : ModelCases(view, &rng, &table_r, &table_d)) {
      const CollinearityFunctor data(model.type, model.observation, model.data, 1.0 / 2.4);
      std::unique_ptr<ceres::CostFunction> analytic(
          CreateCollinearityCost(JacobianType::kAnalytic, data));
      std::unique_ptr<ceres::CostFunction> autodiff(
          CreateCollinearityCost(JacobianType::kAutodiff, data));
      SCOPED_TRACE(EnumName(model.type));
      ExpectAgreement(*analytic, *autodiff, {view.eo, view.point, model.params.data()});
    }
  }
}

// A bundle mark's compact cost is the same residual and Jacobians as the measurement's cost, with
// the camera as a third parameter block (self-calibration) or held in CollinearityCamera; its
// autodiff path agrees with the analytic one.
TEST(CollinearityMarkCost, MatchesTheMeasurementCostWithAndWithoutTheCameraBlock) {
  std::mt19937_64 rng(11);
  const std::vector<double> table_r = {1000.0, 3000.0, 6000.0}, table_d = {1.5, -2.0, 4.0};
  for (int i = 0; i < kNumRandomPoses / 4; ++i) {
    RandomView view = MakeRandomView(&rng);
    for (ModelCase& model : ModelCases(view, &rng, &table_r, &table_d)) {
      SCOPED_TRACE(EnumName(model.type));
      const double inverse_sigma = 1.0 / 2.4;
      const std::unique_ptr<ceres::CostFunction> reference(CreateCollinearityCost(
          JacobianType::kAnalytic,
          CollinearityFunctor(model.type, model.observation, model.data, inverse_sigma)));
      Eigen::Vector2d r_reference;
      std::vector<Eigen::VectorXd> j_reference;
      ASSERT_TRUE(Evaluate(*reference, {view.eo, view.point, model.params.data()}, &r_reference,
                           &j_reference));
      for (const bool camera_block : {true, false}) {
        CollinearityCamera camera;
        camera.model = model.type;
        camera.data = model.data;
        camera.constant_params = camera_block ? nullptr : model.params.data();
        const CollinearityMarkFunctor mark(&camera, model.observation, inverse_sigma);
        const std::unique_ptr<ceres::CostFunction> analytic(
            CreateCollinearityMarkCost(JacobianType::kAnalytic, mark));
        const std::unique_ptr<ceres::CostFunction> autodiff(
            CreateCollinearityMarkCost(JacobianType::kAutodiff, mark));
        std::vector<const double*> parameters = {view.eo, view.point};
        if (camera_block) parameters.push_back(model.params.data());
        ASSERT_EQ(analytic->parameter_block_sizes().size(), parameters.size());
        Eigen::Vector2d r;
        std::vector<Eigen::VectorXd> j;
        ASSERT_TRUE(Evaluate(*analytic, parameters, &r, &j));
        // The same function of the same values (kSameArithmetic: the Jets of the camera's
        // derivatives differ in size without the camera block).
        EXPECT_LE((r - r_reference).cwiseAbs().maxCoeff(),
                  kSameArithmetic * std::max(1.0, r_reference.cwiseAbs().maxCoeff()));
        for (size_t b = 0; b < j.size(); ++b) {
          EXPECT_LE((j[b] - j_reference[b]).cwiseAbs().maxCoeff(),
                    kSameArithmetic * j_reference[b].cwiseAbs().maxCoeff())
              << "block " << b;
        }
        ExpectAgreement(*analytic, *autodiff, parameters);
      }
    }
  }
}

// A zero weight switches the mark off: zero residual and Jacobians, set in the functor inside the
// cost (a bundle adjustment rejects marks so without building its problem again).
TEST(CollinearityMarkCost, ZeroWeightSwitchesTheMarkOff) {
  std::mt19937_64 rng(13);
  RandomView view = MakeRandomView(&rng);
  for (ModelCase& model : ModelCases(view, &rng)) {
    CollinearityCamera camera;
    camera.model = model.type;
    camera.data = model.data;
    const Eigen::Vector2d off_by(5.0, -3.0);
    const CollinearityMarkFunctor mark(&camera, model.observation + off_by, 1.0);
    for (const JacobianType type : {JacobianType::kAnalytic, JacobianType::kAutodiff}) {
      CollinearityMarkFunctor* inside = nullptr;
      const std::unique_ptr<ceres::CostFunction> cost(
          CreateCollinearityMarkCost(type, mark, &inside));
      ASSERT_NE(inside, nullptr);
      const std::vector<const double*> parameters = {view.eo, view.point, model.params.data()};
      Eigen::Vector2d r;
      std::vector<Eigen::VectorXd> j;
      ASSERT_TRUE(Evaluate(*cost, parameters, &r, &j));
      EXPECT_GT(r.norm(), 1.0);
      inside->inverse_sigma = 0.0;
      ASSERT_TRUE(Evaluate(*cost, parameters, &r, &j));
      EXPECT_EQ(r.norm(), 0.0);
      for (size_t b = 0; b < j.size(); ++b) EXPECT_EQ(j[b].norm(), 0.0) << "block " << b;
    }
  }
}

// Numerical differentiation needs steps relative to the values; at UTM magnitudes a relative step
// is metres and the curvature of the model spoils the difference quotient. The gradient checker
// therefore works in a local frame (the model is translation invariant), the autodiff comparison
// above at full magnitude.
RandomView MakeLocalView(std::mt19937_64* rng) {
  RandomView view = MakeRandomView(rng);
  for (int i = 0; i < 2; ++i) {
    const double origin = std::floor(view.eo[i]);
    view.eo[i] -= origin;
    view.point[i] -= origin;
  }
  return view;
}

// Probes a cost with Ceres' gradient checker. The element-wise relative test of Probe() trips
// over cross terms of ~1e-6 next to elements of ~1e7 in the camera block (pure rounding in the
// numeric side); each block is compared relative to its largest element instead (1e-7).
void ExpectGradientCheckerBlocks(const ceres::GradientChecker& checker,
                                 const double* const* parameters) {
  ceres::GradientChecker::ProbeResults results;
  checker.Probe(parameters, 1e-5, &results);
  ASSERT_TRUE(results.return_value);
  for (size_t b = 0; b < results.jacobians.size(); ++b) {
    const double scale = results.numeric_jacobians[b].cwiseAbs().maxCoeff();
    EXPECT_LE((results.jacobians[b] - results.numeric_jacobians[b]).cwiseAbs().maxCoeff(),
              1e-7 * scale)
        << "block " << b;
  }
}

TEST(PoseCost, PassesCeresGradientChecker) {
  std::mt19937_64 rng(3);
  for (int i = 0; i < 50; ++i) {
    RandomView view = MakeLocalView(&rng);
    PoseCostAnalytic cost(PoseCostFunctor(view.observed_um, Eigen::Map<Eigen::Vector3d>(view.point),
                                          view.focal_um, 1.0));
    ceres::NumericDiffOptions numeric_options;
    // Ridders' first step is relative to the value: 1e-2 of a UTM easting would move the camera by
    // kilometres and behind its points. 1e-6 is 0.5 m there and 1e-6 rad for angles.
    numeric_options.ridders_relative_initial_step_size = 1e-6;
    const std::vector<const ceres::Manifold*>* no_manifolds = nullptr;
    ceres::GradientChecker checker(&cost, no_manifolds, numeric_options);
    ceres::GradientChecker::ProbeResults results;
    const double* parameters[] = {view.eo};
    EXPECT_TRUE(checker.Probe(parameters, 1e-6, &results)) << results.error_log;
  }
}

TEST(CollinearityCost, PassesCeresGradientCheckerForEveryCameraModel) {
  std::mt19937_64 rng(5);
  for (int i = 0; i < 30; ++i) {
    RandomView view = MakeLocalView(&rng);
    for (ModelCase& model : ModelCases(view, &rng)) {
      std::unique_ptr<ceres::CostFunction> cost(CreateCollinearityCost(
          JacobianType::kAnalytic,
          CollinearityFunctor(model.type, model.observation, model.data, 1.0)));
      ceres::NumericDiffOptions numeric_options;
      // Ridders' first step is relative to the value: 1e-2 of a UTM easting would move the camera
      // by kilometres and behind its points. 1e-6 is 0.5 m there and 1e-6 rad for angles.
      numeric_options.ridders_relative_initial_step_size = 1e-6;
      const std::vector<const ceres::Manifold*>* no_manifolds = nullptr;
      ceres::GradientChecker checker(cost.get(), no_manifolds, numeric_options);
      const double* parameters[] = {view.eo, view.point, model.params.data()};
      SCOPED_TRACE(EnumName(model.type));
      ExpectGradientCheckerBlocks(checker, parameters);
    }
  }
}

// ------------------------------------------------------------------ earth curvature (ApplyECC)

// The radius of the gradient checks: 50 km instead of 6378 km, so that the chain-rule terms of the
// drop (D / R of the point's Z partial) are far above the numeric differences' error.
constexpr double kSmallEarthRadius = 50000.0;

// The costs with the correction against the plain model evaluated by hand at the point lowered by
// EarthCurvatureDrop: the same residual. The analytic and autodiff paths of the measurement cost
// and of the compact mark cost (with and without the camera block) agree to kAgreementTolerance,
// and the correction changes the Jacobians by far more than that (the test can fail).
TEST(CollinearityCostEarthCurvature, MatchesTheLoweredPointAndAgreesAcrossPaths) {
  std::mt19937_64 rng(17);
  for (int i = 0; i < kNumRandomPoses / 4; ++i) {
    RandomView view = MakeRandomView(&rng);
    ModelCase frame;
    for (ModelCase& model : ModelCases(view, &rng))
      if (model.type == CameraModelType::kFrame) frame = model;
    for (const double radius : {6378137.0, kSmallEarthRadius}) {
      const double inverse_sigma = 1.0 / 2.4;
      Eigen::Vector3d lowered = Eigen::Map<const Eigen::Vector3d>(view.point);
      lowered.z() -= EarthCurvatureDrop(Eigen::Map<const Eigen::Vector3d>(view.eo), lowered, radius);
      const std::unique_ptr<ceres::CostFunction> plain(CreateCollinearityCost(
          JacobianType::kAnalytic,
          CollinearityFunctor(frame.type, frame.observation, frame.data, inverse_sigma)));
      Eigen::Vector2d r_by_hand;
      std::vector<Eigen::VectorXd> j_plain;
      ASSERT_TRUE(Evaluate(*plain, {view.eo, lowered.data(), frame.params.data()}, &r_by_hand,
                           &j_plain));
      const CollinearityFunctor with_ecc(frame.type, frame.observation, frame.data, inverse_sigma,
                                         radius);
      const std::unique_ptr<ceres::CostFunction> analytic(
          CreateCollinearityCost(JacobianType::kAnalytic, with_ecc));
      const std::unique_ptr<ceres::CostFunction> autodiff(
          CreateCollinearityCost(JacobianType::kAutodiff, with_ecc));
      const std::vector<const double*> parameters = {view.eo, view.point, frame.params.data()};
      Eigen::Vector2d r;
      std::vector<Eigen::VectorXd> j;
      ASSERT_TRUE(Evaluate(*analytic, parameters, &r, &j));
      EXPECT_LE((r - r_by_hand).cwiseAbs().maxCoeff(),
                kSameArithmetic * std::max(1.0, r_by_hand.cwiseAbs().maxCoeff()));
      ExpectAgreement(*analytic, *autodiff, parameters);
      if (radius == kSmallEarthRadius) {
        // The point's X, Y partials carry the drop's chain rule: -P_Z (X - X0) / R.
        EXPECT_GT((j[1] - j_plain[1]).cwiseAbs().maxCoeff(),
                  1e3 * kAgreementTolerance * j[1].cwiseAbs().maxCoeff());
      }
      for (const bool camera_block : {true, false}) {
        CollinearityCamera camera;
        camera.model = frame.type;
        camera.data = frame.data;
        camera.constant_params = camera_block ? nullptr : frame.params.data();
        camera.earth_radius_m = radius;
        const CollinearityMarkFunctor mark(&camera, frame.observation, inverse_sigma);
        const std::unique_ptr<ceres::CostFunction> mark_analytic(
            CreateCollinearityMarkCost(JacobianType::kAnalytic, mark));
        const std::unique_ptr<ceres::CostFunction> mark_autodiff(
            CreateCollinearityMarkCost(JacobianType::kAutodiff, mark));
        std::vector<const double*> mark_parameters = {view.eo, view.point};
        if (camera_block) mark_parameters.push_back(frame.params.data());
        Eigen::Vector2d r_mark;
        std::vector<Eigen::VectorXd> j_mark;
        ASSERT_TRUE(Evaluate(*mark_analytic, mark_parameters, &r_mark, &j_mark));
        EXPECT_LE((r_mark - r).cwiseAbs().maxCoeff(),
                  kSameArithmetic * std::max(1.0, r.cwiseAbs().maxCoeff()));
        for (size_t b = 0; b < j_mark.size(); ++b) {
          EXPECT_LE((j_mark[b] - j[b]).cwiseAbs().maxCoeff(), kSameArithmetic * j[b].cwiseAbs().maxCoeff())
              << "block " << b;
        }
        ExpectAgreement(*mark_analytic, *mark_autodiff, mark_parameters);
      }
    }
  }
}

// A camera without the correction gets exactly today's cost type; one with it a type of its own,
// whose functor inside still switches the mark off.
TEST(CollinearityCostEarthCurvature, OnlyCamerasWithTheCorrectionGetTheCorrectedCost) {
  std::mt19937_64 rng(19);
  RandomView view = MakeRandomView(&rng);
  CollinearityCamera camera;
  camera.model = CameraModelType::kFrame;
  camera.constant_params = view.frame_params;
  const CollinearityMarkFunctor mark(&camera, view.film_um, 1.0);
  {
    const std::unique_ptr<ceres::CostFunction> cost(
        CreateCollinearityMarkCost(JacobianType::kAnalytic, mark));
    using Plain = CollinearityMarkCostAnalytic<kFrameNumParams, false, false>;
    EXPECT_NE(dynamic_cast<Plain*>(cost.get()), nullptr);
  }
  camera.earth_radius_m = kSmallEarthRadius;
  {
    const std::unique_ptr<ceres::CostFunction> cost(
        CreateCollinearityMarkCost(JacobianType::kAnalytic, mark));
    using Corrected = CollinearityMarkCostAnalytic<kFrameNumParams, false, true>;
    EXPECT_NE(dynamic_cast<Corrected*>(cost.get()), nullptr);
  }
  for (const JacobianType type : {JacobianType::kAnalytic, JacobianType::kAutodiff}) {
    CollinearityMarkFunctor* inside = nullptr;
    const std::unique_ptr<ceres::CostFunction> cost(CreateCollinearityMarkCost(type, mark, &inside));
    ASSERT_NE(inside, nullptr);
    Eigen::Vector2d r;
    std::vector<Eigen::VectorXd> j;
    ASSERT_TRUE(Evaluate(*cost, {view.eo, view.point}, &r, &j));
    EXPECT_GT(r.norm(), 1.0);
    inside->inverse_sigma = 0.0;
    ASSERT_TRUE(Evaluate(*cost, {view.eo, view.point}, &r, &j));
    EXPECT_EQ(r.norm(), 0.0);
    for (size_t b = 0; b < j.size(); ++b) EXPECT_EQ(j[b].norm(), 0.0) << "block " << b;
  }
}

TEST(CollinearityCostEarthCurvature, PassesCeresGradientChecker) {
  std::mt19937_64 rng(23);
  for (int i = 0; i < 30; ++i) {
    RandomView view = MakeLocalView(&rng);
    CollinearityCamera camera;
    camera.model = CameraModelType::kFrame;
    camera.earth_radius_m = kSmallEarthRadius;
    const std::unique_ptr<ceres::CostFunction> cost(CreateCollinearityMarkCost(
        JacobianType::kAnalytic, CollinearityMarkFunctor(&camera, view.film_um, 1.0)));
    ceres::NumericDiffOptions numeric_options;
    numeric_options.ridders_relative_initial_step_size = 1e-6;  // as above
    const std::vector<const ceres::Manifold*>* no_manifolds = nullptr;
    ceres::GradientChecker checker(cost.get(), no_manifolds, numeric_options);
    const double* parameters[] = {view.eo, view.point, view.frame_params};
    ExpectGradientCheckerBlocks(checker, parameters);
  }
}

TEST(PoseCost, PointBehindCameraFailsInBothPaths) {
  // Camera looking straight down from 1000 m; the point is above it.
  const double eo[6] = {0.0, 0.0, 1000.0, 0.0, 0.0, 0.0};
  const PoseCostFunctor data(Eigen::Vector2d::Zero(), Eigen::Vector3d(10.0, 10.0, 1500.0), 1e5, 1.0);
  for (JacobianType type : {JacobianType::kAnalytic, JacobianType::kAutodiff}) {
    std::unique_ptr<ceres::CostFunction> cost(CreatePoseCost(type, data));
    Eigen::Vector2d residual;
    std::vector<Eigen::VectorXd> jacobians;
    EXPECT_FALSE(Evaluate(*cost, {eo}, &residual, &jacobians)) << EnumName(type);
  }
  const double point[3] = {10.0, 10.0, 1000.0};  // on the camera plane: w = 0
  double frame_params[kFrameNumParams] = {1e5};
  const CollinearityFunctor bundle(CameraModelType::kFrame, Eigen::Vector2d::Zero(),
                                   CameraModelData(), 1.0);
  for (JacobianType type : {JacobianType::kAnalytic, JacobianType::kAutodiff}) {
    std::unique_ptr<ceres::CostFunction> cost(CreateCollinearityCost(type, bundle));
    Eigen::Vector2d residual;
    std::vector<Eigen::VectorXd> jacobians;
    EXPECT_FALSE(Evaluate(*cost, {eo, point, frame_params}, &residual, &jacobians));
  }
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
