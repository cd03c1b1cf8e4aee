// The tables read from and written to files (core/io/tables.h); the formats are in camera_table.cc, frames_table.cc, points_marks_tables.cc and gcp_list.cc.
#include "core/io/tables.h"


#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstring>
#include <deque>
#include <functional>
#include <map>
#include <string_view>

#include "core/io/csv.h"
#include "core/io/text_scanner.h"
#include "core/io/internal/table_fields.h"

namespace photopose {
using namespace table_io;  // NOLINT: the shared table machinery of this folder
// ------------------------------------------------------------------ files

namespace {

// Reads the file at `path` (or standard input for "-"; ReadTextFile's rules) and hands its text
// and its name for messages to `parse`.
template <typename Parse>
Status ReadAndParse(const std::string& path, Parse parse) {
  std::string text;
  PHOTOPOSE_RETURN_IF_ERROR(ReadTextFile(path, &text));
  return parse(text, InputName(path));
}

}  // namespace

Status ReadCameraTable(const std::string& path, std::vector<FrameCamera>* cameras) {
  return ReadAndParse(path, [&](std::string_view text, const std::string& name) {
    return ParseCameraTable(text, name, cameras);
  });
}
Status ReadFramesTable(const std::string& path, const FramesTableOptions& options,
                       std::vector<FrameRecord>* frames) {
  return ReadAndParse(path, [&](std::string_view text, const std::string& name) {
    return ParseFramesTable(text, name, options, frames);
  });
}
Status ReadGroundPoints(const std::string& path, std::vector<GroundPoint>* points) {
  return ReadAndParse(path, [&](std::string_view text, const std::string& name) {
    return ParseGroundPoints(text, name, points);
  });
}
Status ReadImageMarks(const std::string& path, std::vector<ImageMark>* marks) {
  return ReadAndParse(path, [&](std::string_view text, const std::string& name) {
    return ParseImageMarks(text, name, marks);
  });
}
Status ReadGcpList(const std::string& path, GcpList* gcp_list) {
  return ReadAndParse(path, [&](std::string_view text, const std::string& name) {
    return ParseGcpList(text, name, gcp_list);
  });
}

Status ReadGeoTxt(const std::string& path, GeoTxt* geo) {
  return ReadAndParse(path, [&](std::string_view text, const std::string& name) {
    return ParseGeoTxt(text, name, geo);
  });
}

Status WriteCameraTable(const std::string& path, const std::vector<FrameCamera>& cameras) {
  std::string text;
  PHOTOPOSE_RETURN_IF_ERROR(FormatCameraTable(cameras, path, &text));
  return WriteFileAtomically(path, text);
}
Status WriteFramesTable(const std::string& path, const FramesTableOptions& options,
                        const std::vector<FrameRecord>& frames) {
  std::string text;
  PHOTOPOSE_RETURN_IF_ERROR(FormatFramesTable(options, frames, path, &text));
  return WriteFileAtomically(path, text);
}
Status WriteGroundPoints(const std::string& path, const std::vector<GroundPoint>& points) {
  std::string text;
  PHOTOPOSE_RETURN_IF_ERROR(FormatGroundPoints(points, path, &text));
  return WriteFileAtomically(path, text);
}
Status WriteImageMarks(const std::string& path, const std::vector<ImageMark>& marks) {
  std::string text;
  PHOTOPOSE_RETURN_IF_ERROR(FormatImageMarks(marks, path, &text));
  return WriteFileAtomically(path, text);
}


}  // namespace photopose
