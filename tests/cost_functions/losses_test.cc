#include "cost_functions/losses.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "core/types.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

constexpr LossType kRobustLosses[] = {LossType::kHuber, LossType::kSoftL1, LossType::kCauchy,
                                      LossType::kArctan, LossType::kTukey};
// The scale every test uses: 2 standard deviations (the CLI's default --loss_scale).
constexpr double kScale = 2.0;
// Central differences at h = 1e-6 on the squared residual s (rho is smooth away from the kinks of
// Huber and Tukey at s = scale^2 = 4, which the points below avoid): truncation ~h^2 rho''' and
// rounding ~1e-16 rho / h, both below 1e-8 here.
constexpr double kStep = 1e-6;
constexpr double kDerivativeTolerance = 1e-7;

// [rho(s), rho'(s), rho''(s)] of MakeLoss(type, kScale).
Eigen::Vector3d Rho(LossType type, double s) {
  std::unique_ptr<ceres::LossFunction> loss(MakeLoss(type, kScale));
  double rho[3];
  loss->Evaluate(s, rho);
  return Eigen::Vector3d(rho[0], rho[1], rho[2]);
}

TEST(Losses, ValuesAtScaleTwoByHand) {
  // s is the squared whitened residual; a = scale = 2 standard deviations, so a^2 = 4.
  // Huber: s below a^2 is least squares (s = 1: 1); above, 2 a sqrt(s) - a^2 (s = 9: 12 - 4 = 8).
  EXPECT_NEAR(Rho(LossType::kHuber, 1.0)[0], 1.0, 1e-15);
  EXPECT_NEAR(Rho(LossType::kHuber, 9.0)[0], 8.0, 1e-14);
  // Soft L1: 2 a^2 (sqrt(1 + s / a^2) - 1); s = 12: 8 (sqrt(4) - 1) = 8.
  EXPECT_NEAR(Rho(LossType::kSoftL1, 12.0)[0], 8.0, 1e-14);
  // Cauchy: a^2 log(1 + s / a^2); s = 4: 4 log 2.
  EXPECT_NEAR(Rho(LossType::kCauchy, 4.0)[0], 4.0 * std::log(2.0), 1e-14);
  // Arctan: Ceres' ArctanLoss(b) is b atan(s / b), and MakeLoss passes b = a^2 = 4 so that the
  // scale is in standard deviations like the others; s = 4: 4 atan(1) = pi.
  EXPECT_NEAR(Rho(LossType::kArctan, 4.0)[0], kPi, 1e-14);
  // Tukey: a^2 / 3 (1 - (1 - s / a^2)^3) up to a^2, then a^2 / 3; s = 2: 4/3 (1 - 1/8) = 7/6;
  // s = 100: 4/3.
  EXPECT_NEAR(Rho(LossType::kTukey, 2.0)[0], 7.0 / 6.0, 1e-14);
  EXPECT_NEAR(Rho(LossType::kTukey, 100.0)[0], 4.0 / 3.0, 1e-14);
  // kNone is plain least squares: no loss object.
  EXPECT_EQ(MakeLoss(LossType::kNone, kScale), nullptr);
}

TEST(Losses, DerivativesAgreeWithCentralDifferences) {
  for (const LossType type : kRobustLosses) {
    for (const double s : {0.5, 2.5, 9.0, 30.0}) {
      const Eigen::Vector3d rho = Rho(type, s);
      const Eigen::Vector3d plus = Rho(type, s + kStep), minus = Rho(type, s - kStep);
      EXPECT_NEAR(rho[1], (plus[0] - minus[0]) / (2.0 * kStep), kDerivativeTolerance)
          << EnumName(type) << " s = " << s;
      EXPECT_NEAR(rho[2], (plus[1] - minus[1]) / (2.0 * kStep), kDerivativeTolerance)
          << EnumName(type) << " s = " << s;
    }
  }
}

TEST(Losses, TheScaleIsInStandardDeviations) {
  for (const LossType type : kRobustLosses) {
    // At zero every loss is least squares: rho = 0, rho' = 1.
    const Eigen::Vector3d zero = Rho(type, 0.0);
    EXPECT_EQ(zero[0], 0.0) << EnumName(type);
    EXPECT_NEAR(zero[1], 1.0, 1e-15) << EnumName(type);
    // A residual of a tenth of the scale keeps (almost) its full weight: rho'((0.2)^2) is 1
    // (Huber), 0.995 (soft L1), 0.990 (Cauchy), 0.9999 (arctan), 0.980 (Tukey).
    EXPECT_GT(Rho(type, std::pow(0.1 * kScale, 2))[1], 0.97) << EnumName(type);
    // Three times the scale is down-weighted: rho'(36) is 1/3 (Huber), 0.32 (soft L1), 0.1
    // (Cauchy), 1/82 (arctan), 0 (Tukey).
    EXPECT_LT(Rho(type, std::pow(3.0 * kScale, 2))[1], 0.5) << EnumName(type);
  }
}

TEST(Losses, NamesRoundTrip) {
  for (const LossType type : {LossType::kNone, LossType::kHuber, LossType::kSoftL1,
                              LossType::kCauchy, LossType::kArctan, LossType::kTukey}) {
    const std::string name = EnumName(type);
    ASSERT_EQ(ParseEnum<LossType>(name), type) << name;
    EXPECT_NE(std::string(EnumChoices<LossType>()).find(name), std::string::npos) << name;
  }
  EXPECT_EQ(std::string(EnumName(LossType::kSoftL1)), "softl1");
  EXPECT_FALSE(ParseEnum<LossType>("l1").has_value());
  EXPECT_FALSE(ParseEnum<LossType>("").has_value());
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
