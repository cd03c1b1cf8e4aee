#pragma once
// Georeferencing an SfM reconstruction: a block in an arbitrary frame (a COLMAP or OpenSfM model)
// tied to measured camera positions (GNSS: a frames table, an ODM geo.txt) and surveyed ground
// control (an ODM gcp_list.txt, or points + marks tables), each in its own CRS, then adjusted
// with the weighted bundle adjustment and handed back in an output CRS.
//
// The chain (docs/conventions.md, "Georeferenced blocks"):
//  1. CRSs resolved by PROJ; a local topocentric East-North-Up frame (core/geodesy/crs.h) at the
//     centre of the measurements; every measurement transformed into it.
//  2. Matching by image name (exactly, else by the file name without folders when that is unique);
//     names matching no image are counted and listed, never dropped silently. Control points
//     join the block as control / check points with their marks as new observations.
//  3. A robust similarity from the model frame to the local frame (solvers/georeference/
//     similarity.h) on camera centres <-> positions and on control points intersected in the
//     model <-> surveyed, each group with its own robust scale; the whole block is moved by it and
//     the errors of control and check points after it are recorded. A position without height
//     (CameraPositionMeasurement::has_height) takes no part in it.
//  4. (the caller) the bundle adjustment of the block in the local frame, camera positions as
//     priors, control as weighted observations, check points held out.
//  5. The errors of control and check points after the adjustment; every output in the output
//     CRS (GeoreferencedFrames, GeoreferencedPoints) with errors and sigmas along the output
//     CRS's level axes (east / north / up, or grid east / grid north / up), in metres.
// GeoreferenceBlock runs 1-5 in one call; the CLI runs 1-3 (PrepareGeoreference), its usual
// adjustment, then 5 (EvaluateGeoreference).

#include <Eigen/Core>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "core/block.h"
#include "core/geodesy/crs.h"
#include "core/io/exif_gps.h"
#include "core/io/tables.h"
#include "core/status.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/georeference/similarity.h"

