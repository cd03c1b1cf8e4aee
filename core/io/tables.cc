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

namespace photopose {
namespace {

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
const Names& CameraColumns() {
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
const Names& AffineColumns() {
  static const Names* const kColumns = new Names{"A0", "A1", "A2", "B0", "B1", "B2"};
  return *kColumns;
}
const Names& SigmaColumns() {
  static const Names* const kColumns =
      new Names{"SigmaX", "SigmaY", "SigmaZ", "SigmaOmega", "SigmaPhi", "SigmaKappa"};
  return *kColumns;
}
const Names& FrameColumns() {
  static const Names* const kColumns =
      new Names{"Raster", "CameraID",   "PerspectiveX", "PerspectiveY", "PerspectiveZ", "Omega",
                "Phi",    "Kappa",      "Matrix",       "SRS",          "SigmaX",       "SigmaY",
                "SigmaZ", "SigmaOmega", "SigmaPhi",     "SigmaKappa",   "Sigma0",
                "AccuracyX", "AccuracyY", "AccuracyZ", "AccuracyOmega", "AccuracyPhi",
                "AccuracyKappa"};
  return *kColumns;
}
const Names& PointColumns() {
  static const Names* const kColumns =
      new Names{"PointID", "X", "Y", "Z", "AccuracyX", "AccuracyY", "AccuracyZ", "Role"};
  return *kColumns;
}
const Names& MarkColumns() {
  static const Names* const kColumns =
      new Names{"Raster", "PointID", "Column", "Row", "FilmX", "FilmY", "Accuracy", "CameraID"};
  return *kColumns;
}

// ------------------------------------------------------------------ small helpers

std::string Quoted(std::string_view text) { return "'" + EscapeForMessage(text) + "'"; }

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

bool InRange(double value, const ValueRange& range) {
  const bool above_min = range.open_min ? value > range.min : value >= range.min;
  const bool below_max = range.open_max ? value < range.max : value <= range.max;
  return above_min && below_max;  // false for NaN
}

std::string RangeText(const ValueRange& range) {
  return std::string(range.open_min ? "(" : "[") + FormatPlainNumber(range.min) + ", " +
         FormatPlainNumber(range.max) + (range.open_max ? ")" : "]") +
         (range.unit[0] != '\0' ? " " : "") + range.unit;
}

// The range of a column by its schema name (the same name means the same quantity in every
// table), or nullptr for a column without one.
const ValueRange* RangeOf(std::string_view column) {
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

TableColumn LookUp(const CsvHeader& header, std::string_view name) {
  return {header.Column(name), RangeOf(name)};
}

// What is wrong with `value` for a column of `range` ("value is not finite", "1e9 is outside
// [-100000000, 100000000] px"), or "" when nothing is.
std::string ValueProblem(double value, const ValueRange* range) {
  if (!std::isfinite(value)) return "value is not finite";
  if (range != nullptr && !InRange(value, *range))
    return FormatPlainNumber(value) + " is outside " + RangeText(*range);
  return std::string();
}

// "column: '<text>' is outside [min, max] unit" for a value outside its column's range.
Status CheckRange(const CsvRowReader& row, const TableColumn& column, std::string_view label,
                  std::string_view text, double value) {
  if (column.range == nullptr || InRange(value, *column.range)) return Status::Ok();
  return row.Error(column.csv, std::string(label) + Quoted(text) + " is outside " +
                                   RangeText(*column.range));
}
Status CheckRange(const CsvRowReader& row, std::string_view column, std::string_view label,
                  std::string_view text, double value) {
  return CheckRange(row, LookUp(row.header(), column), label, text, value);
}

// A number within its column's range; an empty field gives nullopt.
Status ReadNumber(const CsvRowReader& row, const TableColumn& column,
                  std::optional<double>* value) {
  PHOTOPOSE_RETURN_IF_ERROR(row.Number(column.csv, value));
  if (*value) PHOTOPOSE_RETURN_IF_ERROR(CheckRange(row, column, "", row.Text(column.csv), **value));
  return Status::Ok();
}
Status ReadNumber(const CsvRowReader& row, std::string_view column, std::optional<double>* value) {
  return ReadNumber(row, LookUp(row.header(), column), value);
}

// A number within its column's range; an empty field is an error.
Status ReadRequiredNumber(const CsvRowReader& row, const TableColumn& column, double* value) {
  std::optional<double> number;
  PHOTOPOSE_RETURN_IF_ERROR(ReadNumber(row, column, &number));
  if (!number) return row.Error(column.csv, "is empty");
  *value = *number;
  return Status::Ok();
}
Status ReadRequiredNumber(const CsvRowReader& row, std::string_view column, double* value) {
  return ReadRequiredNumber(row, LookUp(row.header(), column), value);
}

// A list of numbers, each within its column's range.
Status ReadNumberList(const CsvRowReader& row, std::string_view column,
                      std::vector<double>* values) {
  PHOTOPOSE_RETURN_IF_ERROR(row.NumberList(column, values));
  for (size_t i = 0; i < values->size(); ++i) {
    PHOTOPOSE_RETURN_IF_ERROR(CheckRange(row, column, "item " + std::to_string(i + 1) + ": ",
                                         FormatPlainNumber((*values)[i]), (*values)[i]));
  }
  return Status::Ok();
}

// "path:line: " for a known line, else "path: ".
std::string Where(const std::string& path, int line) {
  return line > 0 ? path + ":" + std::to_string(line) + ": " : path + ": ";
}

// One accepted spelling of an enumerated column value.
template <typename Enum>
struct Spelling {
  const char* text;
  Enum value;
};

// Reads an enumerated column: spellings are compared with FoldedName(); an empty field keeps
// *value. The error lists the first `num_listed` spellings.
template <typename Enum, typename Column>
Status ReadEnum(const CsvRowReader& row, const Column& column,
                const std::vector<Spelling<Enum>>& spellings, size_t num_listed, Enum* value) {
  const std::string_view text = row.Text(column);
  if (text.empty()) return Status::Ok();
  const std::string folded = FoldedName(text);
  for (const Spelling<Enum>& spelling : spellings) {
    if (FoldedName(spelling.text) == folded) {
      *value = spelling.value;
      return Status::Ok();
    }
  }
  std::string listed;
  for (size_t i = 0; i < std::min(num_listed, spellings.size()); ++i)
    listed += (i == 0 ? "" : i + 1 == num_listed ? " or " : ", ") + std::string(spellings[i].text);
  return row.Error(column, Quoted(text) + " is not " + listed);
}

// A number with a default for an empty field.
Status ReadNumberOr(const CsvRowReader& row, std::string_view column, double default_value,
                    double* value) {
  std::optional<double> number;
  PHOTOPOSE_RETURN_IF_ERROR(ReadNumber(row, column, &number));
  *value = number.value_or(default_value);
  return Status::Ok();
}

// An optional number that must be positive when given.
Status ReadPositive(const CsvRowReader& row, std::string_view column,
                    std::optional<double>* value) {
  PHOTOPOSE_RETURN_IF_ERROR(ReadNumber(row, column, value));
  if (*value && !(**value > 0.0))
    return row.Error(column, Quoted(row.Text(column)) + " must be positive");
  return Status::Ok();
}

// Three positive accuracies given together (e.g. AccuracyX, AccuracyY, AccuracyZ) or none.
Status ReadAccuracyTriple(const CsvRowReader& row, const std::string_view (&columns)[3],
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
Status ReadSign(const CsvRowReader& row, std::string_view column, int* value) {
  std::optional<long long> number;
  PHOTOPOSE_RETURN_IF_ERROR(row.Integer(column, &number));
  if (!number) return Status::Ok();
  if (*number != 1 && *number != -1)
    return row.Error(column, Quoted(row.Text(column)) + " must be -1 or +1");
  *value = static_cast<int>(*number);
  return Status::Ok();
}

// A positive whole number that fits an int; an empty field gives 0 (not given).
Status ReadCount(const CsvRowReader& row, std::string_view column, int* value) {
  std::optional<long long> number;
  PHOTOPOSE_RETURN_IF_ERROR(row.Integer(column, &number));
  if (number && (*number <= 0 || *number > INT_MAX))
    return row.Error(column, Quoted(row.Text(column)) + " must be a positive whole number");
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
Status CheckUnique(const CsvRowReader& row, std::string_view column, std::string_view key,
                   std::string_view kind, FirstLines* first_lines) {
  int first = 0;
  if (!first_lines->Seen(key, row.line(), &first)) return Status::Ok();
  return row.Error(column, "duplicate " + std::string(kind) + " " + Quoted(key) +
                               " (first on line " + std::to_string(first) + ")");
}

// Both columns of a pair or neither.
Status RequirePairedColumns(const CsvHeader& table, std::string_view a, std::string_view b) {
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
ExtraColumns ReadExtraColumns(const CsvRowReader& row, const std::vector<size_t>& extra) {
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
  void Number(std::string_view column, double value) {
    const std::string problem = ValueProblem(value, RangeOf(column));
    if (!problem.empty()) Fail(column, problem);
    fields_.push_back(FormatNumber(value));
  }
  void OptionalNumber(std::string_view column, const std::optional<double>& value) {
    if (value) {
      Number(column, *value);
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

std::vector<std::string> HeaderFields(const Names& names) {
  return std::vector<std::string>(names.begin(), names.end());
}

// ------------------------------------------------------------------ camera table

const std::vector<Spelling<FilmCoordinateSystem>>& FilmCoordinateSystemSpellings() {
  static const auto* const kSpellings = new std::vector<Spelling<FilmCoordinateSystem>>{
      {"1", FilmCoordinateSystem::kXRightYUp},
      {"2", FilmCoordinateSystem::kXUpYLeft},
      {"3", FilmCoordinateSystem::kXLeftYDown},
      {"4", FilmCoordinateSystem::kXDownYRight},
      {"X_RIGHT_Y_UP", FilmCoordinateSystem::kXRightYUp},
      {"X_UP_Y_LEFT", FilmCoordinateSystem::kXUpYLeft},
      {"X_LEFT_Y_DOWN", FilmCoordinateSystem::kXLeftYDown},
      {"X_DOWN_Y_RIGHT", FilmCoordinateSystem::kXDownYRight}};
  return *kSpellings;
}
const std::vector<Spelling<DistortionType>>& DistortionTypeSpellings() {
  static const auto* const kSpellings = new std::vector<Spelling<DistortionType>>{
      {"DistortionModel", DistortionType::kDistortionModel},
      {"DistortionTable", DistortionType::kDistortionTable}};
  return *kSpellings;
}
const std::vector<Spelling<OrientationType>>& OrientationTypeSpellings() {
  static const auto* const kSpellings = new std::vector<Spelling<OrientationType>>{
      {"OPK", OrientationType::kOpk}, {"Matrix", OrientationType::kMatrix}};
  return *kSpellings;
}
const std::vector<Spelling<bool>>& BooleanSpellings() {
  static const auto* const kSpellings = new std::vector<Spelling<bool>>{
      {"true", true}, {"false", false}, {"1", true}, {"0", false}, {"yes", true}, {"no", false}};
  return *kSpellings;
}

// NRows and NColumns, when given, describe an image: kMinImageSidePx to kMaxImageSidePx.
Status CheckImageSize(const FrameCamera& camera, std::string* column) {
  for (const auto& [name, value] : {std::pair<const char*, int>{"NRows", camera.n_rows},
                                    std::pair<const char*, int>{"NColumns", camera.n_columns}}) {
    if (value != 0 && (value < kMinImageSidePx || value > kMaxImageSidePx)) {
      *column = name;
      return Status::Error(std::to_string(value) + " is outside [" +
                           std::to_string(kMinImageSidePx) + ", " +
                           std::to_string(kMaxImageSidePx) + "] pixels");
    }
  }
  return Status::Ok();
}

// An affine, when given, must be invertible in a meaningful way: its determinant not negligible
// against its coefficients, and a pixel size (sqrt of |det|, or its inverse for AffineDirection
// -1) within the PixelSize range.
Status CheckAffine(const FrameCamera& camera, std::string* column) {
  if (!camera.has_affine) return Status::Ok();
  const auto& a = camera.affine_a;
  const auto& b = camera.affine_b;
  const double scale = std::max({std::abs(a[1]), std::abs(a[2]), std::abs(b[1]), std::abs(b[2])});
  const double det = a[1] * b[2] - a[2] * b[1];
  *column = "A1";
  if (!(std::abs(det) >= kMinAffineDeterminantRatio * scale * scale) || !(scale > 0.0)) {
    return Status::Error("the affine is singular: A1 B2 - A2 B1 = " + FormatNumber(det) +
                         " is negligible against its coefficients (up to " + FormatNumber(scale) +
                         "); the rows of A and B must not be parallel");
  }
  const double pixel_um =
      camera.affine_direction > 0 ? std::sqrt(std::abs(det)) : 1.0 / std::sqrt(std::abs(det));
  if (!(pixel_um > kMinPixelSizeUm && pixel_um < kMaxPixelSizeUm)) {
    return Status::Error(
        "the affine gives pixels of " + FormatNumber(pixel_um) + " um (sqrt |A1 B2 - A2 B1|" +
        (camera.affine_direction > 0 ? "" : ", inverted for AffineDirection -1") + "), outside (" +
        FormatNumber(kMinPixelSizeUm) + ", " + FormatNumber(kMaxPixelSizeUm) + ") um");
  }
  column->clear();
  return Status::Ok();
}

// The largest distance (um) from the principal point to the edge of the image in film
// coordinates: the image's corners when its size is known, else the fiducials, else the end of
// the distortion table; 0 when none of these is given.
double FieldRadiusUm(const FrameCamera& camera) {
  const Eigen::Vector2d principal(camera.principal_x_um, camera.principal_y_um);
  double radius = 0.0;
  if (camera.n_columns > 0 && camera.n_rows > 0) {
    for (const double col : {0.0, static_cast<double>(camera.n_columns)}) {
      for (const double row : {0.0, static_cast<double>(camera.n_rows)}) {
        Eigen::Vector2d film;
        if (FilmFromPixel(camera, {col, row}, PixelOrigin::kCorner, &film).ok())
          radius = std::max(radius, (film - principal).norm());
      }
    }
    if (radius > 0.0) return radius;
  }
  for (const Eigen::Vector2d& fiducial : camera.film_fiducials_um)
    radius = std::max(radius, (fiducial - principal).norm());
  if (radius > 0.0) return radius;
  if (camera.distortion_type == DistortionType::kDistortionTable &&
      !camera.radial_distances_um.empty())
    return camera.radial_distances_um.back();
  return 0.0;
}

// The distortion correction must map the image onto itself without folding it: along every
// direction from the principal point, the corrected radius u . (m - D(m)) of a measured point m at
// radius r increases strictly with r up to the field radius, and stays within a factor
// kMaxDistortionScale of r.
Status CheckDistortionDoesNotFold(const FrameCamera& camera, std::string* column) {
  const double field_um = FieldRadiusUm(camera);
  if (!(field_um > 0.0) || !std::isfinite(field_um)) return Status::Ok();
  *column = camera.distortion_type == DistortionType::kDistortionTable ? "RadialDistortions"
            : (camera.radial_k == std::array<double, 4>{})             ? "Tangential"
                                                                       : "Radial";
  constexpr int kDirections = 16;
  constexpr int kSteps = 256;
  const auto mm = [](double um) { return FormatNumber(std::round(um) / 1000.0) + " mm"; };
  for (int d = 0; d < kDirections; ++d) {
    const double angle = 2.0 * kPi * d / kDirections;
    const Eigen::Vector2d u(std::cos(angle), std::sin(angle));
    double previous = 0.0;
    for (int k = 1; k <= kSteps; ++k) {
      const double r = field_um * k / kSteps;
      const Eigen::Vector2d m = r * u;
      const double corrected = u.dot(m - DistortionInMicrons(camera, m));
      if (!(corrected > previous)) {
        return Status::Error(
            "the distortion folds the image: the corrected radius stops "
            "increasing at " +
            mm(r) +
            " from the principal point, inside the "
            "image (" +
            mm(field_um) + " to its farthest corner)");
      }
      const double scale = corrected / r;
      if (!(scale <= kMaxDistortionScale && scale >= 1.0 / kMaxDistortionScale)) {
        return Status::Error("the distortion correction scales the radius by " +
                             FormatNumber(std::round(scale * 1000.0) / 1000.0) + " at " + mm(r) +
                             " from the principal point; inside the image (" + mm(field_um) +
                             " to its farthest corner) it may change it by a factor of " +
                             FormatNumber(kMaxDistortionScale) + " at most");
      }
      previous = corrected;
    }
  }
  column->clear();
  return Status::Ok();
}

// Checks of a camera beyond FrameCamera::IsValid that keep the table readable and physical: a
// distortion table that is given, of equal lengths and increasing; a sane image size and affine;
// a distortion that does not fold the image. On failure *column names the culprit.
Status CheckCameraTableFields(const FrameCamera& camera, std::string* column) {
  const auto& r = camera.radial_distances_um;
  const auto& d = camera.radial_distortions_um;
  if (camera.distortion_type == DistortionType::kDistortionTable && r.empty()) {
    *column = "RadialDistances";
    return Status::Error("is empty; DistortionTable needs RadialDistances and RadialDistortions");
  }
  if (r.size() != d.size()) {
    *column = "RadialDistortions";
    return Status::Error("has " + std::to_string(d.size()) + " numbers but RadialDistances has " +
                         std::to_string(r.size()));
  }
  for (size_t i = 1; i < r.size(); ++i) {
    if (!(r[i] > r[i - 1])) {
      *column = "RadialDistances";
      return Status::Error("must increase: item " + std::to_string(i + 1) + " (" +
                           FormatNumber(r[i]) + ") is not larger than item " + std::to_string(i) +
                           " (" + FormatNumber(r[i - 1]) + ")");
    }
  }
  if (const Status size = CheckImageSize(camera, column); !size.ok()) return size;
  if (const Status affine = CheckAffine(camera, column); !affine.ok()) return affine;
  column->clear();
  PHOTOPOSE_RETURN_IF_ERROR(camera.IsValid());
  return CheckDistortionDoesNotFold(camera, column);
}

Status ReadAffine(const CsvRowReader& row, FrameCamera* camera) {
  const Names& names = AffineColumns();
  const auto given = std::count_if(names.begin(), names.end(),
                                   [&](std::string_view name) { return row.Has(name); });
  if (given == 0) return Status::Ok();
  std::array<double, 6> values{};
  for (size_t i = 0; i < names.size(); ++i) {
    if (!row.Has(names[i]))
      return row.Error(names[i], "is empty; A0, A1, A2, B0, B1, B2 are given together");
    PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, names[i], &values[i]));
  }
  camera->has_affine = true;
  camera->affine_a = {values[0], values[1], values[2]};
  camera->affine_b = {values[3], values[4], values[5]};
  return Status::Ok();
}

Status ReadDistortion(const CsvRowReader& row, FrameCamera* camera) {
  PHOTOPOSE_RETURN_IF_ERROR(
      ReadEnum(row, "DistortionType", DistortionTypeSpellings(), 2, &camera->distortion_type));
  std::vector<double> values;
  PHOTOPOSE_RETURN_IF_ERROR(ReadNumberList(row, "Radial", &values));
  if (values.size() == 4) {
    camera->radial_k = {values[0], values[1], values[2], values[3]};
  } else if (values.size() == 3) {
    camera->radial_k = {0.0, values[0], values[1], values[2]};
  } else if (!values.empty()) {
    return row.Error("Radial", "has " + std::to_string(values.size()) +
                                   " numbers, expected K0;K1;K2;K3 (4) or K1;K2;K3 (3)");
  }
  PHOTOPOSE_RETURN_IF_ERROR(ReadNumberList(row, "Tangential", &values));
  if (values.size() == 2) {
    camera->tangential_p = {values[0], values[1]};
  } else if (!values.empty()) {
    return row.Error("Tangential",
                     "has " + std::to_string(values.size()) + " numbers, expected P1;P2 (2)");
  }
  PHOTOPOSE_RETURN_IF_ERROR(ReadNumberList(row, "RadialDistances", &camera->radial_distances_um));
  PHOTOPOSE_RETURN_IF_ERROR(
      ReadNumberList(row, "RadialDistortions", &camera->radial_distortions_um));
  return Status::Ok();
}

// `extra`: the header's columns that are not the camera table's.
Status ReadCameraRow(const CsvRowReader& row, const std::vector<size_t>& extra,
                     FrameCamera* camera) {
  FrameCamera c;
  PHOTOPOSE_RETURN_IF_ERROR(row.Integer("ObjectID", &c.object_id));
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredText("CameraID", &c.camera_id));
  PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, "FocalLength", &c.focal_length_um));
  PHOTOPOSE_RETURN_IF_ERROR(ReadNumberOr(row, "PrincipalX", 0.0, &c.principal_x_um));
  PHOTOPOSE_RETURN_IF_ERROR(ReadNumberOr(row, "PrincipalY", 0.0, &c.principal_y_um));
  PHOTOPOSE_RETURN_IF_ERROR(ReadNumberOr(row, "PixelSize", 0.0, &c.pixel_size_um));
  PHOTOPOSE_RETURN_IF_ERROR(ReadCount(row, "NRows", &c.n_rows));
  PHOTOPOSE_RETURN_IF_ERROR(ReadCount(row, "NColumns", &c.n_columns));
  PHOTOPOSE_RETURN_IF_ERROR(ReadCount(row, "NBands", &c.n_bands));
  c.pixel_type = std::string(row.Text("PixelType"));
  c.block_name = std::string(row.Text("BlockName"));
  PHOTOPOSE_RETURN_IF_ERROR(ReadEnum(row, "FilmCoordinateSystem", FilmCoordinateSystemSpellings(),
                                     8, &c.film_coordinate_system));
  PHOTOPOSE_RETURN_IF_ERROR(ReadAffine(row, &c));
  PHOTOPOSE_RETURN_IF_ERROR(ReadSign(row, "AffineDirection", &c.affine_direction));
  PHOTOPOSE_RETURN_IF_ERROR(ReadDistortion(row, &c));
  std::vector<double> fiducials;
  PHOTOPOSE_RETURN_IF_ERROR(row.NumberGroups("FilmFiducials", 2, &fiducials));
  for (size_t i = 0; i < fiducials.size(); ++i) {
    PHOTOPOSE_RETURN_IF_ERROR(CheckRange(row, "FilmFiducials",
                                         "item " + std::to_string(i / 2 + 1) + ": ",
                                         FormatPlainNumber(fiducials[i]), fiducials[i]));
  }
  for (size_t i = 0; i + 1 < fiducials.size(); i += 2)
    c.film_fiducials_um.emplace_back(fiducials[i], fiducials[i + 1]);
  PHOTOPOSE_RETURN_IF_ERROR(
      ReadEnum(row, "OrientationType", OrientationTypeSpellings(), 2, &c.orientation_type));
  PHOTOPOSE_RETURN_IF_ERROR(ReadSign(row, "AngleDirection", &c.angle_direction));
  PHOTOPOSE_RETURN_IF_ERROR(ReadSign(row, "Polarity", &c.polarity));
  PHOTOPOSE_RETURN_IF_ERROR(ReadNumber(row, "AverageZ", &c.average_z_m));
  PHOTOPOSE_RETURN_IF_ERROR(ReadEnum(row, "ApplyECC", BooleanSpellings(), 6, &c.apply_ecc));
  PHOTOPOSE_RETURN_IF_ERROR(ReadNumberOr(row, "EarthRadius", c.earth_radius_m, &c.earth_radius_m));
  c.srs = std::string(row.Text("SRS"));
  c.extra_columns = ReadExtraColumns(row, extra);

  std::string column;
  const Status valid = CheckCameraTableFields(c, &column);
  if (!valid.ok()) return row.Error(column, valid.message());
  *camera = std::move(c);
  return Status::Ok();
}

const char* FilmCoordinateSystemText(FilmCoordinateSystem fcs) {
  switch (fcs) {
    case FilmCoordinateSystem::kXRightYUp:
      return "1";
    case FilmCoordinateSystem::kXUpYLeft:
      return "2";
    case FilmCoordinateSystem::kXLeftYDown:
      return "3";
    case FilmCoordinateSystem::kXDownYRight:
      return "4";
  }
  return "1";
}

std::string CountText(int count) { return count > 0 ? std::to_string(count) : std::string(); }
std::string SignText(int sign) { return sign > 0 ? "1" : "-1"; }

// ------------------------------------------------------------------ frames table

// d(file parameters) / d(eo.parameters): identity for X0, Y0, Z0, and the angle Jacobian of the
// one boundary conversion (core/rotation.h).
Matrix6d FileFromSeedJacobian(RotationConvention convention, const AngleFlags& flags,
                              const Eigen::Vector3d& seed_angles_rad) {
  Matrix6d J = Matrix6d::Identity();
  J.bottomRightCorner<3, 3>() = ConventionFromSeedJacobian(convention, flags, seed_angles_rad);
  return J;
}

// The camera of a frame when cameras are given (nullptr otherwise); a CameraID that is not among
// them is an error "unknown camera '<id>'" for the caller to place.
Status FindCamera(const FramesTableOptions& options, const std::string& camera_id,
                  const FrameCamera** camera) {
  *camera = nullptr;
  if (options.cameras == nullptr) return Status::Ok();
  for (const FrameCamera& c : *options.cameras) {
    if (c.camera_id == camera_id) {
      *camera = &c;
      return Status::Ok();
    }
  }
  return Status::Error("unknown camera " + Quoted(camera_id));
}

AngleFlags FlagsOf(const FrameCamera* camera) {
  AngleFlags flags;
  if (camera != nullptr) flags.angle_direction = camera->angle_direction;
  return flags;
}

Status ReadFrameRotation(const CsvRowReader& row, const FramesTableOptions& options,
                         const FrameCamera* camera, Eigen::Vector3d* seed_angles_rad) {
  bool use_matrix;
  if (camera != nullptr) {
    use_matrix = camera->orientation_type == OrientationType::kMatrix;
  } else {
    use_matrix = !row.Has("Omega") && !row.Has("Phi") && !row.Has("Kappa") && row.Has("Matrix");
  }
  if (use_matrix) {
    std::vector<double> values;
    PHOTOPOSE_RETURN_IF_ERROR(ReadNumberList(row, "Matrix", &values));
    if (values.empty()) return row.Error("Matrix", "is empty");
    if (values.size() != 9) {
      return row.Error("Matrix", "has " + std::to_string(values.size()) +
                                     " numbers, expected 9 (a 3x3 matrix, row by row)");
    }
    const Eigen::Matrix3d R =
        Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(values.data());
    const Status rotation = CheckRotationMatrix(R, kMatrixOrthonormalityTolerance);
    if (!rotation.ok()) return row.Error("Matrix", rotation.message());
    *seed_angles_rad = AnglesFromRotation(RotationConvention::kSeed, R);
    return Status::Ok();
  }
  Eigen::Vector3d angles_deg;
  PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, "Omega", &angles_deg[0]));
  PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, "Phi", &angles_deg[1]));
  PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, "Kappa", &angles_deg[2]));
  *seed_angles_rad =
      SeedAnglesFromConvention(options.convention, FlagsOf(camera), angles_deg / kDegreesPerRadian);
  return Status::Ok();
}

