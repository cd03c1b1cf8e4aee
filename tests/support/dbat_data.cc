#include "tests/support/dbat_data.h"

#include <cmath>
#include <filesystem>
#include <map>
#include <string_view>

#include "core/camera.h"
#include "core/io/csv.h"
#include "core/rotation.h"
#include "core/io/text_scanner.h"
#include "tests/test_data.h"

namespace photopose::testing {
namespace {

// The sensor width DBAT writes after a calibration is ps W (1 + as); printed with 18 digits, it
// agrees with that to far better than this. Anything else is a non-square pixel, not converted.
constexpr double kSensorWidthTolerance = 1e-6;

std::string_view Trim(std::string_view text) {
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.front()))) text.remove_prefix(1);
  while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.remove_suffix(1);
  return text;
}

// The text of the first <tag>...</tag> in `xml`, or nullopt.
std::optional<std::string> Tag(std::string_view xml, const std::string& tag) {
  const std::string open = "<" + tag + ">", close = "</" + tag + ">";
  const size_t begin = xml.find(open);
  if (begin == std::string_view::npos) return std::nullopt;
  const size_t end = xml.find(close, begin);
  if (end == std::string_view::npos) return std::nullopt;
  return std::string(Trim(xml.substr(begin + open.size(), end - begin - open.size())));
}

// Comma-separated numbers of a tag; "auto" reads as 0.
Status Numbers(const std::string& path, std::string_view xml, const std::string& tag,
               size_t min_count, std::vector<double>* values) {
  values->clear();
  const std::optional<std::string> text = Tag(xml, tag);
  if (!text) {
    if (min_count == 0) return Status::Ok();
    return TextError(path, 0, tag, "is missing");
  }
  std::string_view rest = *text;
  while (true) {
    const size_t comma = rest.find(',');
    const std::string_view item = Trim(rest.substr(0, comma));
    if (item == "auto") {
      values->push_back(0.0);
    } else {
      double value = 0.0;
      std::string why;
      if (!ParseFiniteNumber(item, &value, &why)) return TextError(path, 0, tag, why);
      values->push_back(value);
    }
    if (comma == std::string_view::npos) break;
    rest.remove_prefix(comma + 1);
  }
  if (values->size() < min_count)
    return TextError(path, 0, tag, "has fewer than " + std::to_string(min_count) + " numbers");
  return Status::Ok();
}

// The first number of "label:   value unit" lines.
bool FirstNumber(std::string_view text, double* value) {
  const std::vector<std::string_view> words = SplitWords(text);
  std::string why;
  return !words.empty() && ParseFiniteNumber(words[0], value, &why);
}

}  // namespace

