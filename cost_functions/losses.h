#pragma once
// Robust losses of the pose refinement, beside the cost functions they weight. The residuals they
// act on are whitened (one unit = one standard deviation of the mark, cost_functions/
// collinearity_cost.h), so a loss scale is in standard deviations.

#include <ceres/loss_function.h>

#include <optional>
#include <string>

namespace photopose {

enum class LossType { kNone, kHuber, kSoftL1, kCauchy, kArctan, kTukey };

// "none", "huber", "softl1", "cauchy", "arctan", "tukey".
const char* LossTypeName(LossType loss);
std::optional<LossType> ParseLossType(const std::string& name);
// "none, huber, softl1, cauchy, arctan or tukey", for messages and --help.
const char* LossTypeChoices();

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

// ------------------------------------------------------------------ inline definitions

namespace internal {
struct LossName {
  LossType type;
  const char* name;
};
inline constexpr LossName kLossNames[] = {
    {LossType::kNone, "none"},     {LossType::kHuber, "huber"},   {LossType::kSoftL1, "softl1"},
    {LossType::kCauchy, "cauchy"}, {LossType::kArctan, "arctan"}, {LossType::kTukey, "tukey"}};
}  // namespace internal

inline const char* LossTypeName(LossType loss) {
  for (const auto& entry : internal::kLossNames)
    if (entry.type == loss) return entry.name;
  return "?";
}

inline std::optional<LossType> ParseLossType(const std::string& name) {
  for (const auto& entry : internal::kLossNames)
    if (name == entry.name) return entry.type;
  return std::nullopt;
}

inline const char* LossTypeChoices() { return "none, huber, softl1, cauchy, arctan or tukey"; }

}  // namespace photopose
