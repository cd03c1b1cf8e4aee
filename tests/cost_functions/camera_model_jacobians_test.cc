#include "cost_functions/camera_model_jacobians.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// Central differences of the double-only residual with steps relative to each value (1e-6), at
// least 1e-7 (the small unitless affinity and skew, ~1e-4, would otherwise get steps so small
// that rounding of the ~3e3 um intermediate values, 3e-13 / 2h, dominates). Rounding then stays
// below ~2e-6 and truncation (h^2 times the curvature) far below, so 1e-5 absolute (or relative,
// for derivatives larger than 1) separates them from a real error.
constexpr double kRelativeStep = 1e-6;
constexpr double kMinStep = 1e-7;
constexpr double kNumericTolerance = 1e-5;

struct Case {
  CameraModelType type;
  std::vector<double> params;
  std::array<double, 2> observation;
};

// A parameter set per model with every term non-zero, so that every derivative is exercised.
std::vector<Case> Cases() {
  std::vector<double> frame(kFrameNumParams);
  frame[kFrameFocal] = 24000.0;  // um
  frame[kFramePrincipalX] = 30.0;
  frame[kFramePrincipalY] = -20.0;
  frame[kFrameK0] = 1e-4;
  frame[kFrameK1] = 2e-5;
  frame[kFrameK2] = -3e-8;
  frame[kFrameK3] = 1e-11;
  frame[kFrameP1] = 2e-6;
  frame[kFrameP2] = -1e-6;
  frame[kFrameAffinity] = 1e-4;
  frame[kFrameSkew] = -2e-4;
  return {
      {CameraModelType::kFrame, frame, {3000.0, -2000.0}},
      {CameraModelType::kSimplePinhole, {3000.0, 2000.0, 1500.0}, {2300.0, 1800.0}},
      {CameraModelType::kPinhole, {3000.0, 3010.0, 2000.0, 1500.0}, {2300.0, 1800.0}},
      {CameraModelType::kSimpleRadial, {3000.0, 2000.0, 1500.0, -0.05}, {2300.0, 1800.0}},
      {CameraModelType::kRadial, {3000.0, 2000.0, 1500.0, -0.05, 0.01}, {2300.0, 1800.0}},
      {CameraModelType::kOpenCv,
       {3000.0, 3010.0, 2000.0, 1500.0, -0.05, 0.01, 1e-3, -2e-3},
       {2300.0, 1800.0}},
      {CameraModelType::kFullOpenCv,
       {3000.0, 3010.0, 2000.0, 1500.0, -0.05, 0.01, 1e-3, -2e-3, 0.002, 0.01, -0.003, 0.0005},
       {2300.0, 1800.0}},
      {CameraModelType::kOpenCvFisheye,
       {3000.0, 3010.0, 2000.0, 1500.0, 0.03, -0.01, 0.002, -0.0003},
       {2300.0, 1800.0}},
  };
}

// EvaluateCameraModel with the model's own parameter count.
void Evaluate(const Case& c, const double* params, const double* ab, double* residual, double* d_ab,
              double* d_params) {
  const CameraModelData data;
  const double* obs = c.observation.data();
  switch (CameraModelNumParams(c.type)) {
    case 3:
      return EvaluateCameraModel<3>(c.type, params, ab, obs, data, residual, d_ab, d_params);
    case 4:
      return EvaluateCameraModel<4>(c.type, params, ab, obs, data, residual, d_ab, d_params);
    case 5:
      return EvaluateCameraModel<5>(c.type, params, ab, obs, data, residual, d_ab, d_params);
    case 8:
      return EvaluateCameraModel<8>(c.type, params, ab, obs, data, residual, d_ab, d_params);
    case 11:
      return EvaluateCameraModel<11>(c.type, params, ab, obs, data, residual, d_ab, d_params);
    case 12:
      return EvaluateCameraModel<12>(c.type, params, ab, obs, data, residual, d_ab, d_params);
  }
  FAIL() << "no instantiation for " << EnumName(c.type);
}

// The double-only residual, the reference of the derivatives.
Eigen::Vector2d Residual(const Case& c, const double* params, const double* ab) {
  Eigen::Vector2d r;
  CameraModelResidual(c.type, params, ab, c.observation.data(), CameraModelData(), r.data());
  return r;
}

double Step(double value) { return std::max(kMinStep, kRelativeStep * std::abs(value)); }

