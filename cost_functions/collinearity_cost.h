#pragma once
// Ceres cost functions for the collinearity model of core/collinearity.h. Every cost only maps
// pointers and calls the model; the analytic ones use the closed-form partials of the same model.
//
// Residuals are whitened: (observed - projected) / (pixel_size_um * sigma_px), so one unit is one
// standard deviation of the observation and a robust-loss scale of s pixels is s / sigma_px.
//
//  - PoseCost*:     resection. Parameter block: exterior orientation [X0, Y0, Z0, omega, phi, kappa]
//                   (m, rad, seed). The ground point, focal length and the distortion-free ideal
//                   image-plane observation (um) are data.
//  - Collinearity*: bundle adjustment and self-calibration. Parameter blocks: exterior orientation
//                   (6), ground point (3), the camera model's parameters (core/camera_models.h).
//                   The measurement, in the model's observation unit, is data.
// A point behind the camera makes every cost return false (never a silent zero).

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>

#include "core/camera_models.h"
#include "core/collinearity.h"
#include "cost_functions/camera_model_jacobians.h"
#include "core/types.h"

namespace photopose {

// The one switch for the derivative path, used by the library, the CLI and the comparison tool.
enum class JacobianType { kAnalytic, kAutodiff };

inline constexpr EnumNameEntry<JacobianType> kJacobianTypeNames[] = {
    {JacobianType::kAnalytic, "analytic"}, {JacobianType::kAutodiff, "autodiff"}};
constexpr EnumNameTable<JacobianType> EnumNames(JacobianType) {
  return EnumNameTable<JacobianType>(kJacobianTypeNames);
}

// ------------------------------------------------------------------ resection (pose only)

// The templated residual shared by both pose costs.
struct PoseCostFunctor {
  PoseCostFunctor(const Eigen::Vector2d& observed_um, const Eigen::Vector3d& point_in_ground,
                  double focal_um, double inverse_sigma_um)
      : observed_um(observed_um),
        point_in_ground(point_in_ground),
        focal_um(focal_um),
        inverse_sigma_um(inverse_sigma_um) {}

  template <typename T>
  bool operator()(const T* eo, T* residual) const {
    const T point[3] = {T(point_in_ground[0]), T(point_in_ground[1]), T(point_in_ground[2])};
    T xy[2];
    if (!ProjectToImagePlane(eo, point, T(focal_um), xy)) return false;
    residual[0] = (T(observed_um[0]) - xy[0]) * inverse_sigma_um;
    residual[1] = (T(observed_um[1]) - xy[1]) * inverse_sigma_um;
    return true;
  }

  Eigen::Vector2d observed_um;
  Eigen::Vector3d point_in_ground;
  double focal_um;
  double inverse_sigma_um;  // 1 / (pixel_size_um * sigma_px)
};

class PoseCostAnalytic final : public ceres::SizedCostFunction<kResidualSize, kExteriorOrientationSize> {
 public:
  explicit PoseCostAnalytic(const PoseCostFunctor& data) : data_(data) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    double xy[2];
    double* d_eo = (jacobians != nullptr) ? jacobians[0] : nullptr;
    if (!ProjectWithJacobians(parameters[0], data_.point_in_ground.data(), data_.focal_um, xy, d_eo,
                              nullptr, nullptr)) {
      return false;
    }
    residuals[0] = (data_.observed_um[0] - xy[0]) * data_.inverse_sigma_um;
    residuals[1] = (data_.observed_um[1] - xy[1]) * data_.inverse_sigma_um;
    if (d_eo != nullptr) {
      for (int k = 0; k < 2 * kExteriorOrientationSize; ++k) d_eo[k] *= -data_.inverse_sigma_um;
    }
    return true;
  }

 private:
  PoseCostFunctor data_;
};

using PoseCostAutoDiff =
    ceres::AutoDiffCostFunction<PoseCostFunctor, kResidualSize, kExteriorOrientationSize>;

// Creates the pose cost with the requested derivative path (owned by the caller / the problem).
inline ceres::CostFunction* CreatePoseCost(JacobianType type, const PoseCostFunctor& data) {
  if (type == JacobianType::kAutodiff) return new PoseCostAutoDiff(new PoseCostFunctor(data));
  return new PoseCostAnalytic(data);
}

// ------------------------------------------------------------------ bundle (pose, point, camera)

// The templated residual of one measurement for bundle adjustment and self-calibration: the
// seed's collinearity ray (ProjectToNormalized) through a camera model (core/camera_models.h),
// whitened by the measurement's standard deviation in the model's observation unit.
struct CollinearityFunctor {
  CollinearityFunctor(CameraModelType model, const Eigen::Vector2d& observation,
                      const CameraModelData& data, double inverse_sigma)
      : observation{observation.x(), observation.y()},
        inverse_sigma(inverse_sigma),
        data(data),
        model(model) {}

