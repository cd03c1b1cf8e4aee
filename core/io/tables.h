#pragma once
// Reading and writing photopose's tables (docs/formats.md):
//  - the ArcGIS frame-camera camera table (CSV),
//  - the frames table (exterior orientation per raster: PerspectiveX/Y/Z, Omega/Phi/Kappa in decimal
//    degrees or Matrix),
//  - ground points (PointID, X, Y, Z, AccuracyX/Y/Z, Role),
//  - image marks (Raster, PointID, Column/Row in pixels or FilmX/FilmY in um, Accuracy, CameraID),
//  - OpenDroneMap's gcp_list.txt.
// One header for the five, one definition file per format: camera_table.cc, frames_table.cc,
// points_marks_tables.cc (points, marks and their consistency), gcp_list.cc, and tables.cc (the
// file wrappers); the column machinery they share is core/io/internal/table_fields.h.
// CSV header names are case-insensitive. Every reader reports a problem as a Status whose message is
// "file:line: column: what is wrong" and never crashes on bad input: inputs are bounded (core/io/csv.h)
// and every number must lie in its column's physical range (the limits below). Each Read* reads a
// file ("-" for standard input) and hands its text to the matching Parse*, which takes the name to
// use in messages. Each Format* checks every row and returns the text Write* writes; Write* writes
// it atomically (core/io/output_files.h), so a failed run leaves nothing half written.

#include <Eigen/Core>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/block.h"
#include "core/camera.h"
#include "core/io/output_files.h"
#include "core/rotation.h"
#include "core/status.h"
#include "core/types.h"