// SigmaX..SigmaKappa (m, degrees of the file's angles) as a covariance of eo.parameters without
// correlations in the file's parameters: Sigma = J^-1 diag(sigma^2) J^-T.
Status ReadFrameSigmas(const CsvRowReader& row, const FramesTableOptions& options,
                       const FrameCamera* camera, FrameRecord* frame) {
  const Names& names = SigmaColumns();
  const auto given = std::count_if(names.begin(), names.end(),
                                   [&](std::string_view name) { return row.Has(name); });
  if (given == 0) return Status::Ok();
  Vector6d variances;
  for (int i = 0; i < 6; ++i) {
    if (!row.Has(names[i])) {
      return row.Error(names[i],
                       "is empty; SigmaX, SigmaY, SigmaZ, SigmaOmega, SigmaPhi, SigmaKappa are "
                       "given together");
    }
    double sigma = 0.0;
    PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, names[i], &sigma));
    if (sigma < 0.0) return row.Error(names[i], Quoted(row.Text(names[i])) + " is negative");
    if (i >= 3) sigma /= kDegreesPerRadian;
    variances[i] = sigma * sigma;
  }
  const Matrix6d J =
      FileFromSeedJacobian(options.convention, FlagsOf(camera), frame->eo.angles_seed_rad());
  const Eigen::FullPivLU<Matrix6d> lu(J);
  if (!lu.isInvertible()) {
    return row.Error("SigmaOmega",
                     "cannot be converted: the angles are at a gimbal lock of the convention");
  }
  const Matrix6d J_inverse = lu.inverse();
  frame->covariance = J_inverse * variances.asDiagonal() * J_inverse.transpose();
  return Status::Ok();
}

