#include "core/rotation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/types.h"
#include "tests/support/ordered_draws.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// Elementwise formulas and products are evaluated in double; they agree to a few ulps.
constexpr double kElementTolerance = 1e-14;
// Angles recovered from a matrix: asin/atan2 near the limits lose a few digits.
constexpr double kAngleTolerance = 1e-11;

Eigen::Vector3d RandomAngles(std::mt19937_64* rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  return DrawLastFirst<3>([&](int i) { return (i == 1 ? 0.5 * kPi * 0.999 : kPi) * u(*rng); });
}

TEST(Rotation, SeedMatrixIsEquationOneElementByElement) {
  // Equation 1 of the lecture, as printed: [1 0 0; 0 cos w -sin w; 0 sin w cos w] times
  // [cos p 0 sin p; 0 1 0; -sin p 0 cos p] times [cos k -sin k 0; sin k cos k 0; 0 0 1].
  const double w = 0.3, p = -0.2, k = 1.1;
  Eigen::Matrix3d A, B, C;
  A << 1, 0, 0, 0, std::cos(w), -std::sin(w), 0, std::sin(w), std::cos(w);
  B << std::cos(p), 0, std::sin(p), 0, 1, 0, -std::sin(p), 0, std::cos(p);
  C << std::cos(k), -std::sin(k), 0, std::sin(k), std::cos(k), 0, 0, 0, 1;
  const Eigen::Matrix3d expected = A * B * C;
  const Eigen::Matrix3d R = RotationFromAngles(RotationConvention::kSeed, {w, p, k});
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(R(i, j), expected(i, j), kElementTolerance) << i << j;
  // The expanded template (used by the cost functions) is the same matrix.
  double flat[9];
  SeedRotationMatrix(w, p, k, flat);
  for (int i = 0; i < 9; ++i) EXPECT_NEAR(flat[i], expected(i / 3, i % 3), kElementTolerance);
}

TEST(Rotation, OpkMatchesWolfDewittElements) {
  // Wolf & Dewitt, Elements of Photogrammetry, the rotation matrix M (ground -> photo):
  // m11 = cos p cos k, m12 = sin w sin p cos k + cos w sin k, m13 = -cos w sin p cos k + sin w sin k
  // m21 = -cos p sin k, m22 = -sin w sin p sin k + cos w cos k, m23 = cos w sin p sin k + sin w cos k
  // m31 = sin p, m32 = -sin w cos p, m33 = cos w cos p.
  const double w = DegreesToRadians(-0.4109), p = DegreesToRadians(1.2101), k = DegreesToRadians(102.8003);
  const double sw = std::sin(w), cw = std::cos(w), sp = std::sin(p), cp = std::cos(p);
  const double sk = std::sin(k), ck = std::cos(k);
  Eigen::Matrix3d M;
  M << cp * ck, sw * sp * ck + cw * sk, -cw * sp * ck + sw * sk,  //
      -cp * sk, -sw * sp * sk + cw * ck, cw * sp * sk + sw * ck,  //
      sp, -sw * cp, cw * cp;
  const Eigen::Matrix3d R = RotationFromAngles(RotationConvention::kOpk, {w, p, k});
  EXPECT_LE((R - M).cwiseAbs().maxCoeff(), kElementTolerance);
  // And it is the transpose of the seed's matrix for the same three numbers.
  const Eigen::Matrix3d seed = RotationFromAngles(RotationConvention::kSeed, {w, p, k});
  EXPECT_LE((R - seed.transpose()).cwiseAbs().maxCoeff(), kElementTolerance);
}

