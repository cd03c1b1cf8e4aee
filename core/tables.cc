#include "core/tables.h"

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
#include <map>
#include <string_view>

#include "core/csv.h"

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

std::string Quoted(std::string_view text) { return "'" + std::string(text) + "'"; }

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
template <typename Enum>
Status ReadEnum(const CsvRowReader& row, std::string_view column,
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
  PHOTOPOSE_RETURN_IF_ERROR(row.Number(column, &number));
  *value = number.value_or(default_value);
  return Status::Ok();
}

// An optional number that must be positive when given.
Status ReadPositive(const CsvRowReader& row, std::string_view column,
                    std::optional<double>* value) {
  PHOTOPOSE_RETURN_IF_ERROR(row.Number(column, value));
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

// Records where `key` was first seen; a second sighting is an error naming both lines.
Status CheckUnique(const CsvTable& table, int line, std::string_view column, const std::string& key,
                   const std::string& what, std::map<std::string, int>* first_lines) {
  const auto [it, inserted] = first_lines->emplace(key, line);
  if (inserted) return Status::Ok();
  return table.Error(line, column,
                     "duplicate " + what + " (first on line " + std::to_string(it->second) + ")");
}

// Both columns of a pair or neither.
Status RequirePairedColumns(const CsvTable& table, std::string_view a, std::string_view b) {
  if (table.HasColumn(a) && !table.HasColumn(b))
    return table.Error(table.header_line(), b,
                       "required column is missing (" + std::string(a) + " is given)");
  if (table.HasColumn(b) && !table.HasColumn(a))
    return table.Error(table.header_line(), a,
                       "required column is missing (" + std::string(b) + " is given)");
  return Status::Ok();
}

// Columns of a row that the schema does not know, as (header name, value).
ExtraColumns ReadExtraColumns(const CsvTable& table, const CsvRow& row, const Names& known) {
  ExtraColumns extra;
  for (const size_t index : table.ColumnsOtherThan(known))
    extra.emplace_back(table.header()[index], row.fields[index]);
  return extra;
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
    if (!std::isfinite(value)) Fail(column, "value is not finite");
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
    for (const double value : values)
      if (!std::isfinite(value)) Fail(column, "a value is not finite");
    fields_.push_back(FormatNumberList(values));
  }
  void Fail(std::string_view column, std::string_view what) {
    if (error_.empty()) error_ = std::string(column) + ": " + std::string(what);
  }

  std::vector<std::string>* fields() { return &fields_; }
  Status status(const std::string& path) const {
    return error_.empty() ? Status::Ok() : Status::Error(path + ": " + record_ + ": " + error_);
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

// Checks of a camera beyond FrameCamera::IsValid that keep the table readable: a distortion
// table that is given, of equal lengths and increasing. On failure *column names the culprit.
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
  column->clear();
  return camera.IsValid();
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
    PHOTOPOSE_RETURN_IF_ERROR(row.RequiredNumber(names[i], &values[i]));
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
  PHOTOPOSE_RETURN_IF_ERROR(row.NumberList("Radial", &values));
  if (values.size() == 4) {
    camera->radial_k = {values[0], values[1], values[2], values[3]};
  } else if (values.size() == 3) {
    camera->radial_k = {0.0, values[0], values[1], values[2]};
  } else if (!values.empty()) {
    return row.Error("Radial", "has " + std::to_string(values.size()) +
                                   " numbers, expected K0;K1;K2;K3 (4) or K1;K2;K3 (3)");
  }
  PHOTOPOSE_RETURN_IF_ERROR(row.NumberList("Tangential", &values));
  if (values.size() == 2) {
    camera->tangential_p = {values[0], values[1]};
  } else if (!values.empty()) {
    return row.Error("Tangential",
                     "has " + std::to_string(values.size()) + " numbers, expected P1;P2 (2)");
  }
  PHOTOPOSE_RETURN_IF_ERROR(row.NumberList("RadialDistances", &camera->radial_distances_um));
  PHOTOPOSE_RETURN_IF_ERROR(row.NumberList("RadialDistortions", &camera->radial_distortions_um));
  return Status::Ok();
}

Status ReadCameraRow(const CsvTable& table, const CsvRow& csv_row, FrameCamera* camera) {
  const CsvRowReader row(table, csv_row);
  FrameCamera c;
  PHOTOPOSE_RETURN_IF_ERROR(row.Integer("ObjectID", &c.object_id));
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredText("CameraID", &c.camera_id));
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredNumber("FocalLength", &c.focal_length_um));
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
  for (size_t i = 0; i + 1 < fiducials.size(); i += 2)
    c.film_fiducials_um.emplace_back(fiducials[i], fiducials[i + 1]);
  PHOTOPOSE_RETURN_IF_ERROR(
      ReadEnum(row, "OrientationType", OrientationTypeSpellings(), 2, &c.orientation_type));
  PHOTOPOSE_RETURN_IF_ERROR(ReadSign(row, "AngleDirection", &c.angle_direction));
  PHOTOPOSE_RETURN_IF_ERROR(ReadSign(row, "Polarity", &c.polarity));
  PHOTOPOSE_RETURN_IF_ERROR(row.Number("AverageZ", &c.average_z_m));
  PHOTOPOSE_RETURN_IF_ERROR(ReadEnum(row, "ApplyECC", BooleanSpellings(), 6, &c.apply_ecc));
  PHOTOPOSE_RETURN_IF_ERROR(ReadNumberOr(row, "EarthRadius", c.earth_radius_m, &c.earth_radius_m));
  c.srs = std::string(row.Text("SRS"));
  c.extra_columns = ReadExtraColumns(table, csv_row, CameraColumns());

  std::string column;
  const Status valid = CheckCameraTableFields(c, &column);
  if (!valid.ok()) return table.Error(csv_row.line, column, valid.message());
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
    PHOTOPOSE_RETURN_IF_ERROR(row.NumberList("Matrix", &values));
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
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredNumber("Omega", &angles_deg[0]));
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredNumber("Phi", &angles_deg[1]));
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredNumber("Kappa", &angles_deg[2]));
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
    PHOTOPOSE_RETURN_IF_ERROR(row.RequiredNumber(names[i], &sigma));
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