namespace photopose {

// ------------------------------------------------------------------ physical limits
// (docs/formats.md, "Limits and refusals"; a value outside is refused at the line carrying it.)

// Largest magnitude of a ground coordinate (m), a pixel coordinate (px) and a film coordinate or
// camera length (um): far beyond any survey, sensor or lens, still exact in a double to 1e-8.
constexpr double kMaxCoordinate = 1e8;
// Smallest FocalLength of a camera table (um): a thousand times below the shortest lens of any
// camera; a focal length near 0 makes every ray parallel and every adjustment fail unnamed.
constexpr double kMinFocalLengthUm = 1.0;
// Smallest focal length of a COLMAP or BAL camera (px; also of a camera in normalised image
// coordinates, f = 1).
constexpr double kMinFocalLengthPx = 1e-3;
// Largest component of a BAL rotation vector (rad): a hundred and fifty turns.
constexpr double kMaxRotationVectorRad = 1e3;
// PixelSize (um) lies strictly between these; so does the pixel size an affine implies.
constexpr double kMinPixelSizeUm = 1e-3;
constexpr double kMaxPixelSizeUm = 1e3;
// NRows and NColumns, when given (pixels).
constexpr int kMinImageSidePx = 2;
constexpr int kMaxImageSidePx = 1000000;
// An affine is singular when |A1 B2 - A2 B1| < this * max(|A1|, |A2|, |B1|, |B2|)^2: its rows are
// parallel to about a micro-radian.
constexpr double kMinAffineDeterminantRatio = 1e-6;
// Inside the image the distortion correction must keep the corrected radius increasing and within
// this factor of the measured radius (real lenses described by these models stay below 2).
constexpr double kMaxDistortionScale = 3.0;
// A mark may lie outside its image by at most this fraction of the image's width (Column) or
// height (Row), when the camera's image size is known.
constexpr double kMarkOutsideImageFraction = 0.05;

// ------------------------------------------------------------------ camera table
Status ReadCameraTable(const std::string& path, std::vector<FrameCamera>* cameras);
Status ParseCameraTable(std::string_view text, const std::string& file_name,
                        std::vector<FrameCamera>* cameras);
Status WriteCameraTable(const std::string& path, const std::vector<FrameCamera>& cameras);
// The text WriteCameraTable writes; `path` names the file in messages.
Status FormatCameraTable(const std::vector<FrameCamera>& cameras, const std::string& path,
                         std::string* text);

// ------------------------------------------------------------------ frames table
struct FrameRecord {
  std::string raster;     // Raster: image name (key)
  std::string camera_id;  // CameraID
  ExteriorOrientation eo; // internal seed convention, converted on reading / writing
  std::string srs;        // SRS, kept as written
  // Optional 6x6 covariance of eo.parameters (X0, Y0, Z0 in m; seed omega, phi, kappa in rad), as
  // the solver reports it (resection: a-priori with stated accuracies, sigma0^2-scaled without;
  // bundle: sigma0^2-scaled). The writer propagates it to the angles of the convention written and
  // writes the standard deviations.
  std::optional<Matrix6d> covariance;
  std::optional<double> sigma0;  // a posteriori sigma0 (unitless)
  // Accuracy of the exterior orientation as measured (GNSS / IMU), one sigma per component, all
  // three or none: AccuracyX/Y/Z (m) of PerspectiveX/Y/Z and AccuracyOmega/Phi/Kappa (degrees, of
  // the angles as the file gives them: its convention, AngleDirection applied). Kept as read and
  // written back; the block (core/block.h) turns them into prior accuracies.
  std::optional<Eigen::Vector3d> center_accuracy_m;
  std::optional<Eigen::Vector3d> attitude_accuracy_deg;
  // Further numeric/text columns written after the standard ones (e.g. NumObservations).
  std::vector<std::pair<std::string, std::string>> extra_columns;
  int line = 0;  // source line when read, for messages
};

struct FramesTableOptions {
  // Convention of Omega/Phi/Kappa in the file. Angles are decimal degrees.
  RotationConvention convention = RotationConvention::kSeed;
  // Camera table flags (AngleDirection) are looked up by CameraID when the cameras are given.
  const std::vector<FrameCamera>* cameras = nullptr;
};

// Reads Raster, CameraID, PerspectiveX, PerspectiveY, PerspectiveZ and either Omega, Phi, Kappa
// (degrees) or Matrix (nine numbers, row-major, R_camera_from_ground in the file's convention: for
// opk the matrix M, for seed R, for pok R^T). Unknown columns land in extra_columns.
Status ReadFramesTable(const std::string& path, const FramesTableOptions& options,
                       std::vector<FrameRecord>* frames);
Status ParseFramesTable(std::string_view text, const std::string& file_name,
                        const FramesTableOptions& options, std::vector<FrameRecord>* frames);
// Writes the same columns (angles in options.convention, degrees), then SigmaX, SigmaY, SigmaZ (m),
// SigmaOmega, SigmaPhi, SigmaKappa (degrees), Sigma0 where present, then extra columns.
Status WriteFramesTable(const std::string& path, const FramesTableOptions& options,
                        const std::vector<FrameRecord>& frames);
Status FormatFramesTable(const FramesTableOptions& options, const std::vector<FrameRecord>& frames,
                         const std::string& path, std::string* text);

// ------------------------------------------------------------------ ground points
// control: used to orient the images (resection) or as a weighted constraint (bundle adjustment);
// check: only compared with the result; tie: coordinates unknown (a points-table row gives
// approximate values only).

struct GroundPoint {
  std::string point_id;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // X, Y, Z (m)
  std::optional<Eigen::Vector3d> accuracy_m;            // AccuracyX/Y/Z, one sigma (m)
  PointRole role = PointRole::kControl;                 // Role: control (default) | check | tie
  int line = 0;                                         // source line, for messages
};

Status ReadGroundPoints(const std::string& path, std::vector<GroundPoint>* points);
Status ParseGroundPoints(std::string_view text, const std::string& file_name,
                         std::vector<GroundPoint>* points);
Status WriteGroundPoints(const std::string& path, const std::vector<GroundPoint>& points);
Status FormatGroundPoints(const std::vector<GroundPoint>& points, const std::string& path,
                          std::string* text);

// ------------------------------------------------------------------ image marks
struct ImageMark {
  std::string raster;
  std::string point_id;
  // Exactly one of the two is set: Column/Row (pixels; the PixelOrigin is chosen by the consumer,
  // top-left corner by default) or FilmX/FilmY (um).
  std::optional<Eigen::Vector2d> column_row;
  std::optional<Eigen::Vector2d> film_um;
  // Accuracy, one sigma, in the mark's own unit: pixels for Column/Row, um for FilmX/FilmY (the
  // name predates film marks).
  std::optional<double> accuracy_px;
  std::string camera_id;              // CameraID, optional
  int line = 0;                       // source line, for messages
};

Status ReadImageMarks(const std::string& path, std::vector<ImageMark>* marks);
Status ParseImageMarks(std::string_view text, const std::string& file_name,
                       std::vector<ImageMark>* marks);
Status WriteImageMarks(const std::string& path, const std::vector<ImageMark>& marks);
Status FormatImageMarks(const std::vector<ImageMark>& marks, const std::string& path,
                        std::string* text);

// Formats a marks table mark by mark, each checked as FormatImageMarks checks it, with no string
// per row or field: FormatImageMarks uses it, and so does core/io/block_tables.cc to write a block's
// millions of marks without a vector of ImageMark first.
class ImageMarksWriter {
 public:
  // Appends the header to *text, which must outlive the writer; `path` names the file in
  // messages; room is reserved for `num_marks` rows.
  ImageMarksWriter(const std::string& path, size_t num_marks, std::string* text);
  ~ImageMarksWriter();
  ImageMarksWriter(const ImageMarksWriter&) = delete;
  ImageMarksWriter& operator=(const ImageMarksWriter&) = delete;