TEST(Rotation, PokMatchesChineseTextbookElements) {
  // Y-primary system (e.g. Wang Zhizhuo, Principles of Photogrammetry): R = R_phi R_omega R_kappa
  // (photo -> ground) with
  // a1 = cos p cos k - sin p sin w sin k, a2 = -cos p sin k - sin p sin w cos k, a3 = -sin p cos w
  // b1 = cos w sin k, b2 = cos w cos k, b3 = -sin w
  // c1 = sin p cos k + cos p sin w sin k, c2 = -sin p sin k + cos p sin w cos k, c3 = cos p cos w
  // and x = -f (a1 dX + b1 dY + c1 dZ) / (a3 dX + b3 dY + c3 dZ): ground -> camera is R^T.
  const double w = 0.07, p = -0.12, k = 2.5;  // (omega, phi, kappa) in photopose's order
  const double sw = std::sin(w), cw = std::cos(w), sp = std::sin(p), cp = std::cos(p);
  const double sk = std::sin(k), ck = std::cos(k);
  Eigen::Matrix3d G;
  G << cp * ck - sp * sw * sk, -cp * sk - sp * sw * ck, -sp * cw,  //
      cw * sk, cw * ck, -sw,                                        //
      sp * ck + cp * sw * sk, -sp * sk + cp * sw * ck, cp * cw;
  const Eigen::Matrix3d R = RotationFromAngles(RotationConvention::kPok, {w, p, k});
  EXPECT_LE((R - G.transpose()).cwiseAbs().maxCoeff(), kElementTolerance);
}

TEST(Rotation, RoundTripsForEveryConvention) {
  std::mt19937_64 rng(11);
  for (RotationConvention convention :
       {RotationConvention::kSeed, RotationConvention::kOpk, RotationConvention::kPok}) {
    for (int i = 0; i < 2000; ++i) {
      Eigen::Vector3d angles = RandomAngles(&rng);
      // pok is Y-primary: its middle (limited) angle is omega, the first component.
      if (convention == RotationConvention::kPok) std::swap(angles[0], angles[1]);
      const Eigen::Matrix3d R = RotationFromAngles(convention, angles);
      EXPECT_TRUE(CheckRotationMatrix(R).ok());
      const Eigen::Vector3d back = AnglesFromRotation(convention, R);
      EXPECT_LE((back - angles).cwiseAbs().maxCoeff(), kAngleTolerance)
          << EnumName(convention);
      // Through the internal seed angles and back, as the tables do.
      const Eigen::Vector3d seed = AnglesFromRotation(RotationConvention::kSeed, R);
      const Eigen::Matrix3d again = RotationFromAngles(RotationConvention::kSeed, seed);
      EXPECT_LE((again - R).cwiseAbs().maxCoeff(), 1e-13);  // a few ulps of the trig functions
    }
  }
}

TEST(Rotation, GimbalLockGivesTheSameMatrix) {
  for (RotationConvention convention :
       {RotationConvention::kSeed, RotationConvention::kOpk, RotationConvention::kPok}) {
    for (double middle : {kPi / 2, -kPi / 2}) {
      Eigen::Vector3d angles(0.4, middle, -0.3);
      if (convention == RotationConvention::kPok) angles = Eigen::Vector3d(middle, 0.4, -0.3);
      const Eigen::Matrix3d R = RotationFromAngles(convention, angles);
      const Eigen::Matrix3d back = RotationFromAngles(convention, AnglesFromRotation(convention, R));
      EXPECT_LE((back - R).cwiseAbs().maxCoeff(), 1e-12) << EnumName(convention);
    }
  }
}

TEST(Rotation, ConventionsGiveDifferentPosesForTheSameNumbers) {
  const Eigen::Vector3d angles(0.1, 0.2, 0.3);
  const Eigen::Matrix3d seed = RotationFromAngles(RotationConvention::kSeed, angles);
  const Eigen::Matrix3d opk = RotationFromAngles(RotationConvention::kOpk, angles);
  const Eigen::Matrix3d pok = RotationFromAngles(RotationConvention::kPok, angles);
  EXPECT_GT((seed - opk).norm(), 0.1);
  EXPECT_GT((seed - pok).norm(), 0.1);
  EXPECT_GT((opk - pok).norm(), 0.05);
}

TEST(Rotation, RollPitchYawIsEquationOne) {
  const Eigen::Matrix3d R = RotationFromRollPitchYaw(0.05, -0.02, 1.3);
  EXPECT_LE((R - RotationFromAngles(RotationConvention::kSeed, {0.05, -0.02, 1.3})).norm(), 1e-15);
  const Eigen::Vector3d rpy = RollPitchYawFromRotation(R);
  EXPECT_NEAR(rpy[0], 0.05, kAngleTolerance);
  EXPECT_NEAR(rpy[1], -0.02, kAngleTolerance);
  EXPECT_NEAR(rpy[2], 1.3, kAngleTolerance);
}