Status ReadFrameRow(const CsvTable& table, const CsvRow& csv_row, const FramesTableOptions& options,
                    FrameRecord* frame) {
  const CsvRowReader row(table, csv_row);
  FrameRecord f;
  f.line = csv_row.line;
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredText("Raster", &f.raster));
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredText("CameraID", &f.camera_id));
  const FrameCamera* camera = nullptr;
  const Status found = FindCamera(options, f.camera_id, &camera);
  if (!found.ok()) return row.Error("CameraID", found.message());
  Eigen::Vector3d center;
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredNumber("PerspectiveX", &center[0]));
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredNumber("PerspectiveY", &center[1]));
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredNumber("PerspectiveZ", &center[2]));
  f.eo.set_center_in_ground(center);
  Eigen::Vector3d seed_angles = Eigen::Vector3d::Zero();
  PHOTOPOSE_RETURN_IF_ERROR(ReadFrameRotation(row, options, camera, &seed_angles));
  f.eo.set_angles_seed_rad(seed_angles);
  f.srs = std::string(row.Text("SRS"));
  PHOTOPOSE_RETURN_IF_ERROR(ReadFrameSigmas(row, options, camera, &f));
  PHOTOPOSE_RETURN_IF_ERROR(row.Number("Sigma0", &f.sigma0));
  if (f.sigma0 && *f.sigma0 < 0.0)
    return row.Error("Sigma0", Quoted(row.Text("Sigma0")) + " is negative");
  PHOTOPOSE_RETURN_IF_ERROR(ReadAccuracyTriple(row, kAccuracyColumns, &f.center_accuracy_m));
  PHOTOPOSE_RETURN_IF_ERROR(
      ReadAccuracyTriple(row, kAttitudeAccuracyColumns, &f.attitude_accuracy_deg));
  f.extra_columns = ReadExtraColumns(table, csv_row, FrameColumns());
  *frame = std::move(f);
  return Status::Ok();
}

// ------------------------------------------------------------------ ground points and marks

const std::vector<Spelling<PointRole>>& RoleSpellings() {
  static const auto* const kSpellings = new std::vector<Spelling<PointRole>>{
      {"control", PointRole::kControl}, {"check", PointRole::kCheck}, {"tie", PointRole::kTie}};
  return *kSpellings;
}

