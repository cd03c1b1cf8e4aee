#include "core/block_tables.h"

#include "core/csv.h"
#include "core/types.h"

namespace photopose {

Status BlockToTableRecords(const Block& block, const BlockTableWriteOptions& options,
                           BlockTableRecords* records) {
  PHOTOPOSE_RETURN_IF_ERROR(CheckBlock(block));
  BlockTableRecords result;
  for (const BlockCamera& camera : block.cameras) {
    if (camera.model != CameraModelType::kFrame) {
      return Status::Error("camera '" + camera.camera_id + "' is a " +
                           CameraModelTypeName(camera.model) +
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

  result.marks.reserve(block.marks.size());
  for (const BlockMark& mark : block.marks) {
    const BlockImage& image = block.images[mark.image];
    const BlockCamera& camera = block.cameras[image.camera];
    ImageMark row;
    row.raster = image.name;
    row.point_id = block.points[mark.point].id;
    row.camera_id = camera.camera_id;
    row.accuracy_px = mark.accuracy;
    if (mark.unit == MarkUnit::kPixel) {
      row.column_row = mark.measured;
    } else {
      row.film_um = mark.measured;
      const double pixel_um = camera.table.MeanPixelSizeUm();
      if (mark.accuracy) {
        if (!(pixel_um > 0.0)) {
          return Status::Error("image '" + image.name + "': point '" + row.point_id +
                               "': a film mark's accuracy needs the camera's pixel size");
        }
        row.accuracy_px = *mark.accuracy / pixel_um;
      }
    }
    result.marks.push_back(std::move(row));
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

Status WriteBlockTables(const Block& block, const BlockTableFiles& files,
                        const BlockTableWriteOptions& options) {
  BlockTableRecords records;
  PHOTOPOSE_RETURN_IF_ERROR(BlockToTableRecords(block, options, &records));
  if (!files.cameras.empty())
    PHOTOPOSE_RETURN_IF_ERROR(WriteCameraTable(files.cameras, records.cameras));
  if (!files.points.empty())
    PHOTOPOSE_RETURN_IF_ERROR(WriteGroundPoints(files.points, records.points));
  if (!files.marks.empty()) PHOTOPOSE_RETURN_IF_ERROR(WriteImageMarks(files.marks, records.marks));
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
  PHOTOPOSE_RETURN_IF_ERROR(BlockToTableRecords(block, options, &records));
  PHOTOPOSE_RETURN_IF_ERROR(FormatCameraTable(records.cameras, "cameras", &text->cameras));
  PHOTOPOSE_RETURN_IF_ERROR(FormatGroundPoints(records.points, "points", &text->points));
  PHOTOPOSE_RETURN_IF_ERROR(FormatImageMarks(records.marks, "marks", &text->marks));
  FramesTableOptions frames_options;
  frames_options.convention = options.rotation;
  frames_options.cameras = &records.cameras;
  return FormatFramesTable(frames_options, records.frames, "frames", &text->frames);
}

}  // namespace photopose
