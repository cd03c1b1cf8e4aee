#include "core/camera_models.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cctype>
#include <initializer_list>

#include "core/camera.h"

namespace photopose {
namespace {

// Newton iterations of the model inversions: the polynomial models converge in a handful; the
// limit only stops a point far outside the calibrated field.
constexpr int kMaxNewtonIterations = 50;
// Step of the central differences of the inversions' Jacobians: normalised coordinates are O(1),
// film micrometres O(1e4); both steps keep truncation and rounding errors far below the tolerance.
constexpr double kNormalizedStep = 1e-7;
constexpr double kFilmStepUm = 1e-3;
// Convergence of the inversions: 1e-12 in normalised coordinates is 1e-8 px at f = 10000 px;
// 1e-7 um on the film is 1e-8 of the smallest pixel photopose accepts.
constexpr double kNormalizedTolerance = 1e-12;
constexpr double kFilmToleranceUm = 1e-7;

std::string Upper(std::string text) {
  for (char& c : text) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return text;
}

// The parameters of each model (their names are in kCameraModelTypeNames).
struct ModelInfo {
  CameraModelType type;
  std::vector<std::string> params;
};

const std::vector<ModelInfo>& Models() {
  static const auto* const kModels = new std::vector<ModelInfo>{
      {CameraModelType::kFrame,
       {"FocalLength", "PrincipalX", "PrincipalY", "K0", "K1", "K2", "K3", "P1", "P2", "Affinity",
        "Skew"}},
      {CameraModelType::kSimplePinhole, {"f", "cx", "cy"}},
      {CameraModelType::kPinhole, {"fx", "fy", "cx", "cy"}},
      {CameraModelType::kSimpleRadial, {"f", "cx", "cy", "k"}},
      {CameraModelType::kRadial, {"f", "cx", "cy", "k1", "k2"}},
      {CameraModelType::kOpenCv, {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"}},
      {CameraModelType::kFullOpenCv,
       {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6"}},
      {CameraModelType::kOpenCvFisheye, {"fx", "fy", "cx", "cy", "k1", "k2", "k3", "k4"}},
  };
  return *kModels;
}

const ModelInfo& Info(CameraModelType type) {
  for (const ModelInfo& info : Models())
    if (info.type == type) return info;
  return Models().front();
}

// Residual of a model with the observation as the unknown of the inversion (double only).
Eigen::Vector2d Residual(CameraModelType type, const double* params, const CameraModelData& data,
                         const Eigen::Vector2d& ab, const Eigen::Vector2d& observation) {
  double r[2];
  CameraModelResidual(type, params, ab.data(), observation.data(), data, r);
  return {r[0], r[1]};
}

}  // namespace

int CameraModelNumParams(CameraModelType type) {
  return static_cast<int>(Info(type).params.size());
}

std::vector<std::string> CameraModelParamNames(CameraModelType type) { return Info(type).params; }

Status CalibrationParamIndices(CameraModelType type, const std::string& name,
                               std::vector<int>* indices) {
  indices->clear();
  const std::string upper = Upper(name);
  if (type == CameraModelType::kFrame) {
    const std::vector<std::string>& names = Info(type).params;
    for (size_t i = 0; i < names.size(); ++i)
      if (Upper(names[i]) == upper) indices->push_back(static_cast<int>(i));
  } else {
    // The calibration name -> the COLMAP parameter names it selects; a name the model lacks
    // selects nothing.
    const std::vector<std::string>& names = Info(type).params;
    const auto select = [&](std::initializer_list<const char*> wanted) {
      for (const char* name : wanted)
        for (size_t i = 0; i < names.size(); ++i)
          if (names[i] == name) indices->push_back(static_cast<int>(i));
    };
    // f (COLMAP's name) and FocalLength select every focal length of the model.
    if (upper == "FOCALLENGTH" || upper == "F") select({"f", "fx", "fy"});
    if (upper == "PRINCIPALX") select({"cx"});
    if (upper == "PRINCIPALY") select({"cy"});
    if (upper == "K1") select({"k", "k1"});
    if (upper == "K2") select({"k2"});
    if (upper == "K3") select({"k3"});
    if (upper == "P1") select({"p1"});
    if (upper == "P2") select({"p2"});
    // The model's own parameter names select themselves ("fx", "k4").
    if (indices->empty())
      for (size_t i = 0; i < names.size(); ++i)
        if (Upper(names[i]) == upper) indices->push_back(static_cast<int>(i));
  }
  if (indices->empty()) {
    return Status::Error("the " + std::string(EnumName(type)) +
                         " camera model has no parameter '" + name + "'");
  }
  return Status::Ok();
}

std::array<double, kFrameNumParams> FrameModelParams(const FrameCamera& camera) {
  return {camera.focal_length_um, camera.principal_x_um, camera.principal_y_um,
          camera.radial_k[0],     camera.radial_k[1],     camera.radial_k[2],
          camera.radial_k[3],     camera.tangential_p[0], camera.tangential_p[1],
          0.0,                    0.0};
}

CameraModelData FrameModelData(const FrameCamera& camera) {
  CameraModelData data;
  data.polarity_sign = camera.polarity_sign();
  if (camera.distortion_type == DistortionType::kDistortionTable) {
    data.table_radius_um = camera.radial_distances_um.data();
    data.table_distortion_um = camera.radial_distortions_um.data();
    data.table_size = static_cast<int>(
        std::min(camera.radial_distances_um.size(), camera.radial_distortions_um.size()));
  }
  return data;
}

Status SetFrameModelParams(const double* params, FrameCamera* camera) {
  const double b1 = params[kFrameAffinity];
  const double b2 = params[kFrameSkew];
  if (b1 != 0.0 || b2 != 0.0) {
    // film = L (col, row) + t today; the corrected film axes are B film with B = [1 + b1, b2; 0, 1].
    Eigen::Matrix2d L;
    Eigen::Vector2d t;
    Eigen::Vector2d origin, unit_col, unit_row;
    Status status = FilmFromPixel(*camera, {0.0, 0.0}, PixelOrigin::kCorner, &origin);
    if (status.ok()) status = FilmFromPixel(*camera, {1.0, 0.0}, PixelOrigin::kCorner, &unit_col);
    if (status.ok()) status = FilmFromPixel(*camera, {0.0, 1.0}, PixelOrigin::kCorner, &unit_row);
    if (!status.ok()) {
      return Status::Error("affinity and skew cannot be written into camera '" +
                           camera->camera_id + "': " + status.message());
    }
    t = origin;
    L.col(0) = unit_col - origin;
    L.col(1) = unit_row - origin;
    Eigen::Matrix2d B;
    B << 1.0 + b1, b2, 0.0, 1.0;
    const Eigen::Matrix2d BL = B * L;
    const Eigen::Vector2d Bt = B * t;
    camera->has_affine = true;
    camera->affine_direction = +1;
    camera->affine_a = {Bt.x(), BL(0, 0), BL(0, 1)};
    camera->affine_b = {Bt.y(), BL(1, 0), BL(1, 1)};
  }
  camera->focal_length_um = params[kFrameFocal];
  camera->principal_x_um = params[kFramePrincipalX];
  camera->principal_y_um = params[kFramePrincipalY];
  camera->radial_k = {params[kFrameK0], params[kFrameK1], params[kFrameK2], params[kFrameK3]};
  camera->tangential_p = {params[kFrameP1], params[kFrameP2]};
  return Status::Ok();
}

Status NormalizedFromObservation(CameraModelType type, const double* params,
                                 const CameraModelData& data, const Eigen::Vector2d& observation,
                                 Eigen::Vector2d* ab) {
  if (type == CameraModelType::kFrame) {
    if (!(params[kFrameFocal] != 0.0)) return Status::Error("the focal length is zero");
    double ideal[2];
    FrameCorrectFilmPoint(params, observation.data(), data, ideal);
    *ab = Eigen::Vector2d(ideal[0], ideal[1]) / params[kFrameFocal];
    if (!ab->allFinite()) return Status::Error("the corrected observation is not finite");
    return Status::Ok();
  }
  // Forward models: observed = f D(u, v) + c; solve D(u, v) = (observed - c) / f by Newton with a
  // central-difference Jacobian (as COLMAP undistorts).
  const bool two_focals = ColmapModelHasTwoFocals(type);
  const int cx = two_focals ? 2 : 1;
  const double fx = params[0], fy = two_focals ? params[1] : params[0];
  if (!(fx != 0.0) || !(fy != 0.0)) return Status::Error("the focal length is zero");
  const Eigen::Vector2d target((observation.x() - params[cx]) / fx,
                               (observation.y() - params[cx + 1]) / fy);
  auto distort = [&](const Eigen::Vector2d& uv) {
    double ud, vd;
    ColmapDistort(type, params, uv.x(), uv.y(), &ud, &vd);
    return Eigen::Vector2d(ud, vd);
  };
  Eigen::Vector2d uv = target;
  bool converged = false;
  for (int iteration = 0; iteration < kMaxNewtonIterations; ++iteration) {
    const Eigen::Vector2d f = distort(uv) - target;
    if (f.norm() < kNormalizedTolerance) {
      converged = true;
      break;
    }
    Eigen::Matrix2d J;
    for (int j = 0; j < 2; ++j) {
      Eigen::Vector2d h = Eigen::Vector2d::Zero();
      h[j] = kNormalizedStep;
      J.col(j) = (distort(uv + h) - distort(uv - h)) / (2.0 * kNormalizedStep);
    }
    if (!(std::abs(J.determinant()) > 1e-12))
      return Status::Error("the lens distortion folds over at this image point");
    uv -= J.inverse() * f;
    if (!uv.allFinite()) break;
  }
  if (!converged)
    return Status::Error("undistortion did not converge (a point far outside the calibrated field?)");
  *ab = Eigen::Vector2d(uv.x(), -uv.y());
  return Status::Ok();
}

Status ObservationFromNormalized(CameraModelType type, const double* params,
                                 const CameraModelData& data, const Eigen::Vector2d& ab,
                                 Eigen::Vector2d* observation) {
  if (type != CameraModelType::kFrame) {
    // The residual is observation - computed: computed is the residual at observation zero.
    *observation = -Residual(type, params, data, ab, Eigen::Vector2d::Zero());
    return Status::Ok();
  }
  // kFrame: solve correct(film) = c (a, b) for the film point by Newton with a central-difference
  // Jacobian, from the film point without distortion.
  const Eigen::Vector2d target = params[kFrameFocal] * ab;
  const double b1 = params[kFrameAffinity], b2 = params[kFrameSkew];
  const double film_y = data.polarity_sign * target.y() + params[kFramePrincipalY];
  const double x1 = data.polarity_sign * target.x() + params[kFramePrincipalX];
  Eigen::Vector2d film((x1 - b2 * film_y) / (1.0 + b1), film_y);
  for (int iteration = 0; iteration < kMaxNewtonIterations; ++iteration) {
    // Residual(film) = correct(film) - c ab.
    const Eigen::Vector2d f = Residual(type, params, data, ab, film);
    if (f.norm() < kFilmToleranceUm) {
      *observation = film;
      return Status::Ok();
    }
    Eigen::Matrix2d J;
    for (int j = 0; j < 2; ++j) {
      Eigen::Vector2d h = Eigen::Vector2d::Zero();
      h[j] = kFilmStepUm;
      J.col(j) = (Residual(type, params, data, ab, film + h) -
                  Residual(type, params, data, ab, film - h)) /
                 (2.0 * kFilmStepUm);
    }
    if (!(std::abs(J.determinant()) > 1e-12))
      return Status::Error("the lens distortion is not invertible at this image point");
    film -= J.inverse() * f;
    if (!film.allFinite()) break;
  }
  return Status::Error(
      "inverse distortion did not converge (point far outside the calibrated field?)");
}

double CameraModelFocal(CameraModelType type, const double* params) {
  if (ColmapModelHasTwoFocals(type)) return 0.5 * (params[0] + params[1]);
  return params[0];
}

}  // namespace photopose