  template <typename T>
  bool operator()(const T* eo, const T* point, const T* camera, T* residual) const {
    T ab[2];
    if (!ProjectToNormalized(eo, point, ab)) return false;
    CameraModelResidual(model, camera, ab, observation, data, residual);
    residual[0] *= inverse_sigma;
    residual[1] *= inverse_sigma;
    return true;
  }

  // A bundle adjustment holds one per mark (1.7 million for 1000 images): plain doubles, no
  // 16-byte-aligned Eigen member, and the members ordered so that nothing is padded (64 bytes).
  double observation[2];  // film um (kFrame) or pixels (COLMAP models)
  double inverse_sigma;   // 1 / sigma of the measurement, in the observation unit
  CameraModelData data;   // fixed data of the model (points into the camera it came from)
  CameraModelType model;
};
static_assert(sizeof(CollinearityFunctor) <= 64, "one per mark: keep it small");

// The analytic path: the closed-form collinearity partials (core/collinearity.h, c = 1) chained
// with the camera model's derivatives (cost_functions/camera_model_jacobians.h).
template <int kNumParams>
class CollinearityCostAnalytic final
    : public ceres::SizedCostFunction<kResidualSize, kExteriorOrientationSize, kPointSize,
                                      kNumParams> {
 public:
  explicit CollinearityCostAnalytic(const CollinearityFunctor& data) : data_(data) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const double* camera = parameters[2];
    double* d_eo = jacobians != nullptr ? jacobians[0] : nullptr;
    double* d_point = jacobians != nullptr ? jacobians[1] : nullptr;
    double* d_camera = jacobians != nullptr ? jacobians[2] : nullptr;
    double ab[2];
    double ab_eo[2 * kExteriorOrientationSize], ab_point[2 * kPointSize];
    if (!ProjectWithJacobians(parameters[0], parameters[1], 1.0, ab, d_eo ? ab_eo : nullptr,
                              d_point ? ab_point : nullptr, nullptr)) {
      return false;
    }
    const double s = data_.inverse_sigma;
    double r_ab[4];
    if (jacobians == nullptr) {
      // The residual alone needs no derivatives.
      CameraModelResidual(data_.model, camera, ab, data_.observation, data_.data, residuals);
    } else {
      EvaluateCameraModel<kNumParams>(data_.model, camera, ab, data_.observation,
                                      data_.data, residuals, r_ab, d_camera);
    }
    residuals[0] *= s;
    residuals[1] *= s;
    if (jacobians == nullptr) return true;
    if (d_eo != nullptr) {
      for (int k = 0; k < kExteriorOrientationSize; ++k) {
        const double x = ab_eo[k], y = ab_eo[kExteriorOrientationSize + k];
        d_eo[k] = s * (r_ab[0] * x + r_ab[1] * y);
        d_eo[kExteriorOrientationSize + k] = s * (r_ab[2] * x + r_ab[3] * y);
      }
    }
    if (d_point != nullptr) {
      for (int k = 0; k < kPointSize; ++k) {
        const double x = ab_point[k], y = ab_point[kPointSize + k];
        d_point[k] = s * (r_ab[0] * x + r_ab[1] * y);
        d_point[kPointSize + k] = s * (r_ab[2] * x + r_ab[3] * y);
      }
    }
    if (d_camera != nullptr)
      for (int k = 0; k < 2 * kNumParams; ++k) d_camera[k] *= s;
    return true;
  }

 private:
  CollinearityFunctor data_;
};

// Creates the collinearity cost of a measurement with the requested derivative path (owned by the
// caller or the problem). Parameter blocks: exterior orientation (6), ground point (3), camera
// parameters (CameraModelNumParams(data.model)).
ceres::CostFunction* CreateCollinearityCost(JacobianType type, const CollinearityFunctor& data);

// ------------------------------------------------------------------ inline definitions

namespace internal {
template <int kNumParams>
ceres::CostFunction* MakeCollinearityCost(JacobianType type, const CollinearityFunctor& data) {
  if (type == JacobianType::kAutodiff) {
    return new ceres::AutoDiffCostFunction<CollinearityFunctor, kResidualSize,
                                           kExteriorOrientationSize, kPointSize, kNumParams>(
        new CollinearityFunctor(data));
  }
  return new CollinearityCostAnalytic<kNumParams>(data);
}
}  // namespace internal

inline ceres::CostFunction* CreateCollinearityCost(JacobianType type,
                                                   const CollinearityFunctor& data) {
  switch (CameraModelNumParams(data.model)) {
    case 3:
      return internal::MakeCollinearityCost<3>(type, data);
    case 4:
      return internal::MakeCollinearityCost<4>(type, data);
    case 5:
      return internal::MakeCollinearityCost<5>(type, data);
    case 8:
      return internal::MakeCollinearityCost<8>(type, data);
    case 12:
      return internal::MakeCollinearityCost<12>(type, data);
    default:
      return internal::MakeCollinearityCost<kFrameNumParams>(type, data);
  }
}

}  // namespace photopose