Status ReadPointRow(const CsvTable& table, const CsvRow& csv_row, GroundPoint* point) {
  const CsvRowReader row(table, csv_row);
  GroundPoint p;
  p.line = csv_row.line;
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredText("PointID", &p.point_id));
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredNumber("X", &p.position[0]));
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredNumber("Y", &p.position[1]));
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredNumber("Z", &p.position[2]));
  PHOTOPOSE_RETURN_IF_ERROR(ReadAccuracyTriple(row, kAccuracyColumns, &p.accuracy_m));
  PHOTOPOSE_RETURN_IF_ERROR(ReadEnum(row, "Role", RoleSpellings(), 3, &p.role));
  *point = std::move(p);
  return Status::Ok();
}

// Column/Row (pixels) or FilmX/FilmY (um): exactly one pair.
Status ReadMarkPosition(const CsvRowReader& row, ImageMark* mark) {
  const bool pixels = row.Has("Column") || row.Has("Row");
  const bool film = row.Has("FilmX") || row.Has("FilmY");
  if (pixels && film) return row.Error("FilmX", "give either Column/Row or FilmX/FilmY, not both");
  if (!pixels && !film)
    return row.Error("Column", "is empty; give Column and Row (pixels) or FilmX and FilmY (um)");
  const char* x_name = pixels ? "Column" : "FilmX";
  const char* y_name = pixels ? "Row" : "FilmY";
  Eigen::Vector2d xy;
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredNumber(x_name, &xy[0]));
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredNumber(y_name, &xy[1]));
  if (pixels) {
    mark->column_row = xy;
  } else {
    mark->film_um = xy;
  }
  return Status::Ok();
}

Status ReadMarkRow(const CsvTable& table, const CsvRow& csv_row, ImageMark* mark) {
  const CsvRowReader row(table, csv_row);
  ImageMark m;
  m.line = csv_row.line;
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredText("Raster", &m.raster));
  PHOTOPOSE_RETURN_IF_ERROR(row.RequiredText("PointID", &m.point_id));
  PHOTOPOSE_RETURN_IF_ERROR(ReadMarkPosition(row, &m));
  PHOTOPOSE_RETURN_IF_ERROR(ReadPositive(row, "Accuracy", &m.accuracy_px));
  m.camera_id = std::string(row.Text("CameraID"));
  *mark = std::move(m);
  return Status::Ok();
}

// Key of a mark for duplicate detection: (raster, point).
std::string MarkKey(const std::string& raster, const std::string& point_id) {
  return raster + '\n' + point_id;
}
std::string MarkDescription(const std::string& raster, const std::string& point_id) {
  return "mark of point " + Quoted(point_id) + " in image " + Quoted(raster);
}

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

Status ReadCameraTable(const std::string& path, std::vector<FrameCamera>* cameras) {
  CsvTable table;
  PHOTOPOSE_RETURN_IF_ERROR(CsvTable::Read(path, kTableCsvOptions, &table));
  PHOTOPOSE_RETURN_IF_ERROR(table.RequireColumns({"CameraID", "FocalLength"}));
  const Names& affine = AffineColumns();
  const bool has_affine_columns = std::all_of(
      affine.begin(), affine.end(), [&](std::string_view name) { return table.HasColumn(name); });
  if (!has_affine_columns) PHOTOPOSE_RETURN_IF_ERROR(table.RequireColumns({"PixelSize"}));

  std::vector<FrameCamera> result;
  std::map<std::string, int> first_lines;
  for (const CsvRow& row : table.rows()) {
    FrameCamera camera;
    PHOTOPOSE_RETURN_IF_ERROR(ReadCameraRow(table, row, &camera));
    PHOTOPOSE_RETURN_IF_ERROR(CheckUnique(table, row.line, "CameraID", camera.camera_id,
                                          "camera " + Quoted(camera.camera_id), &first_lines));
    result.push_back(std::move(camera));
  }
  *cameras = std::move(result);
  return Status::Ok();
}

Status WriteCameraTable(const std::string& path, const std::vector<FrameCamera>& cameras) {
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
  return WriteFileAtomically(path, contents);
}

