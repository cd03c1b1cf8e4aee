// COLMAP models (colmap.h): records -> block with every check of a value and a reference, and
// block -> records. One file past ~800 lines on purpose: the format's one pair (core/io rule), and
// both directions beside each other so that a camera model or a frame convention has one home;
// the byte layouts alone are in colmap_text.cc and colmap_binary.cc.
#include "core/io/colmap.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <climits>
#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <string_view>
#include <unordered_map>

#include "core/camera.h"
#include "core/collinearity.h"
#include "core/io/csv.h"
#include "core/io/internal/colmap_records.h"
#include "core/io/output_files.h"
#include "core/io/tables.h"
#include "core/io/text_scanner.h"
#include "core/rotation.h"

namespace photopose {

// ------------------------------------------------------------------ shared by both formats

namespace colmap_io {

const std::vector<ModelName>& ColmapModelNames() {
  static const auto* const kNames = new std::vector<ModelName>{{0, "SIMPLE_PINHOLE"},
                                                               {1, "PINHOLE"},
                                                               {2, "SIMPLE_RADIAL"},
                                                               {3, "RADIAL"},
                                                               {4, "OPENCV"},
                                                               {5, "OPENCV_FISHEYE"},
                                                               {6, "FULL_OPENCV"},
                                                               {7, "FOV"},
                                                               {8, "SIMPLE_RADIAL_FISHEYE"},
                                                               {9, "RADIAL_FISHEYE"},
                                                               {10, "THIN_PRISM_FISHEYE"}};
  return *kNames;
}

bool ModelOfName(std::string_view name, CameraModelType* model) {
  for (const ModelName& entry : ColmapModelNames()) {
    // The supported ones are those core/camera_models.h names (kFrame is no COLMAP model).
    if (ParseEnum(name, model) && EnumName(*model) == std::string_view(entry.name)) return true;
  }
  return false;
}

bool ModelOfId(long long id, CameraModelType* model) {
  for (const ModelName& entry : ColmapModelNames())
    if (entry.id == id) return ModelOfName(entry.name, model);
  return false;
}

int ModelId(CameraModelType model) {
  for (const ModelName& entry : ColmapModelNames())
    if (EnumName(model) == std::string_view(entry.name)) return entry.id;
  return -1;
}

std::string SupportedModels() {
  std::string list;
  CameraModelType model;
  for (const ModelName& entry : ColmapModelNames()) {
    if (!ModelOfName(entry.name, &model)) continue;
    if (!list.empty()) list += ", ";
    list += entry.name;
  }
  return list;
}

Status RecordError(const ModelPaths& paths, const std::string& path, Place place,
                   std::string_view field, std::string_view what, size_t entry,
                   size_t entry_bytes) {
  if (paths.format == ColmapFormat::kText)
    return TextError(path, static_cast<int>(place), field, what);
  return Status::Error(
      path + ": byte " +
      std::to_string(static_cast<unsigned long long>(place) + entry * entry_bytes) + ": " +
      std::string(field) + ": " + std::string(what));
}

}  // namespace colmap_io

using colmap_io::Place;
using colmap_io::RecordError;

namespace {

// Binary entry sizes of the lists, for the byte offsets of messages (colmap_binary.cc's layout).
constexpr size_t kPoint2DEntryBytes = 24;
constexpr size_t kTrackEntryBytes = 8;

// Quaternions are normalised as COLMAP does; one whose norm is below this is no rotation at all,
// one whose norm is above its inverse is refused too (its square overflows long before 1e300).
constexpr double kMinQuaternionNorm = 1e-12;
// A kFrame camera is a pinhole in COLMAP's pixels when its film -> pixel mapping has no rotation
// or shear: off-diagonal terms below this fraction of the diagonal ones (pixel sizes are given
// with far fewer digits than this).
constexpr double kPinholeShearTolerance = 1e-12;
// Pixels are square (SIMPLE_PINHOLE rather than PINHOLE) when fx and fy agree to this fraction.
constexpr double kSquarePixelTolerance = 1e-15;
// COLMAP's camera_t and image_t are 32-bit (the binary files hold them so).
constexpr long long kMaxBinaryId = 0xffffffffLL;

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

colmap_io::ModelPaths PathsOf(const std::string& directory, ColmapFormat format) {
  const std::array<const char*, 3> names = ColmapFileNames(format);
  return {format, Path(directory, names[0]), Path(directory, names[1]), Path(directory, names[2])};
}

// ------------------------------------------------------------------ records -> block

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

// "1e+300 is outside [-100000000, 100000000] m", or "" when |value| <= max_magnitude.
std::string OutsideMessage(double value, double max_magnitude, std::string_view unit) {
  if (std::abs(value) <= max_magnitude) return std::string();
  if (!std::isfinite(value)) return FormatNumber(value) + " is not a finite number";
  return FormatNumber(value) + " is outside [" + FormatPlainNumber(-max_magnitude) + ", " +
         FormatPlainNumber(max_magnitude) + "]" + (unit.empty() ? "" : " ") + std::string(unit);
}

// What BlockFromRecords checks and builds, one file after the other.
class ModelBuilder {
 public:
  ModelBuilder(const colmap_io::Records& records, const colmap_io::ModelPaths& paths, Block* block,
               ColmapModelExtras* extras)
      : r_(records), paths_(paths), block_(*block), extras_(extras) {}