  // Checks a mark and appends its row, else "path: mark of point 'P' in image 'I': column: what"
  // (empty names, both or neither position, a value that is not finite or outside its column's
  // range, an accuracy that is not positive).
  // A second mark of a point in an image is found when the marks are all there: at the first
  // other problem, or by Finish.
  Status Add(const ImageMark& mark);
  // After the last Add: "path: mark of point 'P' in image 'I': PointID: the point is marked twice
  // in the image (source lines 3 and 9)" for the first such mark.
  Status Finish();

 private:
  struct State;
  std::unique_ptr<State> state_;
  std::string* text_;
};

// ------------------------------------------------------------------ OpenDroneMap gcp_list.txt
// First line: the CRS (EPSG:xxxx, WGS84 UTM ..., or a proj string); then "X Y Z px py image [name]"
// per line (pixels, origin at the top-left corner, row down). Points without a name are named after
// their coordinates; the same X Y Z under one name is one ground point.
struct GcpList {
  std::string crs;
  std::vector<GroundPoint> points;
  std::vector<ImageMark> marks;
};
Status ReadGcpList(const std::string& path, GcpList* gcp_list);
Status ParseGcpList(std::string_view text, const std::string& file_name, GcpList* gcp_list);
// The text of a gcp_list.txt: the CRS line, then "X Y Z px py image name" per mark, in the order
// of gcp_list.marks (each mark repeats its point's coordinates; numbers as FormatNumber, so they
// read back exactly). Refused, naming `path` and the mark: a mark of a point not in the list, a
// mark without Column/Row (a film mark), a number that is not finite, a CRS that ParseGcpList would refuse, an empty name or one
// with white space (the fields are separated by it).
Status FormatGcpList(const GcpList& gcp_list, const std::string& path, std::string* text);

// ------------------------------------------------------------------ OpenDroneMap geo.txt
// Camera positions. First line: the CRS (as in gcp_list.txt); then per line, positionally (ODM)
//   image x y [z [yaw pitch roll [horizontal_accuracy vertical_accuracy [extras...]]]]
// x, y in the CRS's GIS order (easting or longitude first, as ODM writes them, even for
// EPSG:4326), z in metres; yaw, pitch, roll in degrees; accuracies in metres (one sigma). A line
// "image x y" has no height (has_height false: the position is horizontal only). The fields are
// positional, so a line without z cannot carry attitudes or accuracies: "image x y h v" reads as
// z = h, yaw = v and is refused like every line with 5, 6 or 8 fields (yaw pitch roll come as
// three, the accuracies as two), naming the missing field. Fields after the ninth are ODM's
// extras and are not read. An image named twice is refused.
struct GeoTxtRecord {
  std::string image;
  // x, y, z; z is NaN when the line gives no height (never a height: has_height says so).
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  bool has_height = true;
  std::optional<Eigen::Vector3d> yaw_pitch_roll_deg;
  std::optional<double> horizontal_accuracy_m;
  std::optional<double> vertical_accuracy_m;
  int line = 0;
};
struct GeoTxt {
  std::string crs;
  std::vector<GeoTxtRecord> records;
};
Status ReadGeoTxt(const std::string& path, GeoTxt* geo);
Status ParseGeoTxt(std::string_view text, const std::string& file_name, GeoTxt* geo);
// The text of a geo.txt: the CRS line, then per record "image x y" and, with a height, "z", then
// "yaw pitch roll" (ODM's "0 0 0", not available, when absent and accuracies follow) and the two
// accuracies when both are given (numbers as FormatNumber). Refused, naming `path` and the image:
// a CRS that ParseGeoTxt would refuse, an empty image name or one with white space, a coordinate
// that is not finite, accuracies on a
// record without height (the fields are positional), one accuracy without the other.
Status FormatGeoTxt(const GeoTxt& geo, const std::string& path, std::string* text);

// ------------------------------------------------------------------ consistency
// Checks that every mark names a known point. Messages name the file and line of the mark. (Cameras
// and rasters are resolved, with the same kind of message, when the resection inputs are built.)
Status CheckMarks(const std::string& marks_path, const std::vector<ImageMark>& marks,
                  const std::vector<GroundPoint>& points);

// Checks that a mark lies in its image, give or take kMarkOutsideImageFraction of the image size,
// when the camera gives the image size (NColumns, NRows); film marks are converted to pixels
// first. `origin` is the PixelOrigin of the marks' Column/Row. The error is located:
// "marks.csv:7: Column: the mark of point 'P3' in image 'a.jpg' lies 20000 pixels outside the
// 5472 x 3648 image of camera 'UAV' (at most 5% of the image size is allowed)".
Status CheckMarkInsideImage(const std::string& marks_path, const ImageMark& mark,
                            const FrameCamera& camera, PixelOrigin origin);

}  // namespace photopose
