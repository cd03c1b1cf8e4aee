#pragma once
// An adjusted block written back as the COLMAP model it was read from: the one writer of
// `photopose bundle --out_colmap` and of the Python module's write_adjusted_colmap_model.
//
//  - The marks the adjustment left out (rejected, removed by data snooping:
//    BundleAdjustmentResult::RemovedMarks) leave the tracks: each is written as a keypoint
//    without a 3D point at its POINT2D index (ColmapWriteOptions::marks_left_out), so the indices
//    of the others stay.
//  - A georeferenced block (PrepareGeoreference) is written without the control and check points
//    and marks the georeferencing added (ModelPartOfBlock): a COLMAP model has no place for a
//    point's role or survey, and the model read keeps its own points and tracks. Its coordinates
//    are those of the local East-North-Up frame the block was adjusted in, and georeference.json
//    beside the three files says which frame that is (the PROJ pipeline from EPSG:4979 to it, its
//    origin, the output CRS of the run).
//  - `extras` (ColmapModelExtras of the model read, or null) restore the model's ids, keypoint
//    indices, unmatched keypoints and colours; they describe the model part, so they fit a
//    georeferenced block too.

#include <string>

#include "core/block.h"
#include "core/io/colmap.h"
#include "core/status.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/georeference/georeference.h"

namespace photopose {

// The name of the file beside a georeferenced model that names its frame.
inline constexpr const char* kGeoreferenceJsonName = "georeference.json";

// What the writer writes: the model's three files and, for a georeferenced block, the text of
// georeference.json (empty otherwise).
struct AdjustedColmapModelFiles {
  ColmapModelFiles model;
  std::string georeference_json;
};

// The block as the COLMAP model it was read from holds it: without the control points and marks a
// georeferencing added after the model's own (`georeference` null: the block as it is). Fails when
// the georeference counts more model points or marks than the block has (it belongs to another
// block).
Status ModelPartOfBlock(const Block& block, const GeoreferenceResult* georeference, Block* model);

// Whether the model part of `block` can be written with `extras` (CheckColmapModelWritable): to
// refuse an output before the adjustment that would fill it.
Status CheckAdjustedColmapModelWritable(const Block& block, const GeoreferenceResult* georeference,
                                        const ColmapModelExtras* extras);

// The files of the adjusted model (`block` as adjusted, `adjustment` its result, `georeference`
// null for a block that was not georeferenced) in `format`, in memory: for callers that write
// them with other outputs as one transaction (core/io/output_files.h).
Status FormatAdjustedColmapModel(const Block& block, const BundleAdjustmentResult& adjustment,
                                 const GeoreferenceResult* georeference,
                                 const ColmapModelExtras* extras, ColmapFormat format,
                                 AdjustedColmapModelFiles* files);

// FormatAdjustedColmapModel's files staged in `outputs` as directory/<name> (added when not
// there yet): the model's three files written in pieces as they are formatted (StageColmapModel:
// never held whole), georeference.json when georeferenced. The folder must exist.
Status StageAdjustedColmapModel(const std::string& directory, const Block& block,
                                const BundleAdjustmentResult& adjustment,
                                const GeoreferenceResult* georeference,
                                const ColmapModelExtras* extras, ColmapFormat format,
                                OutputFiles* outputs);

// FormatAdjustedColmapModel written into `directory` (created when missing): the three files of
// `format` and, when georeferenced, georeference.json, all or none (core/io/output_files.h).
Status WriteAdjustedColmapModel(const std::string& directory, const Block& block,
                                const BundleAdjustmentResult& adjustment,
                                const GeoreferenceResult* georeference,
                                const ColmapModelExtras* extras,
                                ColmapFormat format = ColmapFormat::kText);

}  // namespace photopose