  Status Cameras();
  Status Points();
  Status Images();
  Status Tracks() const;

 private:
  // The POINTS2D of one image (the block's image_index): marks of the points in the model,
  // unmatched keypoints into the extras.
  Status ImageMarks(const colmap_io::ImageRecord& im, int image_index);
  // The file name of one of the three files ("cameras.txt"), for messages naming the other file.
  const char* FileName(int file) const { return ColmapFileNames(paths_.format)[file]; }
  // The line of a record for the block's messages (0 in a binary file: it has no lines).
  int LineOf(Place place) const {
    return paths_.format == ColmapFormat::kText ? static_cast<int>(place) : 0;
  }
  Status CameraError(const colmap_io::CameraRecord& c, std::string_view field,
                     std::string_view what) const {
    return RecordError(paths_, paths_.cameras, c.place, field, what);
  }

  const colmap_io::Records& r_;
  const colmap_io::ModelPaths& paths_;
  Block& block_;
  ColmapModelExtras* extras_;
  IdIndex camera_of_id_, point_of_id_, image_of_id_;
  // Per POINTS2D entry of all images (in record order): its mark, or -1.
  std::vector<int> mark_of_point2D_;
};

// A camera parameter: focal lengths in [kMinFocalLengthPx, kMaxCoordinate], the principal point
// within kMaxCoordinate, the distortion coefficients any finite number.
Status ModelBuilder::Cameras() {
  for (const colmap_io::CameraRecord& c : r_.cameras) {
    constexpr long long kMaxSize = INT_MAX;
    for (const auto& [field, size] :
         {std::pair<const char*, long long>{"WIDTH", c.width}, {"HEIGHT", c.height}}) {
      if (size < 1 || size > kMaxSize) {
        return CameraError(
            c, field,
            std::to_string(size) + " is out of range [1, " + std::to_string(kMaxSize) + "]");
      }
    }
    const std::vector<std::string> names = CameraModelParamNames(c.model);
    for (size_t k = 0; k < names.size(); ++k) {
      const std::string field = "PARAMS " + names[k];
      const double value = c.params[k];
      const bool focal = names[k] == "f" || names[k] == "fx" || names[k] == "fy";
      const bool principal = names[k] == "cx" || names[k] == "cy";
      const std::string outside = OutsideMessage(
          value, focal || principal ? kMaxCoordinate : std::numeric_limits<double>::max(), "px");
      if (!outside.empty()) return CameraError(c, field, outside);
      if (focal && !(value >= kMinFocalLengthPx)) {
        return CameraError(c, field,
                           FormatNumber(value) + " is no focal length: it must be at least " +
                               FormatNumber(kMinFocalLengthPx) + " px");
      }
    }
    if (!camera_of_id_.Insert(c.id, static_cast<int>(block_.cameras.size())))
      return CameraError(c, "CAMERA_ID", "camera " + std::to_string(c.id) + " is listed twice");
    BlockCamera camera;
    camera.camera_id = std::to_string(c.id);
    camera.model = c.model;
    camera.table.camera_id = camera.camera_id;
    camera.table.n_columns = static_cast<int>(c.width);
    camera.table.n_rows = static_cast<int>(c.height);
    camera.params = c.params;
    block_.cameras.push_back(std::move(camera));
  }
  camera_of_id_.Freeze();
  return Status::Ok();
}

Status ModelBuilder::Points() {
  block_.points.reserve(r_.points.size());
  for (const colmap_io::PointRecord& p : r_.points) {
    const auto error = [&](std::string_view field, std::string_view what) {
      return RecordError(paths_, paths_.points3D, p.place, field, what);
    };
    const char* const kAxis[] = {"X", "Y", "Z"};
    for (int k = 0; k < 3; ++k) {
      const std::string outside = OutsideMessage(p.xyz[k], kMaxCoordinate, "m");
      if (!outside.empty()) return error(kAxis[k], outside);
    }
    if (!std::isfinite(p.error))
      return error("ERROR", FormatNumber(p.error) + " is not a finite number");
    const int index = static_cast<int>(block_.points.size());
    if (!point_of_id_.Insert(p.id, index))
      return error("POINT3D_ID", "point " + std::to_string(p.id) + " is listed twice");
    BlockPoint point;
    point.id = std::to_string(p.id);
    point.role = PointRole::kTie;
    point.position_m = Eigen::Vector3d(p.xyz[0], p.xyz[1], p.xyz[2]);
    point.line = LineOf(p.place);
    block_.points.push_back(std::move(point));
    if (extras_ != nullptr) {
      extras_->point_rgb.push_back(p.rgb);
      extras_->point_error_px.push_back(p.error);
    }
  }
  point_of_id_.Freeze();
  return Status::Ok();
}

Status ModelBuilder::Images() {
  // A consistent model has one mark per track entry.
  block_.marks.reserve(r_.tracks.size());
  if (extras_ != nullptr) extras_->mark_keypoint_index.reserve(r_.tracks.size());
  mark_of_point2D_.assign(r_.points2D.size(), -1);
  block_.images.reserve(r_.images.size());
  for (const colmap_io::ImageRecord& im : r_.images) {
    const auto error = [&](std::string_view field, std::string_view what) {
      return RecordError(paths_, paths_.images, im.place, field, what);
    };
    const char* const kQ[] = {"QW", "QX", "QY", "QZ"};
    for (int k = 0; k < 4; ++k) {
      if (!std::isfinite(im.q[k]))
        return error(kQ[k], FormatNumber(im.q[k]) + " is not a finite number");
    }
    const char* const kT[] = {"TX", "TY", "TZ"};
    for (int k = 0; k < 3; ++k) {
      const std::string outside = OutsideMessage(im.t[k], kMaxCoordinate, "m");
      if (!outside.empty()) return error(kT[k], outside);
    }
    if (im.name.empty()) return error("NAME", "is missing");
    Eigen::Quaterniond q(im.q[0], im.q[1], im.q[2], im.q[3]);
    const double q_norm = q.coeffs().stableNorm();  // no overflow: 1e300 is named as such
    if (!(q_norm > kMinQuaternionNorm))
      return error("QW", "the quaternion (QW, QX, QY, QZ) is zero");
    if (!(q_norm < 1.0 / kMinQuaternionNorm)) {
      return error("QW", "the quaternion (QW, QX, QY, QZ) has norm " + FormatNumber(q_norm) +
                             "; COLMAP's is a unit quaternion (one with a norm between " +
                             FormatNumber(kMinQuaternionNorm) + " and " +
                             FormatNumber(1.0 / kMinQuaternionNorm) + " is normalised)");
    }
    q.normalize();
    const int camera = camera_of_id_.Find(im.camera_id);
    if (camera < 0) {
      return error("CAMERA_ID",
                   "camera " + std::to_string(im.camera_id) + " is not in " + FileName(0));
    }
    const int image_index = static_cast<int>(block_.images.size());
    if (!image_of_id_.Insert(im.id, image_index))
      return error("IMAGE_ID", "image " + std::to_string(im.id) + " is listed twice");
    if (im.num_points2D > static_cast<size_t>(INT_MAX))
      return error("POINTS2D", "too many entries");
    BlockImage image;
    image.name = im.name;
    image.camera = camera;
    image.eo = EoFromColmapPose(q, Eigen::Vector3d(im.t[0], im.t[1], im.t[2]));
    image.line = LineOf(im.place);
    block_.images.push_back(std::move(image));

    PHOTOPOSE_RETURN_IF_ERROR(ImageMarks(im, image_index));
    if (extras_ != nullptr) {
      extras_->image_ids.push_back(im.id);
      extras_->num_keypoints.push_back(static_cast<int>(im.num_points2D));
    }
  }
  image_of_id_.Freeze();
  return Status::Ok();
}

Status ModelBuilder::ImageMarks(const colmap_io::ImageRecord& im, int image_index) {
  for (size_t k = 0; k < im.num_points2D; ++k) {
    const colmap_io::Point2DRecord& entry = r_.points2D[im.points2D_begin + k];
    const auto entry_error = [&](std::string_view field, std::string_view what) {
      return RecordError(paths_, paths_.images, im.points2D_place, field, what, k,
                         kPoint2DEntryBytes);
    };
    const Eigen::Vector2d xy(entry.x, entry.y);
    for (int axis = 0; axis < 2; ++axis) {
      const std::string outside = OutsideMessage(xy[axis], kMaxCoordinate, "px");
      if (!outside.empty()) return entry_error(axis == 0 ? "POINTS2D X" : "POINTS2D Y", outside);
    }
    if (entry.point3D_id < 0) {
      if (extras_ != nullptr)
        extras_->unmatched.push_back({image_index, static_cast<int>(k), xy});
      continue;
    }
    const int point = point_of_id_.Find(entry.point3D_id);
    if (point < 0) {
      return entry_error("POINTS2D POINT3D_ID", "point " + std::to_string(entry.point3D_id) +
                                                    " is not in " + FileName(2));
    }
    mark_of_point2D_[im.points2D_begin + k] = static_cast<int>(block_.marks.size());
    block_.marks.push_back(MakePixelMark(image_index, point, xy, LineOf(im.points2D_place)));
    if (extras_ != nullptr) extras_->mark_keypoint_index.push_back(static_cast<int>(k));
  }
  return Status::Ok();
}

// Every TRACK entry names a POINTS2D entry of its point, and every mark is in exactly one track.
Status ModelBuilder::Tracks() const {
  std::vector<char> seen(block_.marks.size(), 0);
  for (size_t p = 0; p < r_.points.size(); ++p) {
    const colmap_io::PointRecord& point = r_.points[p];
    for (size_t k = 0; k < point.track_length; ++k) {
      const colmap_io::TrackRecord& entry = r_.tracks[point.track_begin + k];
      // Built only for a message: no string per entry on the way.
      const auto error = [&](std::string_view what) {
        return RecordError(paths_, paths_.points3D, point.track_place, "TRACK",
                           "entry (" + std::to_string(entry.image_id) + ", " +
                               std::to_string(entry.point2D_idx) + ")" + std::string(what),
                           k, kTrackEntryBytes);
      };
      const int image = image_of_id_.Find(entry.image_id);
      if (image < 0) {
        return error(": image " + std::to_string(entry.image_id) + " is not in " + FileName(1));
      }
      const colmap_io::ImageRecord& im = r_.images[image];
      if (entry.point2D_idx >= im.num_points2D) {
        return error(": the image has " + std::to_string(im.num_points2D) + " POINTS2D entries");
      }
      const int mark = mark_of_point2D_[im.points2D_begin + entry.point2D_idx];
      if (mark < 0 || block_.marks[mark].point != static_cast<int>(p))
        return error(": that POINTS2D entry does not name this point");
      if (seen[mark]) return error(" is listed twice");
      seen[mark] = 1;
    }
  }
  for (size_t m = 0; m < seen.size(); ++m) {
    if (!seen[m]) {
      const BlockMark& mark = block_.marks[m];
      return RecordError(paths_, paths_.points3D, r_.points[mark.point].place, "TRACK",
                         "point " + block_.points[mark.point].id + " is observed in image '" +
                             TokenForMessage(block_.images[mark.image].name) +
                             "' but that is not in its track");
    }
  }
  return Status::Ok();
}

// The block of a model's records (every check of both formats), replacing *block and *extras
// only when all is well.
Status BlockFromRecords(const colmap_io::Records& records, const colmap_io::ModelPaths& paths,
                        Block* block, ColmapModelExtras* extras) {
  Block result;
  ColmapModelExtras result_extras;
  ModelBuilder builder(records, paths, &result, extras != nullptr ? &result_extras : nullptr);
  PHOTOPOSE_RETURN_IF_ERROR(builder.Cameras());
  PHOTOPOSE_RETURN_IF_ERROR(builder.Points());
  PHOTOPOSE_RETURN_IF_ERROR(builder.Images());
  PHOTOPOSE_RETURN_IF_ERROR(builder.Tracks());
  result.pixel_origin = PixelOrigin::kCorner;
  result.marks_source = paths.images;
  result.BuildIndex();
  *block = std::move(result);
  if (extras != nullptr) *extras = std::move(result_extras);
  return Status::Ok();
}

// Parses the three files, each given in turn by `bytes_of(file name, &bytes)` (valid until the
// next call), and builds the block.
template <typename BytesOf>
Status ColmapModelFromFiles(const colmap_io::ModelPaths& paths, BytesOf bytes_of, Block* block,
                            ColmapModelExtras* extras) {
  colmap_io::Records records;
  using colmap_io::ModelFile;
  for (const ModelFile file : {ModelFile::kCameras, ModelFile::kPoints3D, ModelFile::kImages}) {
    std::string_view bytes;
    PHOTOPOSE_RETURN_IF_ERROR(bytes_of(file, &bytes));
    PHOTOPOSE_RETURN_IF_ERROR(paths.format == ColmapFormat::kText
                                  ? colmap_io::ParseTextFile(file, bytes, paths, &records)
                                  : colmap_io::ParseBinaryFile(file, bytes, paths, &records));
  }
  return BlockFromRecords(records, paths, block, extras);
}

// ------------------------------------------------------------------ block -> records

// Integer ids: the items' own when every one is a whole number in [0, max_id] written plainly (so
// that it reads back as the same text) and they are unique, else 1..n.
template <typename Items, typename TextOf>
std::vector<long long> NumericIds(const Items& items, TextOf text_of, long long max_id) {
  std::vector<long long> ids(items.size());
  std::unordered_map<long long, int> used;
  used.reserve(items.size());
  bool own = true;
  for (size_t k = 0; k < items.size() && own; ++k) {
    const std::string& text = text_of(items[k]);
    long long id = 0;
    std::string why;
    own = !text.empty() && text.find_first_not_of("0123456789") == std::string::npos &&
          ParseWholeNumber(text, &id, &why) && std::to_string(id) == text && id <= max_id &&
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
  for (const long long id : extras.image_ids) {
    if (id < 0 || id > kMaxBinaryId)
      return Status::Error("the COLMAP extras hold an IMAGE_ID outside [0, 2^32 - 1]");
  }
  return Status::Ok();
}

// Per point, the mean reprojection error of its marks that are not left out (`left_out`: per
// mark, or empty for none); -1 when any of them has none or it has none.
void MeanErrorsOfKeptMarks(const Block& block, const std::vector<char>& left_out,
                           std::vector<double>* point_error_px) {
  std::vector<double> mark_error;
  MarkReprojectionErrors(block, &mark_error);
  std::vector<double> sum(block.points.size(), 0.0);
  std::vector<int> count(block.points.size(), 0);
  for (size_t m = 0; m < block.marks.size(); ++m) {
    if (!left_out.empty() && left_out[m]) continue;
    const int p = block.marks[m].point;
    sum[p] += mark_error[m];  // NaN propagates: the point then has no error
    ++count[p];
  }
  point_error_px->resize(block.points.size());
  for (size_t p = 0; p < sum.size(); ++p)
    (*point_error_px)[p] = count[p] > 0 && std::isfinite(sum[p]) ? sum[p] / count[p] : -1.0;
}

// Per image, the POINT2D index of every mark and unmatched keypoint: `slot` holds, per image from
// offset[image], m >= 0 for mark m and -1 - k for unmatched keypoint k; keypoint_of_mark the index
// of each mark.
Status KeypointSlots(const Block& block, const ColmapModelExtras* extras,
                     std::vector<long long>* offset, std::vector<long long>* slot,
                     std::vector<int>* keypoint_of_mark) {
  const size_t num_images = block.images.size();
  offset->assign(num_images + 1, 0);
  if (extras != nullptr) {
    for (size_t i = 0; i < num_images; ++i)
      (*offset)[i + 1] = (*offset)[i] + extras->num_keypoints[i];
  } else {
    for (const BlockMark& mark : block.marks) ++(*offset)[mark.image + 1];
    for (size_t i = 0; i < num_images; ++i) (*offset)[i + 1] += (*offset)[i];
  }
  constexpr long long kEmpty = std::numeric_limits<long long>::min();
  slot->assign(static_cast<size_t>((*offset)[num_images]), kEmpty);
  keypoint_of_mark->resize(block.marks.size());
  std::vector<long long> next(offset->begin(), offset->end() - 1);
  for (size_t m = 0; m < block.marks.size(); ++m) {
    const int image = block.marks[m].image;
    long long index;
    if (extras != nullptr) {
      index = extras->mark_keypoint_index[m];
      if (index < 0 || index >= extras->num_keypoints[image] ||
          (*slot)[(*offset)[image] + index] != kEmpty) {
        return Status::Error("the COLMAP extras give mark " + std::to_string(m + 1) +
                             " a keypoint index that is out of range or taken");
      }
    } else {
      index = next[image]++ - (*offset)[image];
    }
    (*slot)[(*offset)[image] + index] = static_cast<long long>(m);
    (*keypoint_of_mark)[m] = static_cast<int>(index);
  }
  if (extras == nullptr) return Status::Ok();
  for (size_t k = 0; k < extras->unmatched.size(); ++k) {
    const ColmapKeypoint& keypoint = extras->unmatched[k];
    if (keypoint.index < 0 || keypoint.index >= extras->num_keypoints[keypoint.image] ||
        (*slot)[(*offset)[keypoint.image] + keypoint.index] != kEmpty) {
      return Status::Error("the COLMAP extras give an unmatched keypoint of image '" +
                           block.images[keypoint.image].name +
                           "' an index that is out of range or taken");
    }
    (*slot)[(*offset)[keypoint.image] + keypoint.index] = -1 - static_cast<long long>(k);
  }
  for (size_t i = 0; i < num_images; ++i) {
    for (long long s = (*offset)[i]; s < (*offset)[i + 1]; ++s) {
      if ((*slot)[s] == kEmpty) {
        return Status::Error("the COLMAP extras leave POINT2D index " +
                             std::to_string(s - (*offset)[i]) + " of image '" +
                             block.images[i].name + "' empty");
      }
    }
  }
  return Status::Ok();
}

// The camera records, with the numeric ids of the block's cameras in *camera_ids.
Status CameraRecords(const Block& block, const ColmapWriteOptions& options, std::vector<long long>* camera_ids,
                     colmap_io::Records* records) {
  *camera_ids = NumericIds(
      block.cameras, [](const BlockCamera& c) -> const std::string& { return c.camera_id; },
      options.format == ColmapFormat::kBinary ? kMaxBinaryId
                                              : std::numeric_limits<long long>::max());
  records->cameras.resize(block.cameras.size());
  for (size_t c = 0; c < block.cameras.size(); ++c) {
    colmap_io::CameraRecord& camera = records->cameras[c];
    PHOTOPOSE_RETURN_IF_ERROR(
        ColmapCameraFromBlockCamera(block.cameras[c], &camera.model, &camera.params));
    camera.id = (*camera_ids)[c];
    camera.width = block.cameras[c].table.n_columns;
    camera.height = block.cameras[c].table.n_rows;
  }
  return Status::Ok();
}

// Which points and marks are written: the points with a position, and, when one of their marks
// is left out, with at least two kept; a mark is in its point's track when it is kept and its
// point written.
struct WrittenTracks {
  WrittenTracks(const Block& block, const std::vector<char>& left_out) : block(block), left_out(left_out) {
    const size_t num_points = block.points.size();
    std::vector<int> num_kept(num_points, 0), num_left_out(num_points, 0);
    for (size_t m = 0; m < block.marks.size(); ++m)
      ++(Kept(m) ? num_kept : num_left_out)[block.marks[m].point];
    written.assign(num_points, 0);
    for (size_t p = 0; p < num_points; ++p)
      written[p] = block.points[p].position_m && (num_left_out[p] == 0 || num_kept[p] >= 2);
  }
  bool Kept(size_t m) const { return left_out.empty() || !left_out[m]; }
  bool InTrack(size_t m) const { return Kept(m) && written[block.marks[m].point]; }

  const Block& block;
  const std::vector<char>& left_out;  // ColmapWriteOptions::marks_left_out
  std::vector<char> written;          // one per point
};

// Images with their POINTS2D: marks in pixels (a frame camera's film observations mapped to its
// pixels), unmatched keypoints as they were.
Status ImageRecords(const Block& block, const ColmapModelExtras* extras, const std::vector<long long>& camera_ids,
                    const std::vector<long long>& point_ids, const std::vector<long long>& offset,
                    const std::vector<long long>& slot, const WrittenTracks& tracks, colmap_io::Records* records) {
  const size_t num_images = block.images.size();
  records->images.resize(num_images);
  records->points2D.resize(slot.size());
  for (size_t i = 0; i < num_images; ++i) {
    const BlockImage& image = block.images[i];
    colmap_io::ImageRecord& record = records->images[i];
    record.id = extras != nullptr ? extras->image_ids[i] : static_cast<long long>(i) + 1;
    Eigen::Quaterniond q;
    Eigen::Vector3d t;
    ColmapPoseFromEo(*image.eo, &q, &t);
    record.q = {q.w(), q.x(), q.y(), q.z()};
    record.t = {t.x(), t.y(), t.z()};
    record.camera_id = camera_ids[image.camera];
    record.name = image.name;
    record.points2D_begin = static_cast<size_t>(offset[i]);
    record.num_points2D = static_cast<size_t>(offset[i + 1] - offset[i]);
    const BlockCamera& camera = block.cameras[image.camera];
    for (long long s = offset[i]; s < offset[i + 1]; ++s) {
      colmap_io::Point2DRecord& entry = records->points2D[static_cast<size_t>(s)];
      if (slot[s] < 0) {
        const ColmapKeypoint& keypoint = extras->unmatched[static_cast<size_t>(-1 - slot[s])];
        entry = {keypoint.xy.x(), keypoint.xy.y(), -1};
        continue;
      }
      const size_t m = static_cast<size_t>(slot[s]);
      const BlockMark& mark = block.marks[m];
      Eigen::Vector2d pixel = mark.observation;
      if (camera.model == CameraModelType::kFrame) {
        const Status status =
            PixelFromFilm(camera.table, mark.observation, PixelOrigin::kCorner, &pixel);
        if (!status.ok())
          return Status::Error("mark " + std::to_string(m + 1) + ": " + status.message());
      }
      entry = {pixel.x(), pixel.y(), tracks.InTrack(m) ? point_ids[mark.point] : -1};
    }
  }
  return Status::Ok();
}

// Points with their tracks, in block mark order per point.
void PointRecords(const Block& block, const ColmapModelExtras* extras, const std::vector<long long>& point_ids,
                  const std::vector<int>& keypoint_of_mark, const WrittenTracks& tracks,
                  colmap_io::Records* records) {
  const size_t num_points = block.points.size();
  std::vector<double> point_error;
  MeanErrorsOfKeptMarks(block, tracks.left_out, &point_error);
  std::vector<size_t> track_offset(num_points + 1, 0);
  for (size_t m = 0; m < block.marks.size(); ++m)
    if (tracks.InTrack(m)) ++track_offset[block.marks[m].point + 1];
  for (size_t p = 0; p < num_points; ++p) track_offset[p + 1] += track_offset[p];
  records->tracks.resize(track_offset[num_points]);
  {
    std::vector<size_t> next(track_offset.begin(), track_offset.end() - 1);
    for (size_t m = 0; m < block.marks.size(); ++m) {
      if (!tracks.InTrack(m)) continue;
      const BlockMark& mark = block.marks[m];
      records->tracks[next[mark.point]++] = {static_cast<uint32_t>(records->images[mark.image].id),
                                             static_cast<uint32_t>(keypoint_of_mark[m])};
    }
  }
  records->points.clear();
  for (size_t p = 0; p < num_points; ++p) {
    if (!tracks.written[p]) continue;
    colmap_io::PointRecord point;
    point.id = point_ids[p];
    const Eigen::Vector3d& position = *block.points[p].position_m;
    point.xyz = {position.x(), position.y(), position.z()};
    point.rgb = extras != nullptr ? extras->point_rgb[p] : std::array<unsigned char, 3>{0, 0, 0};
    point.error = point_error[p];
    point.track_begin = track_offset[p];
    point.track_length = track_offset[p + 1] - track_offset[p];
    records->points.push_back(point);
  }
}

// The records of a block (checked by CheckColmapModelWritable first).
Status RecordsFromBlock(const Block& block, const ColmapModelExtras* extras,
                        const ColmapWriteOptions& options, colmap_io::Records* records) {
  const std::vector<char>& left_out = options.marks_left_out;
  if (!left_out.empty() && left_out.size() != block.marks.size()) {
    return Status::Error("ColmapWriteOptions::marks_left_out has " +
                         std::to_string(left_out.size()) + " entries for " +
                         std::to_string(block.marks.size()) + " marks");
  }
  std::vector<long long> camera_ids;
  PHOTOPOSE_RETURN_IF_ERROR(CameraRecords(block, options, &camera_ids, records));
  std::vector<long long> offset, slot;
  std::vector<int> keypoint_of_mark;
  PHOTOPOSE_RETURN_IF_ERROR(KeypointSlots(block, extras, &offset, &slot, &keypoint_of_mark));
  const WrittenTracks tracks(block, left_out);
  const std::vector<long long> point_ids = NumericIds(
      block.points, [](const BlockPoint& p) -> const std::string& { return p.id; },
      std::numeric_limits<long long>::max());
  PHOTOPOSE_RETURN_IF_ERROR(ImageRecords(block, extras, camera_ids, point_ids, offset, slot, tracks, records));
  PointRecords(block, extras, point_ids, keypoint_of_mark, tracks, records);
  return Status::Ok();
}

}  // namespace

// ------------------------------------------------------------------ public

std::array<const char*, 3> ColmapFileNames(ColmapFormat format) {
  if (format == ColmapFormat::kBinary) return {"cameras.bin", "images.bin", "points3D.bin"};
  return {"cameras.txt", "images.txt", "points3D.txt"};
}

Status DetectColmapFormat(const std::string& directory, ColmapFormat* format) {
  std::error_code error;
  if (!std::filesystem::is_directory(directory, error)) {
    return Status::Error(EscapeForMessage(directory) +
                         ": is no folder; a COLMAP model is a folder with cameras, images and "
                         "points3D files (.bin or .txt)");
  }
  std::vector<std::string> missing_binary, missing_text;
  for (const ColmapFormat candidate : {ColmapFormat::kBinary, ColmapFormat::kText}) {
    std::vector<std::string>& missing =
        candidate == ColmapFormat::kBinary ? missing_binary : missing_text;
    for (const char* name : ColmapFileNames(candidate)) {
      // A FIFO or a device counts: it is refused by name when read.
      if (!std::filesystem::exists(Path(directory, name), error)) missing.push_back(name);
    }
    if (missing.empty()) {
      *format = candidate;
      return Status::Ok();
    }
  }
  // Name the files missing from the set that is closer to complete (text on a tie).
  const std::vector<std::string>& closer =
      missing_text.size() <= missing_binary.size() ? missing_text : missing_binary;
  std::string list;
  for (const std::string& name : closer) list += (list.empty() ? "" : ", ") + name;
  return Status::Error(EscapeForMessage(directory) +
                       ": no complete COLMAP model (cameras, images and points3D, all .bin or all "
                       ".txt): " +
                       list + " missing");
}

Status ReadColmapModel(const std::string& directory, Block* block, ColmapModelExtras* extras,
                       ColmapFormat* format) {
  ColmapFormat found = ColmapFormat::kText;
  PHOTOPOSE_RETURN_IF_ERROR(DetectColmapFormat(directory, &found));
  const colmap_io::ModelPaths paths = PathsOf(directory, found);
  // One file in memory at a time: each is parsed before the next is read into the same buffer.
  std::string buffer;
  const auto read = [&](colmap_io::ModelFile file, std::string_view* bytes) {
    const std::string& path = file == colmap_io::ModelFile::kCameras  ? paths.cameras
                              : file == colmap_io::ModelFile::kImages ? paths.images
                                                                      : paths.points3D;
    PHOTOPOSE_RETURN_IF_ERROR(ReadTextFile(path, &buffer));
    *bytes = buffer;
    return Status::Ok();
  };
  PHOTOPOSE_RETURN_IF_ERROR(ColmapModelFromFiles(paths, read, block, extras));
  if (format != nullptr) *format = found;
  return Status::Ok();
}

Status ParseColmapModel(const ColmapModelFiles& files, const std::string& directory, Block* block,
                        ColmapModelExtras* extras) {
  const auto view = [&](colmap_io::ModelFile file, std::string_view* bytes) {
    *bytes = file == colmap_io::ModelFile::kCameras  ? files.cameras
             : file == colmap_io::ModelFile::kImages ? files.images
                                                     : files.points3D;
    return Status::Ok();
  };
  return ColmapModelFromFiles(PathsOf(directory, files.format), view, block, extras);
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
      return Status::Error(name + " has " + CameraModelParamNames(camera.model)[k] + " = " +
                           FormatNumber(p[k]) +
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
  MeanErrorsOfKeptMarks(block, {}, point_error_px);
}

Status CheckColmapCamerasWritable(const Block& block,
                                  const std::vector<std::vector<int>>& calibrated_params) {
  for (size_t c = 0; c < block.cameras.size(); ++c) {
    const BlockCamera& camera = block.cameras[c];
    CameraModelType model;
    std::vector<double> params;
    PHOTOPOSE_RETURN_IF_ERROR(ColmapCameraFromBlockCamera(camera, &model, &params));
    if (camera.table.n_columns <= 0 || camera.table.n_rows <= 0) {
      return Status::Error("camera '" + camera.camera_id +
                           "' has no image size (NColumns, NRows), which COLMAP needs");
    }
    if (camera.model != CameraModelType::kFrame || c >= calibrated_params.size()) continue;
    for (const int k : calibrated_params[c]) {
      if (k >= kFrameK0 && k <= kFrameSkew) {
        return Status::Error("camera '" + camera.camera_id + "': calibrating " +
                             CameraModelParamNames(camera.model)[k] +
                             " would make it no COLMAP pinhole camera (a frame camera is written "
                             "to COLMAP without distortion, affinity and skew)");
      }
    }
  }
  return Status::Ok();
}

Status CheckColmapModelWritable(const Block& block, const ColmapModelExtras* extras) {
  PHOTOPOSE_RETURN_IF_ERROR(CheckBlock(block));
  if (extras != nullptr) PHOTOPOSE_RETURN_IF_ERROR(CheckExtras(block, *extras));
  PHOTOPOSE_RETURN_IF_ERROR(CheckColmapCamerasWritable(block, {}));
  for (const BlockImage& image : block.images) {
    if (!image.eo) {
      return Status::Error("image '" + image.name +
                           "' has no exterior orientation: a COLMAP model holds oriented images "
                           "only");
    }
    // A name must survive a text model too: the rest of a line, its blanks around it trimmed.
    if (image.name.empty() ||
        image.name.find_first_of(std::string_view("\n\r\0", 3)) != std::string::npos ||
        std::string_view(" \t\v\f").find(image.name.front()) != std::string_view::npos ||
        std::string_view(" \t\v\f").find(image.name.back()) != std::string_view::npos)
      return Status::Error("image '" + TokenForMessage(image.name) +
                           "' has a name COLMAP cannot hold");
  }
  return Status::Ok();
}

namespace {

// The model's records, each of its files formatted into format_file(file, format_one), which
// calls format_one(out) with the TextPieces the file goes to.
using FileFormatter = std::function<Status(TextPieces* out)>;
Status FormatModelFiles(const Block& block, const ColmapModelExtras* extras,
                        const ColmapWriteOptions& options,
                        const std::function<Status(colmap_io::ModelFile file,
                                                   const FileFormatter& format_one)>& format_file) {
  PHOTOPOSE_RETURN_IF_ERROR(CheckColmapModelWritable(block, extras));
  colmap_io::Records records;
  PHOTOPOSE_RETURN_IF_ERROR(RecordsFromBlock(block, extras, options, &records));
  for (const colmap_io::ModelFile file :
       {colmap_io::ModelFile::kCameras, colmap_io::ModelFile::kImages,
        colmap_io::ModelFile::kPoints3D}) {
    PHOTOPOSE_RETURN_IF_ERROR(format_file(file, [&](TextPieces* out) {
      return options.format == ColmapFormat::kBinary
                 ? colmap_io::FormatBinaryFile(file, records, out)
                 : colmap_io::FormatTextFile(file, records, out);
    }));
  }
  return Status::Ok();
}

}  // namespace

Status FormatColmapModel(const Block& block, const ColmapModelExtras* extras,
                         const ColmapWriteOptions& options, ColmapModelFiles* files) {
  ColmapModelFiles out;
  out.format = options.format;
  PHOTOPOSE_RETURN_IF_ERROR(FormatModelFiles(
      block, extras, options, [&](colmap_io::ModelFile file, const FileFormatter& format_one) {
        TextPieces whole;
        PHOTOPOSE_RETURN_IF_ERROR(format_one(&whole));
        std::string& text = file == colmap_io::ModelFile::kCameras  ? out.cameras
                            : file == colmap_io::ModelFile::kImages ? out.images
                                                                    : out.points3D;
        text = std::move(whole.text());
        return Status::Ok();
      }));
  *files = std::move(out);
  return Status::Ok();
}

Status StageColmapModel(const Block& block, const ColmapModelExtras* extras,
                        const ColmapWriteOptions& options, const std::string& directory,
                        OutputFiles* outputs) {
  const colmap_io::ModelPaths paths = PathsOf(directory, options.format);
  return FormatModelFiles(
      block, extras, options, [&](colmap_io::ModelFile file, const FileFormatter& format_one) {
        const std::string& path = file == colmap_io::ModelFile::kCameras  ? paths.cameras
                                  : file == colmap_io::ModelFile::kImages ? paths.images
                                                                          : paths.points3D;
        return outputs->StageInPieces(path, format_one);
      });
}

Status WriteColmapModel(const std::string& directory, const Block& block,
                        const ColmapModelExtras* extras, const ColmapWriteOptions& options) {
  // Refused before the folder is made (as the writing refuses them).
  PHOTOPOSE_RETURN_IF_ERROR(CheckColmapModelWritable(block, extras));
  std::error_code error;
  std::filesystem::create_directories(directory, error);
  if (error) return Status::Error(directory + ": cannot create the folder: " + error.message());
  const colmap_io::ModelPaths paths = PathsOf(directory, options.format);
  OutputFiles outputs;
  for (const std::string* path : {&paths.cameras, &paths.images, &paths.points3D})
    PHOTOPOSE_RETURN_IF_ERROR(outputs.AddOutput("", *path));
  PHOTOPOSE_RETURN_IF_ERROR(StageColmapModel(block, extras, options, directory, &outputs));
  return outputs.Commit();
}

}  // namespace photopose
