#include "core/fiducials.h"

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>

#include "core/io/csv.h"

namespace photopose {
namespace {

std::string Micrometres(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.1f um", value);
  return buffer;
}

}  // namespace

Status FitPixelToFilmAffine(const std::vector<Eigen::Vector2d>& column_row,
                            const std::vector<Eigen::Vector2d>& film_um, PixelOrigin origin,
                            std::array<double, 6>* coefficients) {
  const size_t n = column_row.size();
  if (n != film_um.size()) return Status::Error("pixel and film positions differ in number");
  if (n < 3) return Status::Error("an affine transformation needs at least three fiducials");
  const double shift = origin == PixelOrigin::kCenter ? 0.5 : 0.0;
  Eigen::MatrixXd A(n, 3);
  Eigen::VectorXd bx(n), by(n);
  for (size_t i = 0; i < n; ++i) {
    A.row(i) << 1.0, column_row[i].x() + shift, column_row[i].y() + shift;
    bx[i] = film_um[i].x();
    by[i] = film_um[i].y();
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  if (qr.rank() < 3) return Status::Error("the fiducials are collinear: the affine is undetermined");
  const Eigen::Vector3d a = qr.solve(bx), b = qr.solve(by);
  *coefficients = {a[0], a[1], a[2], b[0], b[1], b[2]};
  return Status::Ok();
}

Status FitFiducials(const FrameCamera& camera, const std::vector<MeasuredFiducial>& measured,
                    const FiducialFitOptions& options, const std::string& file, FiducialFit* fit) {
  if (measured.empty()) return Status::Error(file + ": no fiducials");
  const std::string& raster = measured.front().raster;
  const int count = static_cast<int>(camera.film_fiducials_um.size());
  if (count == 0) {
    return Status::Error(WhereInFile(file, measured.front().line, "FiducialID") + "camera '" +
                         camera.camera_id + "' of image '" + raster +
                         "' has no FilmFiducials in the camera table");
  }
  std::vector<Eigen::Vector2d> pixels, films;
  for (const MeasuredFiducial& f : measured) {
    if (f.fiducial_id > count) {
      return Status::Error(WhereInFile(file, f.line, "FiducialID") + std::to_string(f.fiducial_id) +
                           " is not a fiducial of camera '" + camera.camera_id + "' (it has " +
                           std::to_string(count) + ")");
    }
    pixels.push_back(f.column_row);
    films.push_back(camera.film_fiducials_um[f.fiducial_id - 1]);
  }
  FiducialFit result;
  const Status fitted = FitPixelToFilmAffine(pixels, films, options.pixel_origin, &result.affine);
  if (!fitted.ok())
    return Status::Error(WhereInFile(file, measured.front().line, "Column") + "image '" + raster +
                         "': " + fitted.message());
  const std::array<double, 6>& c = result.affine;
  const double det = c[1] * c[5] - c[2] * c[4];
  if (!(std::abs(det) > 0.0) || !std::isfinite(det))
    return Status::Error(WhereInFile(file, measured.front().line, "Column") + "image '" + raster +
                         "': the fitted affine is singular");
  const double shift = options.pixel_origin == PixelOrigin::kCenter ? 0.5 : 0.0;
  double ssq = 0.0;
  const FiducialResidual* worst = nullptr;
  for (size_t i = 0; i < measured.size(); ++i) {
    const double col = pixels[i].x() + shift, row = pixels[i].y() + shift;
    const Eigen::Vector2d fitted_film(c[0] + c[1] * col + c[2] * row, c[3] + c[4] * col + c[5] * row);
    result.residuals.push_back({measured[i].fiducial_id, films[i] - fitted_film, measured[i].line});
  }
  for (const FiducialResidual& r : result.residuals) {
    const double norm = r.residual_um.norm();
    ssq += norm * norm;
    if (worst == nullptr || norm > worst->residual_um.norm()) worst = &r;
  }
  result.rms_um = std::sqrt(ssq / result.residuals.size());
  result.max_um = worst->residual_um.norm();
  result.redundancy = 2 * static_cast<int>(measured.size()) - 6;
  if (!(result.max_um <= options.max_residual_um)) {
    return Status::Error(WhereInFile(file, worst->line, "Column") + "fiducial " +
                         std::to_string(worst->fiducial_id) + " of image '" + raster + "' is " +
                         Micrometres(result.max_um) + " from the affine fitted to the " +
                         std::to_string(measured.size()) + " fiducials (RMS " +
                         Micrometres(result.rms_um) + ", limit " +
                         Micrometres(options.max_residual_um) +
                         "): a misnumbered or mismeasured fiducial");
  }
  *fit = std::move(result);
  return Status::Ok();
}

FrameCamera WithFiducialAffine(const FrameCamera& camera, const FiducialFit& fit) {
  FrameCamera scanned = camera;
  scanned.has_affine = true;
  scanned.affine_direction = +1;
  scanned.affine_a = {fit.affine[0], fit.affine[1], fit.affine[2]};
  scanned.affine_b = {fit.affine[3], fit.affine[4], fit.affine[5]};
  return scanned;
}

}  // namespace photopose
