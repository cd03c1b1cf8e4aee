// OpenSfM / ODM reconstructions (opensfm.h): reconstruction.json and tracks.csv -> block, and back.
// One file past ~800 lines on purpose: the format's one pair (core/io rule), with its JSON fields,
// cameras, tracks, shots and writer as the sections below.
#include "core/io/opensfm.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <string_view>
#include <unordered_map>

#include "core/io/csv.h"
#include "core/io/output_files.h"
#include "core/io/tables.h"
#include "core/io/text_scanner.h"
#include "core/rotation.h"

namespace photopose {
namespace {

using Json = nlohmann::json;

constexpr char kReconstructionFile[] = "reconstruction.json";
constexpr char kTracksFile[] = "tracks.csv";
constexpr char kReferenceLlaFile[] = "reference_lla.json";
constexpr std::string_view kTracksHeader = "OPENSFM_TRACKS_VERSION_v";

// Deepest nesting of arrays and objects accepted: OpenSfM's files nest five deep; the limit keeps
// every recursive walk of the parsed document (destruction, comparison) far from the stack's end.
constexpr int kMaxJsonDepth = 64;
// Most characters of the JSON parser's own message repeated in ours.
constexpr size_t kMaxParserMessageBytes = 200;
// Latitude and longitude of the reference (deg).
constexpr double kMaxLatitudeDeg = 90.0;
constexpr double kMaxLongitudeDeg = 180.0;
// Feature colours are bytes; OpenSfM writes them as numbers.
constexpr double kMaxColour = 255.0;

std::string Path(const std::string& directory, const char* name) {
  return (std::filesystem::path(directory) / name).string();
}

// ------------------------------------------------------------------ JSON fields

// "file: path: what" (path left out when empty).
Status JsonError(const std::string& file, const std::string& path, const std::string& what) {
  return Status::Error(file + ": " + (path.empty() ? "" : path + ": ") + what);
}

// A key of the data (a shot, camera or point id) in a JSON path: quoted and escaped.
std::string DataKey(const std::string& parent, std::string_view key) {
  return (parent.empty() ? "" : parent + ".") + "\"" + TokenForMessage(key) + "\"";
}
std::string Member(const std::string& parent, const char* key) {
  return parent.empty() ? std::string(key) : parent + "." + key;
}

std::string TypeName(const Json& value) {
  if (value.is_number()) return "a number";
  if (value.is_string()) return "a string";
  if (value.is_array()) return "an array";
  if (value.is_object()) return "an object";
  if (value.is_boolean()) return "a boolean";
  if (value.is_null()) return "null";
  return "something else";
}

// One object of the document with its place, for the field readers below.
struct JsonObject {
  const Json& value;
  const std::string& file;
  std::string path;

  const Json* Find(const char* key) const {
    const auto found = value.find(key);
    return found == value.end() ? nullptr : &*found;
  }
  Status Error(const char* key, const std::string& what) const {
    return JsonError(file, Member(path, key), what);
  }