// `extra`: the header's columns that are not the frames table's.
Status ReadFrameRow(const CsvRowReader& row, const std::vector<size_t>& extra,
                    const FramesTableOptions& options, FrameRecord* frame) {
  FrameRecord f;
  f.line = row.line();
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredText("Raster", &f.raster));
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredText("CameraID", &f.camera_id));
  const FrameCamera* camera = nullptr;
  const Status found = FindCamera(options, f.camera_id, &camera);
  if (!found.ok()) return row.Error("CameraID", found.message());
  Eigen::Vector3d center;
  PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, "PerspectiveX", &center[0]));
  PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, "PerspectiveY", &center[1]));
  PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, "PerspectiveZ", &center[2]));
  f.eo.set_center_in_ground(center);
  Eigen::Vector3d seed_angles =
      Eigen::Vector3d::Zero();  // set below; zero quiets -Wmaybe-uninitialized
  PHOTOPOSE_RETURN_IF_ERROR(ReadFrameRotation(row, options, camera, &seed_angles));
  f.eo.set_angles_seed_rad(seed_angles);
  f.srs = std::string(row.Text("SRS"));
  PHOTOPOSE_RETURN_IF_ERROR(ReadFrameSigmas(row, options, camera, &f));
  PHOTOPOSE_RETURN_IF_ERROR(ReadNumber(row, "Sigma0", &f.sigma0));
  if (f.sigma0 && *f.sigma0 < 0.0)
    return row.Error("Sigma0", Quoted(row.Text("Sigma0")) + " is negative");
  PHOTOPOSE_RETURN_IF_ERROR(ReadAccuracyTriple(row, kAccuracyColumns, &f.center_accuracy_m));
  PHOTOPOSE_RETURN_IF_ERROR(
      ReadAccuracyTriple(row, kAttitudeAccuracyColumns, &f.attitude_accuracy_deg));
  f.extra_columns = ReadExtraColumns(row, extra);
  *frame = std::move(f);
  return Status::Ok();
}

