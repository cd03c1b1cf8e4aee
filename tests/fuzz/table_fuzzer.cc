// libFuzzer harness: one table reader of core/tables.h on arbitrary bytes, chosen at build time by
// PHOTOPOSE_FUZZ_TABLE (camera, frames, points, marks, gcp_list). What a reader accepts must be
// inside the physical ranges and must survive a write and a second read unchanged in size.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "core/tables.h"
#include "tests/fuzz/fuzz_util.h"

namespace {

using photopose::Status;
using photopose::fuzz::CheckMessage;

void Require(bool condition) {
  if (!condition) std::abort();
}

void FuzzCameras(std::string_view text) {
  std::vector<photopose::FrameCamera> cameras;
  const Status status = photopose::ParseCameraTable(text, "cameras.csv", &cameras);
  CheckMessage(status);
  if (!status.ok()) return;
  for (const photopose::FrameCamera& camera : cameras) {
    Require(camera.IsValid().ok());
    Require(camera.focal_length_um > 0.0 && camera.focal_length_um <= photopose::kMaxCoordinate);
  }
  std::string written;
  Require(photopose::FormatCameraTable(cameras, "cameras.csv", &written).ok());
  std::vector<photopose::FrameCamera> again;
  Require(photopose::ParseCameraTable(written, "cameras.csv", &again).ok());
  Require(again.size() == cameras.size());
}

void FuzzFrames(std::string_view text) {
  std::vector<photopose::FrameRecord> frames;
  const Status status = photopose::ParseFramesTable(text, "frames.csv", {}, &frames);
  CheckMessage(status);
  if (!status.ok()) return;
  for (const photopose::FrameRecord& frame : frames) Require(frame.eo.parameters.allFinite());
  std::string written;
  Require(photopose::FormatFramesTable({}, frames, "frames.csv", &written).ok());
  std::vector<photopose::FrameRecord> again;
  Require(photopose::ParseFramesTable(written, "frames.csv", {}, &again).ok());
  Require(again.size() == frames.size());
}

void FuzzPoints(std::string_view text) {
  std::vector<photopose::GroundPoint> points;
  const Status status = photopose::ParseGroundPoints(text, "points.csv", &points);
  CheckMessage(status);
  if (!status.ok()) return;
  for (const photopose::GroundPoint& point : points)
    Require(point.position.cwiseAbs().maxCoeff() <= photopose::kMaxCoordinate);
  std::string written;
  Require(photopose::FormatGroundPoints(points, "points.csv", &written).ok());
  std::vector<photopose::GroundPoint> again;
  Require(photopose::ParseGroundPoints(written, "points.csv", &again).ok());
  Require(again.size() == points.size());
}

void FuzzMarks(std::string_view text) {
  std::vector<photopose::ImageMark> marks;
  const Status status = photopose::ParseImageMarks(text, "marks.csv", &marks);
  CheckMessage(status);
  if (!status.ok()) return;
  for (const photopose::ImageMark& mark : marks) Require(mark.column_row.has_value() != mark.film_um.has_value());
  std::string written;
  Require(photopose::FormatImageMarks(marks, "marks.csv", &written).ok());
  std::vector<photopose::ImageMark> again;
  Require(photopose::ParseImageMarks(written, "marks.csv", &again).ok());
  Require(again.size() == marks.size());
}

void FuzzGcpList(std::string_view text) {
  photopose::GcpList gcp;
  const Status status = photopose::ParseGcpList(text, "gcp_list.txt", &gcp);
  CheckMessage(status);
  if (!status.ok()) return;
  for (const photopose::GroundPoint& point : gcp.points)
    Require(point.position.cwiseAbs().maxCoeff() <= photopose::kMaxCoordinate);
  for (const photopose::ImageMark& mark : gcp.marks) Require(mark.column_row->allFinite());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const std::string_view table = PHOTOPOSE_FUZZ_TABLE;
  if (table == "camera") FuzzCameras(text);
  if (table == "frames") FuzzFrames(text);
  if (table == "points") FuzzPoints(text);
  if (table == "marks") FuzzMarks(text);
  if (table == "gcp_list") FuzzGcpList(text);
  return 0;
}