// ------------------------------------------------------------------ frames table

Status ReadFramesTable(const std::string& path, const FramesTableOptions& options,
                       std::vector<FrameRecord>* frames) {
  CsvTable table;
  PHOTOPOSE_RETURN_IF_ERROR(CsvTable::Read(path, kTableCsvOptions, &table));
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

  std::vector<FrameRecord> result;
  std::map<std::string, int> first_lines;
  for (const CsvRow& row : table.rows()) {
    FrameRecord frame;
    PHOTOPOSE_RETURN_IF_ERROR(ReadFrameRow(table, row, options, &frame));
    PHOTOPOSE_RETURN_IF_ERROR(CheckUnique(table, row.line, "Raster", frame.raster,
                                          "raster " + Quoted(frame.raster), &first_lines));
    result.push_back(std::move(frame));
  }
  *frames = std::move(result);
  return Status::Ok();
}

Status WriteFramesTable(const std::string& path, const FramesTableOptions& options,
                        const std::vector<FrameRecord>& frames) {
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
  return WriteFileAtomically(path, contents);
}

// ------------------------------------------------------------------ ground points

Status ReadGroundPoints(const std::string& path, std::vector<GroundPoint>* points) {
  CsvTable table;
  PHOTOPOSE_RETURN_IF_ERROR(CsvTable::Read(path, kTableCsvOptions, &table));
  PHOTOPOSE_RETURN_IF_ERROR(table.RequireColumns({"PointID", "X", "Y", "Z"}));
  if (table.HasColumn("AccuracyX") || table.HasColumn("AccuracyY") || table.HasColumn("AccuracyZ"))
    PHOTOPOSE_RETURN_IF_ERROR(table.RequireColumns({"AccuracyX", "AccuracyY", "AccuracyZ"}));

  std::vector<GroundPoint> result;
  std::map<std::string, int> first_lines;
  for (const CsvRow& row : table.rows()) {
    GroundPoint point;
    PHOTOPOSE_RETURN_IF_ERROR(ReadPointRow(table, row, &point));
    PHOTOPOSE_RETURN_IF_ERROR(CheckUnique(table, row.line, "PointID", point.point_id,
                                          "point " + Quoted(point.point_id), &first_lines));
    result.push_back(std::move(point));
  }
  *points = std::move(result);
  return Status::Ok();
}

Status WriteGroundPoints(const std::string& path, const std::vector<GroundPoint>& points) {
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
  return WriteFileAtomically(path, contents);
}

// ------------------------------------------------------------------ image marks

Status ReadImageMarks(const std::string& path, std::vector<ImageMark>* marks) {
  CsvTable table;
  PHOTOPOSE_RETURN_IF_ERROR(CsvTable::Read(path, kTableCsvOptions, &table));
  PHOTOPOSE_RETURN_IF_ERROR(table.RequireColumns({"Raster", "PointID"}));
  PHOTOPOSE_RETURN_IF_ERROR(RequirePairedColumns(table, "Column", "Row"));
  PHOTOPOSE_RETURN_IF_ERROR(RequirePairedColumns(table, "FilmX", "FilmY"));
  if (!table.HasColumn("Column") && !table.HasColumn("FilmX")) {
    return table.Error(table.header_line(), "Column",
                       "required column is missing (give Column and Row, or FilmX and FilmY)");
  }

  std::vector<ImageMark> result;
  std::map<std::string, int> first_lines;
  for (const CsvRow& row : table.rows()) {
    ImageMark mark;
    PHOTOPOSE_RETURN_IF_ERROR(ReadMarkRow(table, row, &mark));
    PHOTOPOSE_RETURN_IF_ERROR(
        CheckUnique(table, row.line, "PointID", MarkKey(mark.raster, mark.point_id),
                    MarkDescription(mark.raster, mark.point_id), &first_lines));
    result.push_back(std::move(mark));
  }
  *marks = std::move(result);
  return Status::Ok();
}

