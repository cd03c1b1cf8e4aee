#pragma once
// A photogrammetric block: the cameras, images, ground points and image marks that resection and
// bundle adjustment work on, in one model. It is assembled once from the tables (ReadBlock /
// AssembleBlock, core/io/block_tables.h), from a COLMAP model, an OpenSfM reconstruction or a
// BAL / Bundler problem (core/io/colmap.h, core/io/opensfm.h, core/io/bal.h), or built in memory
// (core/simulation/); every consumer (resect, bundle, compare, the benchmarks, the tests) starts
// from it instead of pairing marks with points itself.
//
// Frames and units: the ground frame of the points (metres, Z up); exterior orientations in the
// seed convention (core/types.h); each camera's measurements in the observation unit of its camera
// model (core/camera_models.h: film micrometres for kFrame, pixels for the COLMAP models), while
// every mark also keeps what was read, in its own unit (pixels for Column/Row, micrometres for
// FilmX/FilmY), for reports.
//
// Roles of the ground points: control (surveyed, used as observations, or held fixed when its
// stated accuracy is 0: IsHeldFixed), check (surveyed, kept out of the adjustment and compared with
// it afterwards), tie (unknown coordinates: a point that has marks but no row in the points table,
// or a row with Role tie, whose coordinates are then only approximate values).

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/camera_models.h"
#include "core/enum_names.h"
#include "core/fiducials.h"
#include "core/rotation.h"
#include "core/status.h"
#include "core/types.h"

