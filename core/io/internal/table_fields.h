#pragma once
// What the table readers and writers of core/io/tables.h share, one format per file
// (camera_table.cc, frames_table.cc, points_marks_tables.cc, gcp_list.cc, tables.cc): the column
// names in output order, the physical ranges of the numbers, the readers of numbers, signs and
// counts with their messages, the extra columns. Internal to core/io; not installed.

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

#include "core/enum_names.h"
#include "core/io/csv.h"
#include "core/io/text_scanner.h"
#include "core/io/tables.h"

namespace photopose::table_io {
using ExtraColumns = std::vector<std::pair<std::string, std::string>>;
using Names = std::vector<std::string_view>;

// Header names are matched ignoring case, spaces and underscores (docs/formats.md).
constexpr CsvOptions kTableCsvOptions{/*tolerant_header=*/true};

// A rotation matrix read from a file is accepted when |R R^T - I| stays below this: nine numbers
// written with six decimals are orthonormal to about 3e-6 only.
constexpr double kMatrixOrthonormalityTolerance = 1e-5;

// ------------------------------------------------------------------ column names, in output order

constexpr std::string_view kAccuracyColumns[3] = {"AccuracyX", "AccuracyY", "AccuracyZ"};
constexpr std::string_view kAttitudeAccuracyColumns[3] = {"AccuracyOmega", "AccuracyPhi",
                                                          "AccuracyKappa"};

// clang-format off
inline const Names& CameraColumns() {
  static const Names* const kColumns = new Names{
      "ObjectID", "CameraID", "FocalLength", "PrincipalX", "PrincipalY", "PixelSize",
      "NRows", "NColumns", "NBands", "PixelType", "BlockName", "FilmCoordinateSystem",
      "A0", "A1", "A2", "B0", "B1", "B2", "AffineDirection",
      "DistortionType", "Radial", "Tangential", "RadialDistances", "RadialDistortions",
      "FilmFiducials", "OrientationType", "AngleDirection", "Polarity",
      "AverageZ", "ApplyECC", "EarthRadius", "SRS"};
  return *kColumns;
}
// clang-format on
inline const Names& AffineColumns() {
  static const Names* const kColumns = new Names{"A0", "A1", "A2", "B0", "B1", "B2"};
  return *kColumns;
}
inline const Names& SigmaColumns() {
  static const Names* const kColumns =
      new Names{"SigmaX", "SigmaY", "SigmaZ", "SigmaOmega", "SigmaPhi", "SigmaKappa"};
  return *kColumns;
}
inline const Names& FrameColumns() {
  static const Names* const kColumns =
      new Names{"Raster", "CameraID",   "PerspectiveX", "PerspectiveY", "PerspectiveZ", "Omega",
                "Phi",    "Kappa",      "Matrix",       "SRS",          "SigmaX",       "SigmaY",
                "SigmaZ", "SigmaOmega", "SigmaPhi",     "SigmaKappa",   "Sigma0",
                "AccuracyX", "AccuracyY", "AccuracyZ", "AccuracyOmega", "AccuracyPhi",
                "AccuracyKappa"};
  return *kColumns;
}
inline const Names& PointColumns() {
  static const Names* const kColumns =
      new Names{"PointID", "X", "Y", "Z", "AccuracyX", "AccuracyY", "AccuracyZ", "Role"};
  return *kColumns;
}
inline const Names& MarkColumns() {
  static const Names* const kColumns =
      new Names{"Raster", "PointID", "Column", "Row", "FilmX", "FilmY", "Accuracy", "CameraID"};
  return *kColumns;
}

// ------------------------------------------------------------------ small helpers

// ------------------------------------------------------------------ physical ranges

// The values a numeric column may hold (docs/formats.md, "Limits and refusals"): readers refuse a
// value outside at the line that carries it, writers refuse to write one.
struct ValueRange {
  double min;
  double max;
  bool open_min;     // min itself excluded
  bool open_max;     // max itself excluded
  const char* unit;  // for messages
};

inline bool InRange(double value, const ValueRange& range) {
  const bool above_min = range.open_min ? value > range.min : value >= range.min;
  const bool below_max = range.open_max ? value < range.max : value <= range.max;
  return above_min && below_max;  // false for NaN
}

inline std::string RangeText(const ValueRange& range) {
  return std::string(range.open_min ? "(" : "[") + FormatPlainNumber(range.min) + ", " +
         FormatPlainNumber(range.max) + (range.open_max ? ")" : "]") +
         (range.unit[0] != '\0' ? " " : "") + range.unit;
}

// The range of a column by its schema name (the same name means the same quantity in every
// table), or nullptr for a column without one.
inline const ValueRange* RangeOf(std::string_view column) {
  constexpr ValueRange kGroundCoordinate{-kMaxCoordinate, kMaxCoordinate, false, false, "m"};
  constexpr ValueRange kPixelCoordinate{-kMaxCoordinate, kMaxCoordinate, false, false, "px"};
  constexpr ValueRange kFilmCoordinate{-kMaxCoordinate, kMaxCoordinate, false, false, "um"};
  constexpr ValueRange kPositiveMetres{0.0, kMaxCoordinate, true, false, "m"};
  constexpr ValueRange kPositivePixels{0.0, kMaxCoordinate, true, false, "px"};
  constexpr ValueRange kAngle{-360.0, 360.0, false, false, "degrees"};
  constexpr ValueRange kAffine{-kMaxCoordinate, kMaxCoordinate, false, false, ""};
  static const auto* const kRanges = new std::map<std::string, ValueRange, std::less<>>{
      {"X", kGroundCoordinate},
      {"Y", kGroundCoordinate},
      {"Z", kGroundCoordinate},
      {"PerspectiveX", kGroundCoordinate},
      {"PerspectiveY", kGroundCoordinate},
      {"PerspectiveZ", kGroundCoordinate},
      {"AverageZ", kGroundCoordinate},
      {"AccuracyX", kPositiveMetres},
      {"AccuracyY", kPositiveMetres},
      {"AccuracyZ", kPositiveMetres},
      {"EarthRadius", kPositiveMetres},
      {"Omega", kAngle},
      {"Phi", kAngle},
      {"Kappa", kAngle},
      {"Column", kPixelCoordinate},
      {"Row", kPixelCoordinate},
      {"Accuracy", kPositivePixels},
      {"FilmX", kFilmCoordinate},
      {"FilmY", kFilmCoordinate},
      {"PrincipalX", kFilmCoordinate},
      {"PrincipalY", kFilmCoordinate},
      {"FilmFiducials", kFilmCoordinate},
      {"RadialDistortions", kFilmCoordinate},
      {"RadialDistances", {0.0, kMaxCoordinate, false, false, "um"}},
      {"FocalLength", {kMinFocalLengthUm, kMaxCoordinate, false, false, "um"}},
      {"PixelSize", {kMinPixelSizeUm, kMaxPixelSizeUm, true, true, "um"}},
      {"A0", kAffine},
      {"A1", kAffine},
      {"A2", kAffine},
      {"B0", kAffine},
      {"B1", kAffine},
      {"B2", kAffine}};
  const auto found = kRanges->find(column);
  return found == kRanges->end() ? nullptr : &found->second;
}

// A schema column looked up once per table: its place in the header and the values it may hold
// (nullptr: any finite number).
struct TableColumn {
  CsvColumn csv;
  const ValueRange* range = nullptr;
};

inline TableColumn LookUp(const CsvHeader& header, std::string_view name) {
  return {header.Column(name), RangeOf(name)};
}

// What is wrong with `value` for a column of `range` ("value is not finite", "1e9 is outside
// [-100000000, 100000000] px"), or "" when nothing is.
inline std::string ValueProblem(double value, const ValueRange* range) {
  if (!std::isfinite(value)) return "value is not finite";
  if (range != nullptr && !InRange(value, *range))
    return FormatPlainNumber(value) + " is outside " + RangeText(*range);
  return std::string();
}

// "column: '<text>' is outside [min, max] unit" for a value outside its column's range.
inline Status CheckRange(const CsvRowReader& row, const TableColumn& column, std::string_view label,
                  std::string_view text, double value) {
  if (column.range == nullptr || InRange(value, *column.range)) return Status::Ok();
  return row.Error(column.csv, std::string(label) + QuotedForMessage(text) + " is outside " +
                                   RangeText(*column.range));
}
inline Status CheckRange(const CsvRowReader& row, std::string_view column, std::string_view label,
                  std::string_view text, double value) {
  return CheckRange(row, LookUp(row.header(), column), label, text, value);
}

// A number within its column's range; an empty field gives nullopt.
inline Status ReadNumber(const CsvRowReader& row, const TableColumn& column,
                  std::optional<double>* value) {
  PHOTOPOSE_RETURN_IF_ERROR(row.Number(column.csv, value));
  if (*value) PHOTOPOSE_RETURN_IF_ERROR(CheckRange(row, column, "", row.Text(column.csv), **value));
  return Status::Ok();
}
inline Status ReadNumber(const CsvRowReader& row, std::string_view column, std::optional<double>* value) {
  return ReadNumber(row, LookUp(row.header(), column), value);
}

// A number within its column's range; an empty field is an error.
inline Status ReadRequiredNumber(const CsvRowReader& row, const TableColumn& column, double* value) {
  std::optional<double> number;
  PHOTOPOSE_RETURN_IF_ERROR(ReadNumber(row, column, &number));
  if (!number) return row.Error(column.csv, "is empty");
  *value = *number;
  return Status::Ok();
}
inline Status ReadRequiredNumber(const CsvRowReader& row, std::string_view column, double* value) {
  return ReadRequiredNumber(row, LookUp(row.header(), column), value);
}

// A list of numbers, each within its column's range.
inline Status ReadNumberList(const CsvRowReader& row, std::string_view column,
                      std::vector<double>* values) {
  PHOTOPOSE_RETURN_IF_ERROR(row.NumberList(column, values));
  for (size_t i = 0; i < values->size(); ++i) {
    PHOTOPOSE_RETURN_IF_ERROR(CheckRange(row, column, "item " + std::to_string(i + 1) + ": ",
                                         FormatPlainNumber((*values)[i]), (*values)[i]));
  }
  return Status::Ok();
}

// Reads an enumerated column by the value's name table (core/enum_names.h; EnumNames(Enum{}) for
// an enum): every name and alias is compared with FoldedName(), the tables' rule for names, so
// "x_right_y_up" reads as X_RIGHT_Y_UP; an empty field keeps *value. The error lists every entry
// of the table in its order, aliases included.
template <typename Enum, typename Column>
Status ReadEnum(const CsvRowReader& row, const Column& column, const EnumNameTable<Enum>& names,
                Enum* value) {
  const std::string_view text = row.Text(column);
  if (text.empty()) return Status::Ok();
  const std::string folded = FoldedName(text);
  for (const EnumNameEntry<Enum>& entry : names) {
    if (FoldedName(entry.name) == folded) {
      *value = entry.value;
      return Status::Ok();
    }
  }
  std::string listed;
  const size_t count = static_cast<size_t>(names.end() - names.begin());
  for (size_t i = 0; i < count; ++i)
    listed += (i == 0 ? "" : i + 1 == count ? " or " : ", ") + std::string(names.begin()[i].name);
  return row.Error(column, QuotedForMessage(text) + " is not " + listed);
}

// A number with a default for an empty field.
inline Status ReadNumberOr(const CsvRowReader& row, std::string_view column, double default_value,
                    double* value) {
  std::optional<double> number;
  PHOTOPOSE_RETURN_IF_ERROR(ReadNumber(row, column, &number));
  *value = number.value_or(default_value);
  return Status::Ok();
}

// An optional number that must be positive when given.
inline Status ReadPositive(const CsvRowReader& row, std::string_view column,
                    std::optional<double>* value) {
  PHOTOPOSE_RETURN_IF_ERROR(ReadNumber(row, column, value));
  if (*value && !(**value > 0.0))
    return row.Error(column, QuotedForMessage(row.Text(column)) + " must be positive");
  return Status::Ok();
}

// Three positive accuracies given together (e.g. AccuracyX, AccuracyY, AccuracyZ) or none.
inline Status ReadAccuracyTriple(const CsvRowReader& row, const std::string_view (&columns)[3],
                          std::optional<Eigen::Vector3d>* accuracy) {
  if (!row.Has(columns[0]) && !row.Has(columns[1]) && !row.Has(columns[2])) return Status::Ok();
  Eigen::Vector3d values;
  for (int i = 0; i < 3; ++i) {
    std::optional<double> sigma;
    PHOTOPOSE_RETURN_IF_ERROR(ReadPositive(row, columns[i], &sigma));
    if (!sigma) {
      return row.Error(columns[i], "is empty; " + std::string(columns[0]) + ", " +
                                       std::string(columns[1]) + ", " + std::string(columns[2]) +
                                       " are given together");
    }
    values[i] = *sigma;
  }
  *accuracy = values;
  return Status::Ok();
}

// -1 or +1; an empty field keeps *value (the default).
inline Status ReadSign(const CsvRowReader& row, std::string_view column, int* value) {
  std::optional<long long> number;
  PHOTOPOSE_RETURN_IF_ERROR(row.Integer(column, &number));
  if (!number) return Status::Ok();
  if (*number != 1 && *number != -1)
    return row.Error(column, QuotedForMessage(row.Text(column)) + " must be -1 or +1");
  *value = static_cast<int>(*number);
  return Status::Ok();
}

// A positive whole number that fits an int; an empty field gives 0 (not given).
inline Status ReadCount(const CsvRowReader& row, std::string_view column, int* value) {
  std::optional<long long> number;
  PHOTOPOSE_RETURN_IF_ERROR(row.Integer(column, &number));
  if (number && (*number <= 0 || *number > INT_MAX))
    return row.Error(column,
                     QuotedForMessage(row.Text(column)) + " must be a positive whole number");
  *value = number ? static_cast<int>(*number) : 0;
  return Status::Ok();
}

// An open-addressing hash table of (64-bit hash, value >= 0) entries: linear probing in a
// power-of-two array kept at most half full, so that a look-up mostly reads one cache line and no
// entry is allocated on its own (std::unordered_map allocates a node per entry: a million marks
// made a million allocations).
class FlatHashTable {
 public:
  explicit FlatHashTable(size_t expected = 0) {
    size_t capacity = 16;
    while (capacity < 2 * expected) capacity *= 2;
    Resize(capacity);
  }