Status WriteImageMarks(const std::string& path, const std::vector<ImageMark>& marks) {
  std::string contents = CsvLine(HeaderFields(MarkColumns()));
  std::map<std::string, int>
      first_lines;  // the reader rejects a second mark of a point in an image
  for (const ImageMark& m : marks) {
    RowFields row(MarkDescription(m.raster, m.point_id));
    const auto [first, inserted] = first_lines.emplace(MarkKey(m.raster, m.point_id), m.line);
    if (!inserted) {
      row.Fail("PointID", "the point is marked twice in the image (source lines " +
                              std::to_string(first->second) + " and " + std::to_string(m.line) +
                              ")");
    }
    if (m.raster.empty()) row.Fail("Raster", "is empty");
    if (m.point_id.empty()) row.Fail("PointID", "is empty");
    if (m.column_row.has_value() == m.film_um.has_value())
      row.Fail("Column", "exactly one of Column/Row and FilmX/FilmY must be set");
    if (m.accuracy_px && !(*m.accuracy_px > 0.0)) row.Fail("Accuracy", "must be positive");
    row.Text(m.raster);
    row.Text(m.point_id);
    row.OptionalNumber("Column",
                       m.column_row ? std::optional<double>(m.column_row->x()) : std::nullopt);
    row.OptionalNumber("Row",
                       m.column_row ? std::optional<double>(m.column_row->y()) : std::nullopt);
    row.OptionalNumber("FilmX", m.film_um ? std::optional<double>(m.film_um->x()) : std::nullopt);
    row.OptionalNumber("FilmY", m.film_um ? std::optional<double>(m.film_um->y()) : std::nullopt);
    row.OptionalNumber("Accuracy", m.accuracy_px);
    row.Text(m.camera_id);
    PHOTOPOSE_RETURN_IF_ERROR(row.status(path));
    contents += CsvLine(*row.fields());
  }
  return WriteFileAtomically(path, contents);
}

// ------------------------------------------------------------------ gcp_list.txt

Status ReadGcpList(const std::string& path, GcpList* gcp_list) {
  std::string text;
  PHOTOPOSE_RETURN_IF_ERROR(ReadTextFile(path, &text));
  const auto error = [&path](int line, std::string_view column, const std::string& what) {
    return Status::Error(Where(path, line) + (column.empty() ? "" : std::string(column) + ": ") +
                         what);
  };

  GcpList result;
  // A point measured twice in one image is kept as two marks: ODM accepts it, and the real
  // dataset of tests/core/tables_test.cc has such a pair. The marks table rejects it.
  std::map<std::string, size_t> point_index;  // name -> index in result.points
  size_t start = 0;
  for (int line = 1; start < text.size() || line == 1; ++line) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
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
    double numbers[5];
    for (int i = 0; i < 5; ++i) {
      std::string why;
      if (!ParseFiniteNumber(words[i], &numbers[i], &why)) return error(line, kNumberNames[i], why);
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

// ------------------------------------------------------------------ atomic writes

Status WriteFileAtomically(const std::string& path, const std::string& contents) {
  // The temporary file sits beside the target so that rename() stays within one file system.
  std::string temp_name = path + ".tmp.XXXXXX";
  const int fd = mkstemp(temp_name.data());
  if (fd < 0)
    return Status::Error(path + ": cannot create a temporary file: " + std::strerror(errno));
  const auto fail = [&](const char* what, int error_number, bool is_open) {
    if (is_open) close(fd);
    unlink(temp_name.c_str());
    return Status::Error(path + ": " + what + ": " + std::strerror(error_number));
  };

  // mkstemp creates the file rw-------; keep the mode of the file replaced, else rw-r--r--.
  struct stat target;
  const mode_t mode = stat(path.c_str(), &target) == 0 ? (target.st_mode & 07777) : 0644;
  if (fchmod(fd, mode) != 0) return fail("cannot set permissions", errno, true);

  const char* data = contents.data();
  size_t left = contents.size();
  while (left > 0) {
    const ssize_t written = write(fd, data, left);
    if (written < 0) {
      if (errno == EINTR) continue;
      return fail("cannot write", errno, true);
    }
    data += written;
    left -= static_cast<size_t>(written);
  }
  if (fsync(fd) != 0) return fail("cannot write", errno, true);
  if (close(fd) != 0) return fail("cannot write", errno, false);
  if (rename(temp_name.c_str(), path.c_str()) != 0) return fail("cannot replace", errno, false);
  return Status::Ok();
}

}  // namespace photopose