namespace photopose {

// A measured projection centre (GNSS) of an image named as the block names it.
// Without height (has_height false: a geo.txt line "image x y") it is the vertical through x, y:
// position.z() is not read (NaN from a geo.txt) and the prior constrains the horizontal only
// (PrepareGeoreference).
struct CameraPositionMeasurement {
  std::string image;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // in GeoreferenceInputs::positions_crs
  bool has_height = true;
  std::optional<Eigen::Vector3d> accuracy_m;           // one sigma per axis (E, N, Up), m
  int line = 0;                                        // source line, for messages
};

struct GeoreferenceInputs {
  std::string positions_crs;
  std::string positions_source;  // file name, for messages and reports
  // The line of positions_source that names positions_crs (1: a geo.txt's first line), for
  // messages; 0: the CRS was given beside the source (a --crs flag, an argument).
  int positions_crs_line = 0;
  std::vector<CameraPositionMeasurement> positions;
  // Attitudes the positions' source gives and the chain does not use (the model gives every
  // image's attitude): their count, the source's names for them and why. The Set* functions fill
  // them: a geo.txt's lines with a yaw/pitch/roll other than ODM's "0 0 0" (not available), a
  // frames table's Omega/Phi/Kappa of every row. Reported as one line of
  // GeoreferenceResult::inputs_not_used (docs/formats.md, "OpenDroneMap geo.txt").
  int attitudes_not_used = 0;
  std::string attitude_names;             // "yaw pitch roll", "Omega Phi Kappa"
  std::string attitudes_not_used_reason;  // GeoTxtAttitudesNotUsedReason, ...
  std::string control_crs;
  std::string control_source;
  int control_crs_line = 0;  // as positions_crs_line (1: a gcp_list.txt's first line)
  std::vector<GroundPoint> control_points;  // control / check as their role says
  std::vector<ImageMark> control_marks;     // pixels, (0, 0) the top-left corner of the image
};

// Filling the inputs from what the files hold (the one rule of the CLI and the Python module).
// The camera positions of a geo.txt: accuracy horizontal for east and north, vertical for up, when
// the line gives them. Its yaw/pitch/roll are counted in inputs->attitudes_not_used and not used:
// ODM documents them for radiometric calibration only (0 when not available) and states no
// convention that turns them into the camera's omega/phi/kappa (GeoTxtAttitudesNotUsedReason).
// A line without z gives a position without height (has_height false).
void SetPositionsFromGeoTxt(const GeoTxt& geo, const std::string& source, GeoreferenceInputs* inputs);
// The camera positions of a frames table (PerspectiveX/Y/Z, AccuracyX/Y/Z when given); its
// Omega/Phi/Kappa are counted in inputs->attitudes_not_used and not used
// (FramesAttitudesNotUsedReason). The positions' CRS is each row's SRS, else `given_crs` (the
// caller's, e.g. the CLI's --crs; empty: none), and one for every row: a row whose SRS names
// another CRS (SameCrs) than `given_crs` or than the first row with an SRS, a row without SRS
// when `given_crs` is empty beside rows with one, an SRS PROJ does not know, and a table with no
// SRS value and no `given_crs` are errors naming `source`, the line and SRS (`given_name`, e.g.
// "--crs", is how they name `given_crs`). inputs->positions_crs is `given_crs` when given, else
// the first row's SRS.
Status SetPositionsFromFrames(const std::vector<FrameRecord>& frames, const std::string& given_crs,
                              const std::string& given_name, const std::string& source,
                              GeoreferenceInputs* inputs);
// Why geo.txt and frames-table attitudes are read and not used, as the reports say it.
std::string GeoTxtAttitudesNotUsedReason();
std::string FramesAttitudesNotUsedReason();
// The inputs_not_used line of the inputs' unused attitudes ("geo.txt: 12 attitudes (yaw pitch
// roll) read and not used (...)"), empty when there are none: the one wording of the JSON report,
// the console and the page.
std::string AttitudesNotUsedLine(const GeoreferenceInputs& inputs);
// The positions of images' GPS tags (`gps[i]` of `images[i]`; entries without one skipped) in
// `crs`, DJI's RTK sigmas as their accuracies.
void SetPositionsFromGps(const std::vector<std::string>& images,
                         const std::vector<std::optional<ExifGps>>& gps, const std::string& crs,
                         const std::string& source, GeoreferenceInputs* inputs);
// The control points and marks of a gcp_list.txt; those named in `check_points` become check
// points (an id the list does not have is an error naming `source`).
Status SetControlFromGcpList(const GcpList& gcp_list, const std::vector<std::string>& check_points,
                             const std::string& source, GeoreferenceInputs* inputs);

struct GeoreferenceOptions {
  // Output CRS; empty: the control's CRS, else the positions' CRS when it is projected, else the
  // WGS84 UTM zone of the block's centre.
  std::string out_crs;
  RobustSimilarityOptions similarity;
  // The accuracies of positions and control points that state none (m, one sigma): they weigh
  // the pairs of the similarity as the bundle adjustment will weigh them (BundleAccuracies'
  // camera_m and marker_m: Metashape's 10 m and 5 mm by default).
  double default_camera_accuracy_m = 10.0;
  double default_marker_accuracy_m = 0.005;
};

// Errors of one surveyed point (estimate - surveyed), along the output CRS's level axes at the
// point (m).
struct GeoreferencePointError {
  int point = -1;  // index into Block::points
  std::optional<Eigen::Vector3d> after_similarity_m;  // intersected in the model, moved
  std::optional<Eigen::Vector3d> after_adjustment_m;  // adjusted (control) or intersected (check)
};

// The axes of GeoreferencePointError, GeoreferenceRmse and their reports, in words: "grid east,
// grid north, up" in a projected output CRS, "east, north, up" otherwise (E, N, U for short).
std::string GeoreferenceErrorAxes(const CrsInfo& out_crs_info);

// Per-axis RMSE (m) over the points of one role that have the error. Without such a point
// (count 0) there is no figure: rmse_m and total_m are NaN, never a zero that reads as no error
// (the JSON's null, Python's None, "n/a" on the page and the console).
struct GeoreferenceRmse {
  int count = 0;
  Eigen::Vector3d rmse_m = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  double total_m = std::numeric_limits<double>::quiet_NaN();
};

struct GeoreferenceResult {
  std::string out_crs;  // as resolved (never empty after PrepareGeoreference)
  CrsInfo out_crs_info;
  std::string out_crs_reason;  // why this output CRS ("--out_crs", "the control's CRS", ...)
  LocalFrame frame;            // the local ENU frame the block is adjusted in
  // The model's own points and marks: the first ones of the block; the control points and marks
  // PrepareGeoreference added follow them (ModelPartOfBlock, adjusted_colmap_model.h).
  size_t model_points = 0;
  size_t model_marks = 0;
  std::vector<std::string> heights_notes;  // per input CRS: how its heights were treated
  // Inputs read and not used, one line each with its count and reason ("geo.txt: 12 attitudes
  // (yaw pitch roll) read and not used (...)"); empty when everything read is used.
  std::vector<std::string> inputs_not_used;

