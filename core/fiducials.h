#pragma once
// Scanned film: the interior orientation of each scanned image from its measured fiducial marks.
//
// A film camera's fiducial marks have calibrated film coordinates (camera table FilmFiducials, um).
// A scan places them at some pixel position in every image, differently each time (the film sits in
// the scanner a little shifted and turned, the scan may shrink). A measured-fiducials table says
// where they were found (read by core/io/fiducials_table.h):
//
//   Raster, FiducialID, Column, Row        (pixels, the marks' pixel convention)
//
// FiducialID is the 1-based position of the fiducial in the camera's FilmFiducials list. For each
// image the six affine coefficients pixel -> film (A0-A2, B0-B2 of the camera table, AffineDirection
// +1) are fitted by least squares to its measured fiducials; the residuals (calibrated minus fitted
// film position, um) show how well the scan fits, and a poor fit (a misnumbered or mismeasured
// fiducial) is refused with the fiducial's line.

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/status.h"

namespace photopose {

// One row of the measured-fiducials table (core/io/fiducials_table.h).
struct MeasuredFiducial {
  std::string raster;
  int fiducial_id = 0;  // 1-based index into the camera's FilmFiducials
  Eigen::Vector2d column_row = Eigen::Vector2d::Zero();  // pixels
  int line = 0;                                          // source line, for messages
};

// The least-squares affine pixel -> film, x = A0 + A1 col + A2 row, y = B0 + B1 col + B2 row, of at
// least three point pairs that are not collinear; coefficients in the order A0, A1, A2, B0, B1, B2.
Status FitPixelToFilmAffine(const std::vector<Eigen::Vector2d>& column_row,
                            const std::vector<Eigen::Vector2d>& film_um, PixelOrigin origin,
                            std::array<double, 6>* coefficients);

struct FiducialResidual {
  int fiducial_id = 0;
  Eigen::Vector2d residual_um = Eigen::Vector2d::Zero();  // calibrated - fitted film position
  int line = 0;                                           // of the measurement
};

// The interior orientation of one scanned image.
struct FiducialFit {
  std::array<double, 6> affine{};  // A0, A1, A2, B0, B1, B2: pixel -> film (um)
  std::vector<FiducialResidual> residuals;
  double rms_um = 0.0;      // RMS of the residual norms
  double max_um = 0.0;      // largest residual norm
  int redundancy = 0;       // 2 n - 6: 0 with three fiducials (an exact fit that nothing checks)
};

struct FiducialFitOptions {
  // Largest accepted residual of a fiducial (um): scans fit their fiducials to a few um; a residual
  // beyond this means a misnumbered or mismeasured fiducial.
  double max_residual_um = 30.0;
  PixelOrigin pixel_origin = PixelOrigin::kCorner;
};

// Fits the affine of one image from its measured fiducials (all of the same raster). Errors name
// `file` and the line: an unknown FiducialID, a camera without FilmFiducials, fewer than three
// fiducials, collinear fiducials, or a residual beyond options.max_residual_um.
Status FitFiducials(const FrameCamera& camera, const std::vector<MeasuredFiducial>& measured,
                    const FiducialFitOptions& options, const std::string& file, FiducialFit* fit);

// `camera` with the fitted affine as its pixel -> film map (A0-B2, AffineDirection +1).
FrameCamera WithFiducialAffine(const FrameCamera& camera, const FiducialFit& fit);

}  // namespace photopose
