#include "solvers/georeference/georeference.h"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <unordered_map>

#include "core/io/csv.h"
#include "core/rotation.h"
#include "solvers/bundle/triangulation.h"

namespace photopose {
namespace {

constexpr char kGeographic3d[] = "EPSG:4979";

// The heights (m) at which a position without height is handed to PROJ to find its vertical: the
// points of constant horizontal coordinates lie on the ellipsoid normal through them, a straight
// line in the local frame, so the line found does not depend on these placeholders.
constexpr double kPlaceholderHeightsM[2] = {0.0, 100.0};

// The position with the given height in place of its z (a height-less position's NaN).
Eigen::Vector3d AtHeight(const Eigen::Vector3d& position, double height_m) {
  return Eigen::Vector3d(position.x(), position.y(), height_m);
}

std::string FileNameOf(const std::string& name) {
  const size_t slash = name.find_last_of("/\\");
  return slash == std::string::npos ? name : name.substr(slash + 1);
}

// Image lookup by name: exact, else by the file name without folders when that is unique.
class ImageMatcher {
 public:
  explicit ImageMatcher(const Block& block) : block_(block) {
    for (size_t i = 0; i < block.images.size(); ++i) {
      const std::string file = FileNameOf(block.images[i].name);
      auto [it, inserted] = by_file_.emplace(file, static_cast<int>(i));
      if (!inserted) it->second = -2;  // ambiguous
    }
  }
  int Find(const std::string& name) const {
    const int exact = block_.FindImage(name);
    if (exact >= 0) return exact;
    const auto it = by_file_.find(FileNameOf(name));
    return it == by_file_.end() || it->second < 0 ? -1 : it->second;
  }

