#pragma once
// The control- and check-point tables of an adjusted block (Metashape's GCP and check tables), the
// same for every adjustment of the block so that their figures are measured with one yardstick:
// check points stay out of the adjustment and are intersected afterwards from the adjusted images
// and cameras (solvers/bundle/triangulation.h); control points are compared as adjusted.
//
// Both solvers fill their tables through the one rule behind this function
// (internal::TabulateControlAndCheckPoints); BundleAdjust adds the images' own uncertainty to the
// check points' covariances from its reduced normal matrix.

#include "core/block.h"
#include "solvers/bundle/bundle_adjustment.h"

namespace photopose {

// Fills, from `adjusted` (the block holding the adjusted orientations and cameras):
//  - per check point: the intersection of its marks (sigmas by core/mark_weight.h with the
//    marker-projection defaults) against its surveyed coordinates, error_m = intersected -
//    surveyed (m), covariance = variance_factor times the intersection's a-priori covariance
//    (m^2), num_observations; or a message when it cannot be intersected;
//  - num_control_points and the control RMSE from the control points whose error_m the adjustment
//    has set (adjusted - surveyed; not those whose coordinates data snooping removed), and num_check_points and the check RMSE (m, per axis and
//    total).
// result->points must have one entry per point of the block.
void TabulateControlAndCheckPoints(const Block& adjusted, const BundleAccuracies& accuracies,
                                   double variance_factor, BundleAdjustmentResult* result);

}  // namespace photopose
