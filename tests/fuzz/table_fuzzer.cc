// libFuzzer harness: one table reader of core/io/tables.h on arbitrary bytes, chosen at build time by
// PHOTOPOSE_FUZZ_TABLE (camera, frames, points, marks, gcp_list). What a reader accepts must be
// inside the physical ranges and must survive a write and a second read unchanged in size.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "core/io/tables.h"
#include "tests/fuzz/fuzz_util.h"

namespace {

using photopose::Status;
using photopose::fuzz::CheckMessage;

void Require(bool condition) {
  if (!condition) std::abort();
}

// Parses `text`; every record accepted must pass `check`, and the records must be written and
// read back, as many as before.
template <typename Record, typename Parse, typename Format, typename Check>
void RoundTrip(std::string_view text, Parse parse, Format format, Check check) {
  std::vector<Record> records;
  const Status status = parse(text, &records);
  CheckMessage(status);
  if (!status.ok()) return;
  for (const Record& record : records) Require(check(record));
  std::string written;
  Require(format(records, &written).ok());
  std::vector<Record> again;
  Require(parse(written, &again).ok());
  Require(again.size() == records.size());
}

void FuzzCameras(std::string_view text) {
  RoundTrip<photopose::FrameCamera>(
      text,
      [](std::string_view t, auto* cameras) {
        return photopose::ParseCameraTable(t, "cameras.csv", cameras);
      },
      [](const auto& cameras, std::string* out) {
        return photopose::FormatCameraTable(cameras, "cameras.csv", out);
      },
      [](const photopose::FrameCamera& camera) {
        return camera.IsValid().ok() && camera.focal_length_um > 0.0 &&
               camera.focal_length_um <= photopose::kMaxCoordinate;
      });
}

void FuzzFrames(std::string_view text) {
  RoundTrip<photopose::FrameRecord>(
      text,
      [](std::string_view t, auto* frames) {
        return photopose::ParseFramesTable(t, "frames.csv", {}, frames);
      },
      [](const auto& frames, std::string* out) {
        return photopose::FormatFramesTable({}, frames, "frames.csv", out);
      },
      [](const photopose::FrameRecord& frame) { return frame.eo.parameters.allFinite(); });
}

void FuzzPoints(std::string_view text) {
  RoundTrip<photopose::GroundPoint>(
      text,
      [](std::string_view t, auto* points) {
        return photopose::ParseGroundPoints(t, "points.csv", points);
      },
      [](const auto& points, std::string* out) {
        return photopose::FormatGroundPoints(points, "points.csv", out);
      },
      [](const photopose::GroundPoint& point) {
        return point.position.cwiseAbs().maxCoeff() <= photopose::kMaxCoordinate;
      });
}

void FuzzMarks(std::string_view text) {
  RoundTrip<photopose::ImageMark>(
      text,
      [](std::string_view t, auto* marks) {
        return photopose::ParseImageMarks(t, "marks.csv", marks);
      },
      [](const auto& marks, std::string* out) {
        return photopose::FormatImageMarks(marks, "marks.csv", out);
      },
      [](const photopose::ImageMark& mark) {
        return mark.column_row.has_value() != mark.film_um.has_value();
      });
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

void FuzzGeoTxt(std::string_view text) {
  photopose::GeoTxt geo;
  const Status status = photopose::ParseGeoTxt(text, "geo.txt", &geo);
  CheckMessage(status);
  if (!status.ok()) return;
  for (const photopose::GeoTxtRecord& record : geo.records) {
    // Without height z is NaN, never a number.
    Require(record.has_height ? std::isfinite(record.position.z()) : std::isnan(record.position.z()));
    Require(record.position.head<2>().allFinite() &&
            record.position.head<2>().cwiseAbs().maxCoeff() <= photopose::kMaxCoordinate);
    Require(!record.has_height || std::abs(record.position.z()) <= photopose::kMaxCoordinate);
    Require(record.horizontal_accuracy_m.has_value() == record.vertical_accuracy_m.has_value());
    Require(!record.horizontal_accuracy_m || *record.horizontal_accuracy_m > 0.0);
  }
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
  if (table == "geo_txt") FuzzGeoTxt(text);
  return 0;
}