 private:
  const Block& block_;
  std::unordered_map<std::string, int> by_file_;
};

GeoreferenceRmse Rmse(const Block& block, const std::vector<GeoreferencePointError>& errors,
                      PointRole role, bool after_adjustment) {
  GeoreferenceRmse rmse;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const GeoreferencePointError& e : errors) {
    if (block.points[e.point].role != role) continue;
    const std::optional<Eigen::Vector3d>& error = after_adjustment ? e.after_adjustment_m : e.after_similarity_m;
    if (!error) continue;
    sum += error->cwiseAbs2();
    ++rmse.count;
  }
  if (rmse.count > 0) {
    rmse.rmse_m = (sum / rmse.count).cwiseSqrt();
    rmse.total_m = std::sqrt(sum.sum() / rmse.count);
  }
  return rmse;
}

std::string HeightsNote(const std::string& what, const std::string& crs) {
  CrsInfo info;
  if (!ResolveCrs(crs, &info).ok()) return what + " (" + crs + "): unknown CRS";
  if (info.heights_as_given)
    return what + " (" + crs + ", " + info.name + "): heights taken as given (the CRS has no vertical axis; they are used as heights above the ellipsoid and come back unchanged)";
  return what + " (" + crs + ", " + info.name + "): heights transformed by PROJ as the CRS defines them";
}

// The mean longitude, latitude and height (EPSG:4979) of the measurements: the local frame's
// origin. Positions without height count for the longitude and latitude only.
Status MeasurementCentre(const GeoreferenceInputs& inputs, Eigen::Vector3d* centre) {
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  int count = 0;
  double height_sum = 0.0, control_height_sum = 0.0;
  int height_count = 0, control_count = 0;
  auto add = [&](const std::string& crs, std::vector<Eigen::Vector3d> points,
                 const std::vector<char>& has_height, bool control) -> Status {
    if (points.empty()) return Status::Ok();
    CrsTransform to_geographic;
    PHOTOPOSE_RETURN_IF_ERROR(CrsTransform::Create(crs, kGeographic3d, &to_geographic));
    PHOTOPOSE_RETURN_IF_ERROR(to_geographic.Forward(&points));
    for (size_t k = 0; k < points.size(); ++k) {
      sum += points[k].head<2>();
      ++count;
      if (!has_height[k]) continue;
      height_sum += points[k].z();
      ++height_count;
      if (control) {
        control_height_sum += points[k].z();
        ++control_count;
      }
    }
    return Status::Ok();
  };
  std::vector<Eigen::Vector3d> positions, control;
  std::vector<char> position_has_height;
  for (const CameraPositionMeasurement& m : inputs.positions) {
    positions.push_back(m.has_height ? m.position : AtHeight(m.position, kPlaceholderHeightsM[0]));
    position_has_height.push_back(m.has_height);
  }
  for (const GroundPoint& p : inputs.control_points) control.push_back(p.position);
  PHOTOPOSE_RETURN_IF_ERROR(add(inputs.positions_crs, positions, position_has_height, false));
  PHOTOPOSE_RETURN_IF_ERROR(add(inputs.control_crs, control, std::vector<char>(control.size(), 1), true));
  if (count == 0) return Status::Error("georeferencing needs camera positions or control points");
  if (height_count == 0) {
    return Status::Error(inputs.positions_source + ": none of its " + std::to_string(inputs.positions.size()) +
                         " camera positions has a height and there is no control point: nothing ties the "
                         "model's heights to the ground (give z, or control points)");
  }
  // On the ground when control is known (heights of the local frame stay small).
  *centre = Eigen::Vector3d(sum.x() / count, sum.y() / count,
                            control_count > 0 ? control_height_sum / control_count : height_sum / height_count);
  return Status::Ok();
}

Status ChooseOutputCrs(const GeoreferenceOptions& options, const GeoreferenceInputs& inputs,
                       const Eigen::Vector3d& centre_lon_lat_h, GeoreferenceResult* result) {
  if (!options.out_crs.empty()) {
    result->out_crs = options.out_crs;
    result->out_crs_reason = "asked (--out_crs)";
  } else if (!inputs.control_points.empty()) {
    result->out_crs = inputs.control_crs;
    result->out_crs_reason = "the control's CRS";
  } else {
    CrsInfo positions;
    PHOTOPOSE_RETURN_IF_ERROR(ResolveCrs(inputs.positions_crs, &positions));
    if (positions.projected) {
      result->out_crs = inputs.positions_crs;
      result->out_crs_reason = "the camera positions' CRS (projected)";
    } else {
      result->out_crs = UtmCrsFor(centre_lon_lat_h.x(), centre_lon_lat_h.y());
      result->out_crs_reason = "the WGS84 UTM zone of the block's centre (the positions' CRS is not projected)";
    }
  }
  PHOTOPOSE_RETURN_IF_ERROR(ResolveCrs(result->out_crs, &result->out_crs_info));
  if (result->out_crs_info.geocentric)
    return Status::Error("output CRS '" + result->out_crs + "' is geocentric: give a geographic or projected CRS");
  return Status::Ok();
}

// The model-frame intersection of a point from its marks (model poses), or nothing.
std::optional<Eigen::Vector3d> IntersectInModel(const Block& block, int point) {
  const std::vector<RayObservation> rays = PointRays(block, point, MarkSigmaDefaults());
  if (rays.size() < 2) return std::nullopt;
  TriangulationOptions options;
  options.min_intersection_angle_rad = 0.0;  // a model's scale is arbitrary; only rays matter
  TriangulationResult triangulated;
  if (!TriangulatePoint(options, rays, &triangulated).ok()) return std::nullopt;
  return triangulated.point_m;
}

// Moves the block's images and tie points by the similarity (model -> local).
void MoveBlock(const Similarity3& s, Block* block) {
  for (BlockImage& image : block->images) {
    if (!image.eo) continue;
    const Eigen::Matrix3d R_camera_from_model =
        RotationFromAngles(RotationConvention::kSeed, image.eo->angles_seed_rad());
    image.eo->set_center_in_ground(s.Apply(image.eo->center_in_ground()));
    image.eo->set_angles_seed_rad(AnglesFromRotation(
        RotationConvention::kSeed, R_camera_from_model * s.R_target_from_source.transpose()));
  }
  for (BlockPoint& point : block->points) {
    if (point.role == PointRole::kTie && point.position_m) point.position_m = s.Apply(*point.position_m);
  }
}

// What makes a model unfit to be georeferenced, before any work: nothing to align it with, an
// image without a pose, or a camera with the earth-curvature correction (the local frame holds the
// curvature already).
Status CheckModelCanBeGeoreferenced(const GeoreferenceInputs& inputs, const Block& block) {
  if (inputs.positions.empty() && inputs.control_points.empty())
    return Status::Error("georeferencing needs camera positions or control points");
  for (size_t i = 0; i < block.images.size(); ++i) {
    if (!block.images[i].eo)
      return Status::Error("image '" + block.images[i].name + "' of the model has no pose; georeferencing moves a reconstructed model");
  }
  for (const BlockCamera& camera : block.cameras) {
    if (camera.earth_curvature_radius_m() > 0.0)
      return Status::Error("camera '" + camera.camera_id + "': ApplyECC: a georeferenced block is adjusted in a local "
                           "East-North-Up frame, whose coordinates hold the earth's curvature already; the "
                           "earth-curvature correction would count it twice (set ApplyECC to false)");
  }
  return Status::Ok();
}

// Every CRS the chain will use resolved before any work; one PROJ does not know is named with
// where it was given: its source and line (a geo.txt's or gcp_list.txt's first line), or the
// source alone when it was given beside it, or as the output CRS.
Status CheckCrssKnown(const GeoreferenceOptions& options, const GeoreferenceInputs& inputs) {
  const auto known = [](const std::string& crs, const std::string& where) {
    CrsInfo info;
    const Status resolved = ResolveCrs(crs, &info);
    return resolved.ok() ? resolved : Status::Error(where + ": " + resolved.message());
  };
  const auto at = [](const std::string& source, int line) {
    return line > 0 ? source + ":" + std::to_string(line) : source;
  };
  if (!inputs.positions.empty())
    PHOTOPOSE_RETURN_IF_ERROR(known(inputs.positions_crs, at(inputs.positions_source, inputs.positions_crs_line)));
  if (!inputs.control_points.empty())
    PHOTOPOSE_RETURN_IF_ERROR(known(inputs.control_crs, at(inputs.control_source, inputs.control_crs_line)));
  if (!options.out_crs.empty()) PHOTOPOSE_RETURN_IF_ERROR(known(options.out_crs, "the output CRS"));
  return Status::Ok();
}

// The measurements in the local frame (m, East-North-Up).
struct LocalMeasurements {
  // One per inputs.positions; a position without height at the lower placeholder height.
  std::vector<Eigen::Vector3d> positions;
  // One per inputs.positions: a position without height, the unit direction of its vertical; zero
  // for a position with height.
  std::vector<Eigen::Vector3d> verticals;
  std::vector<size_t> without_height;  // indices into inputs.positions
  std::vector<Eigen::Vector3d> control;  // one per inputs.control_points
};

// Step 1: the CRSs, the local frame, the measurements in it; the notes on heights and on inputs
// not used. A position without height is placed at the lower placeholder height, its vertical's
// direction found from the upper one.
Status MeasurementsInLocalFrame(const GeoreferenceOptions& options, const GeoreferenceInputs& inputs,
                                GeoreferenceResult* out, LocalMeasurements* local) {
  Eigen::Vector3d centre;
  PHOTOPOSE_RETURN_IF_ERROR(MeasurementCentre(inputs, &centre));
  PHOTOPOSE_RETURN_IF_ERROR(ChooseOutputCrs(options, inputs, centre, out));
  PHOTOPOSE_RETURN_IF_ERROR(LocalFrame::Create(kGeographic3d, centre, &out->frame));
  std::vector<Eigen::Vector3d> upper_local;
  for (size_t k = 0; k < inputs.positions.size(); ++k) {
    const CameraPositionMeasurement& m = inputs.positions[k];
    local->positions.push_back(m.has_height ? m.position : AtHeight(m.position, kPlaceholderHeightsM[0]));
    if (m.has_height) continue;
    local->without_height.push_back(k);
    upper_local.push_back(AtHeight(m.position, kPlaceholderHeightsM[1]));
  }
  for (const GroundPoint& p : inputs.control_points) local->control.push_back(p.position);
  local->verticals.assign(inputs.positions.size(), Eigen::Vector3d::Zero());
  if (!local->positions.empty()) {
    Status moved = out->frame.ToLocal(inputs.positions_crs, &local->positions);
    if (moved.ok()) moved = out->frame.ToLocal(inputs.positions_crs, &upper_local);
    if (!moved.ok()) return Status::Error(inputs.positions_source + ": " + moved.message());
    out->heights_notes.push_back(HeightsNote("camera positions", inputs.positions_crs));
    for (size_t j = 0; j < local->without_height.size(); ++j) {
      const size_t k = local->without_height[j];
      local->verticals[k] = (upper_local[j] - local->positions[k]).normalized();
    }
    if (!local->without_height.empty()) {
      out->heights_notes.push_back(
          "camera positions (" + inputs.positions_source + "): " + std::to_string(local->without_height.size()) +
          " without height: only their horizontal position is used (not in the similarity; in the "
          "adjustment a prior on the local East and North, the height free)");
    }
  }
  if (!local->control.empty()) {
    const Status moved = out->frame.ToLocal(inputs.control_crs, &local->control);
    if (!moved.ok()) return Status::Error(inputs.control_source + ": " + moved.message());
    out->heights_notes.push_back(HeightsNote("control", inputs.control_crs));
  }
  out->heights_notes.push_back(HeightsNote("outputs", out->out_crs));
  const std::string attitudes = AttitudesNotUsedLine(inputs);
  if (!attitudes.empty()) out->inputs_not_used.push_back(attitudes);
  return Status::Ok();
}

// Step 2a: each camera position to its image of the model (*position_image: the image of each, or
// -1), written into the image as its measured centre (a position without height: a point of its
// vertical, placed after the similarity).
Status MatchPositions(const GeoreferenceInputs& inputs, const LocalMeasurements& local,
                      const ImageMatcher& matcher, Block* work, std::vector<int>* position_image,
                      GeoreferenceResult* out) {
  position_image->assign(inputs.positions.size(), -1);
  std::vector<char> has_position(work->images.size(), 0);
  for (size_t k = 0; k < inputs.positions.size(); ++k) {
    const int image = matcher.Find(inputs.positions[k].image);
    if (image < 0) {
      out->positions_unmatched.push_back(inputs.positions[k].image);
      continue;
    }
    if (has_position[image]) {
      return Status::Error(inputs.positions_source + ":" + std::to_string(inputs.positions[k].line) +
                           ": image '" + inputs.positions[k].image + "' has a position already");
    }
    has_position[image] = 1;
    (*position_image)[k] = image;
    ++out->positions_matched;
    BlockImage& target = work->images[image];
    target.measured_center_m = local.positions[k];
    target.center_height_measured = inputs.positions[k].has_height;
    out->positions_without_height += !inputs.positions[k].has_height;
    target.center_accuracy_m = inputs.positions[k].accuracy_m;
  }
  out->images_without_position = static_cast<int>(std::count(has_position.begin(), has_position.end(), 0));
  if (!inputs.positions.empty() && out->positions_matched == 0) {
    return Status::Error(inputs.positions_source + ": none of its " + std::to_string(inputs.positions.size()) +
                         " image names matches an image of the model (e.g. '" + inputs.positions[0].image +
                         "' vs '" + (work->images.empty() ? std::string() : work->images[0].name) + "')");
  }
  return Status::Ok();
}

// Step 2b: the control and check points join the block after its own points; *point_of_id holds
// every point's index by id (looked up by hash: Block::FindPoint scans).
Status AddControlPoints(const GeoreferenceInputs& inputs, const LocalMeasurements& local, Block* work,
                        std::unordered_map<std::string, int>* point_of_id) {
  for (size_t p = 0; p < work->points.size(); ++p) point_of_id->emplace(work->points[p].id, static_cast<int>(p));
  for (size_t k = 0; k < inputs.control_points.size(); ++k) {
    const GroundPoint& gp = inputs.control_points[k];
    if (!point_of_id->emplace(gp.point_id, static_cast<int>(work->points.size())).second) {
      return Status::Error(inputs.control_source + ":" + std::to_string(gp.line) + ": point '" + gp.point_id +
                           "': the model has a point of that id; rename the control point");
    }
    BlockPoint point;
    point.id = gp.point_id;
    point.role = gp.role;
    point.surveyed_m = local.control[k];
    point.accuracy_m = gp.accuracy_m;
    if (gp.role == PointRole::kTie) point.position_m = local.control[k];
    point.line = gp.line;
    work->points.push_back(point);
  }
  return Status::Ok();
}

// Step 2c: the control marks join the block (pixels on a COLMAP-model camera, inside the image);
// the block's index is rebuilt and the control points without a mark are named.
Status AddControlMarks(const GeoreferenceInputs& inputs, const ImageMatcher& matcher,
                       const std::unordered_map<std::string, int>& point_of_id, int first_control,
                       Block* work, GeoreferenceResult* out) {
  for (const ImageMark& mark : inputs.control_marks) {
    const int image = matcher.Find(mark.raster);
    const auto found = point_of_id.find(mark.point_id);
    const int point = found == point_of_id.end() ? -1 : found->second;
    if (point < first_control) {
      return Status::Error(inputs.control_source + ":" + std::to_string(mark.line) + ": mark of point '" +
                           mark.point_id + "', which is not a control or check point");
    }
    if (image < 0) {
      out->control_marks_unmatched.push_back(mark.raster + " (line " + std::to_string(mark.line) + ")");
      continue;
    }
    const BlockCamera& camera = work->cameras[work->images[image].camera];
    if (!mark.column_row || camera.model == CameraModelType::kFrame) {
      return Status::Error(inputs.control_source + ":" + std::to_string(mark.line) +
                           ": control marks of a model are pixels (Column/Row) on a COLMAP-model camera");
    }
    PHOTOPOSE_RETURN_IF_ERROR(CheckMarkInsideImage(inputs.control_source, mark, camera.table, PixelOrigin::kCorner));
    BlockMark block_mark = MakePixelMark(image, point, *mark.column_row, mark.line);
    block_mark.accuracy = mark.accuracy_px;
    work->marks.push_back(block_mark);
    ++out->control_marks_matched;
  }
  work->BuildIndex();
  for (size_t p = first_control; p < work->points.size(); ++p) {
    if (work->marks_of_point[p].empty()) out->control_points_without_marks.push_back(work->points[p].id);
  }
  return Status::Ok();
}

// Step 3a: the pairs of the similarity: camera centres <-> positions with a height (group 0),
// control intersected in the model (*in_model, one per point of `work`) <-> surveyed (group 1).
std::vector<SimilarityCorrespondence> SimilarityPairs(const GeoreferenceOptions& options,
                                                      const GeoreferenceInputs& inputs,
                                                      const LocalMeasurements& local,
                                                      const std::vector<int>& position_image, int first_control,
                                                      const Block& work, GeoreferenceResult* out,
                                                      std::vector<std::optional<Eigen::Vector3d>>* in_model) {
  std::vector<SimilarityCorrespondence> pairs;
  for (size_t k = 0; k < inputs.positions.size(); ++k) {
    if (position_image[k] < 0 || !inputs.positions[k].has_height) continue;
    SimilarityCorrespondence pair;
    pair.source = work.images[position_image[k]].eo->center_in_ground();
    pair.target = local.positions[k];
    pair.sigma_m = inputs.positions[k].accuracy_m ? inputs.positions[k].accuracy_m->mean() : options.default_camera_accuracy_m;
    pair.group = 0;
    pairs.push_back(pair);
    out->similarity_labels.push_back("position " + work.images[position_image[k]].name);
  }
  in_model->assign(work.points.size(), std::nullopt);
  for (size_t p = first_control; p < work.points.size(); ++p) {
    (*in_model)[p] = IntersectInModel(work, static_cast<int>(p));
    if (!(*in_model)[p] || work.points[p].role != PointRole::kControl) continue;
    SimilarityCorrespondence pair;
    pair.source = *(*in_model)[p];
    pair.target = *work.points[p].surveyed_m;
    // A point held fixed (accuracy 0) weighs as a default one here: the similarity only aligns
    // the model; the adjustment then holds it.
    pair.sigma_m = work.points[p].accuracy_m && !IsHeldFixed(work.points[p])
                       ? work.points[p].accuracy_m->mean()
                       : options.default_marker_accuracy_m;
    pair.group = out->positions_matched > out->positions_without_height ? 1 : 0;
    pairs.push_back(pair);
    out->similarity_labels.push_back("control " + work.points[p].id);
  }
  return pairs;
}

// Step 3b: the robust similarity of the pairs moves the block into the local frame; a position
// without height then becomes the point of its vertical nearest to the image's centre (its
// height is the model's, never a measurement; the prior leaves it free).
Status AlignModel(const GeoreferenceOptions& options, const LocalMeasurements& local,
                  const std::vector<int>& position_image, const std::vector<SimilarityCorrespondence>& pairs,
                  Block* work, GeoreferenceResult* out) {
  const Status aligned = RobustSimilarity(options.similarity, pairs, &out->model_to_local, &out->similarity);
  if (!aligned.ok()) {
    const std::string without_height =
        out->positions_without_height > 0
            ? "; " + std::to_string(out->positions_without_height) + " camera positions without height take no part in it"
            : "";
    return Status::Error("cannot align the model with the measurements (" + std::to_string(pairs.size()) +
                         " pairs of camera positions and control points intersected in the model" +
                         without_height + "): " + aligned.message());
  }
  MoveBlock(out->model_to_local, work);
  for (const size_t k : local.without_height) {
    if (position_image[k] < 0) continue;
    BlockImage& image = work->images[position_image[k]];
    const Eigen::Vector3d& d = local.verticals[k];
    const Eigen::Vector3d& p0 = local.positions[k];
    image.measured_center_m = p0 + d * d.dot(image.eo->center_in_ground() - p0);
  }
  return Status::Ok();
}

// Step 4: the control and check points' errors after the similarity, along the output CRS's level
// axes at each point, and their RMSEs.
Status ErrorsAfterSimilarity(const Block& work, int first_control,
                             const std::vector<std::optional<Eigen::Vector3d>>& in_model, GeoreferenceResult* out) {
  std::vector<Eigen::Vector3d> surveyed;
  std::vector<int> surveyed_points;
  for (size_t p = first_control; p < work.points.size(); ++p) {
    if (work.points[p].role == PointRole::kTie) continue;
    surveyed.push_back(*work.points[p].surveyed_m);
    surveyed_points.push_back(static_cast<int>(p));
  }
  std::vector<Eigen::Matrix3d> R_level;
  PHOTOPOSE_RETURN_IF_ERROR(LevelAxes(*out, surveyed, &R_level));
  for (size_t k = 0; k < surveyed_points.size(); ++k) {
    const int p = surveyed_points[k];
    GeoreferencePointError error;
    error.point = p;
    if (in_model[p]) error.after_similarity_m = R_level[k] * (out->model_to_local.Apply(*in_model[p]) - surveyed[k]);
    out->point_errors.push_back(error);
  }
  out->control_after_similarity = Rmse(work, out->point_errors, PointRole::kControl, false);
  out->check_after_similarity = Rmse(work, out->point_errors, PointRole::kCheck, false);
  return Status::Ok();
}

// The one CRS of a frames table's positions (SetPositionsFromFrames): a row's SRS, else
// `given_crs`; every row in the same CRS. Each distinct SRS text is resolved once.
Status FramesTableCrs(const std::vector<FrameRecord>& frames, const std::string& given_crs,
                      const std::string& given_name, const std::string& source, std::string* crs) {
  const FrameRecord* first_stated = nullptr;  // the first row with an SRS
  for (const FrameRecord& frame : frames) {
    if (!frame.srs.empty()) {
      first_stated = &frame;
      break;
    }
  }
  if (first_stated == nullptr && given_crs.empty())
    return Status::Error(source + ": no SRS column value and no " + given_name +
                         ": the coordinate system of the positions is unknown");
  const auto row_where = [&](const FrameRecord& frame) {
    return source + ":" + std::to_string(frame.line) + ": SRS: ";
  };
  // Every row is compared with the given CRS, else with the first row that states one.
  const std::string reference = given_crs.empty() ? first_stated->srs : given_crs;
  const std::string reference_words = given_crs.empty()
                                          ? "line " + std::to_string(first_stated->line) + "'s '" +
                                                TokenForMessage(first_stated->srs) + "'"
                                          : given_name + "=" + TokenForMessage(given_crs);
  if (given_crs.empty()) {
    CrsInfo info;
    const Status known = ResolveCrs(reference, &info);
    if (!known.ok()) return Status::Error(row_where(*first_stated) + known.message());
  }
  std::map<std::string, bool> same_as_reference = {{reference, true}};  // by SRS text
  for (const FrameRecord& frame : frames) {
    if (frame.srs.empty()) {
      if (given_crs.empty())
        return Status::Error(row_where(frame) + "empty, and " + reference_words +
                             " names one: give every row's SRS, or " + given_name +
                             " for the rows without one");
      continue;
    }
    auto it = same_as_reference.find(frame.srs);
    if (it == same_as_reference.end()) {
      CrsInfo info;
      const Status known = ResolveCrs(frame.srs, &info);
      if (!known.ok()) return Status::Error(row_where(frame) + known.message());
      bool same = false;
      const Status compared = SameCrs(reference, frame.srs, &same);
      if (!compared.ok())
        return Status::Error(row_where(frame) + "cannot be compared with " + reference_words +
                             ": " + compared.message());
      it = same_as_reference.emplace(frame.srs, same).first;
    }
    if (!it->second)
      return Status::Error(row_where(frame) + "'" + TokenForMessage(frame.srs) +
                           "' is another CRS than " + reference_words +
                           ": the positions of a frames table are in one CRS");
  }
  *crs = reference;
  return Status::Ok();
}

}  // namespace

