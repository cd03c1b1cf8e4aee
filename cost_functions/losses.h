#pragma once
// Robust losses of the pose refinement and of the bundle adjustment's tie marks
// (BundleRobustnessOptions::tie_loss), beside the cost functions they weight. The residuals they
// act on are whitened (one unit = one standard deviation of the mark, cost_functions/
// collinearity_cost.h), so a loss scale is in standard deviations.

#include <ceres/loss_function.h>

#include "core/enum_names.h"

namespace photopose {

enum class LossType { kNone, kHuber, kSoftL1, kCauchy, kArctan, kTukey };

// Names for EnumName / ParseEnum / EnumChoices (core/enum_names.h).
inline constexpr EnumNameEntry<LossType> kLossTypeNames[] = {
    {LossType::kNone, "none"},     {LossType::kHuber, "huber"},   {LossType::kSoftL1, "softl1"},
    {LossType::kCauchy, "cauchy"}, {LossType::kArctan, "arctan"}, {LossType::kTukey, "tukey"}};
constexpr EnumNameTable<LossType> EnumNames(LossType) {
  return EnumNameTable<LossType>(kLossTypeNames);
}

// The Ceres loss of that type at scale `scale` (whitened units: standard deviations); nullptr for
// kNone. Owned by the caller (or by a ceres::Problem that takes ownership).
inline ceres::LossFunction* MakeLoss(LossType type, double scale) {
  switch (type) {
    case LossType::kNone:
      return nullptr;
    case LossType::kHuber:
      return new ceres::HuberLoss(scale);
    case LossType::kSoftL1:
      return new ceres::SoftLOneLoss(scale);
    case LossType::kCauchy:
      return new ceres::CauchyLoss(scale);
    case LossType::kArctan:
      // Ceres' ArctanLoss(a) is rho(s) = a atan(s / a): a is on the squared scale.
      return new ceres::ArctanLoss(scale * scale);
    case LossType::kTukey:
      return new ceres::TukeyLoss(scale);
  }
  return nullptr;
}

}  // namespace photopose
