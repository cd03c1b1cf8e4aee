#pragma once
// The derivatives of a camera model (core/camera_models.h) for the analytic cost functions: the
// model's one templated residual evaluated with Ceres Jets over (a, b) and, when asked, over the
// model's parameters. No second copy of any model is written for the derivatives.

#include <ceres/jet.h>

#include "core/camera_models.h"

namespace photopose {

// Evaluates CameraModelResidual of a model with kNumParams parameters at (a, b) and writes the
// residual (2), d residual / d(a, b) (2 x 2, row-major) and, when d_params is not null,
// d residual / d params (2 x kNumParams, row-major).
template <int kNumParams>
void EvaluateCameraModel(CameraModelType type, const double* params, const double* ab,
                         const double* observation, const CameraModelData& data, double* residual,
                         double* d_ab, double* d_params) {
  if (d_params == nullptr) {
    using Jet = ceres::Jet<double, 2>;
    Jet jet_ab[2] = {Jet(ab[0], 0), Jet(ab[1], 1)};
    Jet jet_params[kNumParams];
    for (int i = 0; i < kNumParams; ++i) jet_params[i] = Jet(params[i]);
    Jet r[2];
    CameraModelResidual(type, jet_params, jet_ab, observation, data, r);
    for (int k = 0; k < 2; ++k) {
      residual[k] = r[k].a;
      d_ab[2 * k] = r[k].v[0];
      d_ab[2 * k + 1] = r[k].v[1];
    }
    return;
  }
  using Jet = ceres::Jet<double, 2 + kNumParams>;
  Jet jet_ab[2] = {Jet(ab[0], 0), Jet(ab[1], 1)};
  Jet jet_params[kNumParams];
  for (int i = 0; i < kNumParams; ++i) jet_params[i] = Jet(params[i], 2 + i);
  Jet r[2];
  CameraModelResidual(type, jet_params, jet_ab, observation, data, r);
  for (int k = 0; k < 2; ++k) {
    residual[k] = r[k].a;
    d_ab[2 * k] = r[k].v[0];
    d_ab[2 * k + 1] = r[k].v[1];
    for (int i = 0; i < kNumParams; ++i) d_params[k * kNumParams + i] = r[k].v[2 + i];
  }
}

}  // namespace photopose