std::string GeoreferenceErrorAxes(const CrsInfo& out_crs_info) {
  return out_crs_info.projected ? "grid east, grid north, up" : "east, north, up";
}

Status PrepareGeoreference(const GeoreferenceOptions& options, const GeoreferenceInputs& inputs,
                           Block* block, GeoreferenceResult* result) {
  const auto start = std::chrono::steady_clock::now();
  PHOTOPOSE_RETURN_IF_ERROR(CheckModelCanBeGeoreferenced(inputs, *block));
  PHOTOPOSE_RETURN_IF_ERROR(CheckCrssKnown(options, inputs));
  GeoreferenceResult out;
  LocalMeasurements local;
  PHOTOPOSE_RETURN_IF_ERROR(MeasurementsInLocalFrame(options, inputs, &out, &local));
  // Matching; control points and marks join a copy of the block.
  Block work = *block;
  const ImageMatcher matcher(work);
  std::vector<int> position_image;
  PHOTOPOSE_RETURN_IF_ERROR(MatchPositions(inputs, local, matcher, &work, &position_image, &out));
  const int first_control = static_cast<int>(work.points.size());
  out.model_points = work.points.size();
  out.model_marks = work.marks.size();
  std::unordered_map<std::string, int> point_of_id;
  PHOTOPOSE_RETURN_IF_ERROR(AddControlPoints(inputs, local, &work, &point_of_id));
  PHOTOPOSE_RETURN_IF_ERROR(AddControlMarks(inputs, matcher, point_of_id, first_control, &work, &out));
  // The similarity, and the errors after it.
  std::vector<std::optional<Eigen::Vector3d>> in_model;
  const std::vector<SimilarityCorrespondence> pairs =
      SimilarityPairs(options, inputs, local, position_image, first_control, work, &out, &in_model);
  PHOTOPOSE_RETURN_IF_ERROR(AlignModel(options, local, position_image, pairs, &work, &out));
  PHOTOPOSE_RETURN_IF_ERROR(ErrorsAfterSimilarity(work, first_control, in_model, &out));
  work.crs = "local ENU (" + out.frame.definition() + ")";
  out.prepare_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  *block = std::move(work);
  *result = std::move(out);
  return Status::Ok();
}