TEST(Rotation, AngleDirectionNegatesOnlyForCounterclockwise) {
  const Eigen::Vector3d angles(0.1, -0.2, 0.3);
  EXPECT_EQ(ApplyAngleDirection(AngleFlags{-1}, angles), angles);
  EXPECT_EQ(ApplyAngleDirection(AngleFlags{+1}, angles), Eigen::Vector3d(-angles));
  EXPECT_EQ(ApplyAngleDirection(AngleFlags{+1}, ApplyAngleDirection(AngleFlags{+1}, angles)), angles);
}

TEST(Rotation, ParsesNamesAndRejectsOthers) {
  EXPECT_EQ(ParseEnum<RotationConvention>("OPK"), RotationConvention::kOpk);
  EXPECT_EQ(ParseEnum<RotationConvention>("rxryrz"), RotationConvention::kSeed);
  EXPECT_EQ(ParseEnum<RotationConvention>("seed"), RotationConvention::kSeed);  // the alias
  EXPECT_STREQ(EnumName(RotationConvention::kSeed), "rxryrz");
  EXPECT_EQ(ParseEnum<RotationConvention>("pok"), RotationConvention::kPok);
  EXPECT_FALSE(ParseEnum<RotationConvention>("kpo").has_value());
}

// The one boundary conversion: the angles of the convention, AngleDirection applied; its inverse;
// and the Jacobian the covariances are propagated with.
TEST(Rotation, BoundaryConversionRoundTripsForEveryConventionAndAngleDirection) {
  std::mt19937_64 rng(5);
  for (RotationConvention convention :
       {RotationConvention::kSeed, RotationConvention::kOpk, RotationConvention::kPok}) {
    for (int direction : {-1, +1}) {
      const AngleFlags flags{direction};
      for (int i = 0; i < 200; ++i) {
        const Eigen::Vector3d seed = RandomAngles(&rng);
        const Eigen::Vector3d out = ConventionAnglesFromSeed(convention, flags, seed);
        // The same rotation, written in the convention (negated for AngleDirection +1).
        const Eigen::Matrix3d R = RotationFromAngles(convention, ApplyAngleDirection(flags, out));
        EXPECT_LE((R - RotationFromAngles(RotationConvention::kSeed, seed)).cwiseAbs().maxCoeff(),
                  1e-13);
        const Eigen::Vector3d back = SeedAnglesFromConvention(convention, flags, out);
        EXPECT_LE((RotationFromAngles(RotationConvention::kSeed, back) -
                   RotationFromAngles(RotationConvention::kSeed, seed))
                      .cwiseAbs()
                      .maxCoeff(),
                  1e-13);
        // The Jacobian against a wider central difference.
        const Eigen::Matrix3d J = ConventionFromSeedJacobian(convention, flags, seed);
        for (int j = 0; j < 3; ++j) {
          Eigen::Vector3d h = Eigen::Vector3d::Zero();
          h[j] = 1e-5;
          Eigen::Vector3d d = ConventionAnglesFromSeed(convention, flags, seed + h) -
                              ConventionAnglesFromSeed(convention, flags, seed - h);
          for (int k = 0; k < 3; ++k) d[k] = WrapAngle(d[k]) / 2e-5;
          if (std::abs(std::cos(out[convention == RotationConvention::kPok ? 0 : 1])) > 0.05)
            EXPECT_LE((J.col(j) - d).cwiseAbs().maxCoeff(), 1e-5);
        }
      }
    }
  }
  // AngleDirection +1 negates exactly.
  const Eigen::Vector3d seed(0.1, -0.2, 0.3);
  EXPECT_LE((ConventionAnglesFromSeed(RotationConvention::kSeed, AngleFlags{+1}, seed) + seed)
                .cwiseAbs()
                .maxCoeff(),
            1e-15);
}