// ------------------------------------------------------------------ ground points and marks

const std::vector<Spelling<PointRole>>& RoleSpellings() {
  static const auto* const kSpellings = new std::vector<Spelling<PointRole>>{
      {"control", PointRole::kControl}, {"check", PointRole::kCheck}, {"tie", PointRole::kTie}};
  return *kSpellings;
}

// The points table's columns, looked up once per table.
struct PointTableColumns {
  explicit PointTableColumns(const CsvHeader& header)
      : point_id(LookUp(header, "PointID")),
        x(LookUp(header, "X")),
        y(LookUp(header, "Y")),
        z(LookUp(header, "Z")),
        accuracy{LookUp(header, kAccuracyColumns[0]), LookUp(header, kAccuracyColumns[1]),
                 LookUp(header, kAccuracyColumns[2])},
        role(LookUp(header, "Role")) {}
  TableColumn point_id, x, y, z, accuracy[3], role;
};

Status ReadPointRow(const CsvRowReader& row, const PointTableColumns& c, GroundPoint* point) {
  GroundPoint p;
  p.line = row.line();
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredText(c.point_id.csv, &p.point_id));
  PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, c.x, &p.position[0]));
  PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, c.y, &p.position[1]));
  PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, c.z, &p.position[2]));
  if (row.Has(c.accuracy[0].csv) || row.Has(c.accuracy[1].csv) || row.Has(c.accuracy[2].csv)) {
    Eigen::Vector3d accuracy;
    for (int i = 0; i < 3; ++i) {
      std::optional<double> sigma;
      PHOTOPOSE_RETURN_IF_ERROR(ReadNumber(row, c.accuracy[i], &sigma));
      if (!sigma) {
        return row.Error(c.accuracy[i].csv,
                         "is empty; AccuracyX, AccuracyY, AccuracyZ are given together");
      }
      accuracy[i] = *sigma;
    }
    p.accuracy_m = accuracy;
  }
  PHOTOPOSE_RETURN_IF_ERROR(ReadEnum(row, c.role.csv, RoleSpellings(), 3, &p.role));
  *point = std::move(p);
  return Status::Ok();
}