Status ReadDbatCameraXml(const std::string& path, DbatCamera* camera) {
  std::string xml;
  PHOTOPOSE_RETURN_IF_ERROR(ReadTextFile(path, &xml));
  // The <camera> element without its calibration information (which repeats tag names).
  const size_t begin = xml.find("<camera>");
  const size_t end = xml.find("</camera>");
  if (begin == std::string::npos || end == std::string::npos)
    return TextError(path, 0, "camera", "no <camera> element");
  std::string element = xml.substr(begin, end - begin);
  const size_t info = element.find("<calibration_info>");
  if (info != std::string::npos) element.erase(info);
  DbatCamera c;
  c.id = Tag(element, "id").value_or("1");
  c.name = Tag(element, "name").value_or("");
  std::vector<double> v;
  PHOTOPOSE_RETURN_IF_ERROR(Numbers(path, element, "model", 1, &v));
  c.model = static_cast<int>(v[0]);
  PHOTOPOSE_RETURN_IF_ERROR(Numbers(path, element, "sensor", 2, &v));
  c.sensor_width_mm = v[0];
  c.sensor_height_mm = v[1];
  PHOTOPOSE_RETURN_IF_ERROR(Numbers(path, element, "image", 2, &v));
  c.image_width_px = static_cast<int>(v[0]);
  c.image_height_px = static_cast<int>(v[1]);
  PHOTOPOSE_RETURN_IF_ERROR(Numbers(path, element, "aspect", 0, &v));
  if (!v.empty()) c.aspect = v[0];
  PHOTOPOSE_RETURN_IF_ERROR(Numbers(path, element, "focal", 1, &v));
  c.focal_mm = v[0];
  PHOTOPOSE_RETURN_IF_ERROR(Numbers(path, element, "cc", 0, &v));
  if (!v.empty()) c.cc_mm = v[0];
  PHOTOPOSE_RETURN_IF_ERROR(Numbers(path, element, "pp", 0, &v));
  if (v.size() >= 2) c.pp_mm = {v[0], v[1]};
  PHOTOPOSE_RETURN_IF_ERROR(Numbers(path, element, "skew", 0, &v));
  if (!v.empty()) c.skew = v[0];
  PHOTOPOSE_RETURN_IF_ERROR(Numbers(path, element, "K", 0, &v));
  for (size_t k = 0; k < v.size() && k < 3; ++k) c.K[k] = v[k];
  PHOTOPOSE_RETURN_IF_ERROR(Numbers(path, element, "P", 0, &v));
  for (size_t k = 0; k < v.size() && k < 2; ++k) c.P[k] = v[k];
  if (!(c.sensor_height_mm > 0.0) || c.image_width_px <= 0 || c.image_height_px <= 0)
    return TextError(path, 0, "sensor", "the sensor height and the image size must be positive");
  *camera = c;
  return Status::Ok();
}

DbatCamera DbatDefaultCamera(const DbatCamera& camera) {
  DbatCamera c = camera;
  c.cc_mm = camera.focal_mm;
  c.pp_mm = 0.5 * c.pixel_mm() * Eigen::Vector2d(c.image_width_px, c.image_height_px);
  c.aspect = 1.0;
  c.skew = 0.0;
  c.K.setZero();
  c.P.setZero();
  return c;
}

Status BlockCameraFromDbat(const DbatCamera& dbat, BlockCamera* camera) {
  if (dbat.model != 3)
    return Status::Error("DBAT camera model " + std::to_string(dbat.model) + " is not converted (3 is)");
  if (dbat.skew != 0.0) {
    return Status::Error(
        "DBAT's skew acts after the lens distortion: it has no exact kFrame equivalent");
  }
  const double ps = dbat.pixel_mm();
  const double as = dbat.as();
  if (dbat.sensor_width_mm != 0.0) {
    const double square = ps * dbat.image_width_px;
    if (std::abs(dbat.sensor_width_mm - square) > kSensorWidthTolerance * square &&
        std::abs(dbat.sensor_width_mm - square * (1.0 + as)) > kSensorWidthTolerance * square)
      return Status::Error("the DBAT sensor width is neither ps W nor ps W (1 + as): non-square pixels");
  }
  BlockCamera c;
  c.camera_id = dbat.id;
  c.model = CameraModelType::kFrame;
  FrameCamera& table = c.table;
  table.camera_id = dbat.id;
  table.pixel_size_um = 1000.0 * ps;
  table.n_columns = dbat.image_width_px;
  table.n_rows = dbat.image_height_px;
  c.params.assign(kFrameNumParams, 0.0);
  std::vector<double>& p = c.params;
  p[kFrameFocal] = 1000.0 * dbat.cc_mm;
  p[kFramePrincipalX] = 1000.0 * (1.0 + as) * (dbat.pp_mm.x() - 0.5 * ps * dbat.image_width_px);
  p[kFramePrincipalY] = 1000.0 * (0.5 * ps * dbat.image_height_px - dbat.pp_mm.y());
  for (int k = 0; k < 3; ++k) p[kFrameK1 + k] = -dbat.K[k];
  p[kFrameP1] = -dbat.P[0];
  p[kFrameP2] = -dbat.P[1];
  p[kFrameAffinity] = as;
  table.focal_length_um = p[kFrameFocal];
  table.principal_x_um = p[kFramePrincipalX];
  table.principal_y_um = p[kFramePrincipalY];
  table.radial_k = {0.0, p[kFrameK1], p[kFrameK2], p[kFrameK3]};
  table.tangential_p = {p[kFrameP1], p[kFrameP2]};
  *camera = std::move(c);
  return Status::Ok();
}

