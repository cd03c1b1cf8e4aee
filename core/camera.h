#pragma once
// Interior orientation: the ArcGIS frame-camera "camera table" (see docs/formats.md for every field)
// and the chain of image coordinates
//
//   pixel (Column, Row)  <->  film (um, FilmCoordinateSystem)  <->  image plane (um)
//
// Pixel: continuous Column/Row, (0, 0) at the top-left corner of the image, Row down, so the centre
// of the first pixel is (0.5, 0.5) (PixelOrigin::kCorner, the default); PixelOrigin::kCenter puts
// (0, 0) at the centre of the first pixel.
// Film: micrometres from the fiducial centre (the image centre for digital cameras), axes as the
// FilmCoordinateSystem says (1: x right, y up, the default).
// Image plane: micrometres from the principal point, lens distortion removed, Polarity applied:
// the ideal (x, y) of the seed's collinearity equations 4-5 for a negative plane at w = -c.

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/enum_names.h"
#include "core/rotation.h"
#include "core/status.h"

namespace photopose {

enum class FilmCoordinateSystem : int {
  kXRightYUp = 1,   // origin at the centre, +x right, +y up (default)
  kXUpYLeft = 2,    // +x up, +y left
  kXLeftYDown = 3,  // +x left, +y down
  kXDownYRight = 4  // +x down, +y right
};
// The camera table's FilmCoordinateSystem values: the numbers 1-4 (written), the ArcGIS names
// accepted as aliases.
inline constexpr EnumNameEntry<FilmCoordinateSystem> kFilmCoordinateSystemNames[] = {
    {FilmCoordinateSystem::kXRightYUp, "1"},
    {FilmCoordinateSystem::kXUpYLeft, "2"},
    {FilmCoordinateSystem::kXLeftYDown, "3"},
    {FilmCoordinateSystem::kXDownYRight, "4"},
    {FilmCoordinateSystem::kXRightYUp, "X_RIGHT_Y_UP"},
    {FilmCoordinateSystem::kXUpYLeft, "X_UP_Y_LEFT"},
    {FilmCoordinateSystem::kXLeftYDown, "X_LEFT_Y_DOWN"},
    {FilmCoordinateSystem::kXDownYRight, "X_DOWN_Y_RIGHT"}};
constexpr EnumNameTable<FilmCoordinateSystem> EnumNames(FilmCoordinateSystem) {
  return EnumNameTable<FilmCoordinateSystem>(kFilmCoordinateSystemNames);
}

enum class DistortionType { kDistortionModel, kDistortionTable };
// The camera table's DistortionType values.
inline constexpr EnumNameEntry<DistortionType> kDistortionTypeNames[] = {
    {DistortionType::kDistortionModel, "DistortionModel"},
    {DistortionType::kDistortionTable, "DistortionTable"}};
constexpr EnumNameTable<DistortionType> EnumNames(DistortionType) {
  return EnumNameTable<DistortionType>(kDistortionTypeNames);
}

enum class OrientationType { kOpk, kMatrix };
// The camera table's OrientationType values.
inline constexpr EnumNameEntry<OrientationType> kOrientationTypeNames[] = {
    {OrientationType::kOpk, "OPK"}, {OrientationType::kMatrix, "Matrix"}};
constexpr EnumNameTable<OrientationType> EnumNames(OrientationType) {
  return EnumNameTable<OrientationType>(kOrientationTypeNames);
}
// Where pixel (0, 0) is: the top-left corner of the top-left pixel, or its centre.
enum class PixelOrigin { kCorner, kCenter };
inline constexpr EnumNameEntry<PixelOrigin> kPixelOriginNames[] = {{PixelOrigin::kCorner, "corner"},
                                                                  {PixelOrigin::kCenter, "center"}};
constexpr EnumNameTable<PixelOrigin> EnumNames(PixelOrigin) {
  return EnumNameTable<PixelOrigin>(kPixelOriginNames);
}

// One row of the camera table. Units in every name; defaults as the schema gives them.
struct FrameCamera {
  std::optional<long long> object_id;  // ObjectID
  std::string camera_id;               // CameraID (required)
  double focal_length_um = 0.0;        // FocalLength (required), micrometres
  double principal_x_um = 0.0;         // PrincipalX: PPA offset from the fiducial centre, um
  double principal_y_um = 0.0;         // PrincipalY, um
  double pixel_size_um = 0.0;          // PixelSize, um (0: not given)
  int n_rows = 0;                      // NRows (0: not given)
  int n_columns = 0;                   // NColumns (0: not given)
  // Pixel marks need a way from pixels to film: A0-B2, or PixelSize with NRows and NColumns (the
  // fiducial centre is the image centre). Film marks need neither (HasPixelToFilm).
  int n_bands = 0;                     // NBands (0: not given)
  std::string pixel_type;              // PixelType, kept as written
  std::string block_name;              // BlockName
  FilmCoordinateSystem film_coordinate_system = FilmCoordinateSystem::kXRightYUp;

