// The text layer of COLMAP models (core/io/colmap.h): cameras.txt, images.txt and points3D.txt
// to and from the records of core/io/internal/colmap_records.h. Only the syntax is checked here
// (numbers, whole numbers of their type, the parameter count of the model); the values and the
// references between records are checked where the block is built (colmap.cc).
#include <algorithm>
#include <limits>
#include <string>

#include "core/io/csv.h"
#include "core/io/internal/colmap_records.h"
#include "core/io/output_files.h"
#include "core/io/text_scanner.h"

namespace photopose::colmap_io {
namespace {

constexpr long long kMaxId = std::numeric_limits<long long>::max();
constexpr long long kMaxImageId = 0xffffffffLL;  // COLMAP's image_t is 32-bit

Status ParseCameras(std::string_view text, const std::string& path, Records* records) {
  return ForEachRecordLine(text, path, /*comma_separates=*/false, [&](TokenScanner* scanner) {
    CameraRecord camera;
    camera.place = scanner->line();
    std::string_view model_name;
    PHOTOPOSE_RETURN_IF_ERROR(scanner->IntegerIn("CAMERA_ID", 0, kMaxId, &camera.id));
    PHOTOPOSE_RETURN_IF_ERROR(scanner->Word("MODEL", &model_name));
    if (!ModelOfName(model_name, &camera.model)) {
      return scanner->Error("MODEL", "camera model '" + TokenForMessage(model_name) +
                                         "' is not supported (supported: " + SupportedModels() +
                                         ")");
    }
    PHOTOPOSE_RETURN_IF_ERROR(scanner->Integer("WIDTH", &camera.width));
    PHOTOPOSE_RETURN_IF_ERROR(scanner->Integer("HEIGHT", &camera.height));
    const std::vector<std::string> names = CameraModelParamNames(camera.model);
    camera.params.resize(names.size());
    for (size_t k = 0; k < names.size(); ++k)
      PHOTOPOSE_RETURN_IF_ERROR(scanner->Number("PARAMS " + names[k], &camera.params[k]));
    if (!scanner->AtEnd()) {
      return scanner->Error("PARAMS", "more than the " + std::to_string(names.size()) +
                                          " parameters of the " + std::string(model_name) +
                                          " model");
    }
    records->cameras.push_back(std::move(camera));
    return Status::Ok();
  });
}

Status ParsePoints(std::string_view text, const std::string& path, Records* records) {
  // A point per line at most; about a track entry per 12 characters (an estimate: the vector
  // grows past it when needed).
  records->points.reserve(static_cast<size_t>(std::count(text.begin(), text.end(), '\n')) + 1);
  records->tracks.reserve(text.size() / 12);
  return ForEachRecordLine(text, path, /*comma_separates=*/false, [&](TokenScanner* scanner) {
    PointRecord point;
    point.place = point.track_place = scanner->line();
    PHOTOPOSE_RETURN_IF_ERROR(scanner->IntegerIn("POINT3D_ID", 0, kMaxId, &point.id));
    const char* const kAxis[] = {"X", "Y", "Z"};
    for (int k = 0; k < 3; ++k) PHOTOPOSE_RETURN_IF_ERROR(scanner->Number(kAxis[k], &point.xyz[k]));
    const char* const kColour[] = {"R", "G", "B"};
    for (int k = 0; k < 3; ++k) {
      long long value = 0;
      PHOTOPOSE_RETURN_IF_ERROR(scanner->IntegerIn(kColour[k], 0, 255, &value));
      point.rgb[k] = static_cast<unsigned char>(value);
    }
    PHOTOPOSE_RETURN_IF_ERROR(scanner->Number("ERROR", &point.error));
    point.track_begin = records->tracks.size();
    while (!scanner->AtEnd()) {
      long long image_id = 0, index = 0;
      PHOTOPOSE_RETURN_IF_ERROR(scanner->IntegerIn("TRACK IMAGE_ID", 0, kMaxImageId, &image_id));
      PHOTOPOSE_RETURN_IF_ERROR(scanner->IntegerIn("TRACK POINT2D_IDX", 0, kMaxImageId, &index));
      records->tracks.push_back({static_cast<uint32_t>(image_id), static_cast<uint32_t>(index)});
    }
    point.track_length = records->tracks.size() - point.track_begin;
    records->points.push_back(point);
    return Status::Ok();
  });
}

Status ParseImages(std::string_view text, const std::string& path, Records* records) {
  TextLines lines(text);
  std::string_view line;
  int line_number = 0;
  while (lines.Next(&line, &line_number)) {
    if (IsBlankOrComment(line)) continue;
    TokenScanner scanner(line, path, line_number);
    ImageRecord image;
    image.place = line_number;
    PHOTOPOSE_RETURN_IF_ERROR(scanner.IntegerIn("IMAGE_ID", 0, kMaxImageId, &image.id));
    const char* const kPose[] = {"QW", "QX", "QY", "QZ", "TX", "TY", "TZ"};
    for (int k = 0; k < 7; ++k) {
      double* value = k < 4 ? &image.q[k] : &image.t[k - 4];
      PHOTOPOSE_RETURN_IF_ERROR(scanner.Number(kPose[k], value));
    }
    PHOTOPOSE_RETURN_IF_ERROR(scanner.IntegerIn("CAMERA_ID", 0, kMaxId, &image.camera_id));
    image.name = std::string(scanner.Rest());

    // POINTS2D: the next physical line, even when empty (an image without keypoints).
    std::string_view points_line;
    int points_line_number = line_number;
    if (!lines.Next(&points_line, &points_line_number)) points_line = std::string_view();
    image.points2D_place = points_line_number;
    TokenScanner points(points_line, path, points_line_number);
    image.points2D_begin = records->points2D.size();
    while (!points.AtEnd()) {
      Point2DRecord entry;
      PHOTOPOSE_RETURN_IF_ERROR(points.Number("POINTS2D X", &entry.x));
      PHOTOPOSE_RETURN_IF_ERROR(points.Number("POINTS2D Y", &entry.y));
      PHOTOPOSE_RETURN_IF_ERROR(
          points.IntegerIn("POINTS2D POINT3D_ID", -1, kMaxId, &entry.point3D_id));
      records->points2D.push_back(entry);
    }
    image.num_points2D = records->points2D.size() - image.points2D_begin;
    records->images.push_back(std::move(image));
  }
  return Status::Ok();
}

void AppendSpaceNumber(double value, std::string* text) {
  text->push_back(' ');
  AppendNumber(value, text);
}

// cameras.txt.
Status FormatCamerasText(const Records& records, TextPieces* out) {
  std::string& cameras = out->text();
  cameras +=
      "# Camera list with one line of data per camera:\n"
      "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
      "# Number of cameras: " +
      std::to_string(records.cameras.size()) + "\n";
  for (const CameraRecord& camera : records.cameras) {
    AppendInteger(camera.id, &cameras);
    cameras += ' ';
    cameras += EnumName(camera.model);
    cameras += ' ';
    AppendInteger(camera.width, &cameras);
    cameras += ' ';
    AppendInteger(camera.height, &cameras);
    for (const double value : camera.params) AppendSpaceNumber(value, &cameras);
    cameras += '\n';
  }
  return Status::Ok();
}

// images.txt: two lines per image, the second its POINTS2D.
Status FormatImagesText(const Records& records, TextPieces* out) {
  std::string& images = out->text();
  size_t num_observations = 0;
  for (const Point2DRecord& entry : records.points2D)
    if (entry.point3D_id >= 0) ++num_observations;
  const size_t num_images = records.images.size();
  out->Reserve(200 * num_images + 40 * records.points2D.size());
  images +=
      "# Image list with two lines of data per image:\n"
      "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
      "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
      "# Number of images: " +
      std::to_string(num_images) + ", mean observations per image: " +
      FormatNumber(num_images > 0 ? static_cast<double>(num_observations) / num_images : 0.0) +
      "\n";
  for (const ImageRecord& image : records.images) {
    AppendInteger(image.id, &images);
    for (const double value : image.q) AppendSpaceNumber(value, &images);
    for (const double value : image.t) AppendSpaceNumber(value, &images);
    images += ' ';
    AppendInteger(image.camera_id, &images);
    images += ' ';
    images += image.name;
    images += '\n';
    for (size_t k = 0; k < image.num_points2D; ++k) {
      const Point2DRecord& entry = records.points2D[image.points2D_begin + k];
      if (k > 0) images += ' ';
      AppendNumber(entry.x, &images);
      AppendSpaceNumber(entry.y, &images);
      images += ' ';
      AppendInteger(entry.point3D_id, &images);
    }
    images += '\n';
    PHOTOPOSE_RETURN_IF_ERROR(out->Piece());
  }
  return Status::Ok();
}

// points3D.txt: a line per point with its track.
Status FormatPointsText(const Records& records, TextPieces* out) {
  std::string& points = out->text();
  const size_t num_points = records.points.size();
  out->Reserve(100 * num_points + 16 * records.tracks.size());
  points +=
      "# 3D point list with one line of data per point:\n"
      "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
      "# Number of points: " +
      std::to_string(num_points) + ", mean track length: " +
      FormatNumber(num_points > 0 ? static_cast<double>(records.tracks.size()) / num_points : 0.0) +
      "\n";
  for (const PointRecord& point : records.points) {
    AppendInteger(point.id, &points);
    for (const double value : point.xyz) AppendSpaceNumber(value, &points);
    for (const unsigned char value : point.rgb) {
      points += ' ';
      AppendInteger(value, &points);
    }
    AppendSpaceNumber(point.error, &points);
    for (size_t k = 0; k < point.track_length; ++k) {
      const TrackRecord& entry = records.tracks[point.track_begin + k];
      points += ' ';
      AppendInteger(entry.image_id, &points);
      points += ' ';
      AppendInteger(entry.point2D_idx, &points);
    }
    points += '\n';
    PHOTOPOSE_RETURN_IF_ERROR(out->Piece());
  }
  return Status::Ok();
}

}  // namespace

Status ParseTextFile(ModelFile file, std::string_view text, const ModelPaths& paths,
                     Records* records) {
  switch (file) {
    case ModelFile::kCameras:
      return ParseCameras(text, paths.cameras, records);
    case ModelFile::kImages:
      return ParseImages(text, paths.images, records);
    case ModelFile::kPoints3D:
      return ParsePoints(text, paths.points3D, records);
  }
  return Status::Error("unknown COLMAP file");
}

Status FormatTextFile(ModelFile file, const Records& records, TextPieces* out) {
  switch (file) {
    case ModelFile::kCameras:
      return FormatCamerasText(records, out);
    case ModelFile::kImages:
      return FormatImagesText(records, out);
    case ModelFile::kPoints3D:
      return FormatPointsText(records, out);
  }
  return Status::Error("unknown COLMAP file");
}

}  // namespace photopose::colmap_io