Status DbatFromBlockCamera(const BlockCamera& camera, const DbatCamera& like, DbatCamera* dbat) {
  if (camera.model != CameraModelType::kFrame || camera.params.size() != kFrameNumParams)
    return Status::Error("only a kFrame camera converts to DBAT's model 3");
  const std::vector<double>& p = camera.params;
  if (p[kFrameK0] != 0.0 || p[kFrameSkew] != 0.0)
    return Status::Error("K0 and the skew have no DBAT model-3 equivalent");
  DbatCamera d = like;
  d.model = 3;
  const double ps = d.pixel_mm();
  const double as = p[kFrameAffinity];
  d.aspect = 1.0 - as;
  d.cc_mm = p[kFrameFocal] / 1000.0;
  d.pp_mm = {p[kFramePrincipalX] / (1000.0 * (1.0 + as)) + 0.5 * ps * d.image_width_px,
             0.5 * ps * d.image_height_px - p[kFramePrincipalY] / 1000.0};
  for (int k = 0; k < 3; ++k) d.K[k] = -p[kFrameK1 + k];
  d.P = {-p[kFrameP1], -p[kFrameP2]};
  d.skew = 0.0;
  *dbat = d;
  return Status::Ok();
}

Status ReadDbatCameraStations(const std::string& path, std::vector<DbatStation>* stations) {
  std::vector<DbatStation> result;
  PHOTOPOSE_RETURN_IF_ERROR(ForEachRecordLineOfFile(path, /*comma_separates=*/true, [&](TokenScanner* s) {
    DbatStation station;
    long long number = 0, id = 0;
    PHOTOPOSE_RETURN_IF_ERROR(s->Integer("EO number", &number));
    PHOTOPOSE_RETURN_IF_ERROR(s->Integer("EO id", &id));
    station.id = static_cast<int>(id);
    const char* const kNames[] = {"x", "y", "z", "omega", "phi", "kappa"};
    for (int k = 0; k < 3; ++k) PHOTOPOSE_RETURN_IF_ERROR(s->Number(kNames[k], &station.center_m[k]));
    for (int k = 0; k < 3; ++k)
      PHOTOPOSE_RETURN_IF_ERROR(s->Number(kNames[3 + k], &station.angles_rad[k]));
    double sigma;
    for (const char* name : {"sx", "sy", "sz", "so", "sp", "sk"})
      PHOTOPOSE_RETURN_IF_ERROR(s->Number(name, &sigma));
    station.label = std::string(s->Rest());
    result.push_back(station);
    return Status::Ok();
  }));
  *stations = std::move(result);
  return Status::Ok();
}

ExteriorOrientation EoFromDbat(const Eigen::Vector3d& center_m, const Eigen::Vector3d& angles_rad) {
  ExteriorOrientation eo;
  eo.set_center_in_ground(center_m);
  eo.set_angles_seed_rad(AnglesFromRotation(
      RotationConvention::kSeed, RotationFromAngles(RotationConvention::kOpk, angles_rad)));
  return eo;
}