  // The value of the first entry of `hash` for which `matches(value)` holds, or -1.
  template <typename Matches>
  long long Find(uint64_t hash, Matches matches) const {
    for (size_t i = Slot(hash);; i = (i + 1) & mask_) {
      const Entry& entry = entries_[i];
      if (entry.value < 0) return -1;
      if (entry.hash == hash && matches(entry.value)) return entry.value;
    }
  }
  void Insert(uint64_t hash, long long value) {
    if (2 * (size_ + 1) > entries_.size()) Resize(2 * entries_.size());
    Place(hash, value);
    ++size_;
  }

 private:
  struct Entry {
    uint64_t hash = 0;
    long long value = -1;  // -1: empty
  };
  // Fibonacci hashing: the high bits of hash * 2^64 / phi, so that keys that differ in their high
  // bits only (a raster id << 32) still spread.
  size_t Slot(uint64_t hash) const {
    return static_cast<size_t>((hash * 0x9E3779B97F4A7C15ull) >> shift_);
  }
  void Place(uint64_t hash, long long value) {
    size_t i = Slot(hash);
    while (entries_[i].value >= 0) i = (i + 1) & mask_;
    entries_[i] = {hash, value};
  }
  void Resize(size_t capacity) {
    std::vector<Entry> old(capacity);
    old.swap(entries_);
    mask_ = capacity - 1;
    shift_ = 64;
    for (size_t c = capacity; c > 1; c /= 2) --shift_;
    for (const Entry& entry : old)
      if (entry.value >= 0) Place(entry.hash, entry.value);
  }