// The marks table's columns, looked up once per table.
struct MarkTableColumns {
  explicit MarkTableColumns(const CsvHeader& header)
      : raster(LookUp(header, "Raster")),
        point_id(LookUp(header, "PointID")),
        column(LookUp(header, "Column")),
        row(LookUp(header, "Row")),
        film_x(LookUp(header, "FilmX")),
        film_y(LookUp(header, "FilmY")),
        accuracy(LookUp(header, "Accuracy")),
        camera_id(LookUp(header, "CameraID")) {}
  TableColumn raster, point_id, column, row, film_x, film_y, accuracy, camera_id;
};

// Column/Row (pixels) or FilmX/FilmY (um): exactly one pair.
Status ReadMarkPosition(const CsvRowReader& row, const MarkTableColumns& c, ImageMark* mark) {
  const bool pixels = row.Has(c.column.csv) || row.Has(c.row.csv);
  const bool film = row.Has(c.film_x.csv) || row.Has(c.film_y.csv);
  if (pixels && film)
    return row.Error(c.film_x.csv, "give either Column/Row or FilmX/FilmY, not both");
  if (!pixels && !film) {
    return row.Error(c.column.csv,
                     "is empty; give Column and Row (pixels) or FilmX and FilmY (um)");
  }
  Eigen::Vector2d xy;
  PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, pixels ? c.column : c.film_x, &xy[0]));
  PHOTOPOSE_RETURN_IF_ERROR(ReadRequiredNumber(row, pixels ? c.row : c.film_y, &xy[1]));
  if (pixels) {
    mark->column_row = xy;
  } else {
    mark->film_um = xy;
  }
  return Status::Ok();
}

// Reads a row into *mark, whose strings keep their buffers from the row before.
Status ReadMarkRow(const CsvRowReader& row, const MarkTableColumns& c, ImageMark* mark) {
  mark->line = row.line();
  mark->column_row.reset();
  mark->film_um.reset();
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredText(c.raster.csv, &mark->raster));
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredText(c.point_id.csv, &mark->point_id));
  PHOTOPOSE_RETURN_IF_ERROR(ReadMarkPosition(row, c, mark));
  PHOTOPOSE_RETURN_IF_ERROR(ReadNumber(row, c.accuracy, &mark->accuracy_px));
  const std::string_view camera_id = row.Text(c.camera_id.csv);
  mark->camera_id.assign(camera_id.data(), camera_id.size());
  return Status::Ok();
}

std::string MarkDescription(std::string_view raster, std::string_view point_id) {
  return "mark of point " + Quoted(point_id) + " in image " + Quoted(raster);
}

// Duplicate marks (a point marked twice in one image), found without a string, an allocation or
// a random look-up per mark: each mark is kept as the dense ids of its raster and point (8 bytes),
// and the check sorts the marks by point (counting sort, stable) and compares each point's rasters
// through a stamp per raster, in time linear in the marks however they are spread.
class DuplicateMarks {
 public:
  // `stable_text`: see NameIds.
  DuplicateMarks(std::string_view stable_text, size_t expected_marks)
      : rasters_(stable_text), points_(stable_text) {
    pairs_.reserve(expected_marks);
  }

  // Adds the next mark (numbered from 0).
  void Add(std::string_view raster, std::string_view point_id) {
    bool is_new = false;
    const int raster_id = rasters_.Id(raster, &is_new);
    pairs_.push_back({raster_id, points_.Id(point_id, &is_new)});
  }
  std::string_view Raster(size_t mark) const { return rasters_.Name(pairs_[mark].raster); }
  std::string_view PointId(size_t mark) const { return points_.Name(pairs_[mark].point); }

  // The first mark (in the order added) whose point and raster an earlier mark has, and that
  // earlier mark (the first of the pair); false when there is none.
  bool FindFirst(size_t* duplicate, size_t* first) const {
    std::vector<size_t> start(points_.size() + 1, 0);
    for (const Pair& pair : pairs_) ++start[pair.point + 1];
    for (size_t p = 0; p < points_.size(); ++p) start[p + 1] += start[p];
    std::vector<uint32_t> by_point(pairs_.size());
    {
      std::vector<size_t> next(start.begin(), start.end() - 1);
      for (size_t m = 0; m < pairs_.size(); ++m)
        by_point[next[pairs_[m].point]++] = static_cast<uint32_t>(m);
    }
    // The last point seen in each raster and its first mark there.
    std::vector<int> point_in_raster(rasters_.size(), -1);
    std::vector<uint32_t> first_in_raster(rasters_.size(), 0);
    bool found = false;
    for (size_t p = 0; p < points_.size(); ++p) {
      for (size_t i = start[p]; i < start[p + 1]; ++i) {
        const uint32_t m = by_point[i];
        const int raster = pairs_[m].raster;
        if (point_in_raster[raster] != static_cast<int>(p)) {
          point_in_raster[raster] = static_cast<int>(p);
          first_in_raster[raster] = m;
        } else if (!found || m < *duplicate) {
          found = true;
          *duplicate = m;
          *first = first_in_raster[raster];
        }
      }
    }
    return found;
  }

 private:
  struct Pair {
    int raster;
    int point;
  };
  NameIds rasters_, points_;
  std::vector<Pair> pairs_;
};

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

// ------------------------------------------------------------------ camera table

