#pragma once
// Camera models: how one image measurement relates to the ray of a ground point. Each model is
// written once, templated on the scalar, and serves the projection (double), the autodiff cost
// (Ceres Jets) and the analytic cost (the closed-form collinearity partials of core/collinearity.h
// chained with this function's derivatives, taken through small Jets of it: see
// cost_functions/camera_model_jacobians.h).
//
// Every model sees the ray through the seed's normalised image coordinates
//
//   (a, b) = (-u / w, -v / w),   (u, v, w) = R_camera_from_ground (X - X0)
//
// i.e. the image plane at unit distance, x right and y up (the seed's equations 4-5 with c = 1).
// A model turns (a, b) and its parameters into the residual "observed - computed" of one
// measurement, in the model's observation unit:
//
//  - kFrame, the ArcGIS frame-camera table (a photogrammetric "backward" model): the observation is
//    the measured film point (um, FilmCoordinateSystem of the table); it is corrected (affinity and
//    skew, principal point, lens distortion, Polarity) into the ideal image plane and compared with
//    the projection c (a, b). Residual in um on the image plane. Parameters (kFrameNumParams):
//      0 c   focal length (um)                 5 K2  radial (mm^-4)
//      1 xp  principal point x (um, film)       6 K3  radial (mm^-6)
//      2 yp  principal point y (um, film)       7 P1  decentring (mm^-1)
//      3 K0  radial (unitless)                  8 P2  decentring (mm^-1)
//      4 K1  radial (mm^-2)                     9 b1  affinity (unitless)   10 b2 skew (unitless)
//    The correction of a measured film point (x, y), all in the table's units:
//      x1 = (1 + b1) x + b2 y,  y1 = y                       (affinity and skew of the film axes)
//      xb = (x1 - xp) / 1000,  yb = (y1 - yp) / 1000          (mm from the principal point)
//      r2 = xb^2 + yb^2,  k = K0 + K1 r2 + K2 r2^2 + K3 r2^3
//      dx = xb k + P1 (r2 + 2 xb^2) + 2 P2 xb yb,  dy = yb k + 2 P1 xb yb + P2 (r2 + 2 yb^2)
//      ideal = Polarity sign * 1000 (xb - dx, yb - dy)          (um)
//    With DistortionType = DistortionTable the radial part is the table's d(r) (um) interpolated
//    linearly in r (d(0) = 0 implied, extrapolated past the last entry), and K, P are unused.
//    b1 and b2 are Metashape's affinity and skew, here as unitless ratios acting on the measured
//    film axes before the principal point (DBAT's "aspect" parameter is b1): being linear in the
//    film coordinates they fold exactly into the camera table's A0-B2 (FoldAffinityIntoAffine).
//  - The COLMAP models (computer-vision "forward" models): the observation is the pixel position
//    (Column, Row; (0, 0) at the top-left corner, Row down, as COLMAP); the ideal normalised point
//    (a, -b) (COLMAP's camera has y down) is distorted and scaled: pixel = f distorted + (cx, cy).
//    Residual in pixels. Parameters as COLMAP orders them:
//      SIMPLE_PINHOLE f, cx, cy                  PINHOLE fx, fy, cx, cy
//      SIMPLE_RADIAL  f, cx, cy, k               RADIAL  f, cx, cy, k1, k2
//      OPENCV         fx, fy, cx, cy, k1, k2, p1, p2
//      FULL_OPENCV    fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6
//      OPENCV_FISHEYE fx, fy, cx, cy, k1, k2, k3, k4
//    with u = a, v = -b, r2 = u^2 + v^2, radial = k1 r2 + k2 r2^2 (OPENCV) or
//    (1 + k1 r2 + k2 r2^2 + k3 r2^3) / (1 + k4 r2 + k5 r2^2 + k6 r2^3) - 1 (FULL_OPENCV) and
//      du = u radial + 2 p1 u v + p2 (r2 + 2 u^2),  dv = v radial + 2 p2 u v + p1 (r2 + 2 v^2);
//    OPENCV_FISHEYE (equidistant): theta = atan(r), theta_d = theta (1 + k1 theta^2 + k2 theta^4
//    + k3 theta^6 + k4 theta^8), (ud, vd) = (u, v) theta_d / r ((u, v) itself at r = 0).
//
// The two families are not the same polynomial with another sign: a backward model corrects a
// measured point, a forward model distorts an ideal one. photopose keeps each as it is defined;
// converting one into the other is a fit, never a change of sign.

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "core/enum_names.h"
#include "core/status.h"

