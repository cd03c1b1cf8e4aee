#pragma once
// The measured-fiducials table of scanned film (docs/formats.md, "Measured fiducials"): where each
// fiducial mark of a scanned photograph was found,
//
//   Raster, FiducialID, Column, Row        (pixels, the marks' pixel convention)
//
// read under the CSV rules of core/io/csv.h into the model's MeasuredFiducial rows, which
// core/fiducials.h fits an affine to. Errors read "file:line: column: what".

#include <string>
#include <vector>

#include "core/fiducials.h"
#include "core/status.h"

namespace photopose {

// Reads Raster, FiducialID, Column, Row (CSV rules of docs/formats.md). A fiducial measured twice
// in one image is an error naming both lines.
Status ReadMeasuredFiducials(const std::string& path, std::vector<MeasuredFiducial>* fiducials);

}  // namespace photopose