Status EvaluateGeoreference(const Block& block, const BundleAdjustmentResult& adjustment,
                            GeoreferenceResult* result) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<Eigen::Vector3d> surveyed;
  for (const GeoreferencePointError& e : result->point_errors) surveyed.push_back(*block.points[e.point].surveyed_m);
  std::vector<Eigen::Matrix3d> R_level;
  PHOTOPOSE_RETURN_IF_ERROR(LevelAxes(*result, surveyed, &R_level));
  for (size_t k = 0; k < result->point_errors.size(); ++k) {
    GeoreferencePointError& e = result->point_errors[k];
    e.after_adjustment_m.reset();
    if (e.point < static_cast<int>(adjustment.points.size()) && adjustment.points[e.point].error_m)
      e.after_adjustment_m = R_level[k] * *adjustment.points[e.point].error_m;
  }
  result->control_after_adjustment = Rmse(block, result->point_errors, PointRole::kControl, true);
  result->check_after_adjustment = Rmse(block, result->point_errors, PointRole::kCheck, true);
  result->evaluated = true;
  result->evaluate_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return Status::Ok();
}

Status GeoreferenceBlock(const GeoreferenceOptions& options, const GeoreferenceInputs& inputs,
                         const BundleAdjustmentOptions& bundle_options,
                         const BundleAdjustmentConfig& config, Block* block,
                         GeoreferenceResult* result, BundleAdjustmentResult* adjustment) {
  GeoreferenceOptions aligned = options;
  aligned.default_camera_accuracy_m = bundle_options.accuracies.camera_m.mean();
  aligned.default_marker_accuracy_m = bundle_options.accuracies.marker_m;
  PHOTOPOSE_RETURN_IF_ERROR(PrepareGeoreference(aligned, inputs, block, result));
  BundleAdjustmentOptions adjusted_options = bundle_options;
  if (!inputs.positions.empty()) adjusted_options.accuracies.camera_positions_are_priors = true;
  PHOTOPOSE_RETURN_IF_ERROR(BundleAdjust(adjusted_options, config, block, adjustment));
  if (!adjustment->summary.IsSolutionUsable()) return Status::Ok();
  return EvaluateGeoreference(*block, *adjustment, result);
}

