// The binary layer of COLMAP models (core/io/colmap.h): cameras.bin, images.bin and points3D.bin
// to and from the records of core/io/internal/colmap_records.h. Only the layout is checked here
// (every field inside the file, counts that the bytes left can hold, a known model id, names
// ending in NUL, ids in range of the records' types, no bytes after the last record); the values
// and the references between records are checked where the block is built (colmap.cc).
//
// The files are little-endian whatever the host (COLMAP writes them so): numbers are assembled
// from their bytes, never read through a cast.
#include <algorithm>
#include <cstring>
#include <limits>
#include <string>

#include "core/io/csv.h"
#include "core/io/internal/colmap_records.h"
#include "core/io/output_files.h"

namespace photopose::colmap_io {
namespace {

// Fixed sizes (bytes) of the records, without their lists: each count is checked against them
// before anything is allocated for it.
constexpr size_t kCameraBytes = 4 + 4 + 8 + 8;         // + 8 per parameter
constexpr size_t kImageBytes = 4 + 7 * 8 + 4 + 1 + 8;  // name of at least its NUL
constexpr size_t kPoint2DBytes = 8 + 8 + 8;
constexpr size_t kPointBytes = 8 + 3 * 8 + 3 + 8 + 8;
constexpr size_t kTrackBytes = 4 + 4;
constexpr uint64_t kNoPoint3D = std::numeric_limits<uint64_t>::max();

// Reads a binary file front to back; errors name the file and the byte offset of the field.
class ByteReader {
 public:
  ByteReader(std::string_view bytes, const std::string& path) : bytes_(bytes), path_(path) {}

  size_t offset() const { return offset_; }
  size_t left() const { return bytes_.size() - offset_; }

  Status Error(size_t offset, std::string_view field, std::string_view what) const {
    return Status::Error(path_ + ": byte " + std::to_string(offset) + ": " + std::string(field) +
                         ": " + std::string(what));
  }

  // An unsigned little-endian integer of `size` bytes.
  Status Unsigned(std::string_view field, size_t size, uint64_t* value) {
    if (left() < size) {
      return Error(offset_, field,
                   "the file ends inside it (" + std::to_string(left()) + " bytes left, " +
                       std::to_string(size) + " needed)");
    }
    uint64_t v = 0;
    for (size_t k = 0; k < size; ++k)
      v |= static_cast<uint64_t>(static_cast<unsigned char>(bytes_[offset_ + k])) << (8 * k);
    offset_ += size;
    *value = v;
    return Status::Ok();
  }
  Status U32(std::string_view field, long long* value) {
    uint64_t v = 0;
    PHOTOPOSE_RETURN_IF_ERROR(Unsigned(field, 4, &v));
    *value = static_cast<long long>(v);
    return Status::Ok();
  }
  Status Double(std::string_view field, double* value) {
    uint64_t bits = 0;
    PHOTOPOSE_RETURN_IF_ERROR(Unsigned(field, 8, &bits));
    std::memcpy(value, &bits, sizeof(bits));
    return Status::Ok();
  }
  // A uint64 that must fit a long long (ids).
  Status Id(std::string_view field, long long* value) {
    const size_t at = offset_;
    uint64_t v = 0;
    PHOTOPOSE_RETURN_IF_ERROR(Unsigned(field, 8, &v));
    if (v > static_cast<uint64_t>(std::numeric_limits<long long>::max()))
      return Error(at, field, std::to_string(v) + " is out of range [0, 2^63 - 1]");
    *value = static_cast<long long>(v);
    return Status::Ok();
  }
  // A count of records of at least `min_bytes` each: refused when the bytes left cannot hold
  // them, so that nothing is allocated for a count the file does not back.
  Status Count(std::string_view field, size_t min_bytes, size_t* count) {
    const size_t at = offset_;
    uint64_t v = 0;
    PHOTOPOSE_RETURN_IF_ERROR(Unsigned(field, 8, &v));
    if (v > left() / min_bytes) {
      return Error(at, field,
                   std::to_string(v) + " records of at least " + std::to_string(min_bytes) +
                       " bytes do not fit in the " + std::to_string(left()) +
                       " bytes left in the file");
    }
    *count = static_cast<size_t>(v);
    return Status::Ok();
  }
  // A NUL-terminated string.
  Status Name(std::string_view field, std::string* name) {
    const size_t end = bytes_.find('\0', offset_);
    if (end == std::string_view::npos) {
      return Error(offset_, field,
                   "no NUL byte ends it before the end of the file (" + std::to_string(left()) +
                       " bytes left)");
    }
    name->assign(bytes_.substr(offset_, end - offset_));
    offset_ = end + 1;
    return Status::Ok();
  }
  Status End() const {
    if (left() == 0) return Status::Ok();
    return Error(offset_, "end", std::to_string(left()) + " bytes after the last record");
  }

