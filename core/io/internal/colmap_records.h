#pragma once
// The records of a COLMAP model as its files hold them, text or binary (core/io/colmap.h): both
// formats are parsed into these and formatted from them, so that the checks and the conversion to
// and from a Block are one code path (colmap.cc) and only the byte layout is per format
// (colmap_text.cc, colmap_binary.cc). Internal to core/io; not installed.

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/camera_models.h"
#include "core/io/colmap.h"
#include "core/status.h"

namespace photopose {
class TextPieces;
}  // namespace photopose

namespace photopose::colmap_io {

// Where a record is, for messages: its line (text) or the byte offset of its first byte (binary).
// A list (POINTS2D, TRACK) has its own: the line that holds it, or the offset of its first entry.
using Place = long long;

struct CameraRecord {
  long long id = 0;  // CAMERA_ID
  CameraModelType model = CameraModelType::kSimplePinhole;
  long long width = 0, height = 0;  // px, as read (checked when the block is built)
  std::vector<double> params;       // CameraModelNumParams(model) values, COLMAP's order
  Place place = 0;
};

struct ImageRecord {
  long long id = 0;           // IMAGE_ID (COLMAP's image_t is 32-bit)
  std::array<double, 4> q{};  // QW QX QY QZ as read (normalised when built)
  std::array<double, 3> t{};  // TX TY TZ (m): x_cam = R(q) X + t
  long long camera_id = 0;    // CAMERA_ID
  std::string name;           // NAME
  size_t points2D_begin = 0;  // its POINTS2D: Records::points2D[begin, begin + size)
  size_t num_points2D = 0;
  Place place = 0;
  Place points2D_place = 0;
};

struct Point2DRecord {
  double x = 0.0, y = 0.0;    // px, COLMAP's pixel convention
  long long point3D_id = -1;  // -1: a keypoint without a 3D point
};

struct PointRecord {
  long long id = 0;                    // POINT3D_ID
  std::array<double, 3> xyz{};         // m
  std::array<unsigned char, 3> rgb{};  // R G B
  double error = 0.0;                  // ERROR (px)
  size_t track_begin = 0;              // its TRACK: Records::tracks[begin, begin + length)
  size_t track_length = 0;
  Place place = 0;
  Place track_place = 0;
};

struct TrackRecord {
  uint32_t image_id = 0;     // IMAGE_ID
  uint32_t point2D_idx = 0;  // POINT2D_IDX
};

// A whole model: the three files' records in file order.
struct Records {
  std::vector<CameraRecord> cameras;
  std::vector<ImageRecord> images;
  std::vector<Point2DRecord> points2D;
  std::vector<PointRecord> points;
  std::vector<TrackRecord> tracks;
};

// The paths of the three files and their format, to name them in messages.
struct ModelPaths {
  ColmapFormat format = ColmapFormat::kText;
  std::string cameras, images, points3D;
};

// "path:line: field: what" (text) or "path: byte N: field: what" (binary); `place` is the record's
// (or a list's) place, and `entry` with `entry_bytes` picks the entry of a binary list (the line
// of a text list holds them all).
Status RecordError(const ModelPaths& paths, const std::string& path, Place place,
                   std::string_view field, std::string_view what, size_t entry = 0,
                   size_t entry_bytes = 0);

// The COLMAP model ids and names (cameras.bin's MODEL_ID, cameras.txt's MODEL) and which of them
// core/camera_models.h supports: one table, so that a model added there is read and written
// here without another line.
struct ModelName {
  int id;
  const char* name;
};
const std::vector<ModelName>& ColmapModelNames();
// The supported model of a COLMAP name / id; false for another one.
bool ModelOfName(std::string_view name, CameraModelType* model);
bool ModelOfId(long long id, CameraModelType* model);
int ModelId(CameraModelType model);
// "SIMPLE_PINHOLE, PINHOLE, ..." (the supported ones), for messages.
std::string SupportedModels();

// The per-format layers: parse one file (named in messages by `paths`) into its part of *records,
// any file in any order (references between them are checked when the block is built); format
// one file of the records into `out` (collected whole, or written in pieces: an error only when
// writing fails).
enum class ModelFile { kCameras, kImages, kPoints3D };
Status ParseTextFile(ModelFile file, std::string_view text, const ModelPaths& paths,
                     Records* records);
Status ParseBinaryFile(ModelFile file, std::string_view bytes, const ModelPaths& paths,
                       Records* records);
Status FormatTextFile(ModelFile file, const Records& records, TextPieces* out);
Status FormatBinaryFile(ModelFile file, const Records& records, TextPieces* out);

}  // namespace photopose::colmap_io
