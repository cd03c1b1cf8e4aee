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
//    marker-projection defaults, times the factor by which variance component estimation
//    rescaled the control marks when result->groups says so: check marks are measured as control
//    marks are) against its surveyed coordinates, error_m = intersected -
//    surveyed (m), covariance = variance_factor times the intersection's a-priori covariance
//    (m^2), num_observations (marks kept); or a message when it cannot be intersected;
//  - its marks tested like the block's observations: the w-test w = v / (s sigma sqrt(r)) of each
//    mark coordinate on the intersection (r its redundancy number there, s = max(1, sigma0)), the
//    worst mark above the critical value rejected and the point intersected again until none is
//    (result->rejected_check_marks; a point left with too few rays says so in its message). The
//    critical value is result->critical_value when the diagnostics set it, else k(alpha) for the
//    default snooping_alpha over the check marks' coordinates (Bonferroni);
//  - num_control_points and the control RMSE from the control points whose error_m the adjustment
//    has set (adjusted - surveyed; not those whose coordinates data snooping removed), and num_check_points and the check RMSE (m, per axis and
//    total).
// result->points must have one entry per point of the block.
void TabulateControlAndCheckPoints(const Block& adjusted, const BundleAccuracies& accuracies,
                                   double variance_factor, BundleAdjustmentResult* result);

// The covariance (m^2) of the error e = estimate - surveyed of a surveyed point that the estimate
// leaves out (a check point's intersection; a control point left out by the cross-validation):
// the estimate's covariance plus the surveyed coordinates' own, diag(a^2), a the point's stated
// accuracy per axis (m), the default marker accuracy `default_marker_m` when it states none, 0
// when it is stated error-free. The one rule behind the check-point verdict (e^T C^-1 e against
// chi-square(3)) and the leave-one-out test: a check point surveyed to 3 cm is not expected to
// meet an intersection of 1 cm sigma within 1 cm.
Eigen::Matrix3d SurveyedPointErrorCovariance(const BlockPoint& point,
                                             const Eigen::Matrix3d& estimate_covariance_m2,
                                             double default_marker_m);

}  // namespace photopose
