#pragma once
// The control- and check-point tables of an adjusted block (Metashape's GCP and check tables), the
// same for every adjustment of the block so that their figures are measured with one yardstick:
// check points stay out of the adjustment and are intersected afterwards from the adjusted images
// and cameras (solvers/bundle/triangulation.h); control points are compared as adjusted.
//
// Used by the Taylor bundle adjustment (solvers/bundle/taylor_bundle.h); BundleAdjust computes the same
// in its own statistics pass (the report of issue 12 proposes that it call these instead).

#include "core/block.h"
#include "solvers/bundle/bundle_adjustment.h"

namespace photopose {

// The default sigma (um) of a film mark of this camera: sigma_px through the camera's pixel size
// when it has one, sigma_film_um otherwise (the BundleAccuracies rule for film marks; the bundle
// plan and statistics use it too).
double DefaultFilmMarkSigmaUm(const BlockCamera& camera, double sigma_px, double sigma_film_um);

// Fills, from `adjusted` (the block holding the adjusted orientations and cameras):
//  - per check point: the intersection of its marks (sigma: its accuracy, else the
//    marker-projection accuracy) against its surveyed coordinates, error_m = intersected -
//    surveyed (m), covariance = variance_factor times the intersection's a-priori covariance
//    (m^2), num_observations; or a message when it cannot be intersected;
//  - num_control_points and the control RMSE from the control points whose error_m the adjustment
//    has set (adjusted - surveyed), and num_check_points and the check RMSE (m, per axis and
//    total).
// result->points must have one entry per point of the block.
void TabulateControlAndCheckPoints(const Block& adjusted, const BundleAccuracies& accuracies,
                                   double variance_factor, BundleAdjustmentResult* result);

}  // namespace photopose
