#pragma once
// DBAT (Damped Bundle Adjustment Toolbox, N. Boerlin) datasets for the tests: the camera XML,
// image list, mark points, control points, camera stations and report of a DBAT project, read
// into a photopose Block with a kFrame camera, and the exact conversion between DBAT's camera
// model 3 / exterior orientation and photopose's kFrame parameters / seed orientation.
// docs/dbat.md derives every formula below; tests/support/dbat_data_test.cc proves them on the
// shared c4040z calibration (../shared/data/dbat_c4040z) without any adjustment.
//
// DBAT's model 3 in its own terms (mm; (x, y) a mark in pixels, x right, y down, measured from
// the top-left corner of the image like the principal point; ps = sensor height / image height
// in mm per pixel; as = 1 - <aspect>):
//   d = ((1 + as)(ps x - ppx), -(ps y - ppy))                          (y turned up)
//   corrected = d + d (K1 r^2 + K2 r^4 + K3 r^6) + tangential(P1, P2; d),  r^2 = |d|^2
//   residual = -cc (Xc / Zc, Yc / Zc) - corrected,  (Xc, Yc, Zc) = M^T (X - X0),
//   M = Rx(omega) Ry(phi) Rz(kappa)
// photopose's kFrame (core/camera_models.h) with the parameters below gives, for the same mark,
// residual_photopose (um) = -1000 residual_DBAT:
//   c = 1000 cc, xp = 1000 (1 + as)(ppx - ps W / 2), yp = 1000 (ps H / 2 - ppy),
//   K1..K3 = -K1..-K3 (DBAT adds its correction, photopose subtracts it), K0 = 0,
//   P1 = -P1, P2 = -P2, Affinity b1 = as, Skew b2 = 0 (DBAT's skew acts after the distortion:
//   a non-zero one has no exact kFrame equivalent and is refused),
//   camera table PixelSize = 1000 ps (um), NColumns W, NRows H, marks read as Column/Row with
//   PixelOrigin::kCorner;
// and the orientation: R_camera_from_ground = M^T = RotationFromAngles(kOpk, (omega, phi, kappa)),
// the seed's (omega, phi, kappa) = AnglesFromRotation(kSeed, M^T), the centre unchanged.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/block.h"
#include "core/status.h"

namespace photopose::testing {

// A DBAT camera XML (<camera> of a dbat_camera document), model 3, in DBAT's units (mm).
struct DbatCamera {
  std::string id;                 // <id>
  std::string name;               // <name>
  int model = 0;                  // <model>: 3 is the only one converted
  double sensor_width_mm = 0.0;   // <sensor> first value; 0 for "auto" (square pixels)
  double sensor_height_mm = 0.0;  // <sensor> second value
  int image_width_px = 0;         // <image>
  int image_height_px = 0;
  double aspect = 1.0;            // <aspect> = 1 - as
  double focal_mm = 0.0;          // <focal>: nominal focal length
  double cc_mm = 0.0;             // <cc>: camera constant (0: not calibrated)
  Eigen::Vector2d pp_mm = Eigen::Vector2d::Zero();  // <pp>, from the top-left corner, y down
  double skew = 0.0;              // <skew>
  Eigen::Vector3d K = Eigen::Vector3d::Zero();     // <K>: K1 (mm^-2), K2 (mm^-4), K3 (mm^-6)
  Eigen::Vector2d P = Eigen::Vector2d::Zero();     // <P>: P1, P2 (mm^-1)

  double pixel_mm() const { return sensor_height_mm / image_height_px; }  // ps
  double as() const { return 1.0 - aspect; }
};

Status ReadDbatCameraXml(const std::string& path, DbatCamera* camera);

// DBAT's default initial values of a camera (set_initial_values io default): camera constant =
// the nominal focal length, principal point at the centre of the sensor, no distortion, aspect 1.
DbatCamera DbatDefaultCamera(const DbatCamera& camera);

// The conversion of the header comment, both ways. The kFrame camera's table carries camera_id,
// PixelSize, NColumns, NRows and the parameters; params in core/camera_models.h order.
Status BlockCameraFromDbat(const DbatCamera& dbat, BlockCamera* camera);
// The inverse (sensor, image size, names and nominal focal from `like`).
Status DbatFromBlockCamera(const BlockCamera& camera, const DbatCamera& like, DbatCamera* dbat);

// One line of a DBAT camera-stations file: "EO number, EO id, x, y, z, omega, phi, kappa, sx, sy,
// sz, so, sp, sk, label". The header says "Unit: degrees" but DBAT 0.9.2 writes the angles in
// RADIANS (photo 1's omega -0.687888 is the report's -39.413082 deg) and the position sigmas in a
// wrong unit (use the report's deviations); the angle sigmas are degrees.
struct DbatStation {
  int id = 0;
  std::string label;                                     // image file name
  Eigen::Vector3d center_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d angles_rad = Eigen::Vector3d::Zero();  // DBAT omega, phi, kappa
};
Status ReadDbatCameraStations(const std::string& path, std::vector<DbatStation>* stations);

// The seed orientation of a DBAT station (header comment).
ExteriorOrientation EoFromDbat(const Eigen::Vector3d& center_m, const Eigen::Vector3d& angles_rad);

// Published figures of a DBAT report (result/report.txt).
struct DbatReport {
  double sigma0 = 0.0;       // "Sigma0:" (unitless, image residuals over their sxy)
  double sigma0_px = 0.0;    // "Sigma0 (pixels):"
  int redundancy = 0;        // "Redundancy"
  int num_observations = 0;  // "Number of observations:" (image coordinates)
  // Camera values and deviations by DBAT's name: "cc", "px", "py", "K1".."K3", "P1", "P2", "as".
  std::vector<std::pair<std::string, Eigen::Vector2d>> camera;  // (value, deviation)
  struct Photo {
    std::string name;
    Eigen::Vector3d angles_deg, angle_sigma_deg;  // omega, phi, kappa
    Eigen::Vector3d center_m, center_sigma_m;     // Xc, Yc, Zc
  };
  std::vector<Photo> photos;
  double overall_rms_px = 0.0;  // "Overall point RMS"
};
Status ReadDbatReport(const std::string& path, DbatReport* report);

// The files of a DBAT project.
struct DbatDataset {
  std::string camera_xml;  // camera XML (input or calibrated)
  std::string images;      // "id, path"
  std::string marks;       // "image id, point id, x, y, sxy"
  std::string control;     // "id, label, x, y, z[, sxyz]"
  // The shared c4040z calibration (../shared/data/dbat_c4040z), with the input camera.
  static DbatDataset C4040z();
};

// The block of a DBAT project: one kFrame camera (BlockCameraFromDbat of `camera`), the images
// (named by their file name, no orientation: DBAT starts without approximate values), the control
// points (surveyed; accuracy_m = sxyz when the file has it, unset for DBAT's "fixed" points, which
// an adjustment reproducing DBAT must hold constant), a tie point per other point id, and the marks
// in pixels (Accuracy = sxy) with their film observations.
Status ReadDbatBlock(const DbatDataset& files, const DbatCamera& camera, Block* block);

}  // namespace photopose::testing
