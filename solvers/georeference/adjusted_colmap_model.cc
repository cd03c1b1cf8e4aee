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

namespace {

// The write options of the model part: the removed marks among the model's own marks (they come
// first) left out of the tracks.
ColmapWriteOptions AdjustedWriteOptions(const Block& block, const Block& model,
                                        const BundleAdjustmentResult& adjustment,
                                        ColmapFormat format) {
  ColmapWriteOptions options;
  options.format = format;
  options.marks_left_out = adjustment.RemovedMarks(block.marks.size());
  options.marks_left_out.resize(model.marks.size());
  return options;
}

// georeference.json: the local frame the model's coordinates are in.
std::string GeoreferenceJson(const GeoreferenceResult& georeference) {
  const LocalFrame& frame = georeference.frame;
  const nlohmann::json json = {
      {"frame", "local East-North-Up (m) of this model's coordinates"},
      {"local_to_epsg4979_proj_pipeline_inverse", frame.definition()},
      {"origin_lon_lat_h",
       {frame.origin_lon_lat_h().x(), frame.origin_lon_lat_h().y(), frame.origin_lon_lat_h().z()}},
      {"note",
       "the PROJ pipeline maps EPSG:4979 (longitude, latitude in degrees, ellipsoidal height in "
       "m) to this frame; run it inverted (e.g. cs2cs/cct -I) to get geographic coordinates, "
       "then to any CRS"},
      {"out_crs", georeference.out_crs}};
  return json.dump(2) + "\n";
}

}  // namespace

Status FormatAdjustedColmapModel(const Block& block, const BundleAdjustmentResult& adjustment,
                                 const GeoreferenceResult* georeference,
                                 const ColmapModelExtras* extras, ColmapFormat format,
                                 AdjustedColmapModelFiles* files) {
  Block copy;
  const Block* model = nullptr;
  PHOTOPOSE_RETURN_IF_ERROR(ModelView(block, georeference, &copy, &model));
  AdjustedColmapModelFiles out;
  PHOTOPOSE_RETURN_IF_ERROR(FormatColmapModel(
      *model, extras, AdjustedWriteOptions(block, *model, adjustment, format), &out.model));
  if (georeference != nullptr) out.georeference_json = GeoreferenceJson(*georeference);
  *files = std::move(out);
  return Status::Ok();
}

Status StageAdjustedColmapModel(const std::string& directory, const Block& block,
                                const BundleAdjustmentResult& adjustment,
                                const GeoreferenceResult* georeference,
                                const ColmapModelExtras* extras, ColmapFormat format,
                                OutputFiles* outputs) {
  Block copy;
  const Block* model = nullptr;
  PHOTOPOSE_RETURN_IF_ERROR(ModelView(block, georeference, &copy, &model));
  PHOTOPOSE_RETURN_IF_ERROR(StageColmapModel(
      *model, extras, AdjustedWriteOptions(block, *model, adjustment, format), directory, outputs));
  if (georeference != nullptr) {
    PHOTOPOSE_RETURN_IF_ERROR(
        outputs->Stage(directory + "/" + kGeoreferenceJsonName, GeoreferenceJson(*georeference)));
  }
  return Status::Ok();
}

Status WriteAdjustedColmapModel(const std::string& directory, const Block& block,
                                const BundleAdjustmentResult& adjustment,
                                const GeoreferenceResult* georeference,
                                const ColmapModelExtras* extras, ColmapFormat format) {
  // Refused before the folder is made (as the writing refuses them).
  PHOTOPOSE_RETURN_IF_ERROR(CheckAdjustedColmapModelWritable(block, georeference, extras));
  std::error_code error;
  std::filesystem::create_directories(directory, error);
  if (error) return Status::Error(directory + ": cannot create the folder: " + error.message());
  OutputFiles outputs;
  for (const char* name : ColmapFileNames(format))
    PHOTOPOSE_RETURN_IF_ERROR(outputs.AddOutput("", directory + "/" + name));
  if (georeference != nullptr)
    PHOTOPOSE_RETURN_IF_ERROR(outputs.AddOutput("", directory + "/" + kGeoreferenceJsonName));
  PHOTOPOSE_RETURN_IF_ERROR(StageAdjustedColmapModel(directory, block, adjustment, georeference,
                                                     extras, format, &outputs));
  return outputs.Commit();
}

}  // namespace photopose
