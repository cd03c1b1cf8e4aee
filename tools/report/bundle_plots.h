#pragma once
// The pictures of `photopose bundle`'s HTML page (tools/report/bundle_html.cc): the plan view of
// the block, each camera's radial distortion and each camera's mean image residuals. Each returns
// an SVG fragment (with its caption where it has one), or an empty string when there is nothing
// to draw; axes, colours and number formats come from tools/report/html_kit.h.

#include <string>

#include "core/block.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/georeference/georeference.h"

namespace photopose::cli {

// The plan view: tie points, cameras with 1-sigma error ellipses, control and check points with
// their residual vectors, each exaggerated by a stated factor, in the block's ground frame or, for
// a georeferenced model (`georeference` not null), in the grid of its projected output CRS.
std::string PlanViewHtml(const Block& block, const BundleAdjustmentResult& result,
                         const GeoreferenceResult* georeference);

// Radial distortion of a camera along the image's x axis (model unit), out to the image corner.
std::string DistortionPlot(const BlockCamera& camera);

// Mean mark residual vectors over the image format of camera `cam` (8 x 6 cells), in `unit`.
std::string ImageResidualPlot(const Block& block, const BundleAdjustmentResult& result, int cam,
                              const std::string& unit);

}  // namespace photopose::cli