 private:
  std::string_view bytes_;
  const std::string& path_;
  size_t offset_ = 0;
};

Status ParseCameras(ByteReader* in, Records* records) {
  size_t count = 0;
  PHOTOPOSE_RETURN_IF_ERROR(in->Count("number of cameras", kCameraBytes, &count));
  records->cameras.reserve(count);
  for (size_t c = 0; c < count; ++c) {
    CameraRecord camera;
    camera.place = static_cast<Place>(in->offset());
    PHOTOPOSE_RETURN_IF_ERROR(in->U32("CAMERA_ID", &camera.id));
    const size_t model_at = in->offset();
    uint64_t model_bits = 0;
    PHOTOPOSE_RETURN_IF_ERROR(in->Unsigned("MODEL_ID", 4, &model_bits));
    const long long model_id = static_cast<int32_t>(static_cast<uint32_t>(model_bits));
    if (!ModelOfId(model_id, &camera.model)) {
      std::string name;
      for (const ModelName& entry : ColmapModelNames())
        if (entry.id == model_id) name = std::string(" (") + entry.name + ")";
      return in->Error(model_at, "MODEL_ID",
                       name.empty()
                           ? std::to_string(model_id) + " is no COLMAP camera model"
                           : "camera model " + std::to_string(model_id) + name +
                                 " is not supported (supported: " + SupportedModels() + ")");
    }
    uint64_t width = 0, height = 0;
    PHOTOPOSE_RETURN_IF_ERROR(in->Unsigned("WIDTH", 8, &width));
    PHOTOPOSE_RETURN_IF_ERROR(in->Unsigned("HEIGHT", 8, &height));
    // Beyond long long is beyond the range the block checks: saturate, it is refused there.
    constexpr uint64_t kMax = std::numeric_limits<long long>::max();
    camera.width = static_cast<long long>(std::min(width, kMax));
    camera.height = static_cast<long long>(std::min(height, kMax));
    const std::vector<std::string> names = CameraModelParamNames(camera.model);
    camera.params.resize(names.size());
    for (size_t k = 0; k < names.size(); ++k)
      PHOTOPOSE_RETURN_IF_ERROR(in->Double("PARAMS " + names[k], &camera.params[k]));
    records->cameras.push_back(std::move(camera));
  }
  return in->End();
}

Status ParseImages(ByteReader* in, Records* records) {
  size_t count = 0;
  PHOTOPOSE_RETURN_IF_ERROR(in->Count("number of images", kImageBytes, &count));
  records->images.reserve(count);
  for (size_t i = 0; i < count; ++i) {
    ImageRecord image;
    image.place = static_cast<Place>(in->offset());
    PHOTOPOSE_RETURN_IF_ERROR(in->U32("IMAGE_ID", &image.id));
    const char* const kPose[] = {"QW", "QX", "QY", "QZ", "TX", "TY", "TZ"};
    for (int k = 0; k < 7; ++k)
      PHOTOPOSE_RETURN_IF_ERROR(in->Double(kPose[k], k < 4 ? &image.q[k] : &image.t[k - 4]));
    PHOTOPOSE_RETURN_IF_ERROR(in->U32("CAMERA_ID", &image.camera_id));
    PHOTOPOSE_RETURN_IF_ERROR(in->Name("NAME", &image.name));
    size_t num_points2D = 0;
    PHOTOPOSE_RETURN_IF_ERROR(in->Count("number of POINTS2D", kPoint2DBytes, &num_points2D));
    image.points2D_place = static_cast<Place>(in->offset());
    image.points2D_begin = records->points2D.size();
    image.num_points2D = num_points2D;
    for (size_t k = 0; k < num_points2D; ++k) {
      Point2DRecord entry;
      PHOTOPOSE_RETURN_IF_ERROR(in->Double("POINTS2D X", &entry.x));
      PHOTOPOSE_RETURN_IF_ERROR(in->Double("POINTS2D Y", &entry.y));
      const size_t id_at = in->offset();
      uint64_t id = 0;
      PHOTOPOSE_RETURN_IF_ERROR(in->Unsigned("POINTS2D POINT3D_ID", 8, &id));
      if (id == kNoPoint3D) {
        entry.point3D_id = -1;
      } else if (id > static_cast<uint64_t>(std::numeric_limits<long long>::max())) {
        return in->Error(id_at, "POINTS2D POINT3D_ID",
                         std::to_string(id) + " is out of range [0, 2^63 - 1] (2^64 - 1: none)");
      } else {
        entry.point3D_id = static_cast<long long>(id);
      }
      records->points2D.push_back(entry);
    }
    records->images.push_back(std::move(image));
  }
  return in->End();
}

Status ParsePoints(ByteReader* in, Records* records) {
  size_t count = 0;
  PHOTOPOSE_RETURN_IF_ERROR(in->Count("number of points", kPointBytes, &count));
  records->points.reserve(count);
  for (size_t p = 0; p < count; ++p) {
    PointRecord point;
    point.place = static_cast<Place>(in->offset());
    PHOTOPOSE_RETURN_IF_ERROR(in->Id("POINT3D_ID", &point.id));
    const char* const kAxis[] = {"X", "Y", "Z"};
    for (int k = 0; k < 3; ++k) PHOTOPOSE_RETURN_IF_ERROR(in->Double(kAxis[k], &point.xyz[k]));
    const char* const kColour[] = {"R", "G", "B"};
    for (int k = 0; k < 3; ++k) {
      uint64_t value = 0;
      PHOTOPOSE_RETURN_IF_ERROR(in->Unsigned(kColour[k], 1, &value));
      point.rgb[k] = static_cast<unsigned char>(value);
    }
    PHOTOPOSE_RETURN_IF_ERROR(in->Double("ERROR", &point.error));
    PHOTOPOSE_RETURN_IF_ERROR(in->Count("track length", kTrackBytes, &point.track_length));
    point.track_place = static_cast<Place>(in->offset());
    point.track_begin = records->tracks.size();
    for (size_t k = 0; k < point.track_length; ++k) {
      long long image_id = 0, index = 0;
      PHOTOPOSE_RETURN_IF_ERROR(in->U32("TRACK IMAGE_ID", &image_id));
      PHOTOPOSE_RETURN_IF_ERROR(in->U32("TRACK POINT2D_IDX", &index));
      records->tracks.push_back({static_cast<uint32_t>(image_id), static_cast<uint32_t>(index)});
    }
    records->points.push_back(point);
  }
  return in->End();
}

// Little-endian appends.
void PutUnsigned(uint64_t value, size_t size, std::string* out) {
  for (size_t k = 0; k < size; ++k) out->push_back(static_cast<char>((value >> (8 * k)) & 0xff));
}
void PutDouble(double value, std::string* out) {
  uint64_t bits = 0;
  std::memcpy(&bits, &value, sizeof(bits));
  PutUnsigned(bits, 8, out);
}

}  // namespace

Status ParseBinaryFile(ModelFile file, std::string_view bytes, const ModelPaths& paths,
                       Records* records) {
  switch (file) {
    case ModelFile::kCameras: {
      ByteReader in(bytes, paths.cameras);
      return ParseCameras(&in, records);
    }
    case ModelFile::kImages: {
      ByteReader in(bytes, paths.images);
      return ParseImages(&in, records);
    }
    case ModelFile::kPoints3D: {
      ByteReader in(bytes, paths.points3D);
      return ParsePoints(&in, records);
    }
  }
  return Status::Error("unknown COLMAP file");
}

namespace {

Status FormatCamerasBinary(const Records& records, TextPieces* out) {
  std::string& cameras = out->text();
  PutUnsigned(records.cameras.size(), 8, &cameras);
  for (const CameraRecord& camera : records.cameras) {
    PutUnsigned(static_cast<uint64_t>(camera.id), 4, &cameras);
    PutUnsigned(static_cast<uint32_t>(static_cast<int32_t>(ModelId(camera.model))), 4, &cameras);
    PutUnsigned(static_cast<uint64_t>(camera.width), 8, &cameras);
    PutUnsigned(static_cast<uint64_t>(camera.height), 8, &cameras);
    for (const double value : camera.params) PutDouble(value, &cameras);
  }
  return Status::Ok();
}

Status FormatImagesBinary(const Records& records, TextPieces* out) {
  std::string& images = out->text();
  out->Reserve(records.images.size() * (kImageBytes + 32) +
               records.points2D.size() * kPoint2DBytes);
  PutUnsigned(records.images.size(), 8, &images);
  for (const ImageRecord& image : records.images) {
    PutUnsigned(static_cast<uint64_t>(image.id), 4, &images);
    for (const double value : image.q) PutDouble(value, &images);
    for (const double value : image.t) PutDouble(value, &images);
    PutUnsigned(static_cast<uint64_t>(image.camera_id), 4, &images);
    images += image.name;
    images.push_back('\0');
    PutUnsigned(image.num_points2D, 8, &images);
    for (size_t k = 0; k < image.num_points2D; ++k) {
      const Point2DRecord& entry = records.points2D[image.points2D_begin + k];
      PutDouble(entry.x, &images);
      PutDouble(entry.y, &images);
      PutUnsigned(entry.point3D_id < 0 ? kNoPoint3D : static_cast<uint64_t>(entry.point3D_id), 8,
                  &images);
    }
    PHOTOPOSE_RETURN_IF_ERROR(out->Piece());
  }
  return Status::Ok();
}

Status FormatPointsBinary(const Records& records, TextPieces* out) {
  std::string& points = out->text();
  out->Reserve(records.points.size() * kPointBytes + records.tracks.size() * kTrackBytes);
  PutUnsigned(records.points.size(), 8, &points);
  for (const PointRecord& point : records.points) {
    PutUnsigned(static_cast<uint64_t>(point.id), 8, &points);
    for (const double value : point.xyz) PutDouble(value, &points);
    for (const unsigned char value : point.rgb) points.push_back(static_cast<char>(value));
    PutDouble(point.error, &points);
    PutUnsigned(point.track_length, 8, &points);
    for (size_t k = 0; k < point.track_length; ++k) {
      const TrackRecord& entry = records.tracks[point.track_begin + k];
      PutUnsigned(entry.image_id, 4, &points);
      PutUnsigned(entry.point2D_idx, 4, &points);
    }
    PHOTOPOSE_RETURN_IF_ERROR(out->Piece());
  }
  return Status::Ok();
}

}  // namespace

// Ids are in range here: the block side numbers cameras within uint32 for this format, image ids
// come from a model (uint32) or are 1..n, point ids are >= 0.
Status FormatBinaryFile(ModelFile file, const Records& records, TextPieces* out) {
  switch (file) {
    case ModelFile::kCameras:
      return FormatCamerasBinary(records, out);
    case ModelFile::kImages:
      return FormatImagesBinary(records, out);
    case ModelFile::kPoints3D:
      return FormatPointsBinary(records, out);
  }
  return Status::Error("unknown COLMAP file");
}

}  // namespace photopose::colmap_io
