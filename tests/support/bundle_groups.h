#pragma once
// A group of an adjustment's objective with the figures a report prints (stated accuracy, RMS,
// their ratio), for tests of the reports' tables and console lines.
#include <string>

#include "solvers/bundle/bundle_adjustment.h"

namespace photopose::testing {

// `count` 12 observations; `stated` and `rms` in `unit` (px, um, m or deg); redundancy share
// unitless.
inline BundleGroupStatistics GroupOf(BundleGroup group, const std::string& unit, double stated,
                                     double rms, double redundancy_share) {
  BundleGroupStatistics g;
  g.group = group;
  g.unit = unit;
  g.count = 12;
  g.stated_accuracy = Eigen::Vector3d::Constant(stated);
  g.rms_total = rms;
  g.ratio = rms / stated;
  g.redundancy_share = redundancy_share;
  return g;
}

}  // namespace photopose::testing