Status ParseCameraTable(std::string_view text, const std::string& file_name,
                        std::vector<FrameCamera>* cameras) {
  CsvReader reader;
  PHOTOPOSE_RETURN_IF_ERROR(reader.Open(text, file_name, kTableCsvOptions));
  const CsvHeader& table = reader.header();
  PHOTOPOSE_RETURN_IF_ERROR(table.RequireColumns({"CameraID", "FocalLength"}));
  const Names& affine = AffineColumns();
  const bool has_affine_columns = std::all_of(
      affine.begin(), affine.end(), [&](std::string_view name) { return table.HasColumn(name); });
  if (!has_affine_columns) PHOTOPOSE_RETURN_IF_ERROR(table.RequireColumns({"PixelSize"}));

  const std::vector<size_t> extra = table.ColumnsOtherThan(CameraColumns());
  std::vector<FrameCamera> result;
  FirstLines first_lines;
  PHOTOPOSE_RETURN_IF_ERROR(reader.ForEachRow([&](const CsvRowReader& row) {
    FrameCamera camera;
    PHOTOPOSE_RETURN_IF_ERROR(ReadCameraRow(row, extra, &camera));
    PHOTOPOSE_RETURN_IF_ERROR(
        CheckUnique(row, "CameraID", camera.camera_id, "camera", &first_lines));
    result.push_back(std::move(camera));
    return Status::Ok();
  }));
  *cameras = std::move(result);
  return Status::Ok();
}

Status FormatCameraTable(const std::vector<FrameCamera>& cameras, const std::string& path,
                         std::string* text) {
  std::vector<std::string> extra_names;
  PHOTOPOSE_RETURN_IF_ERROR(CollectExtraColumnNames(path, cameras, CameraColumns(), &extra_names));
  std::vector<std::string> header = HeaderFields(CameraColumns());
  header.insert(header.end(), extra_names.begin(), extra_names.end());
  std::string contents = CsvLine(header);

  for (const FrameCamera& c : cameras) {
    const std::string record = "camera " + Quoted(c.camera_id);
    std::string column;
    const Status valid = CheckCameraTableFields(c, &column);
    if (!valid.ok()) {
      return Status::Error(path + ": " + record + ": " + (column.empty() ? "" : column + ": ") +
                           valid.message());
    }
    RowFields row(record);
    row.Text(c.object_id ? std::to_string(*c.object_id) : "");
    row.Text(c.camera_id);
    row.Number("FocalLength", c.focal_length_um);
    row.Number("PrincipalX", c.principal_x_um);
    row.Number("PrincipalY", c.principal_y_um);
    row.OptionalNumber("PixelSize", c.pixel_size_um != 0.0 ? std::optional<double>(c.pixel_size_um)
                                                           : std::nullopt);
    row.Text(CountText(c.n_rows));
    row.Text(CountText(c.n_columns));
    row.Text(CountText(c.n_bands));
    row.Text(c.pixel_type);
    row.Text(c.block_name);
    row.Text(FilmCoordinateSystemText(c.film_coordinate_system));
    const Names& affine = AffineColumns();
    for (int i = 0; i < 6; ++i) {
      const double value = i < 3 ? c.affine_a[i] : c.affine_b[i - 3];
      row.OptionalNumber(affine[i], c.has_affine ? std::optional<double>(value) : std::nullopt);
    }
    row.Text(SignText(c.affine_direction));
    row.Text(c.distortion_type == DistortionType::kDistortionTable ? "DistortionTable"
                                                                   : "DistortionModel");
    row.NumberList("Radial", {c.radial_k.begin(), c.radial_k.end()});
    row.NumberList("Tangential", {c.tangential_p.begin(), c.tangential_p.end()});
    row.NumberList("RadialDistances", c.radial_distances_um);
    row.NumberList("RadialDistortions", c.radial_distortions_um);
    std::string fiducials;
    for (size_t i = 0; i < c.film_fiducials_um.size(); ++i) {
      const Eigen::Vector2d& f = c.film_fiducials_um[i];
      if (!f.allFinite()) row.Fail("FilmFiducials", "a value is not finite");
      if (!(f.cwiseAbs().maxCoeff() <= kMaxCoordinate))
        row.Fail("FilmFiducials", "a value is outside " + RangeText(*RangeOf("FilmFiducials")));
      fiducials += (i == 0 ? "" : ";") + FormatNumber(f.x()) + " " + FormatNumber(f.y());
    }
    row.Text(fiducials);
    row.Text(c.orientation_type == OrientationType::kMatrix ? "Matrix" : "OPK");
    row.Text(SignText(c.angle_direction));
    row.Text(SignText(c.polarity));
    row.OptionalNumber("AverageZ", c.average_z_m);
    row.Text(c.apply_ecc ? "true" : "false");
    row.Number("EarthRadius", c.earth_radius_m);
    row.Text(c.srs);
    AppendExtraColumns(c, extra_names, row.fields());
    PHOTOPOSE_RETURN_IF_ERROR(row.status(path));
    contents += CsvLine(*row.fields());
  }
  *text = std::move(contents);
  return Status::Ok();
}

// ------------------------------------------------------------------ frames table

Status ParseFramesTable(std::string_view text, const std::string& file_name,
                        const FramesTableOptions& options, std::vector<FrameRecord>* frames) {
  CsvReader reader;
  PHOTOPOSE_RETURN_IF_ERROR(reader.Open(text, file_name, kTableCsvOptions));
  const CsvHeader& table = reader.header();
  PHOTOPOSE_RETURN_IF_ERROR(
      table.RequireColumns({"Raster", "CameraID", "PerspectiveX", "PerspectiveY", "PerspectiveZ"}));
  const bool any_angle_column =
      table.HasColumn("Omega") || table.HasColumn("Phi") || table.HasColumn("Kappa");
  if (any_angle_column) {
    PHOTOPOSE_RETURN_IF_ERROR(table.RequireColumns({"Omega", "Phi", "Kappa"}));
  } else if (!table.HasColumn("Matrix")) {
    return table.Error(table.header_line(), "Omega",
                       "required column is missing (give Omega, Phi, Kappa or Matrix)");
  }
  const Names& sigmas = SigmaColumns();
  if (std::any_of(sigmas.begin(), sigmas.end(),
                  [&](std::string_view name) { return table.HasColumn(name); }))
    PHOTOPOSE_RETURN_IF_ERROR(table.RequireColumns(sigmas));

  const std::vector<size_t> extra = table.ColumnsOtherThan(FrameColumns());
  std::vector<FrameRecord> result;
  FirstLines first_lines(text);
  PHOTOPOSE_RETURN_IF_ERROR(reader.ForEachRow([&](const CsvRowReader& row) {
    FrameRecord frame;
    PHOTOPOSE_RETURN_IF_ERROR(ReadFrameRow(row, extra, options, &frame));
    PHOTOPOSE_RETURN_IF_ERROR(
        CheckUnique(row, "Raster", row.Text("Raster"), "raster", &first_lines));
    result.push_back(std::move(frame));
    return Status::Ok();
  }));
  *frames = std::move(result);
  return Status::Ok();
}

