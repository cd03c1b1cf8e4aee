#pragma once
// Initial values of a block for the bundle adjustment, where a frames table or a model gave none:
//
//   1. every image without an exterior orientation that sees enough control points is resected
//      from them (solvers/resection/resection.h: the consensus, the outlier tests, least squares);
//   2. every tie point without coordinates seen by two or more oriented images is intersected
//      (solvers/bundle/triangulation.h), kept when its rays meet at a usable angle and fit their marks;
//   3. the images still without orientation are resected from the control points and the tie
//      points intersected so far;
//   4. 2 and 3 repeat until no image is added.
// An image never reached is reported with the reason, never silently dropped; the caller decides
// (photopose bundle adjusts the rest and exits 1).

#include <string>
#include <utility>
#include <vector>

#include "core/block.h"
#include "core/status.h"
#include "solvers/resection/resection.h"

namespace photopose {

struct BlockInitializationOptions {
  // The resection of each image (consensus, outlier tests, refinement).
  ResectionOptions resection;
  // Marks an image needs on points with known coordinates before it is resected (count): four
  // leave one redundant observation pair, so that a wrong P3P branch is caught.
  int min_marks_for_resection = 4;
  // A tie point is intersected when its rays meet at this angle or more (rad; 2 degrees).
  double min_intersection_angle_rad = 0.0349;
  // ... and its rays miss it by less than this RMS angle (rad; about 3 degrees). The orientations
  // are approximate here (start angles of a frames table are often a degree or two off), so the
  // marks' accuracy cannot judge the fit; a larger misfit means a blunder in its marks or a wrong
  // image orientation, and the point waits for more rays.
  double max_ray_misfit_rad = 0.05;
  // Accuracy of marks without one, in their own unit, for the intersections (core/mark_weight.h;
  // film marks take default_sigma_um whatever the pixel size: the orientations are approximate).
  double default_sigma_px = 1.0;  // pixel marks (px)
  double default_sigma_um = 5.0;  // film marks (um)
  int max_rounds = 50;  // of steps 2-3 (count)
};

struct BlockInitializationSummary {
  int images_given = 0;     // orientations that came with the block
  int images_resected = 0;  // oriented here
  int points_given = 0;     // tie points that came with coordinates
  int points_triangulated = 0;
  int rounds = 0;
  // Images still without orientation, with the reason.
  std::vector<std::pair<int, std::string>> not_oriented;
  // Tie points left without coordinates (too few rays, weak intersection, misfit).
  int points_not_triangulated = 0;
  // "12 images with initial values, 3 resected, 0 not oriented; 2 rounds".
  std::string ImagesReport() const;
  // "120 tie points with coordinates, 40 intersected, 1 not".
  std::string TiePointsReport() const;
  // Both in one line: "12 images with initial values, 3 resected, 0 not oriented; 120 tie points
  // with coordinates, 40 intersected, 1 not; 2 rounds".
  std::string BriefReport() const;
};

// Fills in the missing exterior orientations and tie-point coordinates of *block in place. Errors
// only for invalid options or a block without index; images that cannot be oriented are listed.
Status InitializeBlock(const BlockInitializationOptions& options, Block* block,
                       BlockInitializationSummary* summary);

// Removes the listed images (indices into block->images) with their marks, renumbers the rest and
// rebuilds the index. Points keep their indices.
void RemoveImages(const std::vector<std::pair<int, std::string>>& images, Block* block);

}  // namespace photopose