  // Matching.
  int positions_matched = 0;
  // Of those, the positions without height: horizontal priors, not in the similarity.
  int positions_without_height = 0;
  std::vector<std::string> positions_unmatched;  // names that match no image
  int images_without_position = 0;
  int control_marks_matched = 0;
  std::vector<std::string> control_marks_unmatched;  // "image (line N)" of marks on no image
  std::vector<std::string> control_points_without_marks;

  // The similarity model -> local frame and its pairs ("position <image>", "control <id>").
  Similarity3 model_to_local;
  RobustSimilaritySummary similarity;
  std::vector<std::string> similarity_labels;

  std::vector<GeoreferencePointError> point_errors;
  GeoreferenceRmse control_after_similarity, check_after_similarity;
  GeoreferenceRmse control_after_adjustment, check_after_adjustment;
  bool evaluated = false;  // EvaluateGeoreference ran
  // Wall time of the georeferencing's own work (s): PrepareGeoreference (CRSs, matching,
  // intersections, similarity) and EvaluateGeoreference.
  double prepare_seconds = 0.0;
  double evaluate_seconds = 0.0;
};

// Steps 1-3: `block` (a model in its own frame, every image with an exterior orientation) is moved
// into the local frame, gets the camera positions as measured centres (accuracy per row, else
// `default_camera_accuracy_m` when given, else the bundle's default) and the control points and
// marks. Fails (nothing changed) on unknown CRSs (named with the source and line that gave them,
// or as the output CRS), fewer than three usable pairs, pairs on a line,
// a control point id that a model point already has, marks outside their images, or a camera with
// the earth-curvature correction (ApplyECC): the local frame is Cartesian, the earth's curvature
// is in its coordinates already, and the correction would count it twice.
// A position without height is never given one: the similarity uses only the positions with a
// height (and the control); then the image's measured centre is the point of the position's
// vertical (the line of its x, y at every height, from PROJ at two placeholder heights; the result
// does not depend on them) nearest to the image's centre after the similarity, flagged
// BlockImage::center_height_measured = false, so that the adjustment constrains its local X, Y
// only. The vertical at the image is the local frame's Z within the angle between them
// (distance from the frame's origin / the earth's radius: 0.16 mrad at 1 km), so a height change
// of the adjustment moves the constrained point by that change times that angle (1.6 mm for 10 m
// at 1 km).
Status PrepareGeoreference(const GeoreferenceOptions& options, const GeoreferenceInputs& inputs,
                           Block* block, GeoreferenceResult* result);

// Step 5: the control and check errors after the adjustment (from the adjusted block and its
// result), along the level axes of the output CRS.
Status EvaluateGeoreference(const Block& block, const BundleAdjustmentResult& adjustment,
                            GeoreferenceResult* result);

// Steps 1-5 in one call: PrepareGeoreference, BundleAdjust, EvaluateGeoreference.
Status GeoreferenceBlock(const GeoreferenceOptions& options, const GeoreferenceInputs& inputs,
                         const BundleAdjustmentOptions& bundle_options,
                         const BundleAdjustmentConfig& config, Block* block,
                         GeoreferenceResult* result, BundleAdjustmentResult* adjustment);

// The frames of BundleFrames (tools) or any frames in the local frame, moved into the output CRS:
// PerspectiveX/Y/Z in the output CRS, attitudes relative to its level frame at each camera (the
// seed convention, R_camera_from_level), covariances rotated into it; SRS = the output CRS.
Status GeoreferencedFrames(const GeoreferenceResult& result, std::vector<FrameRecord>* frames);

// Points of the local frame -> output CRS coordinates, and the rotations to the level axes there.
Status ToOutputCrs(const GeoreferenceResult& result, std::vector<Eigen::Vector3d>* points);
Status LevelAxes(const GeoreferenceResult& result, const std::vector<Eigen::Vector3d>& points_local,
                 std::vector<Eigen::Matrix3d>* R_level_from_local);

}  // namespace photopose
