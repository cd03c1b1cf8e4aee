// OpenDroneMap's gcp_list.txt: read (core/io/tables.h).
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
namespace {

// ------------------------------------------------------------------ gcp_list.txt

bool IsGcpCrs(std::string_view crs) {
  const std::string lower = FoldedName(crs);  // also drops spaces: "wgs84utm22s"
  if (lower.rfind("epsg:", 0) == 0) {
    return lower.size() > 5 && std::all_of(lower.begin() + 5, lower.end(), [](char c) {
             return std::isdigit(static_cast<unsigned char>(c));
           });
  }
  return lower.rfind("+proj=", 0) == 0 || lower.rfind("wgs84utm", 0) == 0;
}


}  // namespace

// ------------------------------------------------------------------ gcp_list.txt

Status ParseGcpList(std::string_view text, const std::string& file_name, GcpList* gcp_list) {
  PHOTOPOSE_RETURN_IF_ERROR(CheckTextInput(text, file_name));
  const auto error = [&file_name](int line, std::string_view column, const std::string& what) {
    return Status::Error(EscapeForMessage(
        Where(file_name, line) + (column.empty() ? "" : std::string(column) + ": ") + what));
  };

  GcpList result;
  // A point measured twice in one image is kept as two marks: ODM accepts it, and the real
  // dataset of tests/core/io/tables_test.cc has such a pair. The marks table rejects it.
  std::map<std::string, size_t> point_index;  // name -> index in result.points
  size_t start = 0;
  for (int line = 1; start < text.size() || line == 1; ++line) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view content(text.data() + start, end - start);
    start = end + 1;
    const std::vector<std::string_view> words = SplitWords(content);
    if (line == 1) {
      result.crs.clear();
      for (size_t i = 0; i < words.size(); ++i)
        result.crs += (i ? " " : "") + std::string(words[i]);
      if (!IsGcpCrs(result.crs)) {
        return error(1, "CRS",
                     "the first line must name the coordinate system (EPSG:<code>, WGS84 UTM "
                     "<zone><N|S>, or a +proj=... string), got " +
                         Quoted(result.crs));
      }
      continue;
    }
    if (words.empty() || words[0].front() == '#') continue;
    if (words.size() != 6 && words.size() != 7) {
      return error(
          line, "",
          "expected 'X Y Z px py image [name]', got " + std::to_string(words.size()) + " fields");
    }
    static const char* const kNumberNames[5] = {"X", "Y", "Z", "px", "py"};
    // px, py are the marks table's Column, Row and share their range.
    static const char* const kRangeColumns[5] = {"X", "Y", "Z", "Column", "Row"};
    double numbers[5];
    for (int i = 0; i < 5; ++i) {
      std::string why;
      if (!ParseFiniteNumber(words[i], &numbers[i], &why)) return error(line, kNumberNames[i], why);
      const ValueRange& range = *RangeOf(kRangeColumns[i]);
      if (!InRange(numbers[i], range)) {
        return error(line, kNumberNames[i], Quoted(words[i]) + " is outside " + RangeText(range));
      }
    }
    const Eigen::Vector3d position(numbers[0], numbers[1], numbers[2]);
    const std::string image(words[5]);
    const std::string name = words.size() == 7
                                 ? std::string(words[6])
                                 : FormatNumber(numbers[0]) + "_" + FormatNumber(numbers[1]) + "_" +
                                       FormatNumber(numbers[2]);
    const auto [it, inserted] = point_index.emplace(name, result.points.size());
    if (inserted) {
      GroundPoint point;
      point.point_id = name;
      point.position = position;
      point.line = line;
      result.points.push_back(point);
    } else if (result.points[it->second].position != position) {
      const GroundPoint& first = result.points[it->second];
      return error(line, "name",
                   "point " + Quoted(name) + " has other coordinates on line " +
                       std::to_string(first.line) + " (" + FormatNumber(first.position.x()) + " " +
                       FormatNumber(first.position.y()) + " " + FormatNumber(first.position.z()) +
                       ")");
    }
    ImageMark mark;
    mark.raster = image;
    mark.point_id = name;
    mark.column_row = Eigen::Vector2d(numbers[3], numbers[4]);
    mark.line = line;
    result.marks.push_back(std::move(mark));
  }
  *gcp_list = std::move(result);
  return Status::Ok();
}


}  // namespace photopose
