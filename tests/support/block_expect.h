#pragma once
// Comparisons of blocks shared by the I/O and generator tests.
#include <gtest/gtest.h>

#include <string>

#include "core/block.h"

namespace photopose::testing {

// Points (ids and positions) and marks (image, point, observation) exactly equal.
inline ::testing::AssertionResult SamePointsAndMarks(const Block& a, const Block& b) {
  if (a.points.size() != b.points.size())
    return ::testing::AssertionFailure() << a.points.size() << " points against " << b.points.size();
  for (size_t p = 0; p < a.points.size(); ++p) {
    if (a.points[p].id != b.points[p].id || a.points[p].position_m != b.points[p].position_m)
      return ::testing::AssertionFailure() << "point " << p << " ('" << a.points[p].id << "') differs";
  }
  if (a.marks.size() != b.marks.size())
    return ::testing::AssertionFailure() << a.marks.size() << " marks against " << b.marks.size();
  for (size_t m = 0; m < a.marks.size(); ++m) {
    const BlockMark &x = a.marks[m], &y = b.marks[m];
    if (x.image != y.image || x.point != y.point || x.observation != y.observation)
      return ::testing::AssertionFailure() << "mark " << m << " differs";
  }
  return ::testing::AssertionSuccess();
}

}  // namespace photopose::testing