Status FormatFramesTable(const FramesTableOptions& options, const std::vector<FrameRecord>& frames,
                         const std::string& path, std::string* text) {
  // The camera of every frame first: it decides the AngleDirection and whether Matrix is written.
  std::vector<const FrameCamera*> cameras(frames.size(), nullptr);
  bool any_matrix = false, any_covariance = false, any_sigma0 = false;
  bool any_center_accuracy = false, any_attitude_accuracy = false;
  for (size_t i = 0; i < frames.size(); ++i) {
    const Status found = FindCamera(options, frames[i].camera_id, &cameras[i]);
    if (!found.ok())
      return Status::Error(path + ": raster " + Quoted(frames[i].raster) +
                           ": CameraID: " + found.message());
    any_matrix = any_matrix || (cameras[i] != nullptr &&
                                cameras[i]->orientation_type == OrientationType::kMatrix);
    any_covariance = any_covariance || frames[i].covariance.has_value();
    any_sigma0 = any_sigma0 || frames[i].sigma0.has_value();
    any_center_accuracy = any_center_accuracy || frames[i].center_accuracy_m.has_value();
    any_attitude_accuracy = any_attitude_accuracy || frames[i].attitude_accuracy_deg.has_value();
  }
  std::vector<std::string> extra_names;
  PHOTOPOSE_RETURN_IF_ERROR(CollectExtraColumnNames(path, frames, FrameColumns(), &extra_names));
  std::vector<std::string> header = {"Raster",       "CameraID", "PerspectiveX", "PerspectiveY",
                                     "PerspectiveZ", "Omega",    "Phi",          "Kappa"};
  if (any_matrix) header.push_back("Matrix");
  header.push_back("SRS");
  if (any_covariance) header.insert(header.end(), SigmaColumns().begin(), SigmaColumns().end());
  if (any_sigma0) header.push_back("Sigma0");
  if (any_center_accuracy)
    header.insert(header.end(), std::begin(kAccuracyColumns), std::end(kAccuracyColumns));
  if (any_attitude_accuracy)
    header.insert(header.end(), std::begin(kAttitudeAccuracyColumns),
                  std::end(kAttitudeAccuracyColumns));
  header.insert(header.end(), extra_names.begin(), extra_names.end());
  std::string contents = CsvLine(header);

  for (size_t i = 0; i < frames.size(); ++i) {
    const FrameRecord& f = frames[i];
    const FrameCamera* camera = cameras[i];
    const AngleFlags flags = FlagsOf(camera);
    const Eigen::Vector3d seed_angles = f.eo.angles_seed_rad();
    RowFields row("raster " + Quoted(f.raster));
    row.Text(f.raster);
    row.Text(f.camera_id);
    row.Number("PerspectiveX", f.eo.parameters[0]);
    row.Number("PerspectiveY", f.eo.parameters[1]);
    row.Number("PerspectiveZ", f.eo.parameters[2]);
    const Eigen::Vector3d angles_deg =
        ConventionAnglesFromSeed(options.convention, flags, seed_angles) * kDegreesPerRadian;
    row.Number("Omega", angles_deg[0]);
    row.Number("Phi", angles_deg[1]);
    row.Number("Kappa", angles_deg[2]);
    if (any_matrix) {
      std::vector<double> matrix;
      if (camera != nullptr && camera->orientation_type == OrientationType::kMatrix) {
        const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> R =
            RotationFromAngles(RotationConvention::kSeed, seed_angles);
        matrix.assign(R.data(), R.data() + 9);
      }
      row.NumberList("Matrix", matrix);
    }
    row.Text(f.srs);
    if (any_covariance) {
      if (f.covariance) {
        if (!f.covariance->allFinite() || (f.covariance->diagonal().array() < 0.0).any())
          row.Fail("SigmaX", "covariance is not finite or has a negative variance");
        const Matrix6d J = FileFromSeedJacobian(options.convention, flags, seed_angles);
        const Vector6d variances = (J * *f.covariance * J.transpose()).diagonal();
        for (int k = 0; k < 6; ++k) {
          // Rounding can make a zero variance slightly negative.
          const double sigma = std::sqrt(std::max(variances[k], 0.0));
          row.Number(SigmaColumns()[k], k < 3 ? sigma : sigma * kDegreesPerRadian);
        }
      } else {
        for (int k = 0; k < 6; ++k) row.Text("");
      }
    }
    if (any_sigma0) row.OptionalNumber("Sigma0", f.sigma0);
    const auto accuracies = [&row](const std::string_view(&columns)[3],
                                   const std::optional<Eigen::Vector3d>& values) {
      for (int k = 0; k < 3; ++k) {
        if (values && !((*values)[k] > 0.0)) row.Fail(columns[k], "must be positive");
        row.OptionalNumber(columns[k], values ? std::optional<double>((*values)[k]) : std::nullopt);
      }
    };
    if (any_center_accuracy) accuracies(kAccuracyColumns, f.center_accuracy_m);
    if (any_attitude_accuracy) accuracies(kAttitudeAccuracyColumns, f.attitude_accuracy_deg);
    AppendExtraColumns(f, extra_names, row.fields());
    PHOTOPOSE_RETURN_IF_ERROR(row.status(path));
    contents += CsvLine(*row.fields());
  }
  *text = std::move(contents);
  return Status::Ok();
}

// ------------------------------------------------------------------ ground points

Status ParseGroundPoints(std::string_view text, const std::string& file_name,
                         std::vector<GroundPoint>* points) {
  CsvReader reader;
  PHOTOPOSE_RETURN_IF_ERROR(reader.Open(text, file_name, kTableCsvOptions));
  const CsvHeader& table = reader.header();
  PHOTOPOSE_RETURN_IF_ERROR(table.RequireColumns({"PointID", "X", "Y", "Z"}));
  if (table.HasColumn("AccuracyX") || table.HasColumn("AccuracyY") || table.HasColumn("AccuracyZ"))
    PHOTOPOSE_RETURN_IF_ERROR(table.RequireColumns({"AccuracyX", "AccuracyY", "AccuracyZ"}));

  const PointTableColumns columns(table);
  std::vector<GroundPoint> result;
  result.reserve(reader.MaxRows());
  FirstLines first_lines(text);
  PHOTOPOSE_RETURN_IF_ERROR(reader.ForEachRow([&](const CsvRowReader& row) {
    GroundPoint& point = result.emplace_back();
    PHOTOPOSE_RETURN_IF_ERROR(ReadPointRow(row, columns, &point));
    return CheckUnique(row, "PointID", row.Text(columns.point_id.csv), "point", &first_lines);
  }));
  *points = std::move(result);
  return Status::Ok();
}

Status FormatGroundPoints(const std::vector<GroundPoint>& points, const std::string& path,
                          std::string* text) {
  std::string contents = CsvLine(HeaderFields(PointColumns()));
  for (const GroundPoint& p : points) {
    RowFields row("point " + Quoted(p.point_id));
    if (p.point_id.empty()) row.Fail("PointID", "is empty");
    row.Text(p.point_id);
    row.Number("X", p.position.x());
    row.Number("Y", p.position.y());
    row.Number("Z", p.position.z());
    for (int i = 0; i < 3; ++i) {
      if (p.accuracy_m && !((*p.accuracy_m)[i] > 0.0))
        row.Fail(kAccuracyColumns[i], "must be positive");
      row.OptionalNumber(kAccuracyColumns[i],
                         p.accuracy_m ? std::optional<double>((*p.accuracy_m)[i]) : std::nullopt);
    }
    row.Text(p.role == PointRole::kCheck ? "check" : p.role == PointRole::kTie ? "tie" : "control");
    PHOTOPOSE_RETURN_IF_ERROR(row.status(path));
    contents += CsvLine(*row.fields());
  }
  *text = std::move(contents);
  return Status::Ok();
}

// ------------------------------------------------------------------ image marks

Status ParseImageMarks(std::string_view text, const std::string& file_name,
                       std::vector<ImageMark>* marks) {
  CsvReader reader;
  PHOTOPOSE_RETURN_IF_ERROR(reader.Open(text, file_name, kTableCsvOptions));
  const CsvHeader& table = reader.header();
  PHOTOPOSE_RETURN_IF_ERROR(table.RequireColumns({"Raster", "PointID"}));
  PHOTOPOSE_RETURN_IF_ERROR(RequirePairedColumns(table, "Column", "Row"));
  PHOTOPOSE_RETURN_IF_ERROR(RequirePairedColumns(table, "FilmX", "FilmY"));
  if (!table.HasColumn("Column") && !table.HasColumn("FilmX")) {
    return table.Error(table.header_line(), "Column",
                       "required column is missing (give Column and Row, or FilmX and FilmY)");
  }

  const MarkTableColumns columns(table);
  const size_t max_rows = reader.MaxRows();
  std::vector<ImageMark> result;
  result.reserve(max_rows);
  DuplicateMarks duplicates(text, max_rows);
  const Status read = reader.ForEachRow([&](const CsvRowReader& row) {
    ImageMark& mark = result.emplace_back();
    PHOTOPOSE_RETURN_IF_ERROR(ReadMarkRow(row, columns, &mark));
    // The names as views of the text (the mark's strings are copies).
    duplicates.Add(row.Text(columns.raster.csv), row.Text(columns.point_id.csv));
    return Status::Ok();
  });
  // The first problem in the file: a duplicate among the rows before a bad one comes first.
  size_t duplicate = 0, first = 0;
  if (duplicates.FindFirst(&duplicate, &first)) {
    return table.Error(result[duplicate].line, "PointID",
                       "duplicate " +
                           MarkDescription(duplicates.Raster(duplicate),
                                           duplicates.PointId(duplicate)) +
                           " (first on line " + std::to_string(result[first].line) + ")");
  }
  PHOTOPOSE_RETURN_IF_ERROR(read);
  *marks = std::move(result);
  return Status::Ok();
}