Status ReadDbatReport(const std::string& path, DbatReport* report) {
  std::string text;
  PHOTOPOSE_RETURN_IF_ERROR(ReadTextFile(path, &text));
  DbatReport r;
  const std::map<std::string, std::string> kCameraItems = {
      {"Camera Constant", "cc"},
      {"px - principal point x", "px"},
      {"py - principal point y", "py"},
      {"K1 - radial distortion 1", "K1"},
      {"K2 - radial distortion 2", "K2"},
      {"K3 - radial distortion 3", "K3"},
      {"P1 - decentering distortion 1", "P1"},
      {"P2 - decentering distortion 2", "P2"},
      {"as - off-unit aspect parameter", "as"}};
  const std::map<std::string, int> kPhotoItems = {{"Omega", 0}, {"Phi", 1}, {"Kappa", 2},
                                                  {"Xc", 3},    {"Yc", 4},  {"Zc", 5}};
  std::string item;  // the last "Name:" line without a value
  TextLines lines(text);
  std::string_view raw;
  int number = 0;
  const auto after = [](std::string_view line, std::string_view prefix) {
    return line.substr(prefix.size());
  };
  while (lines.Next(&raw, &number)) {
    const std::string_view line = Trim(raw);
    double value = 0.0;
    if (line.rfind("Sigma0 (pixels):", 0) == 0) {
      FirstNumber(after(line, "Sigma0 (pixels):"), &r.sigma0_px);
    } else if (line.rfind("Sigma0:", 0) == 0) {
      FirstNumber(after(line, "Sigma0:"), &r.sigma0);
    } else if (line.rfind("Redundancy", 0) == 0 && FirstNumber(after(line, "Redundancy"), &value)) {
      r.redundancy = static_cast<int>(value);
    } else if (line.rfind("Number of observations:", 0) == 0 &&
               FirstNumber(after(line, "Number of observations:"), &value)) {
      r.num_observations = static_cast<int>(value);
    } else if (line.rfind("Overall point RMS:", 0) == 0) {
      FirstNumber(after(line, "Overall point RMS:"), &r.overall_rms_px);
    } else if (line.rfind("Photo ", 0) == 0 && line.find(':') != std::string_view::npos &&
               line.back() != ':') {
      DbatReport::Photo photo;
      photo.name = std::string(Trim(line.substr(line.find(':') + 1)));
      r.photos.push_back(photo);
    } else if (line.rfind("Value:", 0) == 0 && FirstNumber(after(line, "Value:"), &value)) {
      const auto camera = kCameraItems.find(item);
      const auto photo = kPhotoItems.find(item);
      if (camera != kCameraItems.end() && r.photos.empty()) {
        r.camera.push_back({camera->second, Eigen::Vector2d(value, 0.0)});
      } else if (photo != kPhotoItems.end() && !r.photos.empty()) {
        const int k = photo->second;
        (k < 3 ? r.photos.back().angles_deg[k] : r.photos.back().center_m[k - 3]) = value;
      }
    } else if (line.rfind("Deviation:", 0) == 0 && FirstNumber(after(line, "Deviation:"), &value)) {
      const auto camera = kCameraItems.find(item);
      const auto photo = kPhotoItems.find(item);
      if (camera != kCameraItems.end() && r.photos.empty() && !r.camera.empty()) {
        r.camera.back().second.y() = value;
      } else if (photo != kPhotoItems.end() && !r.photos.empty()) {
        const int k = photo->second;
        (k < 3 ? r.photos.back().angle_sigma_deg[k] : r.photos.back().center_sigma_m[k - 3]) = value;
      }
    } else if (!line.empty() && line.back() == ':') {
      item = std::string(line.substr(0, line.size() - 1));
    }
  }
  if (!(r.sigma0 > 0.0) || r.redundancy <= 0 || r.photos.empty())
    return TextError(path, 0, "", "no Sigma0, Redundancy or photos found: not a DBAT report");
  *report = std::move(r);
  return Status::Ok();
}

DbatDataset DbatDataset::C4040z() {
  const std::string dir = SharedDataPath("dbat_c4040z") + "/";
  return {dir + "c4040z.xml", dir + "images_images.txt", dir + "measurements_markpts.txt",
          dir + "reference_camcal-fixed.txt"};
}

