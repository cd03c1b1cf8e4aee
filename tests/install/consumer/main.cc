// An outside program built against the installed photopose (find_package): simulates a scene with
// the core library, assembles it as a block and resects it with the solvers library (Ceres
// underneath).
#include <iostream>

#include <photopose/core/block.h>
#include <photopose/core/io/block_tables.h>
#include <photopose/core/simulation/synthetic_scene.h>
#include <photopose/solvers/resection/resection.h>

int main() {
  photopose::SyntheticSceneOptions options;
  options.noise_px = 0.0;
  photopose::SyntheticScene scene;
  if (!photopose::MakeSyntheticScene(options, &scene).ok()) return 1;
  photopose::Block block;
  if (!photopose::AssembleBlock(photopose::SceneBlockTables(scene), &block).ok()) return 1;
  photopose::ResectionInput input;
  if (!photopose::MakeResectionInput(block, 0, photopose::ResectionInputOptions(), &input, nullptr)
           .ok())
    return 1;
  input.approximate.reset();  // the consensus finds the initial values
  const photopose::ResectionResult result =
      photopose::ResectImage(photopose::ResectionOptions(), input);
  const double error =
      (result.eo.center_in_ground() - scene.true_frames.front().eo.center_in_ground()).norm();
  std::cout << "resected " << input.image_plane.size() << " marks, position error " << error
            << " m\n";
  return result.success && error < 1e-6 ? 0 : 1;
}