  // A finite number; `fallback` when missing (none: required).
  Status Number(const char* key, std::optional<double> fallback, double* number) const {
    const Json* field = Find(key);
    if (field == nullptr) {
      if (!fallback) return Error(key, "is missing");
      *number = *fallback;
      return Status::Ok();
    }
    if (!field->is_number()) return Error(key, "expected a number, found " + TypeName(*field));
    *number = field->get<double>();
    if (!std::isfinite(*number)) return Error(key, "is not a finite number");
    return Status::Ok();
  }
  // A number within [-max_magnitude, max_magnitude] (`unit` after the range when not empty).
  Status NumberWithin(const char* key, std::optional<double> fallback, double max_magnitude,
                      const char* unit, double* number) const {
    PHOTOPOSE_RETURN_IF_ERROR(Number(key, fallback, number));
    if (!(std::abs(*number) <= max_magnitude)) {
      return Error(key, FormatNumber(*number) + " is outside [" +
                            FormatPlainNumber(-max_magnitude) + ", " +
                            FormatPlainNumber(max_magnitude) + "]" +
                            (*unit != '\0' ? std::string(" ") + unit : ""));
    }
    return Status::Ok();
  }
  // Three numbers, each within max_magnitude; *present false (and no error) when missing and
  // `present` is not null.
  Status Vector3(const char* key, double max_magnitude, const char* unit, Eigen::Vector3d* vector,
                 bool* present = nullptr) const {
    const Json* field = Find(key);
    if (present != nullptr) *present = field != nullptr && !field->is_null();
    if (field == nullptr || (present != nullptr && field->is_null())) {
      return present != nullptr ? Status::Ok() : Error(key, "is missing");
    }
    if (!field->is_array() || field->size() != 3 ||
        !std::all_of(field->begin(), field->end(), [](const Json& v) { return v.is_number(); })) {
      return Error(key, "expected 3 numbers, found " +
                            (field->is_array() ? std::to_string(field->size()) + " values"
                                               : TypeName(*field)));
    }
    for (int k = 0; k < 3; ++k) {
      const double value = (*field)[k].get<double>();
      if (!(std::abs(value) <= max_magnitude)) {
        return Error(key, "value " + std::to_string(k + 1) + ": " + FormatNumber(value) +
                              " is outside [" + FormatPlainNumber(-max_magnitude) + ", " +
                              FormatPlainNumber(max_magnitude) + "]" +
                              (*unit != '\0' ? std::string(" ") + unit : ""));
      }
      (*vector)[k] = value;
    }
    return Status::Ok();
  }
  Status String(const char* key, std::optional<std::string> fallback, std::string* text) const {
    const Json* field = Find(key);
    if (field == nullptr) {
      if (!fallback) return Error(key, "is missing");
      *text = *fallback;
      return Status::Ok();
    }
    if (!field->is_string()) return Error(key, "expected a string, found " + TypeName(*field));
    *text = field->get<std::string>();
    return Status::Ok();
  }
  // A required member that is an object.
  Status Object(const char* key, const Json** object) const {
    const Json* field = Find(key);
    if (field == nullptr) return Error(key, "is missing");
    if (!field->is_object()) return Error(key, "expected an object, found " + TypeName(*field));
    *object = field;
    return Status::Ok();
  }
};

// The deepest nesting of arrays and objects in a JSON text (outside strings), counted before the
// text is parsed.
int JsonDepth(std::string_view text) {
  int depth = 0, deepest = 0;
  bool in_string = false, escaped = false;
  for (const char c : text) {
    if (in_string) {
      if (escaped)
        escaped = false;
      else if (c == '\\')
        escaped = true;
      else if (c == '"')
        in_string = false;
      continue;
    }
    if (c == '"')
      in_string = true;
    else if (c == '[' || c == '{')
      deepest = std::max(deepest, ++depth);
    else if (c == ']' || c == '}')
      --depth;
  }
  return deepest;
}

Status ParseJson(std::string_view text, const std::string& file, Json* document) {
  if (JsonDepth(text) > kMaxJsonDepth) {
    return Status::Error(file + ": arrays and objects nest deeper than " +
                         std::to_string(kMaxJsonDepth) + " levels");
  }
  try {
    *document = Json::parse(text.begin(), text.end());
  } catch (const Json::exception& error) {
    // "[json.exception.parse_error.101] parse error at line 3, column 7: ..." -> from "parse".
    std::string what = error.what();
    const size_t start = what.find("] ");
    if (start != std::string::npos) what.erase(0, start + 2);
    if (what.size() > kMaxParserMessageBytes) what = what.substr(0, kMaxParserMessageBytes) + "...";
    return Status::Error(file + ": not valid JSON: " + EscapeForMessage(what));
  }
  return Status::Ok();
}

// ------------------------------------------------------------------ cameras

// Normalised image coordinates -> pixels of the block (COLMAP convention) and back.
struct ImageScale {
  double size = 1.0;  // max(width, height), px
  double half_width = 0.0, half_height = 0.0;
  ImageScale(int width, int height)
      : size(std::max(width, height)), half_width(0.5 * width), half_height(0.5 * height) {}
};

Status ImageSide(const JsonObject& camera, const char* key, int* side) {
  double value = 0.0;
  PHOTOPOSE_RETURN_IF_ERROR(camera.Number(key, std::nullopt, &value));
  if (!(value == std::floor(value) && value >= 1.0 && value <= kMaxImageSidePx)) {
    return camera.Error(key, FormatNumber(value) +
                                 " is no image size: a whole number of pixels in [1, " +
                                 std::to_string(kMaxImageSidePx) + "] is");
  }
  *side = static_cast<int>(value);
  return Status::Ok();
}

// A normalised focal length, as pixels within the COLMAP reader's limits.
Status Focal(const JsonObject& camera, const char* key, double size, double* focal_px) {
  double focal = 0.0;
  PHOTOPOSE_RETURN_IF_ERROR(camera.Number(key, std::nullopt, &focal));
  *focal_px = focal * size;
  if (!(*focal_px >= kMinFocalLengthPx && *focal_px <= kMaxCoordinate)) {
    return camera.Error(key, FormatNumber(focal) + " is no focal length: times the image size (" +
                                 FormatNumber(size) + " px) it must lie in [" +
                                 FormatNumber(kMinFocalLengthPx) + ", " +
                                 FormatPlainNumber(kMaxCoordinate) + "] px");
  }
  return Status::Ok();
}

// A normalised principal-point offset, as a pixel coordinate.
Status PrincipalPoint(const JsonObject& camera, const char* key, double size, double half,
                      double* pixel) {
  double offset = 0.0;
  PHOTOPOSE_RETURN_IF_ERROR(camera.NumberWithin(key, 0.0, kMaxCoordinate, "", &offset));
  *pixel = half + size * offset;
  if (!(std::abs(*pixel) <= kMaxCoordinate))
    return camera.Error(key, FormatNumber(offset) + " puts the principal point out of reach");
  return Status::Ok();
}

Status Coefficients(const JsonObject& camera, std::initializer_list<const char*> keys,
                    std::vector<double>* params) {
  for (const char* key : keys) {
    double value = 0.0;
    PHOTOPOSE_RETURN_IF_ERROR(camera.Number(key, 0.0, &value));
    params->push_back(value);
  }
  return Status::Ok();
}

Status ReadCamera(const std::string& file, const std::string& cameras_path, const std::string& id,
                  const Json& value, BlockCamera* camera, std::string* projection_type) {
  const JsonObject object{value, file, DataKey(cameras_path, id)};
  if (!value.is_object())
    return JsonError(file, object.path, "expected an object, found " + TypeName(value));
  PHOTOPOSE_RETURN_IF_ERROR(object.String("projection_type", "perspective", projection_type));
  int width = 0, height = 0;
  PHOTOPOSE_RETURN_IF_ERROR(ImageSide(object, "width", &width));
  PHOTOPOSE_RETURN_IF_ERROR(ImageSide(object, "height", &height));
  const ImageScale scale(width, height);
  const std::string& type = *projection_type;
  std::vector<double>& p = camera->params;
  double fx = 0.0, fy = 0.0, cx = scale.half_width, cy = scale.half_height;
  if (type == "perspective" || type == "fisheye") {
    PHOTOPOSE_RETURN_IF_ERROR(Focal(object, "focal", scale.size, &fx));
    if (type == "perspective") {
      camera->model = CameraModelType::kRadial;
      p = {fx, cx, cy};
      PHOTOPOSE_RETURN_IF_ERROR(Coefficients(object, {"k1", "k2"}, &p));
    } else {
      camera->model = CameraModelType::kOpenCvFisheye;
      p = {fx, fx, cx, cy};
      PHOTOPOSE_RETURN_IF_ERROR(Coefficients(object, {"k1", "k2"}, &p));
      p.insert(p.end(), {0.0, 0.0});
    }
  } else if (type == "brown" || type == "radial" || type == "simple_radial" ||
             type == "fisheye_opencv") {
    PHOTOPOSE_RETURN_IF_ERROR(Focal(object, "focal_x", scale.size, &fx));
    PHOTOPOSE_RETURN_IF_ERROR(Focal(object, "focal_y", scale.size, &fy));
    PHOTOPOSE_RETURN_IF_ERROR(PrincipalPoint(object, "c_x", scale.size, scale.half_width, &cx));
    PHOTOPOSE_RETURN_IF_ERROR(PrincipalPoint(object, "c_y", scale.size, scale.half_height, &cy));
    p = {fx, fy, cx, cy};
    if (type == "brown") {
      camera->model = CameraModelType::kFullOpenCv;
      PHOTOPOSE_RETURN_IF_ERROR(Coefficients(object, {"k1", "k2", "p1", "p2", "k3"}, &p));
      p.insert(p.end(), {0.0, 0.0, 0.0});
    } else if (type == "fisheye_opencv") {
      camera->model = CameraModelType::kOpenCvFisheye;
      PHOTOPOSE_RETURN_IF_ERROR(Coefficients(object, {"k1", "k2", "k3", "k4"}, &p));
    } else {
      camera->model = CameraModelType::kOpenCv;
      PHOTOPOSE_RETURN_IF_ERROR(Coefficients(object,
                                             type == "radial"
                                                 ? std::initializer_list<const char*>{"k1", "k2"}
                                                 : std::initializer_list<const char*>{"k1"},
                                             &p));
      p.resize(CameraModelNumParams(camera->model), 0.0);
    }
  } else {
    return object.Error("projection_type",
                        "camera " + DataKey("", id) + " has projection type '" +
                            TokenForMessage(type) +
                            "', which photopose does not read (it reads perspective, brown, "
                            "radial, simple_radial, fisheye and fisheye_opencv)");
  }
  camera->camera_id = id;
  camera->table.camera_id = id;
  camera->table.n_columns = width;
  camera->table.n_rows = height;
  return Status::Ok();
}

// ------------------------------------------------------------------ tracks.csv

// The fields of a version's line.
int TracksFieldCount(int version) { return version == 0 ? 8 : version == 1 ? 9 : 11; }

struct TracksContext {
  const std::string& path;
  std::unordered_map<std::string_view, int> image_of_name;
  std::unordered_map<std::string_view, int> point_of_id;
  std::vector<ImageScale> scale_of_image;
  // (image, point) -> line of its mark: a second observation of a track in an image is an error.
  std::unordered_map<uint64_t, int> line_of_pair;
};

Status TracksNumber(const TracksContext& context, int line, const char* field,
                    std::string_view text, double* value) {
  std::string why;
  if (!ParseFiniteNumber(text, value, &why)) return TextError(context.path, line, field, why);
  return Status::Ok();
}

Status TracksInteger(const TracksContext& context, int line, const char* field,
                     std::string_view text, long long* value) {
  std::string why;
  if (!ParseWholeNumber(text, value, &why)) return TextError(context.path, line, field, why);
  return Status::Ok();
}

// The first line of tracks.csv: the header of version 1 or 2 sets *version and *is_header; any
// other line is data (version 0).
Status TracksHeader(const TracksContext& context, std::string_view line, int line_number, int* version,
                    bool* is_header) {
  *is_header = false;
  if (line.substr(0, kTracksHeader.size()) != kTracksHeader) return Status::Ok();
  const std::string_view number = line.substr(kTracksHeader.size());
  if (number == "1" || number == "2") {
    *version = number[0] - '0';
    *is_header = true;
    return Status::Ok();
  }
  return TextError(context.path, line_number, "",
                   "tracks version '" + TokenForMessage(number) +
                       "' is not one photopose reads (1 or 2; no header: 0)");
}

// The tab-separated fields of a line.
void SplitAtTabs(std::string_view line, std::vector<std::string_view>* fields) {
  fields->clear();
  size_t start = 0;
  while (true) {
    const size_t tab = line.find('\t', start);
    fields->push_back(
        line.substr(start, tab == std::string_view::npos ? line.size() - start : tab - start));
    if (tab == std::string_view::npos) break;
    start = tab + 1;
  }
}

// The feature of a data line of the given version (its field count checked) and its normalised
// image coordinates.
Status ParseTracksFeature(const TracksContext& context, int line_number, int version,
                          const std::vector<std::string_view>& fields, OpenSfmFeature* feature,
                          Eigen::Vector2d* normalized) {
  const int expected = TracksFieldCount(version);
  if (static_cast<int>(fields.size()) != expected) {
    return TextError(context.path, line_number, "",
                     "expected " + std::to_string(expected) +
                         " tab-separated fields (tracks version " + std::to_string(version) +
                         "), found " + std::to_string(fields.size()));
  }
  int k = 2;
  PHOTOPOSE_RETURN_IF_ERROR(
      TracksInteger(context, line_number, "feature_id", fields[k++], &feature->feature_id));
  PHOTOPOSE_RETURN_IF_ERROR(TracksNumber(context, line_number, "x", fields[k++], &normalized->x()));
  PHOTOPOSE_RETURN_IF_ERROR(TracksNumber(context, line_number, "y", fields[k++], &normalized->y()));
  if (version >= 1) {
    PHOTOPOSE_RETURN_IF_ERROR(
        TracksNumber(context, line_number, "scale", fields[k++], &feature->scale));
  }
  const char* const kColour[] = {"r", "g", "b"};
  for (int c = 0; c < 3; ++c) {
    PHOTOPOSE_RETURN_IF_ERROR(
        TracksNumber(context, line_number, kColour[c], fields[k++], &feature->rgb[c]));
    if (!(feature->rgb[c] >= 0.0 && feature->rgb[c] <= kMaxColour)) {
      return TextError(context.path, line_number, kColour[c],
                       FormatNumber(feature->rgb[c]) + " is out of range [0, 255]");
    }
  }
  if (version == 2) {
    PHOTOPOSE_RETURN_IF_ERROR(
        TracksInteger(context, line_number, "segmentation", fields[k++], &feature->segmentation));
    PHOTOPOSE_RETURN_IF_ERROR(
        TracksInteger(context, line_number, "instance", fields[k++], &feature->instance));
  }
  return Status::Ok();
}

// The mark of a data line joins the block (in pixels, inside the coordinate range, at most one per
// track and image); a line of an image or a point not in the reconstruction is counted and left.
Status AddTracksMark(int line_number, const std::vector<std::string_view>& fields,
                     const Eigen::Vector2d& normalized, const OpenSfmFeature& feature, TracksContext* context,
                     Block* block, OpenSfmExtras* extras) {
  const auto image = context->image_of_name.find(fields[0]);
  if (image == context->image_of_name.end()) {
    if (extras != nullptr) ++extras->tracks_of_other_images;
    return Status::Ok();
  }
  const auto point = context->point_of_id.find(fields[1]);
  if (point == context->point_of_id.end()) {
    if (extras != nullptr) ++extras->tracks_of_other_points;
    return Status::Ok();
  }
  const ImageScale& scale = context->scale_of_image[image->second];
  const Eigen::Vector2d pixel(scale.size * normalized.x() + scale.half_width,
                              scale.size * normalized.y() + scale.half_height);
  for (int axis = 0; axis < 2; ++axis) {
    if (!(std::abs(pixel[axis]) <= kMaxCoordinate)) {
      return TextError(context->path, line_number, axis == 0 ? "x" : "y",
                       FormatNumber(normalized[axis]) + " is " + FormatNumber(pixel[axis]) +
                           " px, outside [" + FormatPlainNumber(-kMaxCoordinate) + ", " +
                           FormatPlainNumber(kMaxCoordinate) + "] px");
    }
  }
  const uint64_t pair = static_cast<uint64_t>(image->second) * block->points.size() +
                        static_cast<uint64_t>(point->second);
  const auto [seen, inserted] = context->line_of_pair.emplace(pair, line_number);
  if (!inserted) {
    return TextError(context->path, line_number, "track_id",
                     "track '" + TokenForMessage(fields[1]) + "' is observed twice in image '" +
                         TokenForMessage(fields[0]) + "' (first at line " +
                         std::to_string(seen->second) + ")");
  }
  block->marks.push_back(MakePixelMark(image->second, point->second, pixel, line_number));
  if (extras != nullptr) extras->mark_features.push_back(feature);
  return Status::Ok();
}

Status ReadTracks(std::string_view text, TracksContext* context, Block* block,
                  OpenSfmExtras* extras) {
  TextLines lines(text);
  std::string_view line;
  int line_number = 0;
  int version = 0;
  std::vector<std::string_view> fields;
  bool first = true;
  while (lines.Next(&line, &line_number)) {
    if (first) {
      first = false;
      bool is_header = false;
      PHOTOPOSE_RETURN_IF_ERROR(TracksHeader(*context, line, line_number, &version, &is_header));
      if (is_header) continue;
    }
    if (line.find_first_not_of(" \t\r") == std::string_view::npos) continue;
    SplitAtTabs(line, &fields);
    OpenSfmFeature feature;
    Eigen::Vector2d normalized;
    PHOTOPOSE_RETURN_IF_ERROR(ParseTracksFeature(*context, line_number, version, fields, &feature, &normalized));
    PHOTOPOSE_RETURN_IF_ERROR(AddTracksMark(line_number, fields, normalized, feature, context, block, extras));
  }
  if (extras != nullptr) extras->tracks_version = version;
  return Status::Ok();
}

// ------------------------------------------------------------------ reconstruction.json

Status ReadReferenceLla(const JsonObject& object, OpenSfmReferenceLla* lla) {
  PHOTOPOSE_RETURN_IF_ERROR(
      object.NumberWithin("latitude", std::nullopt, kMaxLatitudeDeg, "deg", &lla->latitude_deg));
  PHOTOPOSE_RETURN_IF_ERROR(
      object.NumberWithin("longitude", std::nullopt, kMaxLongitudeDeg, "deg", &lla->longitude_deg));
  return object.NumberWithin("altitude", std::nullopt, kMaxCoordinate, "m", &lla->altitude_m);
}

// The reconstruction's "cameras" into the block (*camera_of_id: each camera's index by its id).
Status ReadCameras(const JsonObject& reconstruction, const std::string& file, Block* block, OpenSfmExtras* extras,
                   std::unordered_map<std::string, int>* camera_of_id) {
  const Json* cameras = nullptr;
  PHOTOPOSE_RETURN_IF_ERROR(reconstruction.Object("cameras", &cameras));
  for (const auto& [id, value] : cameras->items()) {
    BlockCamera camera;
    std::string type;
    PHOTOPOSE_RETURN_IF_ERROR(ReadCamera(file, "cameras", id, value, &camera, &type));
    camera_of_id->emplace(id, static_cast<int>(block->cameras.size()));
    block->cameras.push_back(std::move(camera));
    extras->projection_types.push_back(type);
  }
  return Status::Ok();
}

// The reconstruction's "shots" into the block's images, their GPS positions and DOPs into extras.
Status ReadShots(const JsonObject& reconstruction, const std::string& file,
                 const std::unordered_map<std::string, int>& camera_of_id, Block* block, OpenSfmExtras* extras) {
  const Json* shots = nullptr;
  PHOTOPOSE_RETURN_IF_ERROR(reconstruction.Object("shots", &shots));
  for (const auto& [id, value] : shots->items()) {
    const JsonObject shot{value, file, DataKey("shots", id)};
    if (!value.is_object())
      return JsonError(file, shot.path, "expected an object, found " + TypeName(value));
    if (id.empty()) return JsonError(file, shot.path, "a shot needs a name");
    Eigen::Vector3d rotation, translation = Eigen::Vector3d::Zero(), gps;
    bool has_translation = false, has_gps = false;
    PHOTOPOSE_RETURN_IF_ERROR(shot.Vector3("rotation", kMaxRotationVectorRad, "rad", &rotation));
    PHOTOPOSE_RETURN_IF_ERROR(
        shot.Vector3("translation", kMaxCoordinate, "m", &translation, &has_translation));
    PHOTOPOSE_RETURN_IF_ERROR(shot.Vector3("gps_position", kMaxCoordinate, "m", &gps, &has_gps));
    std::optional<double> dop;
    if (shot.Find("gps_dop") != nullptr && !shot.Find("gps_dop")->is_null()) {
      double value_m = 0.0;
      PHOTOPOSE_RETURN_IF_ERROR(
          shot.NumberWithin("gps_dop", std::nullopt, kMaxCoordinate, "m", &value_m));
      dop = value_m;
    }
    std::string camera_id;
    PHOTOPOSE_RETURN_IF_ERROR(shot.String("camera", std::nullopt, &camera_id));
    const auto camera = camera_of_id.find(camera_id);
    if (camera == camera_of_id.end()) {
      return shot.Error(
          "camera", "camera " + DataKey("", camera_id) + " is not in the reconstruction's cameras");
    }
    BlockImage image;
    image.name = id;
    image.camera = camera->second;
    image.eo = EoFromComputerVisionPose(RotationFromRotationVector(rotation), translation);
    block->images.push_back(std::move(image));
    extras->gps_position_m.push_back(has_gps ? std::optional<Eigen::Vector3d>(gps) : std::nullopt);
    extras->gps_dop_m.push_back(dop);
  }
  return Status::Ok();
}

// The reconstruction's "points", when present, into the block's tie points, their colours into
// extras.
Status ReadPoints(const JsonObject& reconstruction, const std::string& file, Block* block, OpenSfmExtras* extras) {
  const Json* points = nullptr;
  if (reconstruction.Find("points") != nullptr)
    PHOTOPOSE_RETURN_IF_ERROR(reconstruction.Object("points", &points));
  if (points == nullptr) return Status::Ok();
  block->points.reserve(points->size());
  for (const auto& [id, value] : points->items()) {
    const JsonObject object{value, file, DataKey("points", id)};
    if (!value.is_object())
      return JsonError(file, object.path, "expected an object, found " + TypeName(value));
    Eigen::Vector3d coordinates, colour = Eigen::Vector3d::Zero();
    bool has_colour = false;
    PHOTOPOSE_RETURN_IF_ERROR(object.Vector3("coordinates", kMaxCoordinate, "m", &coordinates));
    PHOTOPOSE_RETURN_IF_ERROR(object.Vector3("color", kMaxColour, "", &colour, &has_colour));
    if (has_colour && colour.minCoeff() < 0.0)
      return object.Error("color", "a colour is in [0, 255]");
    BlockPoint point;
    point.id = id;
    point.role = PointRole::kTie;
    point.position_m = coordinates;
    block->points.push_back(std::move(point));
    extras->point_rgb.push_back({colour.x(), colour.y(), colour.z()});
  }
  return Status::Ok();
}

Status ReadReconstruction(const Json& document, const std::string& file, Block* block,
                          OpenSfmExtras* extras) {
  if (!document.is_array()) {
    return JsonError(file, "", "expected an array of reconstructions, found " + TypeName(document));
  }
  if (document.empty()) return JsonError(file, "", "holds no reconstruction (the array is empty)");
  extras->further_reconstructions = static_cast<int>(
      std::min<size_t>(document.size() - 1, static_cast<size_t>(std::numeric_limits<int>::max())));
  const Json& first = document[0];
  if (!first.is_object())
    return JsonError(file, "[0]", "expected an object, found " + TypeName(first));
  const JsonObject reconstruction{first, file, ""};
  std::unordered_map<std::string, int> camera_of_id;
  PHOTOPOSE_RETURN_IF_ERROR(ReadCameras(reconstruction, file, block, extras, &camera_of_id));
  PHOTOPOSE_RETURN_IF_ERROR(ReadShots(reconstruction, file, camera_of_id, block, extras));
  PHOTOPOSE_RETURN_IF_ERROR(ReadPoints(reconstruction, file, block, extras));
  if (const Json* reference = reconstruction.Find("reference_lla"); reference != nullptr) {
    if (!reference->is_object())
      return reconstruction.Error("reference_lla",
                                  "expected an object, found " + TypeName(*reference));
    OpenSfmReferenceLla lla;
    PHOTOPOSE_RETURN_IF_ERROR(
        ReadReferenceLla(JsonObject{*reference, file, "reference_lla"}, &lla));
    extras->reference_lla = lla;
    extras->reference_lla_source = file;
  }
  return Status::Ok();
}

// ------------------------------------------------------------------ writing

// A block camera in the terms of OpenSfM's projections: every COLMAP parameter by its name
// (absent ones 0), and whether the model is a fisheye.
struct CameraTerms {
  bool fisheye = false;
  std::map<std::string, double> value;
  double operator[](const char* name) const {
    const auto found = value.find(name);
    return found == value.end() ? 0.0 : found->second;
  }
};

CameraTerms TermsOf(const BlockCamera& camera) {
  CameraTerms terms;
  terms.fisheye = camera.model == CameraModelType::kOpenCvFisheye;
  const std::vector<std::string> names = CameraModelParamNames(camera.model);
  for (size_t k = 0; k < names.size(); ++k) {
    if (names[k] == "f") {
      terms.value["fx"] = terms.value["fy"] = camera.params[k];
    } else {
      terms.value[names[k] == "k" ? "k1" : names[k]] = camera.params[k];
    }
  }
  return terms;
}

// Whether OpenSfM's projection `type` is exactly this camera.
bool IsProjection(const std::string& type, const CameraTerms& t, const ImageScale& scale) {
  const bool centred = t["cx"] == scale.half_width && t["cy"] == scale.half_height;
  const bool square = t["fx"] == t["fy"];
  if (t.fisheye) {
    if (type == "fisheye_opencv") return true;
    return type == "fisheye" && centred && square && t["k3"] == 0.0 && t["k4"] == 0.0;
  }
  const bool brown = t["k4"] == 0.0 && t["k5"] == 0.0 && t["k6"] == 0.0;
  const bool radial = brown && t["p1"] == 0.0 && t["p2"] == 0.0 && t["k3"] == 0.0;
  if (type == "brown") return brown;
  if (type == "radial") return radial;
  if (type == "simple_radial") return radial && t["k2"] == 0.0;
  return type == "perspective" && radial && centred && square;
}

Status CameraJson(const BlockCamera& camera, const std::string* preferred, Json* json) {
  const std::string name = "camera '" + TokenForMessage(camera.camera_id) + "'";
  if (camera.model == CameraModelType::kFrame) {
    return Status::Error(name +
                         " is a frame camera (film micrometres): an OpenSfM reconstruction "
                         "holds cameras in pixels (write it as tables or COLMAP)");
  }
  const int width = camera.table.n_columns, height = camera.table.n_rows;
  if (width <= 0 || height <= 0) {
    return Status::Error(name +
                         " has no image size (NColumns, NRows), which OpenSfM's normalised "
                         "coordinates need");
  }
  const ImageScale scale(width, height);
  const CameraTerms t = TermsOf(camera);
  std::string type;
  if (preferred != nullptr && IsProjection(*preferred, t, scale)) {
    type = *preferred;
  } else {
    for (const char* candidate : {"perspective", "brown", "fisheye", "fisheye_opencv"}) {
      if (IsProjection(candidate, t, scale)) {
        type = candidate;
        break;
      }
    }
  }
  if (type.empty()) {
    return Status::Error(name + " (" + std::string(EnumName(camera.model)) +
                         " with k4, k5 or k6) is no OpenSfM projection");
  }
  const double s = scale.size;
  Json& j = *json;
  j = Json::object();
  j["projection_type"] = type;
  j["width"] = width;
  j["height"] = height;
  if (type == "perspective" || type == "fisheye") {
    j["focal"] = t["fx"] / s;
    j["k1"] = t["k1"];
    j["k2"] = t["k2"];
    return Status::Ok();
  }
  j["focal_x"] = t["fx"] / s;
  j["focal_y"] = t["fy"] / s;
  j["c_x"] = (t["cx"] - scale.half_width) / s;
  j["c_y"] = (t["cy"] - scale.half_height) / s;
  j["k1"] = t["k1"];
  if (type == "simple_radial") return Status::Ok();
  j["k2"] = t["k2"];
  if (type == "brown") {
    j["p1"] = t["p1"];
    j["p2"] = t["p2"];
    j["k3"] = t["k3"];
  } else if (type == "fisheye_opencv") {
    j["k3"] = t["k3"];
    j["k4"] = t["k4"];
  }
  return Status::Ok();
}

// Names that tracks.csv cannot hold: empty, or with a tab, a line break or a NUL.
bool IsTracksName(const std::string& name) {
  return !name.empty() && name.find_first_of(std::string("\t\n\r\0", 4)) == std::string::npos;
}

Status CheckExtras(const Block& block, const OpenSfmExtras& extras) {
  if (extras.projection_types.size() != block.cameras.size() ||
      extras.gps_position_m.size() != block.images.size() ||
      extras.gps_dop_m.size() != block.images.size() ||
      extras.point_rgb.size() != block.points.size() ||
      extras.mark_features.size() != block.marks.size()) {
    return Status::Error(
        "the OpenSfM extras do not belong to this block (their cameras, images, points or marks "
        "differ in number)");
  }
  return Status::Ok();
}

// The block's cameras as the reconstruction's "cameras" (in the projection extras name when it
// is exactly the camera).
Status CamerasJson(const Block& block, const OpenSfmExtras* extras, Json* cameras) {
  *cameras = Json::object();
  for (size_t c = 0; c < block.cameras.size(); ++c) {
    Json camera;
    PHOTOPOSE_RETURN_IF_ERROR(CameraJson(
        block.cameras[c], extras != nullptr ? &extras->projection_types[c] : nullptr, &camera));
    (*cameras)[block.cameras[c].camera_id] = std::move(camera);
  }
  return Status::Ok();
}

// The block's images as the reconstruction's "shots" (each oriented, once, with a name tracks.csv
// can hold), with the GPS positions and DOPs of extras.
Status ShotsJson(const Block& block, const OpenSfmExtras* extras, Json* shots) {
  *shots = Json::object();
  for (size_t i = 0; i < block.images.size(); ++i) {
    const BlockImage& image = block.images[i];
    if (!image.eo) {
      return Status::Error(
          "image '" + TokenForMessage(image.name) +
          "' has no exterior orientation: an OpenSfM reconstruction holds oriented "
          "images only");
    }
    if (!IsTracksName(image.name))
      return Status::Error("image '" + TokenForMessage(image.name) +
                           "' has a name tracks.csv cannot hold");
    if (shots->contains(image.name))
      return Status::Error("image '" + TokenForMessage(image.name) + "' is in the block twice");
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    ComputerVisionPoseFromEo(*image.eo, &R, &t);
    const Eigen::Vector3d r = RotationVectorFromRotation(R);
    Json shot = {{"rotation", {r.x(), r.y(), r.z()}},
                 {"translation", {t.x(), t.y(), t.z()}},
                 {"camera", block.cameras[image.camera].camera_id}};
    if (extras != nullptr && extras->gps_position_m[i]) {
      const Eigen::Vector3d& gps = *extras->gps_position_m[i];
      shot["gps_position"] = {gps.x(), gps.y(), gps.z()};
    }
    if (extras != nullptr && extras->gps_dop_m[i]) shot["gps_dop"] = *extras->gps_dop_m[i];
    (*shots)[image.name] = std::move(shot);
  }
  return Status::Ok();
}

// The block's points with a position as the reconstruction's "points" (each once, with an id
// tracks.csv can hold), with the colours of extras.
Status PointsJson(const Block& block, const OpenSfmExtras* extras, Json* points) {
  *points = Json::object();
  for (size_t p = 0; p < block.points.size(); ++p) {
    const BlockPoint& point = block.points[p];
    if (!point.position_m) continue;
    if (!IsTracksName(point.id))
      return Status::Error("point '" + TokenForMessage(point.id) +
                           "' has an id tracks.csv cannot hold");
    if (points->contains(point.id))
      return Status::Error("point '" + TokenForMessage(point.id) + "' is in the block twice");
    const std::array<double, 3> rgb =
        extras != nullptr ? extras->point_rgb[p] : std::array<double, 3>{0.0, 0.0, 0.0};
    const Eigen::Vector3d& X = *point.position_m;
    (*points)[point.id] = {{"color", {rgb[0], rgb[1], rgb[2]}},
                           {"coordinates", {X.x(), X.y(), X.z()}}};
  }
  return Status::Ok();
}

// tracks.csv, version 2: a line per mark of a point with a position, its feature from extras (or
// the mark's index in its image as feature id).
std::string TracksCsv(const Block& block, const OpenSfmExtras* extras) {
  std::string tracks = std::string(kTracksHeader) + "2\n";
  tracks.reserve(tracks.size() + 80 * block.marks.size());
  std::vector<int> marks_in_image(block.images.size(), 0);
  for (size_t m = 0; m < block.marks.size(); ++m) {
    const BlockMark& mark = block.marks[m];
    const BlockImage& image = block.images[mark.image];
    const BlockPoint& point = block.points[mark.point];
    const int index = marks_in_image[mark.image]++;
    if (!point.position_m) continue;
    const BlockCamera& camera = block.cameras[image.camera];
    const ImageScale scale(camera.table.n_columns, camera.table.n_rows);
    OpenSfmFeature feature;
    if (extras != nullptr) {
      feature = extras->mark_features[m];
    } else {
      feature.feature_id = index;
    }
    tracks += image.name;
    tracks += '\t';
    tracks += point.id;
    tracks += '\t';
    AppendInteger(feature.feature_id, &tracks);
    for (const double value : {(mark.observation.x() - scale.half_width) / scale.size,
                               (mark.observation.y() - scale.half_height) / scale.size,
                               feature.scale, feature.rgb[0], feature.rgb[1], feature.rgb[2]}) {
      tracks += '\t';
      AppendNumber(value, &tracks);
    }
    tracks += '\t';
    AppendInteger(feature.segmentation, &tracks);
    tracks += '\t';
    AppendInteger(feature.instance, &tracks);
    tracks += '\n';
  }
  return tracks;
}

}  // namespace

// ------------------------------------------------------------------ public

Status ParseOpenSfmReconstruction(const OpenSfmText& text, const std::string& reconstruction_path,
                                  Block* block, OpenSfmExtras* extras) {
  const std::string directory = std::filesystem::path(reconstruction_path).parent_path().string();
  Block result;
  OpenSfmExtras result_extras;
  {
    Json document;
    PHOTOPOSE_RETURN_IF_ERROR(ParseJson(text.reconstruction_json, reconstruction_path, &document));
    PHOTOPOSE_RETURN_IF_ERROR(
        ReadReconstruction(document, reconstruction_path, &result, &result_extras));
  }
  if (!result_extras.reference_lla && text.reference_lla_json) {
    const std::string path = Path(directory, kReferenceLlaFile);
    Json document;
    PHOTOPOSE_RETURN_IF_ERROR(ParseJson(*text.reference_lla_json, path, &document));
    if (!document.is_object())
      return JsonError(path, "", "expected an object, found " + TypeName(document));
    OpenSfmReferenceLla lla;
    PHOTOPOSE_RETURN_IF_ERROR(ReadReferenceLla(JsonObject{document, path, ""}, &lla));
    result_extras.reference_lla = lla;
    result_extras.reference_lla_source = path;
  }

  const std::string tracks_path = Path(directory, kTracksFile);
  TracksContext context{tracks_path, {}, {}, {}, {}};
  context.image_of_name.reserve(result.images.size());
  for (size_t i = 0; i < result.images.size(); ++i) {
    context.image_of_name.emplace(result.images[i].name, static_cast<int>(i));
    const BlockCamera& camera = result.cameras[result.images[i].camera];
    context.scale_of_image.emplace_back(camera.table.n_columns, camera.table.n_rows);
  }
  context.point_of_id.reserve(result.points.size());
  for (size_t p = 0; p < result.points.size(); ++p)
    context.point_of_id.emplace(result.points[p].id, static_cast<int>(p));
  // About a mark per line: the duplicate check and the marks grow once.
  const size_t num_lines = static_cast<size_t>(
      std::count(text.tracks_csv.begin(), text.tracks_csv.end(), '\n'));
  context.line_of_pair.reserve(num_lines);
  result.marks.reserve(num_lines);
  PHOTOPOSE_RETURN_IF_ERROR(ReadTracks(text.tracks_csv, &context, &result, &result_extras));

  result.pixel_origin = PixelOrigin::kCorner;
  result.marks_source = tracks_path;
  result.BuildIndex();
  *block = std::move(result);
  if (extras != nullptr) *extras = std::move(result_extras);
  return Status::Ok();
}

Status ReadOpenSfmReconstruction(const std::string& path, Block* block, OpenSfmExtras* extras) {
  std::error_code error;
  const bool is_folder = std::filesystem::is_directory(path, error);
  const std::filesystem::path file =
      is_folder ? std::filesystem::path(path) / kReconstructionFile : std::filesystem::path(path);
  const std::string directory = file.parent_path().string();
  OpenSfmText text;
  PHOTOPOSE_RETURN_IF_ERROR(ReadTextFile(file.string(), &text.reconstruction_json));
  PHOTOPOSE_RETURN_IF_ERROR(ReadTextFile(Path(directory, kTracksFile), &text.tracks_csv));
  const std::string reference = Path(directory, kReferenceLlaFile);
  if (std::filesystem::exists(reference, error)) {
    text.reference_lla_json.emplace();
    PHOTOPOSE_RETURN_IF_ERROR(ReadTextFile(reference, &*text.reference_lla_json));
  }
  return ParseOpenSfmReconstruction(text, file.string(), block, extras);
}

Status FormatOpenSfmReconstruction(const Block& block, const OpenSfmExtras* extras,
                                   OpenSfmText* text) {
  PHOTOPOSE_RETURN_IF_ERROR(CheckBlock(block));
  if (extras != nullptr) PHOTOPOSE_RETURN_IF_ERROR(CheckExtras(block, *extras));
  Json reconstruction = Json::object();
  PHOTOPOSE_RETURN_IF_ERROR(CamerasJson(block, extras, &reconstruction["cameras"]));
  PHOTOPOSE_RETURN_IF_ERROR(ShotsJson(block, extras, &reconstruction["shots"]));
  PHOTOPOSE_RETURN_IF_ERROR(PointsJson(block, extras, &reconstruction["points"]));
  if (extras != nullptr && extras->reference_lla) {
    const OpenSfmReferenceLla& lla = *extras->reference_lla;
    reconstruction["reference_lla"] = {{"latitude", lla.latitude_deg},
                                       {"longitude", lla.longitude_deg},
                                       {"altitude", lla.altitude_m}};
  }
  std::string tracks = TracksCsv(block, extras);
  try {
    text->reconstruction_json = Json::array({std::move(reconstruction)}).dump() + "\n";
  } catch (const Json::exception&) {
    return Status::Error("a camera, image or point name is not UTF-8 text, which JSON needs");
  }
  text->tracks_csv = std::move(tracks);
  text->reference_lla_json.reset();
  return Status::Ok();
}

Status WriteOpenSfmReconstruction(const std::string& directory, const Block& block,
                                  const OpenSfmExtras* extras) {
  const std::string reconstruction_path = Path(directory, kReconstructionFile);
  const std::string tracks_path = Path(directory, kTracksFile);
  OutputFiles outputs;
  PHOTOPOSE_RETURN_IF_ERROR(outputs.AddOutput("", reconstruction_path));
  PHOTOPOSE_RETURN_IF_ERROR(outputs.AddOutput("", tracks_path));
  OpenSfmText text;
  PHOTOPOSE_RETURN_IF_ERROR(FormatOpenSfmReconstruction(block, extras, &text));
  PHOTOPOSE_RETURN_IF_ERROR(outputs.Stage(reconstruction_path, text.reconstruction_json));
  PHOTOPOSE_RETURN_IF_ERROR(outputs.Stage(tracks_path, text.tracks_csv));
  return outputs.Commit();
}

}  // namespace photopose
