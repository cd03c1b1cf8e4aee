#include "core/mark_weight.h"

namespace photopose {

double MarkSigma(const BlockMark& mark, const BlockCamera& camera,
                 const MarkSigmaDefaults& defaults) {
  if (mark.accuracy) return *mark.accuracy * mark.observation_units_per_unit;
  if (mark.unit == MarkUnit::kPixel) return defaults.pixel_px * mark.observation_units_per_unit;
  if (defaults.film_from_pixel_size && camera.model == CameraModelType::kFrame &&
      camera.table.pixel_size_um > 0.0)
    return defaults.pixel_px * camera.table.pixel_size_um;
  return defaults.film_um;
}

}  // namespace photopose
