#pragma once
// Blocks whose normal matrix is singular although Ceres' damped Levenberg-Marquardt steps converge
// on them: what BundleAdjust must report as a failure naming the undetermined parameter (the
// library's and the CLI's tests). Synthetic blocks (core/simulation/synthetic_block.h) with the
// usual perturbed start values, so that the solver has work to do.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/block.h"
#include "core/camera.h"
#include "core/camera_models.h"
#include "core/collinearity.h"
#include "core/simulation/synthetic_block.h"

namespace photopose::testing {

struct SingularBlock {
  Block block;
  SyntheticBlockTruth truth;
  int image = -1;  // the image whose orientation is not determined (BlockWithAnImageOnALine)
};

// The exact mark of point X in image `image` at its true orientation (a copy of `like` with the
// image, point and measurement replaced); false when X does not project into the image.
inline bool TrueMark(const Block& block, const SyntheticBlockTruth& truth, int image, int point,
                     const Eigen::Vector3d& X, const BlockMark& like, BlockMark* mark) {
  const BlockCamera& camera = block.cameras[block.images[image].camera];
  double ab[2];
  if (!ProjectToNormalized(truth.eo[image].parameters.data(), X.data(), ab)) return false;
  *mark = like;
  mark->image = image;
  mark->point = point;
  if (!ObservationFromNormalized(camera.model, camera.params.data(), camera.data(), {ab[0], ab[1]},
                                 &mark->observation)
           .ok() ||
      !PixelFromFilm(camera.table, mark->observation, PixelOrigin::kCorner, &mark->measured).ok())
    return false;
  return mark->measured.x() >= 0.0 && mark->measured.y() >= 0.0 &&
         mark->measured.x() <= camera.table.n_columns && mark->measured.y() <= camera.table.n_rows;
}

// 3 lines of 5 nadir images (no attitude jitter), control points, no GNSS. The middle image keeps
// no mark of its own; it sees instead 7 new tie points on one ground line along X below its
// centre (a line through its principal point), also seen by its neighbours, which fix them. Points
// on one line in space leave the image free to turn about that line, its centre moving on a circle
// around it: rotation about X (omega) with a shift in Y, a one-dimensional null space of the
// normal matrix confined to that image.
inline SingularBlock BlockWithAnImageOnALine() {
  SyntheticBlockOptions options;
  options.seed = 5;
  options.num_lines = 3;
  options.images_per_line = 5;
  options.attitude_jitter_deg = 0.0;
  options.position_jitter_m = 0.0;
  options.terrain_relief_m = 0.0;
  options.mark_sigma_px = 0.0;
  options.mark_accuracy_px = 0.5;
  options.control_sigma_m = 0.0;
  options.gnss = false;  // a measured centre would hold the circle's motion
  SingularBlock data;
  const Status made = MakeSyntheticBlock(options, &data.block, &data.truth);
  EXPECT_TRUE(made.ok()) << made.message();
  Block& block = data.block;
  data.image = 7;  // the middle of the middle line
  const Vector6d centre_eo = data.truth.eo[data.image].parameters;
  std::vector<BlockMark> kept;
  BlockMark model_mark;
  for (const BlockMark& mark : block.marks) {
    if (mark.image == data.image) {
      model_mark = mark;
      continue;
    }
    kept.push_back(mark);
  }
  block.marks = kept;
  for (int k = 0; k < 7; ++k) {
    BlockPoint point;
    point.id = "LINE_" + std::to_string(k);
    const Eigen::Vector3d X(centre_eo[0] - 24.0 + 8.0 * k, centre_eo[1], options.ground_height_m);
    point.position_m = X;
    const int index = static_cast<int>(block.points.size());
    block.points.push_back(point);
    data.truth.points_m.push_back(X);
    for (size_t i = 0; i < block.images.size(); ++i) {
      BlockMark mark;
      if (TrueMark(block, data.truth, static_cast<int>(i), index, X, model_mark, &mark))
        block.marks.push_back(mark);
    }
  }
  block.BuildIndex();
  return data;
}

}  // namespace photopose::testing