TEST(CameraModelJacobians, SimplePinholeByHand) {
  // r = observed - (f a + cx, f (-b) + cy) (COLMAP's y points down): f = 1000, cx = 500,
  // cy = 400, (a, b) = (0.1, 0.2), observed (610, 190) -> r = (610 - 600, 190 - 200) = (10, -10).
  // d r / d(a, b) = [-f 0; 0 f]; d r / d(f, cx, cy) = [-a -1 0; b 0 -1].
  const double params[3] = {1000.0, 500.0, 400.0};
  const double ab[2] = {0.1, 0.2};
  const double observation[2] = {610.0, 190.0};
  double residual[2], d_ab[4], d_params[6];
  EvaluateCameraModel<3>(CameraModelType::kSimplePinhole, params, ab, observation,
                         CameraModelData(), residual, d_ab, d_params);
  EXPECT_NEAR(residual[0], 10.0, 1e-12);
  EXPECT_NEAR(residual[1], -10.0, 1e-12);
  const double expected_ab[4] = {-1000.0, 0.0, 0.0, 1000.0};
  for (int k = 0; k < 4; ++k) EXPECT_DOUBLE_EQ(d_ab[k], expected_ab[k]) << k;
  const double expected_params[6] = {-0.1, -1.0, 0.0, 0.2, 0.0, -1.0};
  for (int k = 0; k < 6; ++k) EXPECT_DOUBLE_EQ(d_params[k], expected_params[k]) << k;
}

TEST(CameraModelJacobians, EveryModelAgreesWithCentralDifferences) {
  const double ab[2] = {0.12, -0.08};
  for (const Case& c : Cases()) {
    const int n = CameraModelNumParams(c.type);
    ASSERT_EQ(static_cast<int>(c.params.size()), n) << EnumName(c.type);
    double residual[2], d_ab[4];
    std::vector<double> d_params(2 * n);
    Evaluate(c, c.params.data(), ab, residual, d_ab, d_params.data());
    const Eigen::Vector2d expected = Residual(c, c.params.data(), ab);
    EXPECT_NEAR(residual[0], expected[0], 1e-9) << EnumName(c.type);
    EXPECT_NEAR(residual[1], expected[1], 1e-9) << EnumName(c.type);
    for (int j = 0; j < 2; ++j) {
      double plus[2] = {ab[0], ab[1]}, minus[2] = {ab[0], ab[1]};
      const double h = Step(ab[j]);
      plus[j] += h;
      minus[j] -= h;
      const Eigen::Vector2d numeric =
          (Residual(c, c.params.data(), plus) - Residual(c, c.params.data(), minus)) / (2.0 * h);
      for (int i = 0; i < 2; ++i)
        EXPECT_NEAR(d_ab[2 * i + j], numeric[i], kNumericTolerance)
            << EnumName(c.type) << " d r" << i << " / d ab" << j;
    }
    for (int j = 0; j < n; ++j) {
      std::vector<double> plus = c.params, minus = c.params;
      const double h = Step(c.params[j]);
      plus[j] += h;
      minus[j] -= h;
      const Eigen::Vector2d numeric =
          (Residual(c, plus.data(), ab) - Residual(c, minus.data(), ab)) / (2.0 * h);
      for (int i = 0; i < 2; ++i) {
        // Relative to the size of the derivative too: d r / d K3 is ~1e10 um per mm^-6.
        EXPECT_NEAR(d_params[i * n + j], numeric[i],
                    kNumericTolerance * std::max(1.0, std::abs(numeric[i])))
            << EnumName(c.type) << " d r" << i << " / d param " << j;
      }
    }
  }
}

TEST(CameraModelJacobians, WithoutParameterDerivativesTheRestIsTheSame) {
  const double ab[2] = {-0.05, 0.15};
  for (const Case& c : Cases()) {
    const int n = CameraModelNumParams(c.type);
    double residual[2], d_ab[4], residual_only[2], d_ab_only[4];
    std::vector<double> d_params(2 * n);
    Evaluate(c, c.params.data(), ab, residual, d_ab, d_params.data());
    Evaluate(c, c.params.data(), ab, residual_only, d_ab_only, nullptr);
    for (int i = 0; i < 2; ++i)
      EXPECT_EQ(residual[i], residual_only[i]) << EnumName(c.type);
    for (int k = 0; k < 4; ++k) EXPECT_EQ(d_ab[k], d_ab_only[k]) << EnumName(c.type);
  }
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
