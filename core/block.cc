#include "core/block.h"

#include <Eigen/LU>
#include <cmath>
#include <map>
#include <string_view>
#include <unordered_map>

#include "core/io/csv.h"

namespace photopose {
namespace {

template <typename Items, typename Name>
int FindByName(const Items& items, const std::string& name, Name name_of) {
  for (size_t i = 0; i < items.size(); ++i)
    if (name_of(items[i]) == name) return static_cast<int>(i);
  return -1;
}

bool Finite(const std::optional<Eigen::Vector3d>& v) { return !v || v->allFinite(); }

}  // namespace

CameraModelData BlockCamera::data() const {
  if (model == CameraModelType::kFrame) return FrameModelData(table);
  return CameraModelData();
}

void Block::BuildIndex() {
  marks_of_image.assign(images.size(), {});
  marks_of_point.assign(points.size(), {});
  for (size_t m = 0; m < marks.size(); ++m) {
    const BlockMark& mark = marks[m];
    if (mark.image >= 0 && mark.image < static_cast<int>(images.size()))
      marks_of_image[mark.image].push_back(static_cast<int>(m));
    if (mark.point >= 0 && mark.point < static_cast<int>(points.size()))
      marks_of_point[mark.point].push_back(static_cast<int>(m));
  }
}

int Block::FindCamera(const std::string& camera_id) const {
  return FindByName(cameras, camera_id, [](const BlockCamera& c) { return c.camera_id; });
}

int Block::FindImage(const std::string& name) const {
  return FindByName(images, name, [](const BlockImage& i) { return i.name; });
}

int Block::FindPoint(const std::string& id) const {
  return FindByName(points, id, [](const BlockPoint& p) { return p.id; });
}

Status CheckBlock(const Block& block) {
  for (const BlockCamera& camera : block.cameras) {
    const int expected = CameraModelNumParams(camera.model);
    if (static_cast<int>(camera.params.size()) != expected) {
      return Status::Error("camera '" + camera.camera_id + "' has " +
                           std::to_string(camera.params.size()) + " parameters; the " +
                           EnumName(camera.model) + " model has " +
                           std::to_string(expected));
    }
    for (const double value : camera.params)
      if (!std::isfinite(value))
        return Status::Error("camera '" + camera.camera_id + "' has a non-finite parameter");
  }
  const int num_cameras = static_cast<int>(block.cameras.size());
  for (const BlockImage& image : block.images) {
    if (image.camera < 0 || image.camera >= num_cameras)
      return Status::Error("image '" + image.name + "' has no camera");
    if ((image.eo && !image.eo->parameters.allFinite()) || !Finite(image.measured_center_m) ||
        !Finite(image.center_accuracy_m) || !Finite(image.measured_angles_rad) ||
        !Finite(image.attitude_accuracy_rad))
      return Status::Error("image '" + image.name + "' has a non-finite value");
  }
  for (const BlockPoint& point : block.points) {
    if (!Finite(point.surveyed_m) || !Finite(point.accuracy_m) || !Finite(point.position_m))
      return Status::Error("point '" + point.id + "' has a non-finite coordinate");
    if (point.role != PointRole::kTie && !point.surveyed_m)
      return Status::Error("point '" + point.id + "' is a control or check point without coordinates");
  }
  const int num_images = static_cast<int>(block.images.size());
  const int num_points = static_cast<int>(block.points.size());
  for (size_t m = 0; m < block.marks.size(); ++m) {
    const BlockMark& mark = block.marks[m];
    if (mark.image < 0 || mark.image >= num_images || mark.point < 0 || mark.point >= num_points)
      return Status::Error("mark " + std::to_string(m + 1) + " names no image or point");
    if (!mark.measured.allFinite() || !mark.observation.allFinite() ||
        !(mark.observation_units_per_unit > 0.0) || (mark.accuracy && !(*mark.accuracy > 0.0)))
      return Status::Error("mark " + std::to_string(m + 1) + " has a non-finite or non-positive value");
  }
  return Status::Ok();
}

FrameCamera PixelToFilmCamera(const Block& block, int image) {
  const BlockImage& i = block.images[image];
  const FrameCamera& camera = block.cameras[i.camera].table;
  return i.fiducial_fit ? WithFiducialAffine(camera, *i.fiducial_fit) : camera;
}

namespace {

std::string Where(const std::string& file, int line, const std::string& column) {
  std::string where = file;
  if (line > 0) where += ":" + std::to_string(line);
  return where + ": " + (column.empty() ? "" : column + ": ");
}

std::string Quoted(const std::string& text) { return "'" + text + "'"; }

// The seed-angle standard deviations (rad) of angles whose file sigmas are given (degrees, in
// `convention` with AngleDirection applied): diag(J^-1 diag(sigma^2) J^-T), J the Jacobian of the
// boundary conversion; correlations are dropped.
std::optional<Eigen::Vector3d> SeedAttitudeSigmas(RotationConvention convention,
                                                  const AngleFlags& flags,
                                                  const Eigen::Vector3d& seed_angles_rad,
                                                  const Eigen::Vector3d& file_sigmas_deg) {
  const Eigen::Matrix3d J = ConventionFromSeedJacobian(convention, flags, seed_angles_rad);
  const Eigen::FullPivLU<Eigen::Matrix3d> lu(J);
  if (!lu.isInvertible()) return std::nullopt;
  const Eigen::Matrix3d J_inverse = lu.inverse();
  const Eigen::Vector3d variances = (file_sigmas_deg / kDegreesPerRadian).cwiseAbs2();
  return (J_inverse * variances.asDiagonal() * J_inverse.transpose()).diagonal().cwiseSqrt();
}

// The block camera of a camera-table row.
BlockCamera CameraOf(const FrameCamera& table) {
  BlockCamera camera;
  camera.camera_id = table.camera_id;
  camera.model = CameraModelType::kFrame;
  const std::array<double, kFrameNumParams> params = FrameModelParams(table);
  camera.params.assign(params.begin(), params.end());
  camera.table = table;
  return camera;
}

// Whether a pixel position lies within `fraction` of the image size outside the image; true when
// the camera does not give the size.
bool NearTheImage(const FrameCamera& camera, const Eigen::Vector2d& corner_column_row,
                  double fraction) {
  if (camera.n_columns <= 0 || camera.n_rows <= 0) return true;
  const double w = camera.n_columns, h = camera.n_rows;
  const double c = corner_column_row.x(), r = corner_column_row.y();
  return c >= -fraction * w && c <= (1.0 + fraction) * w && r >= -fraction * h &&
         r <= (1.0 + fraction) * h;
}

}  // namespace

Status AssembleBlock(const BlockTables& tables, Block* block) {
  Block result;
  result.pixel_origin = tables.pixel_origin;
  result.crs = tables.crs;
  result.marks_source = tables.marks_file;

  // Cameras.
  if (tables.cameras.empty())
    return Status::Error(Where(tables.cameras_file, 0, "") + "the camera table has no rows");
  for (const FrameCamera& table : tables.cameras) {
    const Status valid = table.IsValid();
    if (!valid.ok())
      return Status::Error(Where(tables.cameras_file, 0, "") + "camera " +
                           Quoted(table.camera_id) + ": " + valid.message());
    if (result.FindCamera(table.camera_id) >= 0)
      return Status::Error(Where(tables.cameras_file, 0, "CameraID") + "duplicate camera " +
                           Quoted(table.camera_id));
    result.cameras.push_back(CameraOf(table));
  }

  // Name -> index maps hold views of the tables' strings (which outlive them): a block has millions
  // of marks, each looked up by its raster and point.
  // Points of the table.
  std::unordered_map<std::string_view, int> point_index;
  point_index.reserve(tables.points.size());
  for (const GroundPoint& row : tables.points) {
    BlockPoint point;
    point.id = row.point_id;
    point.role = row.role;
    point.line = row.line;
    point.position_m = row.position;
    if (row.role != PointRole::kTie) {
      point.surveyed_m = row.position;
      point.accuracy_m = row.accuracy_m;
    }
    if (!point_index.emplace(row.point_id, static_cast<int>(result.points.size())).second)
      return Status::Error(Where(tables.points_file, row.line, "PointID") + "duplicate point " +
                           Quoted(row.point_id));
    result.points.push_back(std::move(point));
  }

  // Images: from the marks, in order of first appearance, then frames rows without marks.
  std::unordered_map<std::string_view, const FrameRecord*> frame_of;
  for (const FrameRecord& frame : tables.frames) frame_of.emplace(frame.raster, &frame);
  std::unordered_map<std::string_view, int> image_index;
  // The camera of an image named by a mark's or a frame's CameraID; -1 and an error otherwise.
  const auto find_camera = [&](const std::string& camera_id, const std::string& file, int line,
                               int* camera) -> Status {
    *camera = result.FindCamera(camera_id);
    if (*camera < 0)
      return Status::Error(Where(file, line, "CameraID") + "unknown camera " + Quoted(camera_id));
    return Status::Ok();
  };
  const auto add_image = [&](const std::string& raster, const std::string& mark_camera_id,
                             int mark_line) -> Status {
    BlockImage image;
    image.name = raster;
    const auto frame = frame_of.find(raster);
    if (!mark_camera_id.empty()) {
      PHOTOPOSE_RETURN_IF_ERROR(
          find_camera(mark_camera_id, tables.marks_file, mark_line, &image.camera));
    } else if (frame != frame_of.end()) {
      PHOTOPOSE_RETURN_IF_ERROR(find_camera(frame->second->camera_id, tables.frames_file,
                                            frame->second->line, &image.camera));
    } else if (result.cameras.size() == 1) {
      image.camera = 0;
    } else {
      return Status::Error(Where(tables.marks_file, mark_line, "CameraID") + "image " +
                           Quoted(raster) + " names no camera and the camera table has several");
    }
    if (frame != frame_of.end()) {
      const FrameRecord& f = *frame->second;
      if (f.camera_id != result.cameras[image.camera].camera_id) {
        return Status::Error(Where(tables.frames_file, f.line, "CameraID") + "image " +
                             Quoted(raster) + " is of camera " +
                             Quoted(result.cameras[image.camera].camera_id) +
                             " in the marks (line " + std::to_string(mark_line) + ")");
      }
      image.line = f.line;
      image.eo = f.eo;
      image.measured_center_m = f.eo.center_in_ground();
      image.center_accuracy_m = f.center_accuracy_m;
      image.measured_angles_rad = f.eo.angles_seed_rad();
      if (f.attitude_accuracy_deg) {
        image.attitude_accuracy_rad = SeedAttitudeSigmas(
            tables.frames_rotation, result.cameras[image.camera].table.angle_flags(),
            f.eo.angles_seed_rad(), *f.attitude_accuracy_deg);
        if (!image.attitude_accuracy_rad)
          return Status::Error(Where(tables.frames_file, f.line, "AccuracyOmega") +
                               "cannot be converted: the angles are at a gimbal lock of the "
                               "convention");
      }
    }
    image_index.emplace(raster, static_cast<int>(result.images.size()));
    result.images.push_back(std::move(image));
    return Status::Ok();
  };
  for (const ImageMark& mark : tables.marks) {
    const auto found = image_index.find(mark.raster);
    if (found == image_index.end()) {
      PHOTOPOSE_RETURN_IF_ERROR(add_image(mark.raster, mark.camera_id, mark.line));
      continue;
    }
    const BlockImage& image = result.images[found->second];
    if (!mark.camera_id.empty() && mark.camera_id != result.cameras[image.camera].camera_id) {
      return Status::Error(Where(tables.marks_file, mark.line, "CameraID") + "image " +
                           Quoted(mark.raster) + " has marks of two cameras (" +
                           Quoted(result.cameras[image.camera].camera_id) + " and " +
                           Quoted(mark.camera_id) + ")");
    }
  }
  for (const FrameRecord& frame : tables.frames) {
    if (image_index.count(frame.raster) == 0)
      PHOTOPOSE_RETURN_IF_ERROR(add_image(frame.raster, frame.camera_id, frame.line));
  }

  // Scanned film: each image's affine from its measured fiducials.
  std::map<std::string, std::vector<MeasuredFiducial>> fiducials_of;
  for (const MeasuredFiducial& f : tables.fiducials) fiducials_of[f.raster].push_back(f);
  FiducialFitOptions fit_options;
  fit_options.max_residual_um = tables.max_fiducial_residual_um;
  fit_options.pixel_origin = tables.pixel_origin;
  for (const auto& [raster, measured] : fiducials_of) {
    const auto found = image_index.find(raster);
    if (found == image_index.end()) {
      return Status::Error(Where(tables.fiducials_file, measured.front().line, "Raster") +
                           "image " + Quoted(raster) + " has no marks and no frames row");
    }
    BlockImage& image = result.images[found->second];
    FiducialFit fit;
    PHOTOPOSE_RETURN_IF_ERROR(FitFiducials(result.cameras[image.camera].table, measured,
                                           fit_options, tables.fiducials_file, &fit));
    image.fiducial_fit = std::move(fit);
  }

  // Marks.
  std::vector<FrameCamera> pixel_cameras;
  for (size_t i = 0; i < result.images.size(); ++i)
    pixel_cameras.push_back(PixelToFilmCamera(result, static_cast<int>(i)));
  const double origin_shift = tables.pixel_origin == PixelOrigin::kCenter ? 0.5 : 0.0;
  result.marks.reserve(tables.marks.size());
  for (const ImageMark& row : tables.marks) {
    BlockMark mark;
    mark.line = row.line;
    mark.image = image_index.at(row.raster);
    const auto point = point_index.find(row.point_id);
    if (point != point_index.end()) {
      mark.point = point->second;
    } else {
      // A point without a row: a tie point of unknown coordinates.
      BlockPoint tie;
      tie.id = row.point_id;
      tie.role = PointRole::kTie;
      mark.point = static_cast<int>(result.points.size());
      point_index.emplace(row.point_id, mark.point);
      result.points.push_back(std::move(tie));
    }
    mark.accuracy = row.accuracy_px;
    if (row.film_um) {
      mark.unit = MarkUnit::kFilm;
      mark.measured = *row.film_um;
      mark.observation = *row.film_um;
    } else if (row.column_row) {
      mark.unit = MarkUnit::kPixel;
      mark.measured = *row.column_row;
      const FrameCamera& camera = pixel_cameras[mark.image];
      const Status film = FilmFromPixel(camera, mark.measured, tables.pixel_origin, &mark.observation);
      if (!film.ok()) return Status::Error(Where(tables.marks_file, row.line, "Column") + film.message());
      if (!NearTheImage(camera, mark.measured + Eigen::Vector2d::Constant(origin_shift),
                        tables.max_outside_fraction)) {
        const Eigen::Vector2d corner = mark.measured + Eigen::Vector2d::Constant(origin_shift);
        const Eigen::Vector2d size(camera.n_columns, camera.n_rows);
        double outside = 0.0;
        for (int k = 0; k < 2; ++k)
          outside = std::max(outside, corner[k] < 0.0 ? -corner[k] : corner[k] - size[k]);
        return Status::Error(EscapeForMessage(
            Where(tables.marks_file, row.line, "Column") + "the mark of point '" + row.point_id +
            "' in image '" + row.raster + "' lies " + FormatNumber(std::round(outside)) +
            " pixels outside the " + std::to_string(camera.n_columns) + " x " +
            std::to_string(camera.n_rows) + " image of camera '" + camera.camera_id +
            "' (at most " + FormatNumber(tables.max_outside_fraction * 100.0) +
            "% of the image size is allowed)"));
      }
      const Status scale =
          FilmUmPerPixel(camera, mark.measured, tables.pixel_origin, &mark.observation_units_per_unit);
      if (!scale.ok()) return Status::Error(Where(tables.marks_file, row.line, "Column") + scale.message());
    } else {
      return Status::Error(Where(tables.marks_file, row.line, "Column") +
                           "the mark has neither Column/Row nor FilmX/FilmY");
    }
    result.marks.push_back(mark);
  }
  result.BuildIndex();
  PHOTOPOSE_RETURN_IF_ERROR(CheckBlock(result));
  *block = std::move(result);
  return Status::Ok();
}

Status ReadBlock(const BlockFiles& files, Block* block) {
  BlockTables tables;
  tables.cameras_file = files.cameras;
  tables.pixel_origin = files.pixel_origin;
  tables.frames_rotation = files.rotation;
  tables.max_fiducial_residual_um = files.max_fiducial_residual_um;
  PHOTOPOSE_RETURN_IF_ERROR(ReadCameraTable(files.cameras, &tables.cameras));
  if (!files.gcp_list.empty()) {
    GcpList gcp;
    PHOTOPOSE_RETURN_IF_ERROR(ReadGcpList(files.gcp_list, &gcp));
    tables.points = std::move(gcp.points);
    tables.marks = std::move(gcp.marks);
    tables.crs = gcp.crs;
    tables.points_file = tables.marks_file = files.gcp_list;
  } else {
    if (!files.points.empty()) PHOTOPOSE_RETURN_IF_ERROR(ReadGroundPoints(files.points, &tables.points));
    PHOTOPOSE_RETURN_IF_ERROR(ReadImageMarks(files.marks, &tables.marks));
    tables.points_file = files.points;
    tables.marks_file = files.marks;
  }
  if (!files.frames.empty()) {
    FramesTableOptions options;
    options.convention = files.rotation;
    options.cameras = &tables.cameras;
    PHOTOPOSE_RETURN_IF_ERROR(ReadFramesTable(files.frames, options, &tables.frames));
    tables.frames_file = files.frames;
  }
  if (!files.fiducials.empty()) {
    PHOTOPOSE_RETURN_IF_ERROR(ReadMeasuredFiducials(files.fiducials, &tables.fiducials));
    tables.fiducials_file = files.fiducials;
  }
  return AssembleBlock(tables, block);
}

}  // namespace photopose