  std::vector<Entry> entries_;
  size_t size_ = 0;
  size_t mask_ = 0;
  int shift_ = 64;
};

// Dense ids (0, 1, ...) of names in the order they are first seen. The names are kept as views:
// into `stable_text` (the text being parsed) when a name lies in it, else into a copy kept here,
// so that a name is copied once at most, never per row.
class NameIds {
 public:
  explicit NameIds(std::string_view stable_text = {}) : stable_text_(stable_text) {}

  // The id of `name`; *is_new tells whether it is seen for the first time.
  int Id(std::string_view name, bool* is_new) {
    // Marks come image by image: the raster of a row is mostly the one of the row before.
    if (last_id_ >= 0 && name == names_[last_id_]) {
      *is_new = false;
      return last_id_;
    }
    const uint64_t hash = std::hash<std::string_view>()(name);
    long long id = table_.Find(hash, [&](long long k) { return names_[k] == name; });
    *is_new = id < 0;
    if (*is_new) {
      if (!IsStable(name)) name = copies_.emplace_back(name);
      id = static_cast<long long>(names_.size());
      names_.push_back(name);
      table_.Insert(hash, id);
    }
    last_id_ = static_cast<int>(id);
    return last_id_;
  }
  std::string_view Name(int id) const { return names_[id]; }
  size_t size() const { return names_.size(); }

