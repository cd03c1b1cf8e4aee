#pragma once
// A Ceres manifold for the 6-parameter exterior orientation block [X0, Y0, Z0, omega, phi, kappa]
// (m, rad, seed angles), so that the adjustment never meets the Euler angles' singularity.
//
// The block keeps the seed's angles (every cost function and table reads them), but a step is
// taken in a local frame: the centre moves by delta[0..2] (m) and the rotation by a small rotation
// applied on the camera side,
//
//   R_new = R_seed(delta_omega, delta_phi, delta_kappa) R,
//
// and the new angles are read back from R_new (AnglesFromRotation, |phi| <= 90 deg). At delta = 0
// d(angles)/d(delta) = M^-1 with M = [e_x, Rx(omega) e_y, Rx(omega) Ry(phi) e_z] (the axes of the
// three elementary rotations of R = Rx Ry Rz: dR = [M d(angles)]x R), so the step of the
// optimiser is well conditioned at any attitude; only the angles written out are singular at
// phi = +-90 deg, as the seed convention is.
//
// Components can be held fixed (fixed[k] true: the tangent space lacks them), which is how a
// relative block's gauge fixes one coordinate of its second image (COLMAP's convention).

#include <ceres/manifold.h>

#include <Eigen/Core>
#include <Eigen/LU>
#include <array>

#include "core/rotation.h"
#include "core/types.h"

namespace photopose {

class ExteriorOrientationManifold final : public ceres::Manifold {
 public:
  ExteriorOrientationManifold() : ExteriorOrientationManifold(std::array<bool, 6>{}) {}
  explicit ExteriorOrientationManifold(const std::array<bool, 6>& fixed) : fixed_(fixed) {
    for (int k = 0; k < 6; ++k)
      if (!fixed_[k]) free_[tangent_size_++] = k;
  }

  int AmbientSize() const override { return kExteriorOrientationSize; }
  int TangentSize() const override { return tangent_size_; }

  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override {
    double full[6];
    Expand(delta, full);
    for (int k = 0; k < 3; ++k) x_plus_delta[k] = x[k] + full[k];
    if (full[3] == 0.0 && full[4] == 0.0 && full[5] == 0.0) {
      for (int k = 3; k < 6; ++k) x_plus_delta[k] = x[k];
      return true;
    }
    const Eigen::Matrix3d R = RotationFromAngles(RotationConvention::kSeed, {x[3], x[4], x[5]});
    const Eigen::Matrix3d step =
        RotationFromAngles(RotationConvention::kSeed, {full[3], full[4], full[5]});
    const Eigen::Vector3d angles = AnglesFromRotation(RotationConvention::kSeed, step * R);
    for (int k = 0; k < 3; ++k) x_plus_delta[3 + k] = angles[k];
    return true;
  }

  // Row-major AmbientSize x TangentSize.
  bool PlusJacobian(const double* x, double* jacobian) const override {
    Eigen::Matrix<double, 6, 6> full = Eigen::Matrix<double, 6, 6>::Zero();
    full.topLeftCorner<3, 3>().setIdentity();
    full.bottomRightCorner<3, 3>() = AngleRatesFromRotationStep(x[3], x[4]);
    for (int r = 0; r < 6; ++r)
      for (int c = 0; c < tangent_size_; ++c) jacobian[r * tangent_size_ + c] = full(r, free_[c]);
    return true;
  }

  bool Minus(const double* y, const double* x, double* y_minus_x) const override {
    double full[6];
    for (int k = 0; k < 3; ++k) full[k] = y[k] - x[k];
    const Eigen::Matrix3d Rx = RotationFromAngles(RotationConvention::kSeed, {x[3], x[4], x[5]});
    const Eigen::Matrix3d Ry = RotationFromAngles(RotationConvention::kSeed, {y[3], y[4], y[5]});
    const Eigen::Vector3d step =
        AnglesFromRotation(RotationConvention::kSeed, Ry * Rx.transpose());
    for (int k = 0; k < 3; ++k) full[3 + k] = step[k];
    for (int c = 0; c < tangent_size_; ++c) y_minus_x[c] = full[free_[c]];
    return true;
  }

  // Row-major TangentSize x AmbientSize.
  bool MinusJacobian(const double* x, double* jacobian) const override {
    Eigen::Matrix<double, 6, 6> full = Eigen::Matrix<double, 6, 6>::Zero();
    full.topLeftCorner<3, 3>().setIdentity();
    full.bottomRightCorner<3, 3>() = RotationStepFromAngleRates(x[3], x[4]);
    for (int r = 0; r < tangent_size_; ++r)
      for (int c = 0; c < 6; ++c) jacobian[r * 6 + c] = full(free_[r], c);
    return true;
  }

  // M = [e_x, Rx(omega) e_y, Rx(omega) Ry(phi) e_z]: the rotation step per change of the angles.
  static Eigen::Matrix3d RotationStepFromAngleRates(double omega, double phi) {
    const double so = std::sin(omega), co = std::cos(omega);
    const double sp = std::sin(phi), cp = std::cos(phi);
    Eigen::Matrix3d M;
    M << 1.0, 0.0, sp,  //
        0.0, co, -so * cp,  //
        0.0, so, co * cp;
    return M;
  }
  // Its inverse: the change of the angles per rotation step (singular at phi = +-90 deg).
  static Eigen::Matrix3d AngleRatesFromRotationStep(double omega, double phi) {
    return RotationStepFromAngleRates(omega, phi).inverse();
  }

 private:
  void Expand(const double* delta, double* full) const {
    for (int k = 0; k < 6; ++k) full[k] = 0.0;
    for (int c = 0; c < tangent_size_; ++c) full[free_[c]] = delta[c];
  }

  std::array<bool, 6> fixed_;
  std::array<int, 6> free_{};
  int tangent_size_ = 0;
};

}  // namespace photopose
