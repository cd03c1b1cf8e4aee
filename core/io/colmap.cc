#include "core/io/colmap.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <string_view>
#include <unordered_map>

#include "core/camera.h"
#include "core/collinearity.h"
#include "core/io/csv.h"
#include "core/rotation.h"
#include "core/io/tables.h"
#include "core/io/text_scanner.h"

namespace photopose {
namespace {

// Quaternions are normalised as COLMAP does; one whose norm is below this is no rotation at all,
// one whose norm is above its inverse is refused too (its square overflows long before 1e300).
constexpr double kMinQuaternionNorm = 1e-12;
// A kFrame camera is a pinhole in COLMAP's pixels when its film -> pixel mapping has no rotation
// or shear: off-diagonal terms below this fraction of the diagonal ones (pixel sizes are given
// with far fewer digits than this).
constexpr double kPinholeShearTolerance = 1e-12;
// Pixels are square (SIMPLE_PINHOLE rather than PINHOLE) when fx and fy agree to this fraction.
constexpr double kSquarePixelTolerance = 1e-15;

constexpr long long kMaxColmapId = std::numeric_limits<long long>::max();

// COLMAP's pose is a computer-vision pose (core/rotation.h) with its rotation as a quaternion.
ExteriorOrientation EoFromColmapPose(const Eigen::Quaterniond& q, const Eigen::Vector3d& t) {
  return EoFromComputerVisionPose(q.toRotationMatrix(), t);
}

void ColmapPoseFromEo(const ExteriorOrientation& eo, Eigen::Quaterniond* q, Eigen::Vector3d* t) {
  Eigen::Matrix3d R_colmap;
  ComputerVisionPoseFromEo(eo, &R_colmap, t);
  *q = Eigen::Quaterniond(R_colmap);
  q->normalize();
  if (q->w() < 0.0) q->coeffs() *= -1.0;
}

std::string Path(const std::string& directory, const char* name) {
  return (std::filesystem::path(directory) / name).string();
}

// ------------------------------------------------------------------ reading

// The index of each COLMAP id (>= 0): a hash map while reading, then a plain table when the ids
// are dense enough (COLMAP numbers from 1), so that the million lookups of the observations are
// array reads.
class IdIndex {
 public:
  // False when the id is there already.
  bool Insert(long long id, int index) {
    if (!map_.emplace(id, index).second) return false;
    max_id_ = std::max(max_id_, id);
    return true;
  }
  void Freeze() {
    if (max_id_ >= 4 * static_cast<long long>(map_.size()) + 1024) return;
    dense_.assign(static_cast<size_t>(max_id_ + 1), -1);
    for (const auto& [id, index] : map_) dense_[static_cast<size_t>(id)] = index;
    map_.clear();
    is_dense_ = true;
  }
  // The index, or -1.
  int Find(long long id) const {
    if (is_dense_) return id >= 0 && id <= max_id_ ? dense_[static_cast<size_t>(id)] : -1;
    const auto found = map_.find(id);
    return found == map_.end() ? -1 : found->second;
  }

