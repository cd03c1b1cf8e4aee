#include "core/io/block_tables.h"

#include <Eigen/LU>
#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>

#include "core/geodesy/crs.h"
#include "core/io/csv.h"
#include "core/io/fiducials_table.h"
#include "core/io/output_files.h"
#include "core/types.h"

namespace photopose {
namespace {

// The marks table's row of a block mark, into *row (reused from mark to mark: its strings keep
// their buffers, so that no string is allocated per mark).
Status TableMarkOf(const Block& block, const BlockMark& mark, ImageMark* row) {
  const BlockImage& image = block.images[mark.image];
  const BlockCamera& camera = block.cameras[image.camera];
  row->raster = image.name;
  row->point_id = block.points[mark.point].id;
  row->camera_id = camera.camera_id;
  row->accuracy_px = mark.accuracy;
  row->column_row.reset();
  row->film_um.reset();
  if (mark.unit == MarkUnit::kPixel) {
    row->column_row = mark.measured;
  } else {
    row->film_um = mark.measured;
    const double pixel_um = camera.table.MeanPixelSizeUm();
    if (mark.accuracy) {
      if (!(pixel_um > 0.0)) {
        return Status::Error("image '" + image.name + "': point '" + row->point_id +
                             "': a film mark's accuracy needs the camera's pixel size");
      }
      row->accuracy_px = *mark.accuracy / pixel_um;
    }
  }
  return Status::Ok();
}

// The marks table of a block, formatted straight from its marks (no vector of ImageMark: a block
// has millions); with `text` null, only checks that every mark converts.
Status FormatBlockMarks(const Block& block, const std::string& path, std::string* text) {
  std::optional<ImageMarksWriter> writer;
  if (text != nullptr) writer.emplace(path, block.marks.size(), text);
  ImageMark row;
  for (const BlockMark& mark : block.marks) {
    PHOTOPOSE_RETURN_IF_ERROR(TableMarkOf(block, mark, &row));
    if (writer) PHOTOPOSE_RETURN_IF_ERROR(writer->Add(row));
  }
  return writer ? writer->Finish() : Status::Ok();
}

// BlockToTableRecords; with `marks_path` given, the marks are formatted into *marks_text (checked
// only when it is null) instead of records->marks.
Status ToTableRecords(const Block& block, const BlockTableWriteOptions& options,
                      const std::string* marks_path, std::string* marks_text,
                      BlockTableRecords* records) {
  PHOTOPOSE_RETURN_IF_ERROR(CheckBlock(block));
  BlockTableRecords result;
  for (const BlockCamera& camera : block.cameras) {
    if (camera.model != CameraModelType::kFrame) {
      return Status::Error("camera '" + camera.camera_id + "' is a " +
                           EnumName(camera.model) +
                           " camera: the camera table holds frame cameras only (write the block "
                           "as a COLMAP model instead)");
    }
    FrameCamera table = camera.table;
    PHOTOPOSE_RETURN_IF_ERROR(SetFrameModelParams(camera.params.data(), &table));
    result.cameras.push_back(std::move(table));
  }

  for (const BlockPoint& point : block.points) {
    GroundPoint row;
    row.point_id = point.id;
    row.role = point.role;
    if (point.role == PointRole::kTie) {
      if (!options.write_tie_points || !point.position_m) continue;
      row.position = *point.position_m;
    } else {
      row.position = *point.surveyed_m;
      row.accuracy_m = point.accuracy_m;
    }
    result.points.push_back(std::move(row));
  }

  if (marks_path == nullptr) {
    result.marks.resize(block.marks.size());
    for (size_t m = 0; m < block.marks.size(); ++m)
      PHOTOPOSE_RETURN_IF_ERROR(TableMarkOf(block, block.marks[m], &result.marks[m]));
  } else {
    PHOTOPOSE_RETURN_IF_ERROR(FormatBlockMarks(block, *marks_path, marks_text));
  }

  for (const BlockImage& image : block.images) {
    if (!image.measured_center_m && !image.eo) continue;
    if (!image.measured_angles_rad && !image.eo) continue;
    FrameRecord row;
    row.raster = image.name;
    row.camera_id = block.cameras[image.camera].camera_id;
    row.eo.set_center_in_ground(image.measured_center_m ? *image.measured_center_m
                                                        : image.eo->center_in_ground());
    row.eo.set_angles_seed_rad(image.measured_angles_rad ? *image.measured_angles_rad
                                                         : image.eo->angles_seed_rad());
    row.center_accuracy_m = image.center_accuracy_m;
    if (image.attitude_accuracy_rad) {
      if (options.rotation != RotationConvention::kSeed) {
        return Status::Error("image '" + image.name +
                             "': attitude accuracies are per seed angle; write the frames table "
                             "with the rxryrz rotation convention");
      }
      row.attitude_accuracy_deg = *image.attitude_accuracy_rad * (180.0 / M_PI);
    }
    result.frames.push_back(std::move(row));
  }
  *records = std::move(result);
  return Status::Ok();
}

}  // namespace

Status BlockToTableRecords(const Block& block, const BlockTableWriteOptions& options,
                           BlockTableRecords* records) {
  return ToTableRecords(block, options, /*marks_path=*/nullptr, /*marks_text=*/nullptr, records);
}

Status WriteBlockTables(const Block& block, const BlockTableFiles& files,
                        const BlockTableWriteOptions& options) {
  // The marks go from the block to their text directly, before any table is written.
  BlockTableRecords records;
  std::string marks_text;
  PHOTOPOSE_RETURN_IF_ERROR(ToTableRecords(block, options, &files.marks,
                                           files.marks.empty() ? nullptr : &marks_text, &records));
  if (!files.cameras.empty())
    PHOTOPOSE_RETURN_IF_ERROR(WriteCameraTable(files.cameras, records.cameras));
  if (!files.points.empty())
    PHOTOPOSE_RETURN_IF_ERROR(WriteGroundPoints(files.points, records.points));
  if (!files.marks.empty()) PHOTOPOSE_RETURN_IF_ERROR(WriteFileAtomically(files.marks, marks_text));
  if (!files.frames.empty()) {
    FramesTableOptions frames_options;
    frames_options.convention = options.rotation;
    frames_options.cameras = &records.cameras;
    PHOTOPOSE_RETURN_IF_ERROR(WriteFramesTable(files.frames, frames_options, records.frames));
  }
  return Status::Ok();
}

Status FormatBlockTables(const Block& block, const BlockTableWriteOptions& options,
                         BlockTableText* text) {
  BlockTableRecords records;
  const std::string marks_path = "marks";
  std::string marks_text;
  PHOTOPOSE_RETURN_IF_ERROR(ToTableRecords(block, options, &marks_path, &marks_text, &records));
  PHOTOPOSE_RETURN_IF_ERROR(FormatCameraTable(records.cameras, "cameras", &text->cameras));
  PHOTOPOSE_RETURN_IF_ERROR(FormatGroundPoints(records.points, "points", &text->points));
  text->marks = std::move(marks_text);
  FramesTableOptions frames_options;
  frames_options.convention = options.rotation;
  frames_options.cameras = &records.cameras;
  return FormatFramesTable(frames_options, records.frames, "frames", &text->frames);
}

// ------------------------------------------------------------------ from the tables

namespace {

// The earth-curvature correction lowers points by D^2 / (2R) below the tangent plane of a map
// frame (projected or local, heights along the plumb line); in a geographic frame (degrees) or a
// geocentric one (ECEF) it has no meaning. A camera with ApplyECC is refused when a CRS that
// names the block's ground frame -- its own SRS, the gcp_list header, a frames row's SRS --
// resolves (PROJ) to one of those. Texts PROJ does not know stay as written, unchecked (SRS is
// free text); without ApplyECC nothing is resolved.
Status CheckEarthCurvatureFrame(const BlockTables& tables, const FrameCamera& camera) {
  if (!camera.apply_ecc) return Status::Ok();
  std::vector<std::pair<std::string, std::string>> named;  // (CRS text, where it is named)
  if (!camera.srs.empty()) named.emplace_back(camera.srs, tables.cameras_file + ": SRS");
  if (!tables.crs.empty()) named.emplace_back(tables.crs, tables.points_file + ": header");
  for (const FrameRecord& frame : tables.frames) {
    if (frame.srs.empty() || (!frame.camera_id.empty() && frame.camera_id != camera.camera_id)) continue;
    named.emplace_back(frame.srs, tables.frames_file + ":" + std::to_string(frame.line) + ": SRS");
    break;  // one row names the frame of its camera's images
  }
  for (const auto& [text, where] : named) {
    CrsInfo info;
    if (!ResolveCrs(text, &info).ok() || !(info.geographic || info.geocentric)) continue;
    return Status::Error(WhereInFile(tables.cameras_file, 0, "ApplyECC") + "camera " +
                         QuotedForMessage(camera.camera_id) +
                         ": the earth-curvature correction needs a projected or "
                         "local map frame, and the ground frame is " +
                         (info.geographic ? "geographic" : "geocentric") + " (" +
                         TokenForMessage(text) + ", " + where + ")");
  }
  return Status::Ok();
}

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

// A Row of `file`:`line` in the tables' row convention, counted down (rows counted up need the
// camera's NRows).
Status RowCountedDownAt(const BlockTables& tables, const FrameCamera& camera,
                        const std::string& file, int line, double* row) {
  if (tables.pixel_rows == PixelRows::kDown) return Status::Ok();
  if (camera.n_rows <= 0)
    return Status::Error(WhereInFile(file, line, "Row") +
                         "rows counted up need NRows in the camera " + "table (camera " +
                         QuotedForMessage(camera.camera_id) + " has none)");
  *row = RowCountedDown(*row, camera.n_rows, tables.pixel_origin);
  return Status::Ok();
}

// The steps of AssembleBlock, each over the tables and the block assembled so far. Name -> index
// maps hold views of the tables' strings (which outlive them): a block has millions of marks, each
// looked up by its raster and point.
class BlockAssembler {
 public:
  explicit BlockAssembler(const BlockTables& tables) : tables_(tables) {
    result_.pixel_origin = tables.pixel_origin;
    result_.crs = tables.crs;
    result_.marks_source = tables.marks_file;
  }

