#pragma once
// A synthetic block (core/simulation/synthetic_block.h) without mark noise or survey error, its
// true orientations in place of the perturbed start: what an adjustment returns on perfect data.
// Marks state 0.5 px (2 um on the default camera's 4 um pixels).
#include <gtest/gtest.h>

#include "core/block.h"
#include "core/simulation/synthetic_block.h"

namespace photopose::testing {

struct ExactBlock {
  Block block;
  SyntheticBlockTruth truth;
};

inline ExactBlock MakeExactBlock(SyntheticBlockOptions options = SyntheticBlockOptions()) {
  options.mark_sigma_px = 0.0;
  options.mark_accuracy_px = 0.5;
  options.control_sigma_m = 0.0;
  ExactBlock data;
  const Status made = MakeSyntheticBlock(options, &data.block, &data.truth);
  EXPECT_TRUE(made.ok()) << made.message();
  for (size_t i = 0; i < data.block.images.size() && i < data.truth.eo.size(); ++i)
    data.block.images[i].eo = data.truth.eo[i];
  return data;
}

}  // namespace photopose::testing
