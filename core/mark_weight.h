#pragma once
// The one rule for the weight of a mark: its standard deviation (sigma) in its camera model's
// observation unit (film um for kFrame, pixels for the COLMAP models). Every solver that weights
// marks (the bundle plan of the Ceres and Taylor adjustments, their statistics, the intersection
// of check points and of tie points) takes its sigmas from here.
//
//   1. the mark's own accuracy (BlockMark::accuracy, in the mark's unit) times
//      observation_units_per_unit;
//   2. else the default of its group in the mark's unit:
//      - pixel marks: pixel_px times observation_units_per_unit (um per pixel for a kFrame camera,
//        1 for the COLMAP models);
//      - film marks: pixel_px times the camera's pixel size (um) for a kFrame camera with a
//        PixelSize, when film_from_pixel_size; otherwise film_um.
// The group (tie or control marks) and its defaults are the caller's: the bundle adjustment's
// BundleAccuracies (tie_px / tie_film_um, marker_projection_px / marker_projection_film_um).

#include "core/block.h"

namespace photopose {

// The default sigmas of one group of marks, each in its own unit.
struct MarkSigmaDefaults {
  double pixel_px = 1.0;  // a pixel mark's sigma (px)
  double film_um = 5.0;   // a film mark's sigma (um) when the pixel size does not give one
  // Film marks of a kFrame camera with PixelSize take pixel_px times the pixel size (um): one
  // accuracy stated in pixels for both kinds of marks of a scanned or digital frame image.
  bool film_from_pixel_size = true;
};

// The sigma of `mark` in the observation unit of `camera` (its image's camera), by the rule above.
double MarkSigma(const BlockMark& mark, const BlockCamera& camera,
                 const MarkSigmaDefaults& defaults);

// True when MarkSigma gives `mark` its group's film_um: a film mark without an accuracy of its
// own whose camera does not turn pixel_px into micrometres (no kFrame camera with a PixelSize, or
// film_from_pixel_size off). The CLI refuses --film_tie_accuracy and
// --film_marker_projection_accuracy for a block without such a mark.
bool TakesFilmDefault(const BlockMark& mark, const BlockCamera& camera,
                      const MarkSigmaDefaults& defaults);

// True when MarkSigma gives `mark` its group's pixel_px (times the observation units or the pixel
// size): a mark without an accuracy of its own that does not take the film default. The CLI
// refuses --tie_accuracy and --marker_projection_accuracy for a block without such a mark.
bool TakesPixelDefault(const BlockMark& mark, const BlockCamera& camera,
                       const MarkSigmaDefaults& defaults);

}  // namespace photopose
