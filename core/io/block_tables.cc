#include "core/io/block_tables.h"

#include <optional>
#include <string>

#include "core/io/csv.h"
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

}  // namespace photopose