Status ToOutputCrs(const GeoreferenceResult& result, std::vector<Eigen::Vector3d>* points) {
  return result.frame.FromLocal(result.out_crs, points);
}

Status LevelAxes(const GeoreferenceResult& result, const std::vector<Eigen::Vector3d>& points_local,
                 std::vector<Eigen::Matrix3d>* R_level_from_local) {
  return result.frame.LevelFrames(result.out_crs, points_local, R_level_from_local);
}

Status GeoreferencedFrames(const GeoreferenceResult& result, std::vector<FrameRecord>* frames) {
  std::vector<Eigen::Vector3d> centres;
  for (const FrameRecord& frame : *frames) centres.push_back(frame.eo.center_in_ground());
  std::vector<Eigen::Matrix3d> R_level;
  PHOTOPOSE_RETURN_IF_ERROR(LevelAxes(result, centres, &R_level));
  std::vector<Eigen::Vector3d> out = centres;
  PHOTOPOSE_RETURN_IF_ERROR(ToOutputCrs(result, &out));
  for (size_t i = 0; i < frames->size(); ++i) {
    FrameRecord& frame = (*frames)[i];
    const Eigen::Vector3d angles = frame.eo.angles_seed_rad();
    // Attitude relative to the level frame: R_camera_from_level = R_camera_from_local R_local_from_level.
    auto level_angles = [&](const Eigen::Vector3d& a) {
      return AnglesFromRotation(RotationConvention::kSeed,
                                RotationFromAngles(RotationConvention::kSeed, a) * R_level[i].transpose());
    };
    const Eigen::Vector3d new_angles = level_angles(angles);
    if (frame.covariance) {
      // J = d(new parameters) / d(local parameters): the centre rotates, the angles numerically.
      Matrix6d J = Matrix6d::Zero();
      J.topLeftCorner<3, 3>() = R_level[i];
      constexpr double kStep = 1e-7;
      for (int k = 0; k < 3; ++k) {
        Eigen::Vector3d plus = angles, minus = angles;
        plus[k] += kStep;
        minus[k] -= kStep;
        Eigen::Vector3d difference = level_angles(plus) - level_angles(minus);
        for (int r = 0; r < 3; ++r) difference[r] = std::remainder(difference[r], 2.0 * M_PI);
        J.block<3, 1>(3, 3 + k) = difference / (2.0 * kStep);
      }
      frame.covariance = J * *frame.covariance * J.transpose();
    }
    frame.eo.set_center_in_ground(out[i]);
    frame.eo.set_angles_seed_rad(new_angles);
    frame.srs = result.out_crs_info.definition;  // what PROJ was given: "EPSG:32632" for ODM's "WGS84 UTM 32N"
  }
  return Status::Ok();
}

