// The ArcGIS frame-camera table: read, checked, written (core/io/tables.h).
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

// ------------------------------------------------------------------ camera table

// ApplyECC's spellings ("true" and "false" written). A bool has no EnumNames of its own (no
// namespace to find it in), so the reader is handed this table.
constexpr EnumNameEntry<bool> kBooleanNames[] = {{true, "true"}, {false, "false"}, {true, "1"},
                                                 {false, "0"},   {true, "yes"},    {false, "no"}};

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
      ReadEnum(row, "DistortionType", EnumNames(DistortionType{}), &camera->distortion_type));
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
  PHOTOPOSE_RETURN_IF_ERROR(ReadEnum(row, "FilmCoordinateSystem",
                                     EnumNames(FilmCoordinateSystem{}), &c.film_coordinate_system));
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
      ReadEnum(row, "OrientationType", EnumNames(OrientationType{}), &c.orientation_type));
  PHOTOPOSE_RETURN_IF_ERROR(ReadSign(row, "AngleDirection", &c.angle_direction));
  PHOTOPOSE_RETURN_IF_ERROR(ReadSign(row, "Polarity", &c.polarity));
  PHOTOPOSE_RETURN_IF_ERROR(ReadNumber(row, "AverageZ", &c.average_z_m));
  PHOTOPOSE_RETURN_IF_ERROR(
      ReadEnum(row, "ApplyECC", EnumNameTable<bool>(kBooleanNames), &c.apply_ecc));
  PHOTOPOSE_RETURN_IF_ERROR(ReadNumberOr(row, "EarthRadius", c.earth_radius_m, &c.earth_radius_m));
  c.srs = std::string(row.Text("SRS"));
  c.extra_columns = ReadExtraColumns(row, extra);

  std::string column;
  const Status valid = CheckCameraTableFields(c, &column);
  if (!valid.ok()) return row.Error(column, valid.message());
  *camera = std::move(c);
  return Status::Ok();
}

std::string CountText(int count) { return count > 0 ? std::to_string(count) : std::string(); }
std::string SignText(int sign) { return sign > 0 ? "1" : "-1"; }


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
    const std::string record = "camera " + QuotedForMessage(c.camera_id);
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
    row.Text(EnumName(c.film_coordinate_system));
    const Names& affine = AffineColumns();
    for (int i = 0; i < 6; ++i) {
      const double value = i < 3 ? c.affine_a[i] : c.affine_b[i - 3];
      row.OptionalNumber(affine[i], c.has_affine ? std::optional<double>(value) : std::nullopt);
    }
    row.Text(SignText(c.affine_direction));
    row.Text(EnumName(c.distortion_type));
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
    row.Text(EnumName(c.orientation_type));
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


}  // namespace photopose