  // A0 + A1 col + A2 row / B0 + B1 col + B2 row (AffineDirection +1: pixel -> film, um), or the
  // reverse mapping film -> pixel (AffineDirection -1). When given, it replaces PixelSize + FCS.
  bool has_affine = false;
  std::array<double, 3> affine_a{{0.0, 0.0, 0.0}};
  std::array<double, 3> affine_b{{0.0, 0.0, 0.0}};
  int affine_direction = +1;

  DistortionType distortion_type = DistortionType::kDistortionModel;
  // Radial K0..K3 in the table's millimetre-based units: K0 (unitless), K1 (mm^-2), K2 (mm^-4),
  // K3 (mm^-6); tangential P1, P2 (mm^-1). See DistortionInMicrons for the model.
  std::array<double, 4> radial_k{{0.0, 0.0, 0.0, 0.0}};
  std::array<double, 2> tangential_p{{0.0, 0.0}};
  // DistortionTable: radial distance r[i] (um) and radial distortion d[i] (um), r ascending.
  std::vector<double> radial_distances_um;
  std::vector<double> radial_distortions_um;

  std::vector<Eigen::Vector2d> film_fiducials_um;  // FilmFiducials, film coordinates (um)
  OrientationType orientation_type = OrientationType::kOpk;
  int angle_direction = -1;  // AngleDirection: -1 clockwise (default), +1 counterclockwise
  int polarity = -1;         // Polarity: -1 negative plane (default), +1 positive plane
  std::optional<double> average_z_m;  // AverageZ (m); the inverse projection uses 0 when unset
  bool apply_ecc = false;             // ApplyECC: earth-curvature correction
  double earth_radius_m = 6378137.0;  // EarthRadius (m)
  std::string srs;                    // SRS, kept as written
  // Columns the schema does not know, in table order (header name, value), kept for output.
  std::vector<std::pair<std::string, std::string>> extra_columns;