// Why any source's attitudes are not used: the one reason every source's reason ends with.
constexpr char kModelGivesTheAttitudes[] = "the model gives the attitudes";

std::string GeoTxtAttitudesNotUsedReason() {
  // ODM's own conversion (opendm/photo.py, compute_opk) builds its north-east-down frame from an
  // ECEF north vector and the ECEF -Z axis, which are not orthogonal off the poles: a nadir image
  // with yaw 0 gets kappa = 90 degrees + longitude. No convention is stated that could be tested.
  return std::string("ODM documents them for radiometric calibration only, 0 when not available, and "
                     "states no convention that gives the camera's omega/phi/kappa; ") +
         kModelGivesTheAttitudes;
}

std::string FramesAttitudesNotUsedReason() {
  return std::string(kModelGivesTheAttitudes) +
         "; with a model a frames table gives the camera positions only";
}

std::string AttitudesNotUsedLine(const GeoreferenceInputs& inputs) {
  if (inputs.attitudes_not_used <= 0) return "";
  return inputs.positions_source + ": " + std::to_string(inputs.attitudes_not_used) +
         (inputs.attitudes_not_used == 1 ? " attitude" : " attitudes") + " (" + inputs.attitude_names +
         ") read and not used (" + inputs.attitudes_not_used_reason + ")";
}