namespace photopose {

struct FrameCamera;  // core/camera.h

enum class CameraModelType {
  kFrame,          // the ArcGIS frame-camera table (backward model), observations in film um
  kSimplePinhole,  // COLMAP SIMPLE_PINHOLE
  kPinhole,        // COLMAP PINHOLE
  kSimpleRadial,   // COLMAP SIMPLE_RADIAL
  kRadial,         // COLMAP RADIAL
  kOpenCv,         // COLMAP OPENCV
  kFullOpenCv,     // COLMAP FULL_OPENCV
  kOpenCvFisheye,  // COLMAP OPENCV_FISHEYE
};

// COLMAP's names (FRAME is photopose's own); case is ignored when parsing (core/enum_names.h).
inline constexpr EnumNameEntry<CameraModelType> kCameraModelTypeNames[] = {
    {CameraModelType::kFrame, "FRAME"},
    {CameraModelType::kSimplePinhole, "SIMPLE_PINHOLE"},
    {CameraModelType::kPinhole, "PINHOLE"},
    {CameraModelType::kSimpleRadial, "SIMPLE_RADIAL"},
    {CameraModelType::kRadial, "RADIAL"},
    {CameraModelType::kOpenCv, "OPENCV"},
    {CameraModelType::kFullOpenCv, "FULL_OPENCV"},
    {CameraModelType::kOpenCvFisheye, "OPENCV_FISHEYE"}};
constexpr EnumNameTable<CameraModelType> EnumNames(CameraModelType) {
  return EnumNameTable<CameraModelType>(kCameraModelTypeNames, NameMatch::kIgnoreCase);
}

// Number of parameters of each model, and the largest.
int CameraModelNumParams(CameraModelType type);
constexpr int kFrameNumParams = 11;
constexpr int kMaxCameraModelParams = 12;

// Whether a COLMAP model has two focal lengths (fx, fy, then cx, cy) rather than one (f, cx, cy).
constexpr bool ColmapModelHasTwoFocals(CameraModelType type) {
  return type == CameraModelType::kPinhole || type == CameraModelType::kOpenCv ||
         type == CameraModelType::kFullOpenCv || type == CameraModelType::kOpenCvFisheye;
}

// Indices of the kFrame parameters.
enum FrameParam : int {
  kFrameFocal = 0,
  kFramePrincipalX = 1,
  kFramePrincipalY = 2,
  kFrameK0 = 3,
  kFrameK1 = 4,
  kFrameK2 = 5,
  kFrameK3 = 6,
  kFrameP1 = 7,
  kFrameP2 = 8,
  kFrameAffinity = 9,
  kFrameSkew = 10,
};

// The parameter names of a model, in parameter order (kFrame: "FocalLength", "PrincipalX",
// "PrincipalY", "K0", "K1", "K2", "K3", "P1", "P2", "Affinity", "Skew"; COLMAP models: "f", "fx",
// "fy", "cx", "cy", "k", "k1" ... "k6", "p1", "p2").
std::vector<std::string> CameraModelParamNames(CameraModelType type);

// The parameters a self-calibration name selects (the names of `photopose bundle --calibrate`):
// FocalLength, PrincipalX, PrincipalY, K0, K1, K2, K3, P1, P2, Affinity, Skew (case-insensitive).
// For the COLMAP models FocalLength is f (or fx and fy), PrincipalX/Y are cx/cy, K1 is k1 (k for
// SIMPLE_RADIAL), K2 k2, K3 k3, P1 p1, P2 p2; each of the model's own parameter names
// (CameraModelParamNames: f, fx, fy, cx, cy, k, k1 ... k6, p1, p2) selects that parameter, and f
// selects fx and fy of the models with two focal lengths. A name the model lacks is an error naming
// it and the model.
Status CalibrationParamIndices(CameraModelType type, const std::string& name,
                               std::vector<int>* indices);

// Fixed data of a model's residual, never estimated. The pointers refer to the camera the data
// came from and must outlive every use.
struct CameraModelData {
  double polarity_sign = 1.0;  // kFrame: FrameCamera::polarity_sign() (+1 for Polarity -1)
  // kFrame with DistortionType = DistortionTable: table_size radial distances (um, increasing) and
  // distortions (um); null for the polynomial model. They point at the heap buffers of the camera
  // table's vectors, which stay put when the camera (or a vector of cameras) is moved.
  const double* table_radius_um = nullptr;
  const double* table_distortion_um = nullptr;
  int table_size = 0;
};

// The kFrame parameters and fixed data of a camera-table row, and the reverse (affinity and skew
// folded into A0-B2, see FoldAffinityIntoAffine).
std::array<double, kFrameNumParams> FrameModelParams(const FrameCamera& camera);
CameraModelData FrameModelData(const FrameCamera& camera);
// Writes c, xp, yp, K0..K3, P1, P2 into *camera, and folds b1, b2 into its pixel -> film affine
// (built from PixelSize, FilmCoordinateSystem and the image size when the camera has none). Fails
// when b1 or b2 is non-zero and the camera has no way from pixels to film.
Status SetFrameModelParams(const double* params, FrameCamera* camera);

// ------------------------------------------------------------------ the models

namespace camera_model_internal {

using std::sqrt;

// The table's radial distortion d(r) (um) at r (um): linear interpolation with d(0) = 0 implied
// when the table starts later, linear extrapolation past the last entry.
template <typename T>
T TableDistortion(const double* r, const double* d, int n, const T& radius) {
  if (n <= 0) return T(0.0);
  double r0 = 0.0, d0 = 0.0;
  int i = 0;
  if (r[0] <= 0.0) {
    r0 = r[0];
    d0 = d[0];
    i = 1;
  }
  for (; i < n; ++i) {
    if (radius <= T(r[i]) || i + 1 == n) {
      const double span = r[i] - r0;
      if (!(span > 0.0)) return T(d0);
      return T(d0) + (radius - T(r0)) * ((d[i] - d0) / span);
    }
    r0 = r[i];
    d0 = d[i];
  }
  return T(d0);
}

}  // namespace camera_model_internal

// kFrame: the ideal image-plane point (um) of a measured film point (um). Exact (no iteration).
template <typename T>
void FrameCorrectFilmPoint(const T* p, const double* film_um, const CameraModelData& data,
                           T* ideal_um) {
  const T x1 = (T(1.0) + p[kFrameAffinity]) * film_um[0] + p[kFrameSkew] * film_um[1];
  const T y1 = T(film_um[1]);
  if (data.table_radius_um != nullptr) {
    const T xb = x1 - p[kFramePrincipalX];
    const T yb = y1 - p[kFramePrincipalY];
    const T r2 = xb * xb + yb * yb;
    T dx(0.0), dy(0.0);
    if (r2 > T(0.0)) {
      using std::sqrt;
      const T r = sqrt(r2);
      const T scale = camera_model_internal::TableDistortion(
                          data.table_radius_um, data.table_distortion_um, data.table_size, r) /
                      r;
      dx = xb * scale;
      dy = yb * scale;
    }
    ideal_um[0] = data.polarity_sign * (xb - dx);
    ideal_um[1] = data.polarity_sign * (yb - dy);
    return;
  }
  const T xb = (x1 - p[kFramePrincipalX]) * 1e-3;  // mm
  const T yb = (y1 - p[kFramePrincipalY]) * 1e-3;
  const T r2 = xb * xb + yb * yb;
  const T k = p[kFrameK0] + r2 * (p[kFrameK1] + r2 * (p[kFrameK2] + r2 * p[kFrameK3]));
  const T dx = xb * k + p[kFrameP1] * (r2 + 2.0 * xb * xb) + 2.0 * p[kFrameP2] * xb * yb;
  const T dy = yb * k + 2.0 * p[kFrameP1] * xb * yb + p[kFrameP2] * (r2 + 2.0 * yb * yb);
  ideal_um[0] = data.polarity_sign * 1e3 * (xb - dx);
  ideal_um[1] = data.polarity_sign * 1e3 * (yb - dy);
}

// COLMAP's distortion of a normalised point (u, v) (y down), per model, written once.
template <typename T>
void ColmapDistort(CameraModelType type, const T* p, const T& u, const T& v, T* ud, T* vd) {
  switch (type) {
    case CameraModelType::kSimpleRadial: {
      const T radial = p[3] * (u * u + v * v);
      *ud = u + u * radial;
      *vd = v + v * radial;
      return;
    }
    case CameraModelType::kRadial: {
      const T r2 = u * u + v * v;
      const T radial = r2 * (p[3] + p[4] * r2);
      *ud = u + u * radial;
      *vd = v + v * radial;
      return;
    }
    case CameraModelType::kOpenCv:
    case CameraModelType::kFullOpenCv: {
      const T uu = u * u, vv = v * v, uv = u * v, r2 = uu + vv;
      T radial = r2 * (p[4] + p[5] * r2);
      if (type == CameraModelType::kFullOpenCv) {
        radial = (T(1.0) + r2 * (p[4] + r2 * (p[5] + r2 * p[8]))) /
                     (T(1.0) + r2 * (p[9] + r2 * (p[10] + r2 * p[11]))) -
                 T(1.0);
      }
      *ud = u + u * radial + 2.0 * p[6] * uv + p[7] * (r2 + 2.0 * uu);
      *vd = v + v * radial + 2.0 * p[7] * uv + p[6] * (r2 + 2.0 * vv);
      return;
    }
    case CameraModelType::kOpenCvFisheye: {
      const T r2 = u * u + v * v;
      // Below this r^2 theta_d / r = 1 - r^2 / 3 + ... is 1 to double precision (as COLMAP).
      if (!(r2 > T(1e-32))) {
        *ud = u;
        *vd = v;
        return;
      }
      using std::atan;
      using std::sqrt;
      const T r = sqrt(r2);
      const T theta = atan(r);
      const T t2 = theta * theta;
      const T theta_d = theta * (T(1.0) + t2 * (p[4] + t2 * (p[5] + t2 * (p[6] + t2 * p[7]))));
      const T scale = theta_d / r;
      *ud = u * scale;
      *vd = v * scale;
      return;
    }
    default:
      *ud = u;
      *vd = v;
      return;
  }
}

// The residual "observed - computed" of one measurement: observation in the model's unit (film um
// for kFrame, pixels otherwise), (a, b) the seed's normalised image coordinates of the ray.
template <typename T>
void CameraModelResidual(CameraModelType type, const T* p, const T* ab, const double* observation,
                         const CameraModelData& data, T* residual) {
  if (type == CameraModelType::kFrame) {
    T ideal[2];
    FrameCorrectFilmPoint(p, observation, data, ideal);
    residual[0] = ideal[0] - p[kFrameFocal] * ab[0];
    residual[1] = ideal[1] - p[kFrameFocal] * ab[1];
    return;
  }
  // COLMAP camera frame: x right, y down, z forward, so (u, v) = (a, -b).
  const T u = ab[0];
  const T v = -ab[1];
  T ud, vd;
  ColmapDistort(type, p, u, v, &ud, &vd);
  const bool two_focals = ColmapModelHasTwoFocals(type);
  const int cx = two_focals ? 2 : 1;
  const T& fx = p[0];
  const T& fy = two_focals ? p[1] : p[0];
  residual[0] = observation[0] - (fx * ud + p[cx]);
  residual[1] = observation[1] - (fy * vd + p[cx + 1]);
}

// ------------------------------------------------------------------ double-only helpers

// The normalised coordinates (a, b) of the ray of a measurement, for fixed parameters: kFrame
// exactly (ideal / c), the forward models by Newton iteration on their distortion to 1e-12 of the
// normalised coordinates. Fails (outside the model's invertible region) with a reason.
Status NormalizedFromObservation(CameraModelType type, const double* params,
                                 const CameraModelData& data, const Eigen::Vector2d& observation,
                                 Eigen::Vector2d* ab);
// The measurement (model unit) of the ray (a, b): the forward models exactly, kFrame by Newton
// iteration of its correction to 1e-7 um. Fails when the iteration does not converge.
Status ObservationFromNormalized(CameraModelType type, const double* params,
                                 const CameraModelData& data, const Eigen::Vector2d& ab,
                                 Eigen::Vector2d* observation);

// The focal length of a model in its observation unit per unit of normalised coordinates (c for
// kFrame, f or the mean of fx and fy): the scale from angles to residual units.
double CameraModelFocal(CameraModelType type, const double* params);

}  // namespace photopose
