#include "cost_functions/priors.h"

#include <gtest/gtest.h>

namespace photopose {
namespace {

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
  GroundPointPrior ground(Eigen::Vector3d(1.0, 2.0, 3.0), Eigen::Vector3d(0.1, 0.1, 0.2));
  const double point[3] = {1.1, 2.0, 2.6};
  const double* point_parameters[] = {point};
  ASSERT_TRUE(ground.Evaluate(point_parameters, residual, jacobians));
  EXPECT_NEAR(residual[0], 1.0, 1e-12);
  EXPECT_NEAR(residual[2], -2.0, 1e-12);
}

}  // namespace
}  // namespace photopose