  // Consistency of the fields (positive focal length, PixelSize not negative, a non-singular
  // affine, ...). A camera without any way from pixels to film is valid: it serves film marks, and
  // a pixel mark that needs the way is refused where it is read (PixelToFilmStatus).
  Status IsValid() const;
  // Whether pixels can be turned into film: A0-B2 given, or PixelSize with NRows and NColumns.
  bool HasPixelToFilm() const;
  // Ok when HasPixelToFilm(); otherwise the error naming what is missing.
  Status PixelToFilmStatus() const;
  // The camera's AngleDirection as core/rotation.h takes it.
  AngleFlags angle_flags() const { return AngleFlags{angle_direction}; }
  // Sign applied to ideal film coordinates to get negative-plane coordinates: +1 for Polarity -1.
  double polarity_sign() const { return polarity > 0 ? -1.0 : 1.0; }
  // Film micrometres per pixel for residual scaling: PixelSize, else the mean affine scale.
  double MeanPixelSizeUm() const;
};

// Pixel (Column, Row) -> film (um) and back. Status errors when the camera has no way from pixels to
// film (no PixelSize with NRows/NColumns, no affine): PixelToFilmStatus().
Status FilmFromPixel(const FrameCamera& camera, const Eigen::Vector2d& column_row,
                     PixelOrigin origin, Eigen::Vector2d* film_um);
Status PixelFromFilm(const FrameCamera& camera, const Eigen::Vector2d& film_um, PixelOrigin origin,
                     Eigen::Vector2d* column_row);

// Film micrometres per pixel at a pixel position: the local scale sqrt|det J| of the pixel -> film
// map (J its 2 x 2 Jacobian, by differences over one pixel; exact for the affine maps of the camera
// table). Errors as FilmFromPixel.
Status FilmUmPerPixel(const FrameCamera& camera, const Eigen::Vector2d& column_row,
                      PixelOrigin origin, double* um_per_pixel);

// The lens distortion present at a measured point, in um: measured = ideal + distortion.
// DistortionModel (xb, yb the film coordinates relative to the principal point, in mm, r^2 = xb^2+yb^2):
//   dx = xb (K0 + K1 r^2 + K2 r^4 + K3 r^6) + P1 (r^2 + 2 xb^2) + 2 P2 xb yb
//   dy = yb (K0 + K1 r^2 + K2 r^4 + K3 r^6) + 2 P1 xb yb + P2 (r^2 + 2 yb^2)
// DistortionTable: radial d(r) by linear interpolation of (r[i], d[i]) (d(0) = 0 when the table
// starts later; linear extrapolation past the last entry), dx = xb d(r) / r.
Eigen::Vector2d DistortionInMicrons(const FrameCamera& camera, const Eigen::Vector2d& xy_from_pp_um);

// Film (um) -> ideal image plane (um): subtract the principal point, remove distortion (evaluated at
// the measured point), apply Polarity. Exact, no iteration.
Eigen::Vector2d ImagePlaneFromFilm(const FrameCamera& camera, const Eigen::Vector2d& film_um);
// Ideal image plane (um) -> film (um): the inverse, by fixed-point/Newton iteration to 1e-6 px.
// Returns an error when the iteration does not converge (far outside the calibrated field).
Status FilmFromImagePlane(const FrameCamera& camera, const Eigen::Vector2d& image_plane_um,
                          Eigen::Vector2d* film_um);

// Compositions of the above.
Status ImagePlaneFromPixel(const FrameCamera& camera, const Eigen::Vector2d& column_row,
                           PixelOrigin origin, Eigen::Vector2d* image_plane_um);
Status PixelFromImagePlane(const FrameCamera& camera, const Eigen::Vector2d& image_plane_um,
                           PixelOrigin origin, Eigen::Vector2d* column_row);

// The camera table's conversion of unit-free computer-vision coefficients (OpenCV's k1, k2, k3, p1,
// p2 for normalised coordinates) to its millimetre-based ones, f in mm:
// K1 = k1 / f^2, K2 = k2 / f^4, K3 = k3 / f^6, P1 = -p1 / f, P2 = -p2 / f (K0 = 0).
void DistortionFromComputerVision(double k1, double k2, double k3, double p1, double p2,
                                  double focal_length_mm, std::array<double, 4>* radial_k,
                                  std::array<double, 2>* tangential_p);

// Fits the six affine coefficients (pixel -> film, AffineDirection +1) from measured fiducials:
// pixel positions of the camera's FilmFiducials, in the same order. Needs at least three.
Status FitAffineFromFiducials(const FrameCamera& camera,
                              const std::vector<Eigen::Vector2d>& fiducials_column_row,
                              PixelOrigin origin, FrameCamera* calibrated);

}  // namespace photopose