TEST(Rotation, ComputerVisionPoseByHand) {
  // The identity pose of COLMAP / OpenSfM looks along +z with y down: the seed's camera (u, v, w)
  // = (x, -y, -z) is Rx(pi), omega = pi; t = (1, 2, 3) puts the centre at -(1, 2, 3).
  const ExteriorOrientation eo =
      EoFromComputerVisionPose(Eigen::Matrix3d::Identity(), Eigen::Vector3d(1.0, 2.0, 3.0));
  EXPECT_NEAR((eo.center_in_ground() - Eigen::Vector3d(-1.0, -2.0, -3.0)).norm(), 0.0,
              kElementTolerance);
  const Eigen::Matrix3d R = RotationFromAngles(RotationConvention::kSeed, eo.angles_seed_rad());
  EXPECT_LT(
      (R - Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal().toDenseMatrix()).cwiseAbs().maxCoeff(),
      kElementTolerance);
  // And back, for random poses.
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::Vector3d r = DrawLastFirst<3>([&](int) { return 3.0 * u(rng); });
    const Eigen::Vector3d t = DrawLastFirst<3>([&](int) { return 100.0 * u(rng); });
    const Eigen::Matrix3d R_cv = RotationFromRotationVector(r);
    Eigen::Matrix3d R_back;
    Eigen::Vector3d t_back;
    ComputerVisionPoseFromEo(EoFromComputerVisionPose(R_cv, t), &R_back, &t_back);
    EXPECT_LT((R_back - R_cv).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((t_back - t).norm(), 1e-12 * 100.0);
  }
}

TEST(Rotation, RotationVectorByHandAndBack) {
  // A quarter turn about z takes x to y.
  const Eigen::Matrix3d R = RotationFromRotationVector(Eigen::Vector3d(0.0, 0.0, 0.5 * kPi));
  EXPECT_LT((R * Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitY()).norm(), kElementTolerance);
  EXPECT_EQ(RotationFromRotationVector(Eigen::Vector3d::Zero()), Eigen::Matrix3d::Identity());
  EXPECT_LT(RotationVectorFromRotation(Eigen::Matrix3d::Identity()).norm(), kElementTolerance);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 100; ++trial) {
    const double angle = 3.0 * std::abs(u(rng));  // drawn first (tests/support/ordered_draws.h)
    const Eigen::Vector3d r = DrawLastFirst<3>([&](int) { return u(rng); }).normalized() * angle;
    EXPECT_LT((RotationVectorFromRotation(RotationFromRotationVector(r)) - r).norm(), 1e-12);
  }
}

TEST(Rotation, CheckRotationMatrixRejectsReflectionsAndScaling) {
  EXPECT_TRUE(CheckRotationMatrix(Eigen::Matrix3d::Identity()).ok());
  EXPECT_FALSE(CheckRotationMatrix(-Eigen::Matrix3d::Identity()).ok());
  EXPECT_FALSE(CheckRotationMatrix(1.01 * Eigen::Matrix3d::Identity()).ok());
  Eigen::Matrix3d nan = Eigen::Matrix3d::Identity();
  nan(0, 0) = std::nan("");
  EXPECT_FALSE(CheckRotationMatrix(nan).ok());
}

TEST(Rotation, WrapAngleStaysInHalfOpenInterval) {
  EXPECT_NEAR(WrapAngle(3 * kPi), kPi, 1e-12);
  EXPECT_NEAR(WrapAngle(-kPi), kPi, 1e-12);
  EXPECT_NEAR(WrapAngle(0.5 + 4 * kPi), 0.5, 1e-12);
}

// WrapAngle returns an angle already in (-pi, pi] without the remainder call: bit for bit what the
// remainder gives, also at the ends (-pi goes to pi, pi stays) and just inside and outside them.
TEST(Rotation, WrapAngleShortcutIsTheRemainderBitForBit) {
  const auto by_remainder = [](double a) {
    a = std::remainder(a, 2.0 * kPi);
    return a <= -kPi ? a + 2.0 * kPi : a;
  };
  std::vector<double> angles = {0.0, -0.0, 1e-300, -1e-300, 0.5, -2.0, 3.0, -3.0};
  for (const double end : {kPi, -kPi, 2.0 * kPi, -2.0 * kPi, 3.0 * kPi}) {
    angles.push_back(end);
    angles.push_back(std::nextafter(end, 0.0));
    angles.push_back(std::nextafter(end, 2.0 * end));
  }
  for (int k = -400; k <= 400; ++k) angles.push_back(k * 0.0123456789);
  for (const double a : angles) {
    const double wrapped = WrapAngle(a);
    const double expected = by_remainder(a);
    EXPECT_EQ(std::signbit(wrapped), std::signbit(expected)) << a;
    EXPECT_EQ(wrapped, expected) << a;
  }
  EXPECT_EQ(WrapAngle(-kPi), kPi);
  EXPECT_TRUE(std::isnan(WrapAngle(std::nan(""))));
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