  Status AddCameras();
  Status AddPoints();
  // From the marks, in order of first appearance, then frames rows without marks.
  Status AddImages();
  // Scanned film: each image's affine from its measured fiducials.
  Status FitScannedFilm();
  Status AddMarks();
  Block& result() { return result_; }

 private:
  // The camera of an image named by a mark's or a frame's CameraID; an error otherwise.
  Status FindCamera(const std::string& camera_id, const std::string& file, int line,
                    int* camera) const;
  Status AddImage(const std::string& raster, const std::string& mark_camera_id, int mark_line);
  // The frames row's orientation, measured centre and attitude (with its accuracies) of `image`.
  Status TakeFrame(const FrameRecord& frame, int mark_line, BlockImage* image) const;
  // The block mark of a marks-table row (its point added as a tie point when it has no row).
  Status MarkOf(const ImageMark& row, const std::vector<FrameCamera>& pixel_cameras,
                BlockMark* mark);
  // A pixel mark: its film observation through the image's pixel -> film map and the local um per
  // pixel; refused farther than max_outside_fraction outside its image.
  Status PixelMark(const ImageMark& row, const FrameCamera& camera, BlockMark* mark) const;

  const BlockTables& tables_;
  Block result_;
  std::unordered_map<std::string_view, int> point_index_;
  std::unordered_map<std::string_view, int> image_index_;
  std::unordered_map<std::string_view, const FrameRecord*> frame_of_;
};

Status BlockAssembler::AddCameras() {
  if (tables_.cameras.empty())
    return Status::Error(WhereInFile(tables_.cameras_file, 0, "") + "the camera table has no rows");
  for (const FrameCamera& table : tables_.cameras) {
    const Status valid = table.IsValid();
    if (!valid.ok())
      return Status::Error(WhereInFile(tables_.cameras_file, 0, "") + "camera " +
                           QuotedForMessage(table.camera_id) + ": " + valid.message());
    if (result_.FindCamera(table.camera_id) >= 0)
      return Status::Error(WhereInFile(tables_.cameras_file, 0, "CameraID") + "duplicate camera " +
                           QuotedForMessage(table.camera_id));
    PHOTOPOSE_RETURN_IF_ERROR(CheckEarthCurvatureFrame(tables_, table));
    FrameCamera rows_down = table;
    if (tables_.pixel_rows == PixelRows::kUp) {
      const Status flipped = AffineWithRowsFlipped(&rows_down);
      if (!flipped.ok())
        return Status::Error(WhereInFile(tables_.cameras_file, 0, "NRows") + flipped.message());
    }
    result_.cameras.push_back(CameraOf(rows_down));
  }
  return Status::Ok();
}

Status BlockAssembler::AddPoints() {
  point_index_.reserve(tables_.points.size());
  for (const GroundPoint& row : tables_.points) {
    BlockPoint point;
    point.id = row.point_id;
    point.role = row.role;
    point.line = row.line;
    point.position_m = row.position;
    if (row.role != PointRole::kTie) {
      point.surveyed_m = row.position;
      point.accuracy_m = row.accuracy_m;
    }
    if (!point_index_.emplace(row.point_id, static_cast<int>(result_.points.size())).second)
      return Status::Error(WhereInFile(tables_.points_file, row.line, "PointID") +
                           "duplicate point " + QuotedForMessage(row.point_id));
    result_.points.push_back(std::move(point));
  }
  return Status::Ok();
}

Status BlockAssembler::FindCamera(const std::string& camera_id, const std::string& file, int line,
                                  int* camera) const {
  *camera = result_.FindCamera(camera_id);
  if (*camera < 0)
    return Status::Error(WhereInFile(file, line, "CameraID") + "unknown camera " +
                         QuotedForMessage(camera_id));
  return Status::Ok();
}

Status BlockAssembler::TakeFrame(const FrameRecord& f, int mark_line, BlockImage* image) const {
  if (f.camera_id != result_.cameras[image->camera].camera_id) {
    return Status::Error(WhereInFile(tables_.frames_file, f.line, "CameraID") + "image " +
                         QuotedForMessage(image->name) + " is of camera " +
                         QuotedForMessage(result_.cameras[image->camera].camera_id) +
                         " in the marks (line " + std::to_string(mark_line) + ")");
  }
  image->line = f.line;
  image->eo = f.eo;
  image->measured_center_m = f.eo.center_in_ground();
  image->center_accuracy_m = f.center_accuracy_m;
  image->measured_angles_rad = f.eo.angles_seed_rad();
  if (f.attitude_accuracy_deg) {
    image->attitude_accuracy_rad = SeedAttitudeSigmas(
        tables_.frames_rotation, result_.cameras[image->camera].table.angle_flags(),
        f.eo.angles_seed_rad(), *f.attitude_accuracy_deg);
    if (!image->attitude_accuracy_rad)
      return Status::Error(WhereInFile(tables_.frames_file, f.line, "AccuracyOmega") +
                           "cannot be converted: the angles are at a gimbal lock of the "
                           "convention");
  }
  return Status::Ok();
}

Status BlockAssembler::AddImage(const std::string& raster, const std::string& mark_camera_id,
                                int mark_line) {
  BlockImage image;
  image.name = raster;
  const auto frame = frame_of_.find(raster);
  if (!mark_camera_id.empty()) {
    PHOTOPOSE_RETURN_IF_ERROR(
        FindCamera(mark_camera_id, tables_.marks_file, mark_line, &image.camera));
  } else if (frame != frame_of_.end()) {
    PHOTOPOSE_RETURN_IF_ERROR(FindCamera(frame->second->camera_id, tables_.frames_file,
                                         frame->second->line, &image.camera));
  } else if (result_.cameras.size() == 1) {
    image.camera = 0;
  } else {
    return Status::Error(WhereInFile(tables_.marks_file, mark_line, "CameraID") + "image " +
                         QuotedForMessage(raster) +
                         " names no camera and the camera table has several");
  }
  if (frame != frame_of_.end()) PHOTOPOSE_RETURN_IF_ERROR(TakeFrame(*frame->second, mark_line, &image));
  image_index_.emplace(raster, static_cast<int>(result_.images.size()));
  result_.images.push_back(std::move(image));
  return Status::Ok();
}

Status BlockAssembler::AddImages() {
  for (const FrameRecord& frame : tables_.frames) frame_of_.emplace(frame.raster, &frame);
  for (const ImageMark& mark : tables_.marks) {
    const auto found = image_index_.find(mark.raster);
    if (found == image_index_.end()) {
      PHOTOPOSE_RETURN_IF_ERROR(AddImage(mark.raster, mark.camera_id, mark.line));
      continue;
    }
    const BlockImage& image = result_.images[found->second];
    if (!mark.camera_id.empty() && mark.camera_id != result_.cameras[image.camera].camera_id) {
      return Status::Error(WhereInFile(tables_.marks_file, mark.line, "CameraID") + "image " +
                           QuotedForMessage(mark.raster) + " has marks of two cameras (" +
                           QuotedForMessage(result_.cameras[image.camera].camera_id) + " and " +
                           QuotedForMessage(mark.camera_id) + ")");
    }
  }
  for (const FrameRecord& frame : tables_.frames) {
    if (image_index_.count(frame.raster) == 0)
      PHOTOPOSE_RETURN_IF_ERROR(AddImage(frame.raster, frame.camera_id, frame.line));
  }
  return Status::Ok();
}

Status BlockAssembler::FitScannedFilm() {
  std::map<std::string, std::vector<MeasuredFiducial>> fiducials_of;
  for (const MeasuredFiducial& f : tables_.fiducials) fiducials_of[f.raster].push_back(f);
  FiducialFitOptions fit_options;
  fit_options.max_residual_um = tables_.max_fiducial_residual_um;
  fit_options.pixel_origin = tables_.pixel_origin;
  for (const auto& [raster, measured] : fiducials_of) {
    const auto found = image_index_.find(raster);
    if (found == image_index_.end()) {
      return Status::Error(WhereInFile(tables_.fiducials_file, measured.front().line, "Raster") +
                           "image " + QuotedForMessage(raster) + " has no marks and no frames row");
    }
    BlockImage& image = result_.images[found->second];
    const FrameCamera& camera = result_.cameras[image.camera].table;
    std::vector<MeasuredFiducial> rows_down = measured;
    for (MeasuredFiducial& f : rows_down)
      PHOTOPOSE_RETURN_IF_ERROR(
          RowCountedDownAt(tables_, camera, tables_.fiducials_file, f.line, &f.column_row.y()));
    FiducialFit fit;
    PHOTOPOSE_RETURN_IF_ERROR(
        FitFiducials(camera, rows_down, fit_options, tables_.fiducials_file, &fit));
    image.fiducial_fit = std::move(fit);
  }
  return Status::Ok();
}

Status BlockAssembler::PixelMark(const ImageMark& row, const FrameCamera& camera,
                                 BlockMark* mark) const {
  const double origin_shift = tables_.pixel_origin == PixelOrigin::kCenter ? 0.5 : 0.0;
  mark->unit = MarkUnit::kPixel;
  mark->measured = *row.column_row;
  PHOTOPOSE_RETURN_IF_ERROR(
      RowCountedDownAt(tables_, camera, tables_.marks_file, row.line, &mark->measured.y()));
  const Status film = FilmFromPixel(camera, mark->measured, tables_.pixel_origin, &mark->observation);
  if (!film.ok())
    return Status::Error(WhereInFile(tables_.marks_file, row.line, "Column") + film.message());
  const Eigen::Vector2d corner = mark->measured + Eigen::Vector2d::Constant(origin_shift);
  if (!NearTheImage(camera, corner, tables_.max_outside_fraction)) {
    const Eigen::Vector2d size(camera.n_columns, camera.n_rows);
    double outside = 0.0;
    for (int k = 0; k < 2; ++k)
      outside = std::max(outside, corner[k] < 0.0 ? -corner[k] : corner[k] - size[k]);
    return Status::Error(EscapeForMessage(
        WhereInFile(tables_.marks_file, row.line, "Column") + "the mark of point '" + row.point_id +
        "' in image '" + row.raster + "' lies " + FormatNumber(std::round(outside)) +
        " pixels outside the " + std::to_string(camera.n_columns) + " x " +
        std::to_string(camera.n_rows) + " image of camera '" + camera.camera_id + "' (at most " +
        FormatNumber(tables_.max_outside_fraction * 100.0) + "% of the image size is allowed)"));
  }
  const Status scale = FilmUmPerPixel(camera, mark->measured, tables_.pixel_origin,
                                      &mark->observation_units_per_unit);
  if (!scale.ok())
    return Status::Error(WhereInFile(tables_.marks_file, row.line, "Column") + scale.message());
  return Status::Ok();
}

Status BlockAssembler::MarkOf(const ImageMark& row, const std::vector<FrameCamera>& pixel_cameras,
                              BlockMark* mark) {
  mark->line = row.line;
  mark->image = image_index_.at(row.raster);
  const auto point = point_index_.find(row.point_id);
  if (point != point_index_.end()) {
    mark->point = point->second;
  } else {
    // A point without a row: a tie point of unknown coordinates.
    BlockPoint tie;
    tie.id = row.point_id;
    tie.role = PointRole::kTie;
    mark->point = static_cast<int>(result_.points.size());
    point_index_.emplace(row.point_id, mark->point);
    result_.points.push_back(std::move(tie));
  }
  mark->accuracy = row.accuracy_px;
  if (row.film_um) {
    mark->unit = MarkUnit::kFilm;
    mark->measured = *row.film_um;
    mark->observation = *row.film_um;
    return Status::Ok();
  }
  if (row.column_row) return PixelMark(row, pixel_cameras[mark->image], mark);
  return Status::Error(WhereInFile(tables_.marks_file, row.line, "Column") +
                       "the mark has neither Column/Row nor FilmX/FilmY");
}

Status BlockAssembler::AddMarks() {
  std::vector<FrameCamera> pixel_cameras;
  for (size_t i = 0; i < result_.images.size(); ++i)
    pixel_cameras.push_back(PixelToFilmCamera(result_, static_cast<int>(i)));
  result_.marks.reserve(tables_.marks.size());
  for (const ImageMark& row : tables_.marks) {
    BlockMark mark;
    PHOTOPOSE_RETURN_IF_ERROR(MarkOf(row, pixel_cameras, &mark));
    result_.marks.push_back(mark);
  }
  result_.BuildIndex();
  return Status::Ok();
}

}  // namespace

Status AssembleBlock(const BlockTables& tables, Block* block) {
  BlockAssembler assembler(tables);
  PHOTOPOSE_RETURN_IF_ERROR(assembler.AddCameras());
  PHOTOPOSE_RETURN_IF_ERROR(assembler.AddPoints());
  PHOTOPOSE_RETURN_IF_ERROR(assembler.AddImages());
  PHOTOPOSE_RETURN_IF_ERROR(assembler.FitScannedFilm());
  PHOTOPOSE_RETURN_IF_ERROR(assembler.AddMarks());
  PHOTOPOSE_RETURN_IF_ERROR(CheckBlock(assembler.result()));
  *block = std::move(assembler.result());
  return Status::Ok();
}

Status ReadBlock(const BlockFiles& files, Block* block) {
  BlockTables tables;
  tables.cameras_file = files.cameras;
  tables.pixel_origin = files.pixel_origin;
  tables.pixel_rows = files.pixel_rows;
  tables.frames_rotation = files.rotation;
  tables.max_fiducial_residual_um = files.max_fiducial_residual_um;
  PHOTOPOSE_RETURN_IF_ERROR(ReadCameraTable(files.cameras, &tables.cameras));
  if (!files.gcp_list.empty()) {
    if (files.pixel_rows == PixelRows::kUp)
      return Status::Error(files.gcp_list + ": rows counted up apply to a marks table; a " +
                           "gcp_list.txt counts pixel rows down from the top-left corner " +
                           "(OpenDroneMap's definition)");
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