void SetPositionsFromGeoTxt(const GeoTxt& geo, const std::string& source, GeoreferenceInputs* inputs) {
  inputs->positions_crs = geo.crs;
  inputs->positions_source = source;
  inputs->positions_crs_line = 1;  // the CRS is the file's first line (core/io/tables.h)
  inputs->positions.clear();
  inputs->attitudes_not_used = 0;
  inputs->attitude_names = "yaw pitch roll";
  inputs->attitudes_not_used_reason = GeoTxtAttitudesNotUsedReason();
  for (const GeoTxtRecord& record : geo.records) {
    if (record.yaw_pitch_roll_deg && !record.yaw_pitch_roll_deg->isZero(0.0)) ++inputs->attitudes_not_used;
    CameraPositionMeasurement m;
    m.image = record.image;
    m.position = record.position;
    m.has_height = record.has_height;
    if (record.horizontal_accuracy_m && record.vertical_accuracy_m)
      m.accuracy_m = Eigen::Vector3d(*record.horizontal_accuracy_m, *record.horizontal_accuracy_m,
                                     *record.vertical_accuracy_m);
    m.line = record.line;
    inputs->positions.push_back(m);
  }
}

Status SetPositionsFromFrames(const std::vector<FrameRecord>& frames, const std::string& given_crs,
                              const std::string& given_name, const std::string& source,
                              GeoreferenceInputs* inputs) {
  std::string crs;
  PHOTOPOSE_RETURN_IF_ERROR(FramesTableCrs(frames, given_crs, given_name, source, &crs));
  inputs->positions_crs = crs;
  inputs->positions_source = source;
  inputs->positions_crs_line = 0;
  inputs->positions.clear();
  // A frames row always has an attitude (Omega/Phi/Kappa or Matrix; core/io/tables.h).
  inputs->attitudes_not_used = static_cast<int>(frames.size());
  inputs->attitude_names = "Omega Phi Kappa";
  inputs->attitudes_not_used_reason = FramesAttitudesNotUsedReason();
  for (const FrameRecord& frame : frames) {
    CameraPositionMeasurement m;
    m.image = frame.raster;
    m.position = frame.eo.center_in_ground();
    m.accuracy_m = frame.center_accuracy_m;
    m.line = frame.line;
    inputs->positions.push_back(m);
  }
  return Status::Ok();
}

