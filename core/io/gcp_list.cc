// OpenDroneMap's gcp_list.txt and geo.txt: read and written (core/io/tables.h).
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
#include <limits>
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

// The first line of gcp_list.txt and geo.txt: the CRS, its words joined by one space.
Status ReadCrsLine(const std::vector<std::string_view>& words, const std::string& file_name,
                   std::string* crs) {
  crs->clear();
  for (size_t i = 0; i < words.size(); ++i) *crs += (i ? " " : "") + std::string(words[i]);
  if (IsGcpCrs(*crs)) return Status::Ok();
  return Status::Error(EscapeForMessage(
      WhereInFile(file_name, 1) +
      "CRS: the first line must name the coordinate system (EPSG:<code>, WGS84 UTM <zone><N|S>, "
      "or a +proj=... string), got " +
      QuotedForMessage(*crs)));
}

// The lines of a text after its first, split into words; blank and '#' lines skipped.
template <typename Visit>
Status ForEachDataLine(std::string_view text, Visit visit) {
  size_t start = 0;
  for (int line = 1; start < text.size() || line == 1; ++line) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view content(text.data() + start, end - start);
    start = end + 1;
    const std::vector<std::string_view> words = SplitWords(content);
    if (line > 1 && (words.empty() || words[0].front() == '#')) continue;
    PHOTOPOSE_RETURN_IF_ERROR(visit(line, words));
  }
  return Status::Ok();
}

// A name written as one field of a gcp_list.txt / geo.txt line: not empty, no white space.
bool IsOneWord(std::string_view name) {
  return !name.empty() && std::none_of(name.begin(), name.end(),
                                       [](char c) { return std::isspace(static_cast<unsigned char>(c)); });
}

// The first line of a gcp_list.txt / geo.txt written: the CRS, refused as ReadCrsLine refuses it.
Status AppendCrsLine(const std::string& crs, const std::string& path, std::string* text) {
  if (!IsGcpCrs(crs)) {
    return Status::Error(EscapeForMessage(
        path + ": CRS: " + QuotedForMessage(crs) +
        " cannot be written as the first line (EPSG:<code>, WGS84 UTM <zone><N|S>, or a +proj=... string)"));
  }
  *text += crs + "\n";
  return Status::Ok();
}

}  // namespace

// ------------------------------------------------------------------ gcp_list.txt

Status ParseGcpList(std::string_view text, const std::string& file_name, GcpList* gcp_list) {
  PHOTOPOSE_RETURN_IF_ERROR(CheckTextInput(text, file_name));
  const auto error = [&file_name](int line, std::string_view column, const std::string& what) {
    return Status::Error(EscapeForMessage(
        WhereInFile(file_name, line) + (column.empty() ? "" : std::string(column) + ": ") + what));
  };

  GcpList result;
  // A point measured twice in one image is kept as two marks: ODM accepts it, and the real
  // dataset of tests/core/io/tables_test.cc has such a pair. The marks table rejects it.
  std::map<std::string, size_t> point_index;  // name -> index in result.points
  PHOTOPOSE_RETURN_IF_ERROR(ForEachDataLine(text, [&](int line, const std::vector<std::string_view>& words) -> Status {
    if (line == 1) return ReadCrsLine(words, file_name, &result.crs);
    // ODM allows extra fields after the name; they are not read.
    if (words.size() < 6) {
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
        return error(line, kNumberNames[i],
                     QuotedForMessage(words[i]) + " is outside " + RangeText(range));
      }
    }
    const Eigen::Vector3d position(numbers[0], numbers[1], numbers[2]);
    const std::string image(words[5]);
    const std::string name = words.size() >= 7
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
                   "point " + QuotedForMessage(name) + " has other coordinates on line " +
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
    return Status::Ok();
  }));
  *gcp_list = std::move(result);
  return Status::Ok();
}

Status FormatGcpList(const GcpList& gcp_list, const std::string& path, std::string* text) {
  std::string out;
  PHOTOPOSE_RETURN_IF_ERROR(AppendCrsLine(gcp_list.crs, path, &out));
  std::map<std::string, const GroundPoint*> points;
  for (const GroundPoint& point : gcp_list.points) points.emplace(point.point_id, &point);
  for (const ImageMark& mark : gcp_list.marks) {
    const auto error = [&](const std::string& what) {
      return Status::Error(EscapeForMessage(path + ": mark of point " + QuotedForMessage(mark.point_id) + " in image " +
                                            QuotedForMessage(mark.raster) + ": " + what));
    };
    if (!IsOneWord(mark.point_id) || !IsOneWord(mark.raster))
      return error("names must be one word (the fields of a line are separated by white space)");
    const auto point = points.find(mark.point_id);
    if (point == points.end()) return error("the point is not in the list");
    if (!mark.column_row) return error("a gcp_list.txt holds pixel marks (Column, Row) only");
    if (!point->second->position.allFinite() || !mark.column_row->allFinite())
      return error("a coordinate is not a finite number");
    for (const double value : {point->second->position.x(), point->second->position.y(), point->second->position.z(),
                               mark.column_row->x(), mark.column_row->y()}) {
      AppendFormattedNumber(value, &out);
      out += ' ';
    }
    out += mark.raster + " " + mark.point_id + "\n";
  }
  *text = std::move(out);
  return Status::Ok();
}

// ------------------------------------------------------------------ geo.txt