 private:
  bool IsStable(std::string_view name) const {
    const std::less<const char*> before;
    return !before(name.data(), stable_text_.data()) &&
           !before(stable_text_.data() + stable_text_.size(), name.data() + name.size());
  }

  std::string_view stable_text_;
  FlatHashTable table_;
  std::vector<std::string_view> names_;  // by id
  std::deque<std::string> copies_;
  int last_id_ = -1;
};

// The line each name was first seen on, for duplicate checks that name both lines.
class FirstLines {
 public:
  explicit FirstLines(std::string_view stable_text = {}) : ids_(stable_text) {}
  // Whether `name` was seen before, on *first_line; else it is recorded at `line`.
  bool Seen(std::string_view name, int line, int* first_line) {
    bool is_new = false;
    const int id = ids_.Id(name, &is_new);
    if (is_new) lines_.push_back(line);
    *first_line = lines_[id];
    return !is_new;
  }

 private:
  NameIds ids_;
  std::vector<int> lines_;
};

// Records where `key` was first seen; a second sighting is an error naming both lines:
// "duplicate <kind> '<key>' (first on line N)".
inline Status CheckUnique(const CsvRowReader& row, std::string_view column, std::string_view key,
                   std::string_view kind, FirstLines* first_lines) {
  int first = 0;
  if (!first_lines->Seen(key, row.line(), &first)) return Status::Ok();
  return row.Error(column, "duplicate " + std::string(kind) + " " + QuotedForMessage(key) +
                               " (first on line " + std::to_string(first) + ")");
}

// Both columns of a pair or neither.
inline Status RequirePairedColumns(const CsvHeader& table, std::string_view a, std::string_view b) {
  if (table.HasColumn(a) && !table.HasColumn(b))
    return table.Error(table.header_line(), b,
                       "required column is missing (" + std::string(a) + " is given)");
  if (table.HasColumn(b) && !table.HasColumn(a))
    return table.Error(table.header_line(), a,
                       "required column is missing (" + std::string(b) + " is given)");
  return Status::Ok();
}

// The fields of a row in the columns `extra` (CsvHeader::ColumnsOtherThan the schema's), as
// (header name, value).
inline ExtraColumns ReadExtraColumns(const CsvRowReader& row, const std::vector<size_t>& extra) {
  ExtraColumns values;
  for (const size_t index : extra) {
    const std::string& name = row.header().header()[index];
    values.emplace_back(name, std::string(row.Text(CsvColumn{name, index})));
  }
  return values;
}

// The union of the extra column names of `records`, in first-seen order. Names that clash with a
// standard column are an error: the file would not read back.
template <typename Record>
Status CollectExtraColumnNames(const std::string& path, const std::vector<Record>& records,
                               const Names& standard, std::vector<std::string>* names) {
  names->clear();
  for (const Record& record : records) {
    for (const auto& [name, value] : record.extra_columns) {
      const std::string folded = FoldedName(name);
      if (folded.empty()) return Status::Error(path + ": an extra column has no name");
      for (const std::string_view standard_name : standard) {
        if (FoldedName(standard_name) == folded)
          return Status::Error(path + ": extra column '" + name + "' is a standard column");
      }
      if (std::none_of(names->begin(), names->end(),
                       [&](const std::string& n) { return FoldedName(n) == folded; }))
        names->push_back(name);
    }
  }
  return Status::Ok();
}

// Values of `record`'s extra columns in the order of `names` (empty where it has none).
template <typename Record>
void AppendExtraColumns(const Record& record, const std::vector<std::string>& names,
                        std::vector<std::string>* fields) {
  for (const std::string& name : names) {
    std::string value;
    for (const auto& [n, v] : record.extra_columns)
      if (FoldedName(n) == FoldedName(name)) value = v;
    fields->push_back(value);
  }
}

// The fields of one output row. Numbers must be finite (readers reject anything else); the first
// offence is kept and reported as "path: <record>: <column>: value is not finite".
class RowFields {
 public:
  explicit RowFields(std::string record) : record_(std::move(record)) {}

