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
//  - BundleCost*:   bundle adjustment and self-calibration. Parameter blocks: exterior orientation
//                   (6), ground point (3), intrinsics (kIntrinsicsSize: c, xp, yp (um), K0..K3,
//                   P1, P2 in camera-table units). The measured film point (um) is data.
// A point behind the camera makes every cost return false (never a silent zero).

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>

#include "core/collinearity.h"
#include "core/types.h"

namespace photopose {

// The one switch for the derivative path, used by the library, the CLI and the comparison tool.
enum class JacobianType { kAnalytic, kAutodiff };

std::optional<JacobianType> ParseJacobianType(const std::string& name);
const char* JacobianTypeName(JacobianType type);

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

// ------------------------------------------------------------------ bundle (pose, point, intrinsics)

struct BundleCostFunctor {
  BundleCostFunctor(const Eigen::Vector2d& film_um, double polarity_sign, double inverse_sigma_um)
      : film_um(film_um), polarity_sign(polarity_sign), inverse_sigma_um(inverse_sigma_um) {}

  template <typename T>
  bool operator()(const T* eo, const T* point, const T* intrinsics, T* residual) const {
    const double film[2] = {film_um[0], film_um[1]};
    if (!SelfCalibratingResidual(eo, point, intrinsics, film, polarity_sign, residual)) return false;
    residual[0] *= inverse_sigma_um;
    residual[1] *= inverse_sigma_um;
    return true;
  }

  Eigen::Vector2d film_um;   // measured film coordinates (um), FilmCoordinateSystem of the camera
  double polarity_sign;      // FrameCamera::polarity_sign()
  double inverse_sigma_um;   // 1 / (pixel_size_um * sigma_px)
};

class BundleCostAnalytic final
    : public ceres::SizedCostFunction<kResidualSize, kExteriorOrientationSize, kPointSize,
                                      kIntrinsicsSize> {
 public:
  explicit BundleCostAnalytic(const BundleCostFunctor& data) : data_(data) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  BundleCostFunctor data_;
};

using BundleCostAutoDiff = ceres::AutoDiffCostFunction<BundleCostFunctor, kResidualSize,
                                                       kExteriorOrientationSize, kPointSize,
                                                       kIntrinsicsSize>;

inline ceres::CostFunction* CreateBundleCost(JacobianType type, const BundleCostFunctor& data) {
  if (type == JacobianType::kAutodiff) return new BundleCostAutoDiff(new BundleCostFunctor(data));
  return new BundleCostAnalytic(data);
}

// ------------------------------------------------------------------ inline definitions

inline std::optional<JacobianType> ParseJacobianType(const std::string& name) {
  if (name == "analytic") return JacobianType::kAnalytic;
  if (name == "autodiff") return JacobianType::kAutodiff;
  return std::nullopt;
}

inline const char* JacobianTypeName(JacobianType type) {
  return type == JacobianType::kAnalytic ? "analytic" : "autodiff";
}

inline bool BundleCostAnalytic::Evaluate(double const* const* parameters, double* residuals,
                                         double** jacobians) const {
  const double* eo = parameters[0];
  const double* point = parameters[1];
  const double* in = parameters[2];
  const double s = data_.inverse_sigma_um;
  const double pol = data_.polarity_sign;

  double xy[2];
  double* d_eo = jacobians != nullptr ? jacobians[0] : nullptr;
  double* d_point = jacobians != nullptr ? jacobians[1] : nullptr;
  double d_focal[2];
  if (!ProjectWithJacobians(eo, point, in[kFocalLength], xy, d_eo, d_point, d_focal)) return false;

  // The corrected observation, exactly as CorrectFilmPoint (mm inside, um outside).
  const double xb = (data_.film_um[0] - in[kPrincipalX]) * 1e-3;
  const double yb = (data_.film_um[1] - in[kPrincipalY]) * 1e-3;
  const double r2 = xb * xb + yb * yb;
  const double radial = in[kK0] + r2 * (in[kK1] + r2 * (in[kK2] + r2 * in[kK3]));
  const double dx = xb * radial + in[kP1] * (r2 + 2.0 * xb * xb) + 2.0 * in[kP2] * xb * yb;
  const double dy = yb * radial + 2.0 * in[kP1] * xb * yb + in[kP2] * (r2 + 2.0 * yb * yb);
  residuals[0] = (pol * (xb - dx) * 1e3 - xy[0]) * s;
  residuals[1] = (pol * (yb - dy) * 1e3 - xy[1]) * s;
  if (jacobians == nullptr) return true;

  if (d_eo != nullptr)
    for (int k = 0; k < 2 * kExteriorOrientationSize; ++k) d_eo[k] *= -s;
  if (d_point != nullptr)
    for (int k = 0; k < 2 * kPointSize; ++k) d_point[k] *= -s;
  double* d_in = jacobians[2];
  if (d_in != nullptr) {
    // Rows x (0..8) and y (9..17) of the 2 x 9 row-major block.
    double* jx = d_in;
    double* jy = d_in + kIntrinsicsSize;
    const double ps = pol * s;
    jx[kFocalLength] = -d_focal[0] * s;
    jy[kFocalLength] = -d_focal[1] * s;
    // d radial / d r^2 and the partials of the distortion with respect to xb, yb.
    const double radial_prime = in[kK1] + r2 * (2.0 * in[kK2] + 3.0 * r2 * in[kK3]);
    const double ddx_dxb = radial + 2.0 * xb * xb * radial_prime + 6.0 * in[kP1] * xb + 2.0 * in[kP2] * yb;
    const double ddx_dyb = 2.0 * xb * yb * radial_prime + 2.0 * in[kP1] * yb + 2.0 * in[kP2] * xb;
    const double ddy_dxb = 2.0 * xb * yb * radial_prime + 2.0 * in[kP1] * yb + 2.0 * in[kP2] * xb;
    const double ddy_dyb = radial + 2.0 * yb * yb * radial_prime + 2.0 * in[kP1] * xb + 6.0 * in[kP2] * yb;
    // xb = (film - xp) / 1000, ideal = 1000 (xb - dx): d ideal / d xp = -(1 - ddx_dxb), etc.
    jx[kPrincipalX] = -(1.0 - ddx_dxb) * ps;
    jx[kPrincipalY] = ddx_dyb * ps;
    jy[kPrincipalX] = ddy_dxb * ps;
    jy[kPrincipalY] = -(1.0 - ddy_dyb) * ps;
    double power = 1e3;  // ideal is in um: d ideal / d K_i = -1000 xb r^(2i)
    const int k_index[4] = {kK0, kK1, kK2, kK3};
    for (int i = 0; i < 4; ++i) {
      jx[k_index[i]] = -xb * power * ps;
      jy[k_index[i]] = -yb * power * ps;
      power *= r2;
    }
    jx[kP1] = -(r2 + 2.0 * xb * xb) * 1e3 * ps;
    jy[kP1] = -2.0 * xb * yb * 1e3 * ps;
    jx[kP2] = -2.0 * xb * yb * 1e3 * ps;
    jy[kP2] = -(r2 + 2.0 * yb * yb) * 1e3 * ps;
  }
  return true;
}

}  // namespace photopose