 private:
  std::unordered_map<long long, int> map_;
  std::vector<int> dense_;
  long long max_id_ = -1;
  bool is_dense_ = false;
};

// A COLMAP camera parameter: focal lengths in [kMinFocalLengthPx, kMaxCoordinate], the principal
// point within kMaxCoordinate, the distortion coefficients any finite number.
Status CameraParam(TokenScanner* scanner, const std::string& name, double* value) {
  const std::string field = "PARAMS " + name;
  if (name == "cx" || name == "cy")
    return scanner->NumberWithin(field, kMaxCoordinate, "px", value);
  if (name != "f" && name != "fx" && name != "fy") return scanner->Number(field, value);
  PHOTOPOSE_RETURN_IF_ERROR(scanner->NumberWithin(field, kMaxCoordinate, "px", value));
  if (!(*value >= kMinFocalLengthPx)) {
    return scanner->Error(field, FormatNumber(*value) + " is no focal length: it must be at least " +
                                     FormatNumber(kMinFocalLengthPx) + " px");
  }
  return Status::Ok();
}

Status ReadCameras(std::string_view text, const std::string& path, Block* block,
                   IdIndex* camera_of_id) {
  return ForEachRecordLine(text, path, /*comma_separates=*/false, [&](TokenScanner* scanner) {
    long long id = 0, width = 0, height = 0;
    std::string_view model_name;
    PHOTOPOSE_RETURN_IF_ERROR(scanner->IntegerIn("CAMERA_ID", 0, kMaxColmapId, &id));
    PHOTOPOSE_RETURN_IF_ERROR(scanner->Word("MODEL", &model_name));
    CameraModelType model = CameraModelType::kFrame;  // not a COLMAP model: refused below
    if (!ParseEnum(model_name, &model) || model == CameraModelType::kFrame) {
      return scanner->Error("MODEL", "camera model '" + TokenForMessage(model_name) +
                                         "' is not supported (supported: SIMPLE_PINHOLE, PINHOLE, "
                                         "SIMPLE_RADIAL, RADIAL, OPENCV, FULL_OPENCV, "
                                         "OPENCV_FISHEYE)");
    }
    constexpr long long kMaxSize = std::numeric_limits<int>::max();
    PHOTOPOSE_RETURN_IF_ERROR(scanner->IntegerIn("WIDTH", 1, kMaxSize, &width));
    PHOTOPOSE_RETURN_IF_ERROR(scanner->IntegerIn("HEIGHT", 1, kMaxSize, &height));
    BlockCamera camera;
    camera.camera_id = std::to_string(id);
    camera.model = model;
    camera.table.camera_id = camera.camera_id;
    camera.table.n_columns = static_cast<int>(width);
    camera.table.n_rows = static_cast<int>(height);
    const int num_params = CameraModelNumParams(model);
    camera.params.resize(num_params);
    const std::vector<std::string> names = CameraModelParamNames(model);
    for (int k = 0; k < num_params; ++k)
      PHOTOPOSE_RETURN_IF_ERROR(CameraParam(scanner, names[k], &camera.params[k]));
    if (!scanner->AtEnd()) {
      return scanner->Error("PARAMS", "more than the " + std::to_string(num_params) +
                                          " parameters of the " + std::string(model_name) +
                                          " model");
    }
    if (!camera_of_id->Insert(id, static_cast<int>(block->cameras.size())))
      return scanner->Error("CAMERA_ID", "camera " + std::to_string(id) + " is listed twice");
    block->cameras.push_back(std::move(camera));
    return Status::Ok();
  });
}

// A points3D.txt TRACK entry, checked once the images are read (12 bytes: a model has millions;
// the line is the point's).
struct TrackEntry {
  uint32_t image_id;  // COLMAP's image_t is 32-bit
  int keypoint;
  int point;
};
constexpr long long kMaxImageId = 0xffffffffLL;

Status ReadPoints(std::string_view text, const std::string& path, Block* block,
                  ColmapModelExtras* extras, IdIndex* point_of_id,
                  std::vector<TrackEntry>* tracks) {
  // A point per line at most; about a track entry per 12 characters (an estimate: the vector
  // grows past it when needed).
  block->points.reserve(static_cast<size_t>(std::count(text.begin(), text.end(), '\n')) + 1);
  tracks->reserve(text.size() / 12);
  return ForEachRecordLine(text, path, /*comma_separates=*/false, [&](TokenScanner* scanner) {
    long long id = 0;
    PHOTOPOSE_RETURN_IF_ERROR(scanner->IntegerIn("POINT3D_ID", 0, kMaxColmapId, &id));
    Eigen::Vector3d position;
    PHOTOPOSE_RETURN_IF_ERROR(scanner->NumberWithin("X", kMaxCoordinate, "m", &position.x()));
    PHOTOPOSE_RETURN_IF_ERROR(scanner->NumberWithin("Y", kMaxCoordinate, "m", &position.y()));
    PHOTOPOSE_RETURN_IF_ERROR(scanner->NumberWithin("Z", kMaxCoordinate, "m", &position.z()));
    std::array<unsigned char, 3> rgb;
    const char* const kColour[] = {"R", "G", "B"};
    for (int k = 0; k < 3; ++k) {
      long long value = 0;
      PHOTOPOSE_RETURN_IF_ERROR(scanner->IntegerIn(kColour[k], 0, 255, &value));
      rgb[k] = static_cast<unsigned char>(value);
    }
    double error = 0.0;
    PHOTOPOSE_RETURN_IF_ERROR(scanner->Number("ERROR", &error));
    const int index = static_cast<int>(block->points.size());
    if (!point_of_id->Insert(id, index))
      return scanner->Error("POINT3D_ID", "point " + std::to_string(id) + " is listed twice");
    while (!scanner->AtEnd()) {
      long long image_id = 0, keypoint = 0;
      PHOTOPOSE_RETURN_IF_ERROR(scanner->IntegerIn("TRACK IMAGE_ID", 0, kMaxImageId, &image_id));
      PHOTOPOSE_RETURN_IF_ERROR(
          scanner->IntegerIn("TRACK POINT2D_IDX", 0, std::numeric_limits<int>::max(), &keypoint));
      tracks->push_back({static_cast<uint32_t>(image_id), static_cast<int>(keypoint), index});
    }
    BlockPoint point;
    point.id = std::to_string(id);
    point.role = PointRole::kTie;
    point.position_m = position;
    point.line = scanner->line();
    block->points.push_back(std::move(point));
    if (extras != nullptr) {
      extras->point_rgb.push_back(rgb);
      extras->point_error_px.push_back(error);
    }
    return Status::Ok();
  });
}

Status ReadImages(std::string_view text, const std::string& path, const IdIndex& camera_of_id,
                  const IdIndex& point_of_id, Block* block, ColmapModelExtras* extras,
                  IdIndex* image_of_id, std::vector<long long>* keypoint_offset,
                  std::vector<int>* mark_of_keypoint) {
  TextLines lines(text);
  std::string_view line;
  int line_number = 0;
  keypoint_offset->assign(1, 0);
  while (lines.Next(&line, &line_number)) {
    if (IsBlankOrComment(line)) continue;
    TokenScanner scanner(line, path, line_number);
    long long id = 0, camera_id = 0;
    double qw, qx, qy, qz;
    Eigen::Vector3d t;
    PHOTOPOSE_RETURN_IF_ERROR(scanner.IntegerIn("IMAGE_ID", 0, kMaxImageId, &id));
    PHOTOPOSE_RETURN_IF_ERROR(scanner.Number("QW", &qw));
    PHOTOPOSE_RETURN_IF_ERROR(scanner.Number("QX", &qx));
    PHOTOPOSE_RETURN_IF_ERROR(scanner.Number("QY", &qy));
    PHOTOPOSE_RETURN_IF_ERROR(scanner.Number("QZ", &qz));
    PHOTOPOSE_RETURN_IF_ERROR(scanner.NumberWithin("TX", kMaxCoordinate, "m", &t.x()));
    PHOTOPOSE_RETURN_IF_ERROR(scanner.NumberWithin("TY", kMaxCoordinate, "m", &t.y()));
    PHOTOPOSE_RETURN_IF_ERROR(scanner.NumberWithin("TZ", kMaxCoordinate, "m", &t.z()));
    PHOTOPOSE_RETURN_IF_ERROR(scanner.IntegerIn("CAMERA_ID", 0, kMaxColmapId, &camera_id));
    const std::string_view name = scanner.Rest();
    if (name.empty()) return scanner.Error("NAME", "is missing");
    Eigen::Quaterniond q(qw, qx, qy, qz);
    const double q_norm = q.coeffs().stableNorm();  // no overflow: 1e300 is named as such
    if (!(q_norm > kMinQuaternionNorm))
      return scanner.Error("QW", "the quaternion (QW, QX, QY, QZ) is zero");
    if (!(q_norm < 1.0 / kMinQuaternionNorm)) {
      return scanner.Error("QW", "the quaternion (QW, QX, QY, QZ) has norm " + FormatNumber(q_norm) +
                                     "; COLMAP's is a unit quaternion (one with a norm between " +
                                     FormatNumber(kMinQuaternionNorm) + " and " +
                                     FormatNumber(1.0 / kMinQuaternionNorm) + " is normalised)");
    }
    q.normalize();
    const int camera = camera_of_id.Find(camera_id);
    if (camera < 0) {
      return scanner.Error("CAMERA_ID", "camera " + std::to_string(camera_id) +
                                            " is not in cameras.txt");
    }
    const int image_index = static_cast<int>(block->images.size());
    if (!image_of_id->Insert(id, image_index))
      return scanner.Error("IMAGE_ID", "image " + std::to_string(id) + " is listed twice");
    BlockImage image;
    image.name = std::string(name);
    image.camera = camera;
    image.eo = EoFromColmapPose(q, t);
    image.line = line_number;
    block->images.push_back(std::move(image));

    // POINTS2D: the next physical line, even when empty (an image without keypoints).
    std::string_view points_line;
    int points_line_number = line_number;
    if (!lines.Next(&points_line, &points_line_number)) points_line = std::string_view();
    TokenScanner points(points_line, path, points_line_number);
    int keypoint = 0;
    while (!points.AtEnd()) {
      Eigen::Vector2d xy;
      long long point_id = 0;
      PHOTOPOSE_RETURN_IF_ERROR(points.NumberWithin("POINTS2D X", kMaxCoordinate, "px", &xy.x()));
      PHOTOPOSE_RETURN_IF_ERROR(points.NumberWithin("POINTS2D Y", kMaxCoordinate, "px", &xy.y()));
      PHOTOPOSE_RETURN_IF_ERROR(points.IntegerIn("POINTS2D POINT3D_ID", -1, kMaxColmapId, &point_id));
      if (point_id < 0) {
        mark_of_keypoint->push_back(-1);
        if (extras != nullptr) extras->unmatched.push_back({image_index, keypoint, xy});
      } else {
        const int point = point_of_id.Find(point_id);
        if (point < 0) {
          return points.Error("POINTS2D POINT3D_ID", "point " + std::to_string(point_id) +
                                                         " is not in points3D.txt");
        }
        mark_of_keypoint->push_back(static_cast<int>(block->marks.size()));
        BlockMark mark;
        mark.image = image_index;
        mark.point = point;
        mark.unit = MarkUnit::kPixel;
        mark.measured = xy;
        mark.observation = xy;
        mark.line = points_line_number;
        block->marks.push_back(mark);
        if (extras != nullptr) extras->mark_keypoint_index.push_back(keypoint);
      }
      if (keypoint == std::numeric_limits<int>::max())
        return points.Error("POINTS2D", "too many entries");
      ++keypoint;
    }
    keypoint_offset->push_back(static_cast<long long>(mark_of_keypoint->size()));
    if (extras != nullptr) {
      extras->image_ids.push_back(id);
      extras->num_keypoints.push_back(keypoint);
    }
  }
  return Status::Ok();
}

// Every TRACK entry names a POINTS2D entry of its point, and every mark is in exactly one track.
Status CheckTracks(const std::string& points_path, const std::vector<TrackEntry>& tracks,
                   const IdIndex& image_of_id,
                   const std::vector<long long>& keypoint_offset,
                   const std::vector<int>& mark_of_keypoint, const Block& block) {
  std::vector<char> seen(block.marks.size(), 0);
  for (const TrackEntry& entry : tracks) {
    // Built only for a message: no string per entry on the way.
    const auto where = [&entry] {
      return "(" + std::to_string(entry.image_id) + ", " + std::to_string(entry.keypoint) + ")";
    };
    const int image = image_of_id.Find(entry.image_id);
    if (image < 0) {
      return TextError(points_path, block.points[entry.point].line, "TRACK",
                       "entry " + where() + ": image " + std::to_string(entry.image_id) +
                           " is not in images.txt");
    }
    const long long begin = keypoint_offset[image];
    const long long count = keypoint_offset[image + 1] - begin;
    if (entry.keypoint >= count) {
      return TextError(points_path, block.points[entry.point].line, "TRACK",
                       "entry " + where() + ": the image has " + std::to_string(count) +
                           " POINTS2D entries");
    }
    const int mark = mark_of_keypoint[begin + entry.keypoint];
    if (mark < 0 || block.marks[mark].point != entry.point) {
      return TextError(points_path, block.points[entry.point].line, "TRACK",
                       "entry " + where() + ": that POINTS2D entry does not name this point");
    }
    if (seen[mark]) {
      return TextError(points_path, block.points[entry.point].line, "TRACK", "entry " + where() + " is listed twice");
    }
    seen[mark] = 1;
  }
  for (size_t m = 0; m < seen.size(); ++m) {
    if (!seen[m]) {
      const BlockMark& mark = block.marks[m];
      return TextError(points_path, block.points[mark.point].line, "TRACK",
                       "point " + block.points[mark.point].id + " is observed in image '" +
                           TokenForMessage(block.images[mark.image].name) +
                           "' but that is not in its track");
    }
  }
  return Status::Ok();
}

// ------------------------------------------------------------------ writing

// Integer ids: the items' own when every one is a whole number >= 0 written plainly (so that it
// reads back as the same text) and they are unique, else 1..n.
template <typename Items, typename TextOf>
std::vector<long long> NumericIds(const Items& items, TextOf text_of) {
  std::vector<long long> ids(items.size());
  std::unordered_map<long long, int> used;
  used.reserve(items.size());
  bool own = true;
  for (size_t k = 0; k < items.size() && own; ++k) {
    const std::string& text = text_of(items[k]);
    long long id = 0;
    std::string why;
    own = !text.empty() && text.find_first_not_of("0123456789") == std::string::npos &&
          ParseWholeNumber(text, &id, &why) && std::to_string(id) == text &&
          used.emplace(id, 0).second;
    ids[k] = id;
  }
  if (!own)
    for (size_t k = 0; k < ids.size(); ++k) ids[k] = static_cast<long long>(k) + 1;
  return ids;
}

Status CheckExtras(const Block& block, const ColmapModelExtras& extras) {
  if (extras.image_ids.size() != block.images.size() ||
      extras.num_keypoints.size() != block.images.size() ||
      extras.mark_keypoint_index.size() != block.marks.size() ||
      extras.point_rgb.size() != block.points.size()) {
    return Status::Error(
        "the COLMAP extras do not belong to this block (their images, marks or points differ in "
        "number)");
  }
  for (const ColmapKeypoint& keypoint : extras.unmatched) {
    if (keypoint.image < 0 || keypoint.image >= static_cast<int>(block.images.size()))
      return Status::Error("the COLMAP extras name an unmatched keypoint of no image");
  }
  return Status::Ok();
}

void AppendSpaceNumber(double value, std::string* text) {
  text->push_back(' ');
  AppendNumber(value, text);
}

}  // namespace

// ------------------------------------------------------------------ public

namespace {

// The model from its three texts: `text_of(file name, &text)` gives each in turn (cameras.txt,
// points3D.txt, images.txt), valid until the next call; `directory` names them in messages.
template <typename TextOf>
Status ColmapModelFromTexts(const std::string& directory, TextOf text_of, Block* block,
                            ColmapModelExtras* extras) {
  Block result;
  ColmapModelExtras result_extras;
  ColmapModelExtras* kept = extras != nullptr ? &result_extras : nullptr;
  IdIndex camera_of_id, point_of_id, image_of_id;
  std::vector<TrackEntry> tracks;
  std::vector<long long> keypoint_offset;
  std::vector<int> mark_of_keypoint;
  std::string_view text;
  PHOTOPOSE_RETURN_IF_ERROR(text_of("cameras.txt", &text));
  PHOTOPOSE_RETURN_IF_ERROR(ReadCameras(text, Path(directory, "cameras.txt"), &result, &camera_of_id));
  camera_of_id.Freeze();
  const std::string points_path = Path(directory, "points3D.txt");
  PHOTOPOSE_RETURN_IF_ERROR(text_of("points3D.txt", &text));
  PHOTOPOSE_RETURN_IF_ERROR(ReadPoints(text, points_path, &result, kept, &point_of_id, &tracks));
  point_of_id.Freeze();
  // A consistent model has one mark per track entry.
  result.marks.reserve(tracks.size());
  mark_of_keypoint.reserve(tracks.size());
  if (kept != nullptr) kept->mark_keypoint_index.reserve(tracks.size());
  const std::string images_path = Path(directory, "images.txt");
  PHOTOPOSE_RETURN_IF_ERROR(text_of("images.txt", &text));
  PHOTOPOSE_RETURN_IF_ERROR(ReadImages(text, images_path, camera_of_id, point_of_id, &result, kept,
                                       &image_of_id, &keypoint_offset, &mark_of_keypoint));
  image_of_id.Freeze();
  PHOTOPOSE_RETURN_IF_ERROR(
      CheckTracks(points_path, tracks, image_of_id, keypoint_offset, mark_of_keypoint, result));
  result.pixel_origin = PixelOrigin::kCorner;
  result.marks_source = images_path;
  result.BuildIndex();
  *block = std::move(result);
  if (extras != nullptr) *extras = std::move(result_extras);
  return Status::Ok();
}

}  // namespace

Status ReadColmapModel(const std::string& directory, Block* block, ColmapModelExtras* extras) {
  // One file in memory at a time: each is parsed before the next is read into the same buffer.
  std::string buffer;
  const auto read = [&](const char* name, std::string_view* text) {
    PHOTOPOSE_RETURN_IF_ERROR(ReadTextFile(Path(directory, name), &buffer));
    *text = buffer;
    return Status::Ok();
  };
  return ColmapModelFromTexts(directory, read, block, extras);
}

Status ParseColmapModel(const ColmapModelText& text, const std::string& directory, Block* block,
                        ColmapModelExtras* extras) {
  const auto view = [&](const char* name, std::string_view* view) {
    const std::string_view file = name;
    *view = file == "cameras.txt" ? text.cameras : file == "images.txt" ? text.images : text.points3D;
    return Status::Ok();
  };
  return ColmapModelFromTexts(directory, view, block, extras);
}

Status ColmapCameraFromBlockCamera(const BlockCamera& camera, CameraModelType* model,
                                   std::vector<double>* params) {
  if (camera.model != CameraModelType::kFrame) {
    *model = camera.model;
    *params = camera.params;
    return Status::Ok();
  }
  const std::string name = "camera '" + camera.camera_id + "'";
  const std::vector<double>& p = camera.params;
  for (int k = kFrameK0; k <= kFrameSkew; ++k) {
    if (p[k] != 0.0) {
      return Status::Error(name + " has " + CameraModelParamNames(camera.model)[k] +
                           " = " + FormatNumber(p[k]) +
                           ": only a frame camera without distortion, affinity and skew is a "
                           "COLMAP pinhole camera");
    }
  }
  if (camera.table.distortion_type == DistortionType::kDistortionTable)
    return Status::Error(name + " has a distortion table: it is no COLMAP pinhole camera");
  // pixel = A film + p0 (exact: the mapping is affine), film = s c (a, b) + principal point.
  Eigen::Vector2d p0, px, py;
  Status status = PixelFromFilm(camera.table, {0.0, 0.0}, PixelOrigin::kCorner, &p0);
  if (status.ok()) status = PixelFromFilm(camera.table, {1.0, 0.0}, PixelOrigin::kCorner, &px);
  if (status.ok()) status = PixelFromFilm(camera.table, {0.0, 1.0}, PixelOrigin::kCorner, &py);
  if (!status.ok()) return Status::Error(name + ": " + status.message());
  Eigen::Matrix2d A;
  A.col(0) = px - p0;
  A.col(1) = py - p0;
  const double s = camera.table.polarity_sign();
  const Eigen::Matrix2d M = s * p[kFrameFocal] * A;  // pixel offset per unit of (a, b)
  const double scale = M.cwiseAbs().maxCoeff();
  if (!(std::abs(M(0, 1)) <= kPinholeShearTolerance * scale &&
        std::abs(M(1, 0)) <= kPinholeShearTolerance * scale && M(0, 0) > 0.0 && M(1, 1) < 0.0)) {
    return Status::Error(name +
                         ": its film axes are not Column right and Row down in the image (film "
                         "coordinate system, affine or Polarity): it is no COLMAP pinhole camera");
  }
  const double fx = M(0, 0), fy = -M(1, 1);
  const Eigen::Vector2d principal =
      A * Eigen::Vector2d(p[kFramePrincipalX], p[kFramePrincipalY]) + p0;
  if (std::abs(fx - fy) <= kSquarePixelTolerance * fx) {
    *model = CameraModelType::kSimplePinhole;
    *params = {fx, principal.x(), principal.y()};
  } else {
    *model = CameraModelType::kPinhole;
    *params = {fx, fy, principal.x(), principal.y()};
  }
  return Status::Ok();
}

void MarkReprojectionErrors(const Block& block, std::vector<double>* error_px) {
  error_px->assign(block.marks.size(), std::numeric_limits<double>::quiet_NaN());
  std::vector<CameraModelData> data(block.cameras.size());
  for (size_t c = 0; c < block.cameras.size(); ++c) data[c] = block.cameras[c].data();
  for (size_t m = 0; m < block.marks.size(); ++m) {
    const BlockMark& mark = block.marks[m];
    const BlockImage& image = block.images[mark.image];
    const BlockPoint& point = block.points[mark.point];
    if (!image.eo || !point.position_m) continue;
    double ab[2];
    if (!ProjectToNormalized(image.eo->data(), point.position_m->data(), ab)) continue;
    const BlockCamera& camera = block.cameras[image.camera];
    double residual[2];
    CameraModelResidual(camera.model, camera.params.data(), ab, mark.observation.data(),
                        data[image.camera], residual);
    // Film marks of a frame camera: um on the image plane -> pixels with the camera's pixel size.
    double units_per_pixel = mark.observation_units_per_unit;
    if (mark.unit == MarkUnit::kFilm && camera.model == CameraModelType::kFrame) {
      const double pixel_um = camera.table.MeanPixelSizeUm();
      units_per_pixel = pixel_um > 0.0 ? pixel_um : 1.0;
    }
    (*error_px)[m] = std::hypot(residual[0], residual[1]) / units_per_pixel;
  }
}

void MeanReprojectionErrors(const Block& block, std::vector<double>* point_error_px) {
  std::vector<double> mark_error;
  MarkReprojectionErrors(block, &mark_error);
  std::vector<double> sum(block.points.size(), 0.0);
  std::vector<int> count(block.points.size(), 0);
  for (size_t m = 0; m < block.marks.size(); ++m) {
    const int p = block.marks[m].point;
    sum[p] += mark_error[m];  // NaN propagates: the point then has no error
    ++count[p];
  }
  point_error_px->resize(block.points.size());
  for (size_t p = 0; p < sum.size(); ++p)
    (*point_error_px)[p] = count[p] > 0 && std::isfinite(sum[p]) ? sum[p] / count[p] : -1.0;
}

Status CheckColmapModelWritable(const Block& block, const ColmapModelExtras* extras) {
  PHOTOPOSE_RETURN_IF_ERROR(CheckBlock(block));
  if (extras != nullptr) PHOTOPOSE_RETURN_IF_ERROR(CheckExtras(block, *extras));
  for (const BlockCamera& camera : block.cameras) {
    CameraModelType model;
    std::vector<double> params;
    PHOTOPOSE_RETURN_IF_ERROR(ColmapCameraFromBlockCamera(camera, &model, &params));
    if (camera.table.n_columns <= 0 || camera.table.n_rows <= 0) {
      return Status::Error("camera '" + camera.camera_id +
                           "' has no image size (NColumns, NRows), which COLMAP needs");
    }
  }
  for (const BlockImage& image : block.images) {
    if (!image.eo) {
      return Status::Error("image '" + image.name +
                           "' has no exterior orientation: a COLMAP model holds oriented images "
                           "only");
    }
    if (image.name.empty() || image.name.find_first_of("\n\r") != std::string::npos ||
        image.name.front() == ' ' || image.name.back() == ' ')
      return Status::Error("image '" + image.name + "' has a name COLMAP cannot hold");
  }
  return Status::Ok();
}

Status FormatColmapModel(const Block& block, const ColmapModelExtras* extras,
                         ColmapModelText* text) {
  PHOTOPOSE_RETURN_IF_ERROR(CheckColmapModelWritable(block, extras));
  const size_t num_images = block.images.size();
  const size_t num_points = block.points.size();

  // cameras.txt
  std::string cameras_text =
      "# Camera list with one line of data per camera:\n"
      "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
      "# Number of cameras: " +
      std::to_string(block.cameras.size()) + "\n";
  const std::vector<long long> camera_ids =
      NumericIds(block.cameras, [](const BlockCamera& c) -> const std::string& { return c.camera_id; });
  for (size_t c = 0; c < block.cameras.size(); ++c) {
    const BlockCamera& camera = block.cameras[c];
    CameraModelType model;
    std::vector<double> params;
    PHOTOPOSE_RETURN_IF_ERROR(ColmapCameraFromBlockCamera(camera, &model, &params));
    AppendInteger(camera_ids[c], &cameras_text);
    cameras_text += ' ';
    cameras_text += EnumName(model);
    cameras_text += ' ';
    AppendInteger(camera.table.n_columns, &cameras_text);
    cameras_text += ' ';
    AppendInteger(camera.table.n_rows, &cameras_text);
    for (const double value : params) AppendSpaceNumber(value, &cameras_text);
    cameras_text += '\n';
  }

  // Keypoint slots: per image, its marks at their POINT2D index (or in block order) and the
  // unmatched keypoints; -1 - k in a slot is unmatched keypoint k, m >= 0 mark m.
  std::vector<long long> offset(num_images + 1, 0);
  if (extras != nullptr) {
    for (size_t i = 0; i < num_images; ++i) offset[i + 1] = offset[i] + extras->num_keypoints[i];
  } else {
    for (const BlockMark& mark : block.marks) ++offset[mark.image + 1];
    for (size_t i = 0; i < num_images; ++i) offset[i + 1] += offset[i];
  }
  constexpr long long kEmpty = std::numeric_limits<long long>::min();
  std::vector<long long> slot(static_cast<size_t>(offset[num_images]), kEmpty);
  std::vector<int> keypoint_of_mark(block.marks.size());
  {
    std::vector<long long> next(offset.begin(), offset.end() - 1);
    for (size_t m = 0; m < block.marks.size(); ++m) {
      const int image = block.marks[m].image;
      long long index;
      if (extras != nullptr) {
        index = extras->mark_keypoint_index[m];
        if (index < 0 || index >= extras->num_keypoints[image] ||
            slot[offset[image] + index] != kEmpty) {
          return Status::Error("the COLMAP extras give mark " + std::to_string(m + 1) +
                               " a keypoint index that is out of range or taken");
        }
      } else {
        index = next[image]++ - offset[image];
      }
      slot[offset[image] + index] = static_cast<long long>(m);
      keypoint_of_mark[m] = static_cast<int>(index);
    }
    if (extras != nullptr) {
      for (size_t k = 0; k < extras->unmatched.size(); ++k) {
        const ColmapKeypoint& keypoint = extras->unmatched[k];
        if (keypoint.index < 0 || keypoint.index >= extras->num_keypoints[keypoint.image] ||
            slot[offset[keypoint.image] + keypoint.index] != kEmpty) {
          return Status::Error("the COLMAP extras give an unmatched keypoint of image '" +
                               block.images[keypoint.image].name +
                               "' an index that is out of range or taken");
        }
        slot[offset[keypoint.image] + keypoint.index] = -1 - static_cast<long long>(k);
      }
      for (size_t i = 0; i < num_images; ++i) {
        for (long long s = offset[i]; s < offset[i + 1]; ++s) {
          if (slot[s] == kEmpty) {
            return Status::Error("the COLMAP extras leave POINT2D index " +
                                 std::to_string(s - offset[i]) + " of image '" +
                                 block.images[i].name + "' empty");
          }
        }
      }
    }
  }

  // Pixel positions of the marks (a frame camera's film observations mapped to its pixels).
  std::vector<Eigen::Vector2d> pixel(block.marks.size());
  for (size_t m = 0; m < block.marks.size(); ++m) {
    const BlockMark& mark = block.marks[m];
    const BlockCamera& camera = block.cameras[block.images[mark.image].camera];
    if (camera.model != CameraModelType::kFrame) {
      pixel[m] = mark.observation;
      continue;
    }
    const Status status =
        PixelFromFilm(camera.table, mark.observation, PixelOrigin::kCorner, &pixel[m]);
    if (!status.ok()) return Status::Error("mark " + std::to_string(m + 1) + ": " + status.message());
  }

  const std::vector<long long> point_ids =
      NumericIds(block.points, [](const BlockPoint& p) -> const std::string& { return p.id; });
  std::vector<double> point_error;
  MeanReprojectionErrors(block, &point_error);

  // images.txt
  size_t num_observations = 0;
  for (const BlockMark& mark : block.marks)
    if (block.points[mark.point].position_m) ++num_observations;
  std::string images_text;
  images_text.reserve(200 * num_images + 40 * slot.size());
  images_text +=
      "# Image list with two lines of data per image:\n"
      "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
      "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
      "# Number of images: " +
      std::to_string(num_images) + ", mean observations per image: " +
      FormatNumber(num_images > 0 ? static_cast<double>(num_observations) / num_images : 0.0) +
      "\n";
  std::vector<long long> image_ids(num_images);
  for (size_t i = 0; i < num_images; ++i) {
    const BlockImage& image = block.images[i];
    image_ids[i] = extras != nullptr ? extras->image_ids[i] : static_cast<long long>(i) + 1;
    Eigen::Quaterniond q;
    Eigen::Vector3d t;
    ColmapPoseFromEo(*image.eo, &q, &t);
    AppendInteger(image_ids[i], &images_text);
    for (const double value : {q.w(), q.x(), q.y(), q.z(), t.x(), t.y(), t.z()})
      AppendSpaceNumber(value, &images_text);
    images_text += ' ';
    AppendInteger(camera_ids[image.camera], &images_text);
    images_text += ' ';
    images_text += image.name;
    images_text += '\n';
    for (long long s = offset[i]; s < offset[i + 1]; ++s) {
      if (s > offset[i]) images_text += ' ';
      if (slot[s] >= 0) {
        const size_t m = static_cast<size_t>(slot[s]);
        AppendNumber(pixel[m].x(), &images_text);
        AppendSpaceNumber(pixel[m].y(), &images_text);
        images_text += ' ';
        const int p = block.marks[m].point;
        AppendInteger(block.points[p].position_m ? point_ids[p] : -1, &images_text);
      } else {
        const ColmapKeypoint& keypoint = extras->unmatched[static_cast<size_t>(-1 - slot[s])];
        AppendNumber(keypoint.xy.x(), &images_text);
        AppendSpaceNumber(keypoint.xy.y(), &images_text);
        images_text += " -1";
      }
    }
    images_text += '\n';
  }

  // points3D.txt: tracks in block mark order per point.
  std::vector<size_t> track_offset(num_points + 1, 0);
  for (const BlockMark& mark : block.marks) ++track_offset[mark.point + 1];
  for (size_t p = 0; p < num_points; ++p) track_offset[p + 1] += track_offset[p];
  std::vector<int> track(block.marks.size());
  {
    std::vector<size_t> next(track_offset.begin(), track_offset.end() - 1);
    for (size_t m = 0; m < block.marks.size(); ++m)
      track[next[block.marks[m].point]++] = static_cast<int>(m);
  }
  size_t num_written_points = 0;
  for (const BlockPoint& point : block.points)
    if (point.position_m) ++num_written_points;
  std::string points_text;
  points_text.reserve(100 * num_points + 16 * block.marks.size());
  points_text +=
      "# 3D point list with one line of data per point:\n"
      "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
      "# Number of points: " +
      std::to_string(num_written_points) + ", mean track length: " +
      FormatNumber(num_written_points > 0
                       ? static_cast<double>(num_observations) / num_written_points
                       : 0.0) +
      "\n";
  for (size_t p = 0; p < num_points; ++p) {
    const BlockPoint& point = block.points[p];
    if (!point.position_m) continue;
    AppendInteger(point_ids[p], &points_text);
    for (int k = 0; k < 3; ++k) AppendSpaceNumber((*point.position_m)[k], &points_text);
    const std::array<unsigned char, 3> rgb =
        extras != nullptr ? extras->point_rgb[p] : std::array<unsigned char, 3>{0, 0, 0};
    for (int k = 0; k < 3; ++k) {
      points_text += ' ';
      AppendInteger(rgb[k], &points_text);
    }
    AppendSpaceNumber(point_error[p], &points_text);
    for (size_t k = track_offset[p]; k < track_offset[p + 1]; ++k) {
      const int m = track[k];
      points_text += ' ';
      AppendInteger(image_ids[block.marks[m].image], &points_text);
      points_text += ' ';
      AppendInteger(keypoint_of_mark[m], &points_text);
    }
    points_text += '\n';
  }

  text->cameras = std::move(cameras_text);
  text->images = std::move(images_text);
  text->points3D = std::move(points_text);
  return Status::Ok();
}

Status WriteColmapModel(const std::string& directory, const Block& block,
                        const ColmapModelExtras* extras) {
  ColmapModelText text;
  PHOTOPOSE_RETURN_IF_ERROR(FormatColmapModel(block, extras, &text));
  std::error_code error;
  std::filesystem::create_directories(directory, error);
  if (error) return Status::Error(directory + ": cannot create the folder: " + error.message());
  PHOTOPOSE_RETURN_IF_ERROR(WriteFileAtomically(Path(directory, "cameras.txt"), text.cameras));
  PHOTOPOSE_RETURN_IF_ERROR(WriteFileAtomically(Path(directory, "images.txt"), text.images));
  PHOTOPOSE_RETURN_IF_ERROR(WriteFileAtomically(Path(directory, "points3D.txt"), text.points3D));
  return Status::Ok();
}

}  // namespace photopose