  void Text(std::string_view text) { fields_.emplace_back(text); }
  // Within `range` (nullptr: any finite number), by default its column's (RangeOf).
  void Number(std::string_view column, double value) { Number(column, value, RangeOf(column)); }
  void Number(std::string_view column, double value, const ValueRange* range) {
    const std::string problem = ValueProblem(value, range);
    if (!problem.empty()) Fail(column, problem);
    fields_.push_back(FormatNumber(value));
  }
  void OptionalNumber(std::string_view column, const std::optional<double>& value) {
    OptionalNumber(column, value, RangeOf(column));
  }
  void OptionalNumber(std::string_view column, const std::optional<double>& value,
                      const ValueRange* range) {
    if (value) {
      Number(column, *value, range);
    } else {
      fields_.emplace_back();
    }
  }
  void NumberList(std::string_view column, const std::vector<double>& values) {
    const ValueRange* range = RangeOf(column);
    for (const double value : values) {
      if (!std::isfinite(value)) {
        Fail(column, "a value is not finite");
      } else if (range != nullptr && !InRange(value, *range)) {
        Fail(column, FormatPlainNumber(value) + " is outside " + RangeText(*range));
      }
    }
    fields_.push_back(FormatNumberList(values));
  }
  void Fail(std::string_view column, std::string_view what) {
    if (error_.empty()) error_ = std::string(column) + ": " + std::string(what);
  }

  std::vector<std::string>* fields() { return &fields_; }
  Status status(const std::string& path) const {
    if (error_.empty()) return Status::Ok();
    return Status::Error(EscapeForMessage(path + ": " + record_ + ": " + error_));
  }

 private:
  std::string record_;
  std::string error_;
  std::vector<std::string> fields_;
};

inline std::vector<std::string> HeaderFields(const Names& names) {
  return std::vector<std::string>(names.begin(), names.end());
}
}  // namespace photopose::table_io
