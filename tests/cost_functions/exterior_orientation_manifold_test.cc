#include "cost_functions/exterior_orientation_manifold.h"

#include <ceres/manifold_test_utils.h>
#include <gtest/gtest.h>

#include <array>

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// Ceres' own manifold checks (Plus/Minus round trips, Jacobians against Ridders' numerical
// differentiation). The angles are read back through AnglesFromRotation, good to ~1e-15 rad away
// from phi = +-90 deg; 1e-9 leaves room for the numerical derivatives.
constexpr double kTolerance = 1e-9;

// The names EXPECT_THAT_MANIFOLD_INVARIANTS_HOLD uses unqualified (it is written for namespace
// ceres).
using ceres::HasCorrectMinusJacobianAt;
using ceres::HasCorrectPlusJacobianAt;
using ceres::HasCorrectRightMultiplyByPlusJacobianAt;
using ceres::MinusPlusIsIdentityAt;
using ceres::MinusPlusJacobianIsIdentityAt;
using ceres::PlusMinusIsIdentityAt;
using ceres::Vector;
using ceres::XMinusXIsZeroAt;
using ceres::XPlusZeroIsXAt;

Eigen::VectorXd Eo(double x, double y, double z, double omega, double phi, double kappa) {
  Eigen::VectorXd eo(6);
  eo << x, y, z, omega, phi, kappa;
  return eo;
}

