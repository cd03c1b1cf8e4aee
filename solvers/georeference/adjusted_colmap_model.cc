#include "solvers/georeference/adjusted_colmap_model.h"

#include <array>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <system_error>

#include "core/io/output_files.h"

namespace photopose {

Status ModelPartOfBlock(const Block& block, const GeoreferenceResult* georeference, Block* model) {
  *model = block;
  if (georeference == nullptr) return Status::Ok();
  // PrepareGeoreference appends the control after the model's own points and marks, so the model
  // is the first model_points points and model_marks marks (no model mark names a control point).
  if (georeference->model_points > block.points.size() ||
      georeference->model_marks > block.marks.size()) {
    return Status::Error(
        "the georeference does not belong to this block (it counts " +
        std::to_string(georeference->model_points) + " model points and " +
        std::to_string(georeference->model_marks) + " model marks, the block has " +
        std::to_string(block.points.size()) + " points and " + std::to_string(block.marks.size()) +
        " marks)");
  }
  model->points.resize(georeference->model_points);
  model->marks.resize(georeference->model_marks);
  model->BuildIndex();
  return Status::Ok();
}

namespace {

// The model's part of `block` (ModelPartOfBlock): the block itself when nothing was added to it,
// else the part copied into *copy. No copy of a block of millions of marks (200 MB at a thousand
// images) just to write it.
Status ModelView(const Block& block, const GeoreferenceResult* georeference, Block* copy,
                 const Block** model) {
  *model = &block;
  if (georeference == nullptr) return Status::Ok();
  PHOTOPOSE_RETURN_IF_ERROR(ModelPartOfBlock(block, georeference, copy));
  *model = copy;
  return Status::Ok();
}

}  // namespace

Status CheckAdjustedColmapModelWritable(const Block& block, const GeoreferenceResult* georeference,
                                        const ColmapModelExtras* extras) {
  Block copy;
  const Block* model = nullptr;
  PHOTOPOSE_RETURN_IF_ERROR(ModelView(block, georeference, &copy, &model));
  return CheckColmapModelWritable(*model, extras);
}

Status FormatAdjustedColmapModel(const Block& block, const BundleAdjustmentResult& adjustment,
                                 const GeoreferenceResult* georeference,
                                 const ColmapModelExtras* extras, ColmapFormat format,
                                 AdjustedColmapModelFiles* files) {
  Block copy;
  const Block* model = nullptr;
  PHOTOPOSE_RETURN_IF_ERROR(ModelView(block, georeference, &copy, &model));
  ColmapWriteOptions options;
  options.format = format;
  // The model's own marks come first: the removed ones among them are the first entries.
  options.marks_left_out = adjustment.RemovedMarks(block.marks.size());
  options.marks_left_out.resize(model->marks.size());
  AdjustedColmapModelFiles out;
  PHOTOPOSE_RETURN_IF_ERROR(FormatColmapModel(*model, extras, options, &out.model));
  if (georeference != nullptr) {
    const LocalFrame& frame = georeference->frame;
    const nlohmann::json json = {
        {"frame", "local East-North-Up (m) of this model's coordinates"},
        {"local_to_epsg4979_proj_pipeline_inverse", frame.definition()},
        {"origin_lon_lat_h",
         {frame.origin_lon_lat_h().x(), frame.origin_lon_lat_h().y(), frame.origin_lon_lat_h().z()}},
        {"note",
         "the PROJ pipeline maps EPSG:4979 (longitude, latitude in degrees, ellipsoidal height in "
         "m) to this frame; run it inverted (e.g. cs2cs/cct -I) to get geographic coordinates, "
         "then to any CRS"},
        {"out_crs", georeference->out_crs}};
    out.georeference_json = json.dump(2) + "\n";
  }
  *files = std::move(out);
  return Status::Ok();
}

Status WriteAdjustedColmapModel(const std::string& directory, const Block& block,
                                const BundleAdjustmentResult& adjustment,
                                const GeoreferenceResult* georeference,
                                const ColmapModelExtras* extras, ColmapFormat format) {
  AdjustedColmapModelFiles files;
  PHOTOPOSE_RETURN_IF_ERROR(
      FormatAdjustedColmapModel(block, adjustment, georeference, extras, format, &files));
  std::error_code error;
  std::filesystem::create_directories(directory, error);
  if (error) return Status::Error(directory + ": cannot create the folder: " + error.message());
  const std::array<const char*, 3> names = ColmapFileNames(format);
  const std::string* contents[] = {&files.model.cameras, &files.model.images, &files.model.points3D};
  OutputFiles outputs;
  for (const char* name : names)
    PHOTOPOSE_RETURN_IF_ERROR(outputs.AddOutput("", directory + "/" + name));
  if (georeference != nullptr)
    PHOTOPOSE_RETURN_IF_ERROR(outputs.AddOutput("", directory + "/" + kGeoreferenceJsonName));
  for (size_t k = 0; k < names.size(); ++k)
    PHOTOPOSE_RETURN_IF_ERROR(outputs.Stage(directory + "/" + names[k], *contents[k]));
  if (georeference != nullptr) {
    PHOTOPOSE_RETURN_IF_ERROR(
        outputs.Stage(directory + "/" + kGeoreferenceJsonName, files.georeference_json));
  }
  return outputs.Commit();
}

}  // namespace photopose
