#include "core/camera.h"

#include <Eigen/Dense>
#include <cmath>

#include "core/camera_models.h"
#include "core/fiducials.h"

namespace photopose {
namespace {

// Pixel -> film for PixelSize + FilmCoordinateSystem, column/row relative to the image centre.
Eigen::Vector2d FilmFromCentredPixel(FilmCoordinateSystem fcs, double dc, double dr, double ps) {
  switch (fcs) {
    case FilmCoordinateSystem::kXRightYUp:
      return {dc * ps, -dr * ps};
    case FilmCoordinateSystem::kXUpYLeft:
      return {-dr * ps, -dc * ps};
    case FilmCoordinateSystem::kXLeftYDown:
      return {-dc * ps, dr * ps};
    case FilmCoordinateSystem::kXDownYRight:
      return {dr * ps, dc * ps};
  }
  return {0.0, 0.0};
}

Eigen::Vector2d CentredPixelFromFilm(FilmCoordinateSystem fcs, const Eigen::Vector2d& f, double ps) {
  switch (fcs) {
    case FilmCoordinateSystem::kXRightYUp:
      return {f.x() / ps, -f.y() / ps};
    case FilmCoordinateSystem::kXUpYLeft:
      return {-f.y() / ps, -f.x() / ps};
    case FilmCoordinateSystem::kXLeftYDown:
      return {-f.x() / ps, f.y() / ps};
    case FilmCoordinateSystem::kXDownYRight:
      return {f.y() / ps, f.x() / ps};
  }
  return {0.0, 0.0};
}

double PixelOriginShift(PixelOrigin origin) { return origin == PixelOrigin::kCenter ? 0.5 : 0.0; }

}  // namespace

Status FrameCamera::IsValid() const {
  if (camera_id.empty()) return Status::Error("CameraID is empty");
  if (!(focal_length_um > 0.0) || !std::isfinite(focal_length_um))
    return Status::Error("FocalLength must be a positive number of micrometres");
  if (pixel_size_um < 0.0 || !std::isfinite(pixel_size_um))
    return Status::Error("PixelSize must be a positive number of micrometres");
  if (n_rows < 0 || n_columns < 0) return Status::Error("NRows and NColumns must be positive");
  if (has_affine) {
    const double det = affine_a[1] * affine_b[2] - affine_a[2] * affine_b[1];
    if (!(std::abs(det) > 0.0)) return Status::Error("affine A1 B2 - A2 B1 is zero: not invertible");
  }
  if (angle_direction != 1 && angle_direction != -1) return Status::Error("AngleDirection must be -1 or +1");
  if (polarity != 1 && polarity != -1) return Status::Error("Polarity must be -1 or +1");
  if (affine_direction != 1 && affine_direction != -1) return Status::Error("AffineDirection must be -1 or +1");
  if (!(earth_radius_m > 0.0)) return Status::Error("EarthRadius must be positive");
  if (distortion_type == DistortionType::kDistortionTable) {
    if (radial_distances_um.size() != radial_distortions_um.size())
      return Status::Error("RadialDistances and RadialDistortions differ in length");
    for (size_t i = 1; i < radial_distances_um.size(); ++i)
      if (!(radial_distances_um[i] > radial_distances_um[i - 1]))
        return Status::Error("RadialDistances must be strictly increasing");
  }
  return Status::Ok();
}

bool FrameCamera::HasPixelToFilm() const {
  return has_affine || (pixel_size_um > 0.0 && n_rows > 0 && n_columns > 0);
}

Status FrameCamera::PixelToFilmStatus() const {
  if (HasPixelToFilm()) return Status::Ok();
  std::string missing;
  if (!(pixel_size_um > 0.0)) missing = "PixelSize";
  if (n_rows <= 0 || n_columns <= 0)
    missing += std::string(missing.empty() ? "" : ", ") + "NRows and NColumns";
  return Status::Error("camera '" + camera_id + "' has no " + missing +
                       " (nor A0-A2/B0-B2): pixel marks cannot be turned into film coordinates");
}

double FrameCamera::MeanPixelSizeUm() const {
  if (pixel_size_um > 0.0) return pixel_size_um;
  if (has_affine) {
    const double det = std::abs(affine_a[1] * affine_b[2] - affine_a[2] * affine_b[1]);
    const double scale = std::sqrt(det);
    return affine_direction > 0 ? scale : 1.0 / scale;
  }
  return 1.0;
}

Status FilmFromPixel(const FrameCamera& camera, const Eigen::Vector2d& column_row, PixelOrigin origin,
                     Eigen::Vector2d* film_um) {
  const double col = column_row.x() + PixelOriginShift(origin);
  const double row = column_row.y() + PixelOriginShift(origin);
  if (camera.has_affine) {
    const auto& a = camera.affine_a;
    const auto& b = camera.affine_b;
    if (camera.affine_direction > 0) {
      *film_um = {a[0] + a[1] * col + a[2] * row, b[0] + b[1] * col + b[2] * row};
    } else {
      // col = A0 + A1 x + A2 y, row = B0 + B1 x + B2 y: solve for (x, y).
      Eigen::Matrix2d M;
      M << a[1], a[2], b[1], b[2];
      *film_um = M.inverse() * Eigen::Vector2d(col - a[0], row - b[0]);
    }
    return Status::Ok();
  }
  PHOTOPOSE_RETURN_IF_ERROR(camera.PixelToFilmStatus());
  *film_um = FilmFromCentredPixel(camera.film_coordinate_system, col - 0.5 * camera.n_columns,
                                  row - 0.5 * camera.n_rows, camera.pixel_size_um);
  return Status::Ok();
}

Status PixelFromFilm(const FrameCamera& camera, const Eigen::Vector2d& film_um, PixelOrigin origin,
                     Eigen::Vector2d* column_row) {
  Eigen::Vector2d cr;
  if (camera.has_affine) {
    const auto& a = camera.affine_a;
    const auto& b = camera.affine_b;
    if (camera.affine_direction < 0) {
      cr = {a[0] + a[1] * film_um.x() + a[2] * film_um.y(),
            b[0] + b[1] * film_um.x() + b[2] * film_um.y()};
    } else {
      Eigen::Matrix2d M;
      M << a[1], a[2], b[1], b[2];
      cr = M.inverse() * Eigen::Vector2d(film_um.x() - a[0], film_um.y() - b[0]);
    }
  } else {
    PHOTOPOSE_RETURN_IF_ERROR(camera.PixelToFilmStatus());
    cr = CentredPixelFromFilm(camera.film_coordinate_system, film_um, camera.pixel_size_um) +
         Eigen::Vector2d(0.5 * camera.n_columns, 0.5 * camera.n_rows);
  }
  *column_row = cr - Eigen::Vector2d::Constant(PixelOriginShift(origin));
  return Status::Ok();
}

Status FilmUmPerPixel(const FrameCamera& camera, const Eigen::Vector2d& column_row,
                      PixelOrigin origin, double* um_per_pixel) {
  Eigen::Vector2d at, right, down;
  PHOTOPOSE_RETURN_IF_ERROR(FilmFromPixel(camera, column_row, origin, &at));
  PHOTOPOSE_RETURN_IF_ERROR(FilmFromPixel(camera, column_row + Eigen::Vector2d(1, 0), origin, &right));
  PHOTOPOSE_RETURN_IF_ERROR(FilmFromPixel(camera, column_row + Eigen::Vector2d(0, 1), origin, &down));
  Eigen::Matrix2d J;
  J.col(0) = right - at;
  J.col(1) = down - at;
  *um_per_pixel = std::sqrt(std::abs(J.determinant()));
  return Status::Ok();
}

Eigen::Vector2d DistortionInMicrons(const FrameCamera& camera, const Eigen::Vector2d& xy_um) {
  // The kFrame model of core/camera_models.h with the principal point at the origin: its ideal
  // point is polarity (xy - distortion).
  std::array<double, kFrameNumParams> params = FrameModelParams(camera);
  params[kFramePrincipalX] = params[kFramePrincipalY] = 0.0;
  const CameraModelData data = FrameModelData(camera);
  double ideal[2];
  FrameCorrectFilmPoint(params.data(), xy_um.data(), data, ideal);
  return xy_um - data.polarity_sign * Eigen::Vector2d(ideal[0], ideal[1]);
}

Eigen::Vector2d ImagePlaneFromFilm(const FrameCamera& camera, const Eigen::Vector2d& film_um) {
  const std::array<double, kFrameNumParams> params = FrameModelParams(camera);
  double ideal[2];
  FrameCorrectFilmPoint(params.data(), film_um.data(), FrameModelData(camera), ideal);
  return {ideal[0], ideal[1]};
}

Status FilmFromImagePlane(const FrameCamera& camera, const Eigen::Vector2d& image_plane_um,
                          Eigen::Vector2d* film_um) {
  // The kFrame model's inverse at c = 1: its "normalised" point is then the image-plane point.
  std::array<double, kFrameNumParams> params = FrameModelParams(camera);
  params[kFrameFocal] = 1.0;
  return ObservationFromNormalized(CameraModelType::kFrame, params.data(), FrameModelData(camera),
                                   image_plane_um, film_um);
}

Status ImagePlaneFromPixel(const FrameCamera& camera, const Eigen::Vector2d& column_row,
                           PixelOrigin origin, Eigen::Vector2d* image_plane_um) {
  Eigen::Vector2d film;
  const Status status = FilmFromPixel(camera, column_row, origin, &film);
  if (!status.ok()) return status;
  *image_plane_um = ImagePlaneFromFilm(camera, film);
  return Status::Ok();
}

Status PixelFromImagePlane(const FrameCamera& camera, const Eigen::Vector2d& image_plane_um,
                           PixelOrigin origin, Eigen::Vector2d* column_row) {
  Eigen::Vector2d film;
  Status status = FilmFromImagePlane(camera, image_plane_um, &film);
  if (!status.ok()) return status;
  return PixelFromFilm(camera, film, origin, column_row);
}

void DistortionFromComputerVision(double k1, double k2, double k3, double p1, double p2, double f_mm,
                                  std::array<double, 4>* radial_k, std::array<double, 2>* tangential_p) {
  const double f2 = f_mm * f_mm;
  *radial_k = {0.0, k1 / f2, k2 / (f2 * f2), k3 / (f2 * f2 * f2)};
  *tangential_p = {-p1 / f_mm, -p2 / f_mm};
}

Status FitAffineFromFiducials(const FrameCamera& camera,
                              const std::vector<Eigen::Vector2d>& fiducials_column_row,
                              PixelOrigin origin, FrameCamera* calibrated) {
  if (fiducials_column_row.size() != camera.film_fiducials_um.size())
    return Status::Error("measured fiducials and FilmFiducials differ in number");
  FiducialFit fit;
  PHOTOPOSE_RETURN_IF_ERROR(FitPixelToFilmAffine(fiducials_column_row, camera.film_fiducials_um,
                                                 origin, &fit.affine));
  *calibrated = WithFiducialAffine(camera, fit);
  return Status::Ok();
}

}  // namespace photopose