TEST(ExteriorOrientationManifold, ARotationStepOnTheCameraSideByHand) {
  const ExteriorOrientationManifold manifold;
  EXPECT_EQ(manifold.AmbientSize(), 6);
  EXPECT_EQ(manifold.TangentSize(), 6);
  // From the identity attitude a step (0, 0, 0.1) is Rz(0.1) I: kappa = 0.1, and the centre just
  // adds its part.
  const double x[6] = {10.0, 20.0, 30.0, 0.0, 0.0, 0.0};
  const double delta[6] = {1.0, -2.0, 0.5, 0.0, 0.0, 0.1};
  double y[6];
  ASSERT_TRUE(manifold.Plus(x, delta, y));
  const double expected[6] = {11.0, 18.0, 30.5, 0.0, 0.0, 0.1};
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(y[k], expected[k], 1e-15) << k;
  // From omega = 90 deg a step about the camera's x axis adds to omega: Rx(0.2) Rx(pi/2) =
  // Rx(pi/2 + 0.2).
  const double tilted[6] = {0.0, 0.0, 0.0, kPi / 2.0, 0.0, 0.0};
  const double about_x[6] = {0.0, 0.0, 0.0, 0.2, 0.0, 0.0};
  ASSERT_TRUE(manifold.Plus(tilted, about_x, y));
  EXPECT_NEAR(y[3], kPi / 2.0 + 0.2, 1e-14);
  EXPECT_NEAR(y[4], 0.0, 1e-14);
  EXPECT_NEAR(y[5], 0.0, 1e-14);
  // M at (omega, phi) = (90 deg, 0): its columns are e_x, Rx(90) e_y = e_z and
  // Rx(90) Ry(0) e_z = -e_y.
  const Eigen::Matrix3d M = ExteriorOrientationManifold::RotationStepFromAngleRates(kPi / 2.0, 0.0);
  Eigen::Matrix3d expected_M;
  expected_M << 1.0, 0.0, 0.0,  //
      0.0, 0.0, -1.0,           //
      0.0, 1.0, 0.0;
  EXPECT_LT((M - expected_M).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(ExteriorOrientationManifold, InvariantsHoldAtGeneralAndSteepAttitudes) {
  const ExteriorOrientationManifold manifold;
  const Eigen::VectorXd points[] = {
      // A nadir aerial frame, in a local origin: at UTM magnitudes (4e6 m) the numerical
      // derivative of the centre rows is only good to ~2e-8 (rounding of x + h), while the
      // centre's part of Plus is an exact addition at any magnitude.
      Eo(500.0, 400.0, 300.0, 0.02, -0.03, 1.2),
      Eo(-3.0, 7.0, 40.0, 0.8, 0.6, -2.9),  // an oblique view
      Eo(1.0, 2.0, 3.0, -1.3, 1.45, 0.4),   // phi 83 deg: near the Euler singularity
  };
  for (const Eigen::VectorXd& x : points) {
    Eigen::VectorXd delta(6), y(6);
    delta << 0.5, -0.25, 1.0, 0.01, -0.02, 0.03;
    y = x;
    y.tail<3>() += Eigen::Vector3d(-0.05, 0.04, 0.1);
    y.head<3>() += Eigen::Vector3d(3.0, -1.0, 2.0);
    EXPECT_THAT_MANIFOLD_INVARIANTS_HOLD(manifold, x, delta, y, kTolerance);
  }
}

TEST(ExteriorOrientationManifold, PlusJacobianIsTheInverseOfTheAngleRates) {
  const double x[6] = {0.0, 0.0, 0.0, 0.3, -0.4, 0.9};
  const ExteriorOrientationManifold manifold;
  double plus[36], minus[36];
  ASSERT_TRUE(manifold.PlusJacobian(x, plus));
  ASSERT_TRUE(manifold.MinusJacobian(x, minus));
  const Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>> P(plus), Q(minus);
  // Minus' Jacobian times Plus' is the identity of the tangent space (centre rows included).
  EXPECT_LT((Q * P - Eigen::Matrix<double, 6, 6>::Identity()).cwiseAbs().maxCoeff(), 1e-12);
  // The centre moves as it is: an exact identity block, and nothing couples centre and angles.
  EXPECT_TRUE((P.topLeftCorner<3, 3>().array() == Eigen::Matrix3d::Identity().array()).all());
  EXPECT_TRUE((P.topRightCorner<3, 3>().array() == 0.0).all());
  EXPECT_TRUE((P.bottomLeftCorner<3, 3>().array() == 0.0).all());
  // The angle block is M^-1 (M from the header's formula, checked by hand above).
  const Eigen::Matrix3d M = ExteriorOrientationManifold::RotationStepFromAngleRates(0.3, -0.4);
  EXPECT_LT((P.bottomRightCorner<3, 3>() * M - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(),
            1e-12);
}

TEST(ExteriorOrientationManifold, FixedComponentsLeaveTheTangentSpace) {
  // Fix Y0 and kappa: the tangent space is (X0, Z0, omega, phi).
  const ExteriorOrientationManifold manifold(
      std::array<bool, 6>{false, true, false, false, false, true});
  ASSERT_EQ(manifold.TangentSize(), 4);
  const Eigen::VectorXd x = Eo(10.0, 20.0, 30.0, 0.1, -0.2, 0.3);
  // A step moves only the free components: Y0 stays, and the rotation step has no kappa part.
  const double delta[4] = {1.0, 2.0, 0.0, 0.0};
  double y[6];
  ASSERT_TRUE(manifold.Plus(x.data(), delta, y));
  EXPECT_EQ(y[0], 11.0);
  EXPECT_EQ(y[1], 20.0);
  EXPECT_EQ(y[2], 32.0);
  for (int k = 3; k < 6; ++k) EXPECT_EQ(y[k], x[k]) << k;
  // The round trip Minus(Plus(x, d), x) = d and the Jacobians hold in the smaller space.
  Eigen::VectorXd d(4);
  d << 0.5, -1.0, 0.02, -0.01;
  EXPECT_THAT(manifold, MinusPlusIsIdentityAt(x, d, kTolerance));
  EXPECT_THAT(manifold, HasCorrectPlusJacobianAt(x, kTolerance));
  EXPECT_THAT(manifold, HasCorrectMinusJacobianAt(x, kTolerance));
  EXPECT_THAT(manifold, MinusPlusJacobianIsIdentityAt(x, kTolerance));
  // The Plus Jacobian is the 6 x 4 selection of the free columns: the Y0 row is zero.
  double jacobian[24];
  ASSERT_TRUE(manifold.PlusJacobian(x.data(), jacobian));
  for (int c = 0; c < 4; ++c) EXPECT_EQ(jacobian[1 * 4 + c], 0.0) << c;
  EXPECT_EQ(jacobian[0 * 4 + 0], 1.0);
  EXPECT_EQ(jacobian[2 * 4 + 1], 1.0);
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
