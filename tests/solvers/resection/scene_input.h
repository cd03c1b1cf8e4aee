#pragma once
// One image of a seeded synthetic scene as the solvers see it, through the library's one assembly
// (core/block.h, MakeResectionInput): for the solver tests.

#include <gtest/gtest.h>

#include <vector>

#include "core/io/block_tables.h"
#include "core/simulation/synthetic_scene.h"
#include "solvers/resection/resection.h"

namespace photopose::testing {

struct SceneInput {
  SyntheticScene scene;
  ResectionInput input;
  std::vector<int> marks;      // block (= scene) mark of each observation
  std::vector<double> sigmas;  // standard deviation of each observation, image-plane units
  std::vector<int> all;        // 0 .. n - 1
  ExteriorOrientation truth;
};

inline SceneInput MakeSceneInput(const SyntheticSceneOptions& options, int image = 0) {
  SceneInput s;
  EXPECT_TRUE(MakeSyntheticScene(options, &s.scene).ok());
  Block block;
  EXPECT_TRUE(AssembleBlock(SceneBlockTables(s.scene), &block).ok());
  EXPECT_TRUE(MakeResectionInput(block, image, ResectionInputOptions(), &s.input, &s.marks).ok());
  for (size_t i = 0; i < s.input.image_plane.size(); ++i) {
    s.sigmas.push_back(s.input.sigma[i] * s.input.observation_units_per_unit[i]);
    s.all.push_back(static_cast<int>(i));
  }
  s.truth = s.scene.true_frames[image].eo;
  return s;
}

}  // namespace photopose::testing