struct ImageMarksWriter::State {
  State(const std::string& path, size_t num_marks)
      : path(path),
        duplicates(std::string_view(), num_marks),
        column(RangeOf("Column")),
        row(RangeOf("Row")),
        film_x(RangeOf("FilmX")),
        film_y(RangeOf("FilmY")),
        accuracy(RangeOf("Accuracy")) {
    lines.reserve(num_marks);
  }
  // The reader rejects a second mark of a point in an image: "path: mark of point 'P' in image
  // 'I': PointID: the point is marked twice in the image (source lines 3 and 9)" for the first
  // such mark up to `last` (all when npos), if any.
  Status CheckDuplicates(size_t last) const {
    size_t duplicate = 0, first = 0;
    if (!duplicates.FindFirst(&duplicate, &first) || duplicate > last) return Status::Ok();
    return Status::Error(EscapeForMessage(
        path + ": " + MarkDescription(duplicates.Raster(duplicate), duplicates.PointId(duplicate)) +
        ": PointID: the point is marked twice in the image (source lines " +
        std::to_string(lines[first]) + " and " + std::to_string(lines[duplicate]) + ")"));
  }

  const std::string path;
  DuplicateMarks duplicates;
  std::vector<int> lines;  // source line of every mark added
  const ValueRange *column, *row, *film_x, *film_y, *accuracy;
};

ImageMarksWriter::ImageMarksWriter(const std::string& path, size_t num_marks, std::string* text)
    : state_(std::make_unique<State>(path, num_marks)), text_(text) {
  // About 70 bytes per row for names of a dozen characters: one allocation, mostly.
  text_->reserve(text_->size() + 128 + 80 * num_marks);
  *text_ += CsvLine(HeaderFields(MarkColumns()));
}

ImageMarksWriter::~ImageMarksWriter() = default;

Status ImageMarksWriter::Add(const ImageMark& m) {
  const size_t number = state_->lines.size();
  state_->duplicates.Add(m.raster, m.point_id);
  state_->lines.push_back(m.line);
  // The first problem in the order of the columns, as RowFields keeps it (a duplicate, checked at
  // the end or at the first other problem, comes first); no string is made for a good row.
  std::string problem;
  const auto fail = [&problem](std::string_view column, const std::string& what) {
    if (problem.empty()) problem = std::string(column) + ": " + what;
  };
  if (m.raster.empty()) fail("Raster", "is empty");
  if (m.point_id.empty()) fail("PointID", "is empty");
  if (m.column_row.has_value() == m.film_um.has_value())
    fail("Column", "exactly one of Column/Row and FilmX/FilmY must be set");
  if (m.accuracy_px && !(*m.accuracy_px > 0.0)) fail("Accuracy", "must be positive");
  const auto check = [&fail](std::string_view column, const ValueRange* range, double value) {
    if (std::isfinite(value) && InRange(value, *range)) return;
    fail(column, ValueProblem(value, range));
  };
  if (m.column_row) {
    check("Column", state_->column, m.column_row->x());
    check("Row", state_->row, m.column_row->y());
  }
  if (m.film_um) {
    check("FilmX", state_->film_x, m.film_um->x());
    check("FilmY", state_->film_y, m.film_um->y());
  }
  if (m.accuracy_px) check("Accuracy", state_->accuracy, *m.accuracy_px);
  if (!problem.empty()) {
    PHOTOPOSE_RETURN_IF_ERROR(state_->CheckDuplicates(number));
    return Status::Error(EscapeForMessage(state_->path + ": " +
                                          MarkDescription(m.raster, m.point_id) + ": " + problem));
  }

  std::string& text = *text_;
  AppendCsvField(m.raster, &text);
  text += ',';
  AppendCsvField(m.point_id, &text);
  const auto number_field = [&text](const std::optional<double>& value) {
    text += ',';
    if (value) AppendFormattedNumber(*value, &text);
  };
  number_field(m.column_row ? std::optional<double>(m.column_row->x()) : std::nullopt);
  number_field(m.column_row ? std::optional<double>(m.column_row->y()) : std::nullopt);
  number_field(m.film_um ? std::optional<double>(m.film_um->x()) : std::nullopt);
  number_field(m.film_um ? std::optional<double>(m.film_um->y()) : std::nullopt);
  number_field(m.accuracy_px);
  text += ',';
  AppendCsvField(m.camera_id, &text);
  text += '\n';
  return Status::Ok();
}

Status ImageMarksWriter::Finish() { return state_->CheckDuplicates(std::string::npos); }

Status FormatImageMarks(const std::vector<ImageMark>& marks, const std::string& path,
                        std::string* text) {
  std::string contents;
  ImageMarksWriter writer(path, marks.size(), &contents);
  for (const ImageMark& m : marks) PHOTOPOSE_RETURN_IF_ERROR(writer.Add(m));
  PHOTOPOSE_RETURN_IF_ERROR(writer.Finish());
  *text = std::move(contents);
  return Status::Ok();
}

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

// ------------------------------------------------------------------ consistency

Status CheckMarks(const std::string& marks_path, const std::vector<ImageMark>& marks,
                  const std::vector<GroundPoint>& points) {
  std::map<std::string, int> known;
  for (const GroundPoint& p : points) known.emplace(p.point_id, p.line);
  for (const ImageMark& m : marks) {
    if (known.count(m.point_id) == 0)
      return Status::Error(Where(marks_path, m.line) + "PointID: unknown point " +
                           Quoted(m.point_id));
  }
  return Status::Ok();
}

// ------------------------------------------------------------------ marks inside their image

Status CheckMarkInsideImage(const std::string& marks_path, const ImageMark& mark,
                            const FrameCamera& camera, PixelOrigin origin) {
  if (camera.n_columns <= 0 || camera.n_rows <= 0) return Status::Ok();
  Eigen::Vector2d column_row;
  if (mark.column_row) {
    column_row = *mark.column_row;
  } else if (!mark.film_um || !PixelFromFilm(camera, *mark.film_um, origin, &column_row).ok()) {
    return Status::Ok();  // no way to pixels: other checks say why
  }
  const Eigen::Vector2d size(camera.n_columns, camera.n_rows);
  const Eigen::Vector2d margin = kMarkOutsideImageFraction * size;
  const double shift = origin == PixelOrigin::kCenter ? 0.5 : 0.0;  // corner-based from here on
  for (int k = 0; k < 2; ++k) {
    const double value = column_row[k] + shift;
    const double outside = value < 0.0 ? -value : value - size[k];
    if (!(outside <= margin[k])) {
      const char* column =
          mark.column_row ? (k == 0 ? "Column" : "Row") : (k == 0 ? "FilmX" : "FilmY");
      return Status::Error(EscapeForMessage(
          Where(marks_path, mark.line) + column + ": the mark of point '" + mark.point_id +
          "' in image '" + mark.raster + "' lies " + FormatNumber(std::round(outside)) +
          " pixels outside the " + std::to_string(camera.n_columns) + " x " +
          std::to_string(camera.n_rows) + " image of camera '" + camera.camera_id + "' (at most " +
          FormatNumber(kMarkOutsideImageFraction * 100.0) + "% of the image size is allowed)"));
    }
  }
  return Status::Ok();
}

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
