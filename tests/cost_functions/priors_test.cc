#include "cost_functions/priors.h"

#include <gtest/gtest.h>

#include <memory>

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// Numerical-differentiation step and the agreement it allows: the lever-arm prior is smooth, and
// central differences at 1e-6 are good to ~1e-9 relative at these magnitudes.
constexpr double kStep = 1e-6;
constexpr double kNumericTolerance = 1e-7;

TEST(Priors, ResidualsAndJacobiansAreWhitened) {
  const double eo[6] = {10.0, 20.0, 30.0, 0.1, 0.2, kPi - 0.01};
  const double* parameters[] = {eo};
  double residual[3];
  double jacobian[18];
  double* jacobians[] = {jacobian};
  CameraPositionPrior position(Eigen::Vector3d(9.0, 20.5, 30.0), Eigen::Vector3d(0.5, 0.25, 1.0));
  ASSERT_TRUE(position.Evaluate(parameters, residual, jacobians));
  EXPECT_DOUBLE_EQ(residual[0], 2.0);
  EXPECT_DOUBLE_EQ(residual[1], -2.0);
  EXPECT_DOUBLE_EQ(residual[2], 0.0);
  EXPECT_DOUBLE_EQ(jacobian[0], 2.0);
  EXPECT_DOUBLE_EQ(jacobian[3], 0.0);
  // Attitude differences wrap: kappa = pi - 0.01 against -pi + 0.01 is -0.02, not 2 pi - 0.02.
  AttitudePrior attitude(Eigen::Vector3d(0.1, 0.2, -kPi + 0.01), Eigen::Vector3d::Constant(0.01));
  ASSERT_TRUE(attitude.Evaluate(parameters, residual, jacobians));
  EXPECT_NEAR(residual[2], -2.0, 1e-9);
  EXPECT_DOUBLE_EQ(jacobian[3], 100.0);  // row 0, column omega
}

TEST(Priors, ControlPointRowsSplitXYAndZ) {
  // Surveyed (1, 2, 3) m with sigmas (0.1, 0.2, 0.5) m; the estimate (1.1, 1.9, 2.0):
  // whitened residuals (0.1 / 0.1, -0.1 / 0.2, -1.0 / 0.5) = (1, -0.5, -2).
  const Eigen::Vector3d surveyed(1.0, 2.0, 3.0), sigma(0.1, 0.2, 0.5);
  const double point[3] = {1.1, 1.9, 2.0};
  const double* parameters[] = {point};
  double residual[2];
  double jacobian[6];
  double* jacobians[] = {jacobian};
  GroundPointPriorRows xy(surveyed, sigma, 0, 1);
  ASSERT_TRUE(xy.Evaluate(parameters, residual, jacobians));
  EXPECT_NEAR(residual[0], 1.0, 1e-12);
  EXPECT_NEAR(residual[1], -0.5, 1e-12);
  // Row-major 2 x 3: d r0 / dX = 1 / 0.1, d r1 / dY = 1 / 0.2, nothing else.
  const double expected_xy[6] = {10.0, 0.0, 0.0, 0.0, 5.0, 0.0};
  for (int k = 0; k < 6; ++k) EXPECT_DOUBLE_EQ(jacobian[k], expected_xy[k]) << k;
  // (Z, 0): the second row is a zero row with a zero Jacobian.
  GroundPointPriorRows z(surveyed, sigma, 2, -1);
  ASSERT_TRUE(z.Evaluate(parameters, residual, jacobians));
  EXPECT_NEAR(residual[0], -2.0, 1e-12);
  EXPECT_EQ(residual[1], 0.0);
  const double expected_z[6] = {0.0, 0.0, 2.0, 0.0, 0.0, 0.0};
  for (int k = 0; k < 6; ++k) EXPECT_DOUBLE_EQ(jacobian[k], expected_z[k]) << k;
  // Without Jacobians only the residuals are written.
  residual[0] = residual[1] = 99.0;
  ASSERT_TRUE(xy.Evaluate(parameters, residual, nullptr));
  EXPECT_NEAR(residual[0], 1.0, 1e-12);
}

TEST(Priors, LeverArmIsTurnedIntoTheGroundFrame) {
  // kappa = 90 deg, omega = phi = 0: R_camera_from_ground = Rz(90) = [0 -1 0; 1 0 0; 0 0 1], so a
  // lever arm l = (1, 2, 3) m in the camera frame is R^T l = (2, -1, 3) m in the ground frame.
  // With X0 = (100, 200, 50) the antenna is at (102, 199, 53); measured (102, 199.5, 52) with
  // sigmas (0.5, 0.5, 2) gives residuals (0, -1, 0.5).
  const double eo[6] = {100.0, 200.0, 50.0, 0.0, 0.0, kPi / 2.0};
  const double lever[3] = {1.0, 2.0, 3.0};
  const double* parameters[] = {eo, lever};
  std::unique_ptr<ceres::CostFunction> prior(CameraPositionLeverArmPrior::Create(
      Eigen::Vector3d(102.0, 199.5, 52.0), Eigen::Vector3d(0.5, 0.5, 2.0)));
  double residual[3];
  double d_eo[18], d_lever[9];
  double* jacobians[] = {d_eo, d_lever};
  ASSERT_TRUE(prior->Evaluate(parameters, residual, jacobians));
  EXPECT_NEAR(residual[0], 0.0, 1e-12);
  EXPECT_NEAR(residual[1], -1.0, 1e-12);
  EXPECT_NEAR(residual[2], 0.5, 1e-12);
  // d residual / d lever = R^T / sigma (row-major 3 x 3).
  const double expected_lever[9] = {0.0, 2.0, 0.0, -2.0, 0.0, 0.0, 0.0, 0.0, 0.5};
  for (int k = 0; k < 9; ++k) EXPECT_NEAR(d_lever[k], expected_lever[k], 1e-12) << k;
  // d residual / d eo against central differences at a general attitude.
  const double general[6] = {100.0, 200.0, 50.0, 0.3, -0.2, 1.1};
  const double* general_parameters[] = {general, lever};
  ASSERT_TRUE(prior->Evaluate(general_parameters, residual, jacobians));
  for (int j = 0; j < 6; ++j) {
    double plus[6], minus[6], r_plus[3], r_minus[3];
    for (int k = 0; k < 6; ++k) plus[k] = minus[k] = general[k];
    plus[j] += kStep;
    minus[j] -= kStep;
    const double* p_plus[] = {plus, lever};
    const double* p_minus[] = {minus, lever};
    ASSERT_TRUE(prior->Evaluate(p_plus, r_plus, nullptr));
    ASSERT_TRUE(prior->Evaluate(p_minus, r_minus, nullptr));
    for (int i = 0; i < 3; ++i)
      EXPECT_NEAR(d_eo[6 * i + j], (r_plus[i] - r_minus[i]) / (2.0 * kStep), kNumericTolerance)
          << "row " << i << " column " << j;
  }
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
