#pragma once
// Prior cost functions for the weighted bundle adjustment (the bundle-objective seed note):
// control-point residuals / marker accuracy, camera-position (GNSS) residuals / camera accuracy, and
// attitude residuals / attitude accuracy. Residuals are whitened: (estimate - measured) / sigma, per
// axis. All but the lever-arm prior are linear in their parameters; their Jacobians are the
// diagonal 1 / sigma.

#include <ceres/ceres.h>

#include <Eigen/Core>

#include "core/rotation.h"
#include "core/types.h"

namespace photopose {

// Camera-position (GNSS) prior on X0, Y0, Z0. Parameter block: exterior orientation (6).
class CameraPositionPrior final : public ceres::SizedCostFunction<3, kExteriorOrientationSize> {
 public:
  CameraPositionPrior(const Eigen::Vector3d& measured_m, const Eigen::Vector3d& sigma_m)
      : measured_m_(measured_m), inverse_sigma_(sigma_m.cwiseInverse()) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    for (int i = 0; i < 3; ++i) residuals[i] = (parameters[0][i] - measured_m_[i]) * inverse_sigma_[i];
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, 3, 6, Eigen::RowMajor>> J(jacobians[0]);
      J.setZero();
      J.leftCols<3>() = inverse_sigma_.asDiagonal();
    }
    return true;
  }

 private:
  Eigen::Vector3d measured_m_;
  Eigen::Vector3d inverse_sigma_;
};

// Attitude prior on the seed angles omega, phi, kappa (rad; differences wrapped to (-pi, pi]).
// Parameter block: exterior orientation (6).
class AttitudePrior final : public ceres::SizedCostFunction<3, kExteriorOrientationSize> {
 public:
  AttitudePrior(const Eigen::Vector3d& measured_rad, const Eigen::Vector3d& sigma_rad)
      : measured_rad_(measured_rad), inverse_sigma_(sigma_rad.cwiseInverse()) {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    for (int i = 0; i < 3; ++i)
      residuals[i] = WrapAngle(parameters[0][3 + i] - measured_rad_[i]) * inverse_sigma_[i];
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, 3, 6, Eigen::RowMajor>> J(jacobians[0]);
      J.setZero();
      J.rightCols<3>() = inverse_sigma_.asDiagonal();
    }
    return true;
  }

 private:
  Eigen::Vector3d measured_rad_;
  Eigen::Vector3d inverse_sigma_;
};

// Two rows of a ground (control) point prior, for bundle adjustment: (X, Y) with axes {0, 1}, or
// (Z, 0) with axes {2, -1} (-1: a zero row). Split this way, every residual block on an eliminated
// point is 2 rows tall like the collinearity blocks, which keeps Ceres' fixed-size Schur
// specialisation (2, 3, 6) usable. Parameter block: ground point (3). Sigmas in metres.
class GroundPointPriorRows final : public ceres::SizedCostFunction<2, kPointSize> {
 public:
  GroundPointPriorRows(const Eigen::Vector3d& measured_m, const Eigen::Vector3d& sigma_m, int axis0,
                       int axis1)
      : measured_m_(measured_m), inverse_sigma_(sigma_m.cwiseInverse()), axes_{axis0, axis1} {}

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    double* J = (jacobians != nullptr) ? jacobians[0] : nullptr;
    for (int row = 0; row < 2; ++row) {
      const int axis = axes_[row];
      residuals[row] =
          axis < 0 ? 0.0 : (parameters[0][axis] - measured_m_[axis]) * inverse_sigma_[axis];
      if (J != nullptr)
        for (int k = 0; k < 3; ++k) J[3 * row + k] = (k == axis) ? inverse_sigma_[axis] : 0.0;
    }
    return true;
  }

 private:
  Eigen::Vector3d measured_m_;
  Eigen::Vector3d inverse_sigma_;
  int axes_[2];
};

// Camera-position (GNSS) prior with a lever arm: the antenna X0 + R^T l (l in the camera frame,
// m; R = R_camera_from_ground) against the measured position. Parameter blocks: exterior
// orientation (6), lever arm (3). Sigmas in metres. For autodiff (a handful per image).
struct CameraPositionLeverArmPrior {
  CameraPositionLeverArmPrior(const Eigen::Vector3d& measured_m, const Eigen::Vector3d& sigma_m)
      : measured_m(measured_m), inverse_sigma(sigma_m.cwiseInverse()) {}

  template <typename T>
  bool operator()(const T* eo, const T* lever, T* residual) const {
    T R[9];
    SeedRotationMatrix(eo[3], eo[4], eo[5], R);
    for (int i = 0; i < 3; ++i) {
      const T antenna = eo[i] + R[i] * lever[0] + R[3 + i] * lever[1] + R[6 + i] * lever[2];
      residual[i] = (antenna - measured_m[i]) * inverse_sigma[i];
    }
    return true;
  }

  static ceres::CostFunction* Create(const Eigen::Vector3d& measured_m,
                                     const Eigen::Vector3d& sigma_m) {
    return new ceres::AutoDiffCostFunction<CameraPositionLeverArmPrior, 3,
                                           kExteriorOrientationSize, 3>(
        new CameraPositionLeverArmPrior(measured_m, sigma_m));
  }

  Eigen::Vector3d measured_m;
  Eigen::Vector3d inverse_sigma;
};

}  // namespace photopose