Status ReadDbatBlock(const DbatDataset& files, const DbatCamera& camera, Block* block) {
  Block result;
  BlockCamera block_camera;
  PHOTOPOSE_RETURN_IF_ERROR(BlockCameraFromDbat(camera, &block_camera));
  result.cameras.push_back(block_camera);
  const FrameCamera& table = result.cameras[0].table;

  std::map<long long, int> image_of_id;
  PHOTOPOSE_RETURN_IF_ERROR(ForEachRecordLineOfFile(files.images, /*comma_separates=*/true, [&](TokenScanner* s) {
    long long id = 0;
    PHOTOPOSE_RETURN_IF_ERROR(s->Integer("id", &id));
    const std::string path(s->Rest());
    if (path.empty()) return s->Error("path", "is missing");
    if (!image_of_id.emplace(id, static_cast<int>(result.images.size())).second)
      return s->Error("id", "image " + std::to_string(id) + " is listed twice");
    BlockImage image;
    image.name = std::filesystem::path(path).filename().string();
    image.camera = 0;
    image.line = s->line();
    result.images.push_back(image);
    return Status::Ok();
  }));

  std::map<std::string, int> point_of_id;
  PHOTOPOSE_RETURN_IF_ERROR(ForEachRecordLineOfFile(files.control, /*comma_separates=*/true, [&](TokenScanner* s) {
    std::string_view id, label;
    PHOTOPOSE_RETURN_IF_ERROR(s->Word("id", &id));
    PHOTOPOSE_RETURN_IF_ERROR(s->Word("label", &label));
    Eigen::Vector3d X;
    for (const int k : {0, 1, 2}) PHOTOPOSE_RETURN_IF_ERROR(s->Number("xyz", &X[k]));
    BlockPoint point;
    point.id = std::string(id);
    point.role = PointRole::kControl;
    point.surveyed_m = X;
    point.position_m = X;
    point.line = s->line();
    if (!s->AtEnd()) {
      double sigma = 0.0;
      PHOTOPOSE_RETURN_IF_ERROR(s->Number("sxyz", &sigma));
      if (!(sigma > 0.0)) return s->Error("sxyz", "must be positive");
      point.accuracy_m = Eigen::Vector3d::Constant(sigma);
    }
    if (!point_of_id.emplace(point.id, static_cast<int>(result.points.size())).second)
      return s->Error("id", "control point " + point.id + " is listed twice");
    result.points.push_back(point);
    return Status::Ok();
  }));

  const double pixel_um = table.pixel_size_um;
  PHOTOPOSE_RETURN_IF_ERROR(ForEachRecordLineOfFile(files.marks, /*comma_separates=*/true, [&](TokenScanner* s) {
    long long image_id = 0;
    std::string_view point_id;
    Eigen::Vector2d xy;
    double sxy = 0.0;
    PHOTOPOSE_RETURN_IF_ERROR(s->Integer("image id", &image_id));
    PHOTOPOSE_RETURN_IF_ERROR(s->Word("point id", &point_id));
    PHOTOPOSE_RETURN_IF_ERROR(s->Number("x", &xy.x()));
    PHOTOPOSE_RETURN_IF_ERROR(s->Number("y", &xy.y()));
    PHOTOPOSE_RETURN_IF_ERROR(s->Number("sxy", &sxy));
    if (!(sxy > 0.0)) return s->Error("sxy", "must be positive");
    const auto image = image_of_id.find(image_id);
    if (image == image_of_id.end())
      return s->Error("image id", "image " + std::to_string(image_id) + " is not in the image list");
    const std::string id(point_id);
    auto point = point_of_id.find(id);
    if (point == point_of_id.end()) {
      BlockPoint tie;
      tie.id = id;
      tie.role = PointRole::kTie;
      point = point_of_id.emplace(id, static_cast<int>(result.points.size())).first;
      result.points.push_back(tie);
    }
    BlockMark mark;
    mark.image = image->second;
    mark.point = point->second;
    mark.unit = MarkUnit::kPixel;
    mark.measured = xy;
    mark.accuracy = sxy;
    mark.observation_units_per_unit = pixel_um;
    mark.line = s->line();
    PHOTOPOSE_RETURN_IF_ERROR(FilmFromPixel(table, xy, PixelOrigin::kCorner, &mark.observation));
    result.marks.push_back(mark);
    return Status::Ok();
  }));
  result.pixel_origin = PixelOrigin::kCorner;
  result.marks_source = files.marks;
  result.BuildIndex();
  *block = std::move(result);
  return Status::Ok();
}

}  // namespace photopose::testing