Status FormatGeoTxt(const GeoTxt& geo, const std::string& path, std::string* text) {
  std::string out;
  PHOTOPOSE_RETURN_IF_ERROR(AppendCrsLine(geo.crs, path, &out));
  for (const GeoTxtRecord& record : geo.records) {
    const auto error = [&](const std::string& what) {
      return Status::Error(EscapeForMessage(path + ": image " + QuotedForMessage(record.image) + ": " + what));
    };
    if (!IsOneWord(record.image))
      return error("the name must be one word (the fields of a line are separated by white space)");
    const bool accuracies = record.horizontal_accuracy_m.has_value() || record.vertical_accuracy_m.has_value();
    if (accuracies && !(record.horizontal_accuracy_m && record.vertical_accuracy_m))
      return error("the accuracies come as two (horizontal vertical)");
    if (!record.has_height && (accuracies || record.yaw_pitch_roll_deg))
      return error("a line without height cannot give attitudes or accuracies (the fields are positional)");
    const int numbers = record.has_height ? 3 : 2;
    if (!record.position.head(numbers).allFinite()) return error("a coordinate is not a finite number");
    out += record.image;
    for (int i = 0; i < numbers; ++i) {
      out += ' ';
      AppendFormattedNumber(record.position[i], &out);
    }
    if (record.yaw_pitch_roll_deg || accuracies) {
      const Eigen::Vector3d ypr = record.yaw_pitch_roll_deg.value_or(Eigen::Vector3d::Zero());
      for (int i = 0; i < 3; ++i) {
        out += ' ';
        AppendFormattedNumber(ypr[i], &out);
      }
    }
    if (accuracies) {
      out += ' ';
      AppendFormattedNumber(*record.horizontal_accuracy_m, &out);
      out += ' ';
      AppendFormattedNumber(*record.vertical_accuracy_m, &out);
    }
    out += '\n';
  }
  *text = std::move(out);
  return Status::Ok();
}

Status ParseGeoTxt(std::string_view text, const std::string& file_name, GeoTxt* geo) {
  PHOTOPOSE_RETURN_IF_ERROR(CheckTextInput(text, file_name));
  const auto error = [&file_name](int line, std::string_view column, const std::string& what) {
    return Status::Error(EscapeForMessage(
        WhereInFile(file_name, line) + (column.empty() ? "" : std::string(column) + ": ") + what));
  };
  GeoTxt result;
  std::map<std::string, int> line_of_image;
  PHOTOPOSE_RETURN_IF_ERROR(ForEachDataLine(text, [&](int line, const std::vector<std::string_view>& words) -> Status {
    if (line == 1) return ReadCrsLine(words, file_name, &result.crs);
    const size_t n = words.size();
    // The fields are positional (ODM reads them so): z, then yaw pitch roll, then the two
    // accuracies. A count that stops inside a group is refused, naming the first missing field.
    static const char* const kNames[9] = {"image", "x", "y", "z", "yaw", "pitch", "roll",
                                          "horizontal_accuracy", "vertical_accuracy"};
    if (n < 3 || n == 5 || n == 6 || n == 8) {
      const std::string got = std::to_string(n - 1) + (n == 2 ? " number" : " numbers");
      std::string why = "missing: expected 'image x y [z [yaw pitch roll [horizontal_accuracy vertical_accuracy]]]', got " + got;
      if (n == 5 || n == 6) {
        why += " (x y z and " + std::string(n == 5 ? "yaw" : "yaw pitch") +
               ": yaw pitch roll come as three; the fields are positional, so a line without z cannot give accuracies)";
      } else if (n == 8) {
        why += " (the accuracies come as two: horizontal vertical)";
      }
      return error(line, kNames[n], why);
    }
    double numbers[9] = {0};
    for (size_t i = 1; i < std::min<size_t>(n, 9); ++i) {
      std::string why;
      if (!ParseFiniteNumber(words[i], &numbers[i], &why)) return error(line, kNames[i], why);
    }
    const bool has_height = n >= 4;
    for (int i = 1; i <= (has_height ? 3 : 2); ++i) {
      const ValueRange& range = *RangeOf(i == 1 ? "X" : i == 2 ? "Y" : "Z");
      if (!InRange(numbers[i], range))
        return error(line, kNames[i],
                     QuotedForMessage(words[i]) + " is outside " + RangeText(range));
    }
    GeoTxtRecord record;
    record.image = std::string(words[0]);
    // No height is NaN, never a number that could pass for one.
    record.position = Eigen::Vector3d(numbers[1], numbers[2],
                                      has_height ? numbers[3] : std::numeric_limits<double>::quiet_NaN());
    record.has_height = has_height;
    record.line = line;
    if (n >= 7) {
      for (int i = 4; i <= 6; ++i) {
        if (std::abs(numbers[i]) > 360.0)
          return error(line, kNames[i],
                       QuotedForMessage(words[i]) +
                           " is not an angle in degrees (at most 360 in magnitude)");
      }
      record.yaw_pitch_roll_deg = Eigen::Vector3d(numbers[4], numbers[5], numbers[6]);
    }
    if (n >= 9) {
      for (int i = 7; i <= 8; ++i) {
        if (!(numbers[i] > 0.0 && numbers[i] <= 1e6))
          return error(
              line, kNames[i],
              QuotedForMessage(words[i]) + " must be a positive accuracy in metres (at most 1e6)");
      }
      record.horizontal_accuracy_m = numbers[7];
      record.vertical_accuracy_m = numbers[8];
    }
    const auto [it, inserted] = line_of_image.emplace(record.image, line);
    if (!inserted) {
      return error(
          line, "image",
          QuotedForMessage(record.image) + " is already on line " + std::to_string(it->second));
    }
    result.records.push_back(std::move(record));
    return Status::Ok();
  }));
  *geo = std::move(result);
  return Status::Ok();
}


}  // namespace photopose
