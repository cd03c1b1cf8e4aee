#include "core/mark_weight.h"

namespace photopose {

double MarkSigma(const BlockMark& mark, const BlockCamera& camera,
                 const MarkSigmaDefaults& defaults) {
  if (mark.accuracy) return *mark.accuracy * mark.observation_units_per_unit;
  if (mark.unit == MarkUnit::kPixel) return defaults.pixel_px * mark.observation_units_per_unit;
  if (TakesFilmDefault(mark, camera, defaults)) return defaults.film_um;
  return defaults.pixel_px * camera.table.pixel_size_um;
}

bool TakesFilmDefault(const BlockMark& mark, const BlockCamera& camera,
                      const MarkSigmaDefaults& defaults) {
  if (mark.accuracy || mark.unit != MarkUnit::kFilm) return false;
  return !(defaults.film_from_pixel_size && camera.model == CameraModelType::kFrame &&
           camera.table.pixel_size_um > 0.0);
}

bool TakesPixelDefault(const BlockMark& mark, const BlockCamera& camera,
                       const MarkSigmaDefaults& defaults) {
  return !mark.accuracy && !TakesFilmDefault(mark, camera, defaults);
}

}  // namespace photopose