namespace photopose {

// The interior orientation of one camera of a block.
struct BlockCamera {
  std::string camera_id;
  CameraModelType model = CameraModelType::kFrame;
  // CameraModelNumParams(model) values in the order of core/camera_models.h (units there).
  std::vector<double> params;
  // kFrame: the camera-table row (pixel <-> film, flags, fiducials, distortion table, extra
  // columns); params start from it (FrameModelParams) and are written back into it on output
  // (SetFrameModelParams). Other models: only camera_id, n_columns and n_rows are meaningful.
  FrameCamera table;
  // The model's fixed data (Polarity, distortion table), pointing into `table`.
  CameraModelData data() const;
  // The radius of the earth-curvature correction of this camera's images (m): the table's
  // EarthRadius for a kFrame camera with ApplyECC, else 0 (none; the COLMAP, OpenSfM and BAL
  // cameras carry no such setting). core/collinearity.h (LowerByEarthCurvature) applies it.
  double earth_curvature_radius_m() const;
};

// One image: its camera, its exterior orientation when known, and measured position / attitude.
struct BlockImage {
  std::string name;  // Raster
  int camera = -1;   // index into Block::cameras
  // Exterior orientation (seed): approximate values from a frames table or a model, or the result
  // of an adjustment; unset when nothing is known yet.
  std::optional<ExteriorOrientation> eo;
  // Measured projection centre (GNSS, m, ground frame) and its per-image accuracy (m, one sigma
  // per axis). A frames table's PerspectiveX/Y/Z are the measured centre; the accuracy columns
  // AccuracyX/Y/Z, when given, make it a prior of the bundle adjustment (otherwise the adjustment's
  // default accuracy decides whether it is one).
  std::optional<Eigen::Vector3d> measured_center_m;
  std::optional<Eigen::Vector3d> center_accuracy_m;
  // False when the measurement gives no height (an ODM geo.txt line "image x y"): the prior then
  // constrains X and Y only, and measured_center_m.z() is not a measurement but the height the
  // centre had when the position was attached (solvers/georeference/georeference.h), kept finite
  // for the solvers and never compared with an adjusted height.
  bool center_height_measured = true;
  // Measured attitude (seed angles, rad) and its per-image accuracy (rad, one sigma per angle).
  std::optional<Eigen::Vector3d> measured_angles_rad;
  std::optional<Eigen::Vector3d> attitude_accuracy_rad;
  int line = 0;  // line of the frames table it came from (0: none), for messages
  // Scanned film: the image's own pixel -> film affine, fitted to its measured fiducials
  // (core/fiducials.h); it replaces the camera table's pixel -> film map for this image's pixel
  // marks (PixelToFilmCamera).
  std::optional<FiducialFit> fiducial_fit;
};

// The role of a ground point (the points table's Role column).
enum class PointRole { kControl, kCheck, kTie };
// "control", "check", "tie": the points table's Role values (core/enum_names.h).
inline constexpr EnumNameEntry<PointRole> kPointRoleNames[] = {
    {PointRole::kControl, "control"}, {PointRole::kCheck, "check"}, {PointRole::kTie, "tie"}};
constexpr EnumNameTable<PointRole> EnumNames(PointRole) {
  return EnumNameTable<PointRole>(kPointRoleNames);
}

// One ground point.
struct BlockPoint {
  std::string id;
  PointRole role = PointRole::kTie;
  // Control and check points: the surveyed coordinates (m) and their per-point accuracy (m, one
  // sigma per axis; unset: the adjustment's default marker accuracy). Positive on every axis, or 0
  // on all three: a control point taken as error-free, held fixed (IsHeldFixed); a check point
  // with 0 is only compared (InvalidPointAccuracyAxis states the rule).
  std::optional<Eigen::Vector3d> surveyed_m;
  std::optional<Eigen::Vector3d> accuracy_m;
  // The current estimate (m): an initial value (a points-table row of a tie point, a COLMAP
  // point, a triangulation) or the result of an adjustment; unset when not known yet.
  std::optional<Eigen::Vector3d> position_m;
  int line = 0;  // line of the points table it came from (0: none), for messages
};

// The rule of a point's stated accuracy (m, per axis): every axis positive (a weighted
// observation), or all three exactly 0 (error-free). The first axis (0..2) that breaks it — a
// negative or non-finite value, or 0 beside a non-zero one — or -1 when none does. The points
// table's reader and writer and CheckBlock apply it.
int InvalidPointAccuracyAxis(const Eigen::Vector3d& accuracy_m);

// A control point stated error-free (AccuracyX = AccuracyY = AccuracyZ = 0): the one rule that
// decides which points an adjustment holds fixed on their surveyed coordinates (no prior, no
// residual, part of the datum; BundleAdjust and TaylorBundleAdjust add them to the config's
// constant points). Its marks stay weighted observations.
bool IsHeldFixed(const BlockPoint& point);

// The unit of a mark as it was measured.
enum class MarkUnit {
  kPixel,  // Column/Row, pixels ((0, 0) the top-left corner of the image unless stated otherwise)
  kFilm,   // FilmX/FilmY, micrometres in the camera's FilmCoordinateSystem
};
// The unit's symbol in reports and messages: "px", "um".
inline constexpr EnumNameEntry<MarkUnit> kMarkUnitNames[] = {{MarkUnit::kPixel, "px"},
                                                            {MarkUnit::kFilm, "um"}};
constexpr EnumNameTable<MarkUnit> EnumNames(MarkUnit) {
  return EnumNameTable<MarkUnit>(kMarkUnitNames);
}

// One measurement of a point in an image.
struct BlockMark {
  int image = -1;  // index into Block::images
  int point = -1;  // index into Block::points
  MarkUnit unit = MarkUnit::kPixel;
  Eigen::Vector2d measured = Eigen::Vector2d::Zero();  // as read, in `unit`
  std::optional<double> accuracy;                       // as read, in `unit`, one sigma
  // The measurement in the camera model's observation unit (film um for kFrame, pixels for the
  // COLMAP models) and that unit per mark unit (um per pixel for pixel marks of a kFrame camera,
  // 1 otherwise): residuals and sigmas convert with it.
  Eigen::Vector2d observation = Eigen::Vector2d::Zero();
  double observation_units_per_unit = 1.0;
  int line = 0;  // line of the marks file it came from (0: none), for messages
};

struct Block {
  std::vector<BlockCamera> cameras;
  std::vector<BlockImage> images;
  std::vector<BlockPoint> points;
  std::vector<BlockMark> marks;
  // Pixel origin of the pixel marks as read (corner: (0, 0) the top-left corner of the image).
  PixelOrigin pixel_origin = PixelOrigin::kCorner;
  // Coordinate reference system of the ground frame as given (gcp_list header, SRS), or empty.
  std::string crs;
  // The file the marks came from, named in messages about marks.
  std::string marks_source;

  // Marks of every image and of every point (indices into marks), in marks order. Filled by
  // BuildIndex(); every function that changes the marks calls it again.
  std::vector<std::vector<int>> marks_of_image;
  std::vector<std::vector<int>> marks_of_point;
  void BuildIndex();

  // Index by name, or -1.
  int FindCamera(const std::string& camera_id) const;
  int FindImage(const std::string& name) const;
  int FindPoint(const std::string& id) const;
};

// A mark measured in pixels of a camera whose observation unit is the pixel (the COLMAP models):
// unit kPixel, measured = observation = pixel_px, no accuracy; `line` of the file it came from.
BlockMark MakePixelMark(int image, int point, const Eigen::Vector2d& pixel_px, int line);

// The camera-table row that turns this image's pixels into film: its camera's row, with the image's
// fiducial affine when it has one. kFrame cameras only.
FrameCamera PixelToFilmCamera(const Block& block, int image);

// Structural checks: every index in range, parameter counts match the models, every number
// finite. Names the first offence.
Status CheckBlock(const Block& block);

}  // namespace photopose