void SetPositionsFromGps(const std::vector<std::string>& images,
                         const std::vector<std::optional<ExifGps>>& gps, const std::string& crs,
                         const std::string& source, GeoreferenceInputs* inputs) {
  inputs->positions_crs = crs;
  inputs->positions_source = source;
  inputs->positions_crs_line = 0;
  inputs->positions.clear();
  inputs->attitudes_not_used = 0;
  inputs->attitude_names.clear();
  inputs->attitudes_not_used_reason.clear();
  for (size_t i = 0; i < images.size() && i < gps.size(); ++i) {
    if (!gps[i]) continue;
    CameraPositionMeasurement m;
    m.image = images[i];
    m.position = gps[i]->lon_lat_height;
    m.accuracy_m = gps[i]->rtk_sigma_enu_m;
    inputs->positions.push_back(m);
  }
}

Status SetControlFromGcpList(const GcpList& gcp_list, const std::vector<std::string>& check_points,
                             const std::string& source, GeoreferenceInputs* inputs) {
  std::vector<GroundPoint> points = gcp_list.points;
  for (const std::string& id : check_points) {
    auto it = std::find_if(points.begin(), points.end(), [&](const GroundPoint& p) { return p.point_id == id; });
    if (it == points.end()) return Status::Error("'" + id + "' is not a point of " + source);
    it->role = PointRole::kCheck;
  }
  inputs->control_crs = gcp_list.crs;
  inputs->control_source = source;
  inputs->control_crs_line = 1;  // the CRS is the file's first line (core/io/tables.h)
  inputs->control_points = std::move(points);
  inputs->control_marks = gcp_list.marks;
  return Status::Ok();
}

}  // namespace photopose
