#include "core/mark_weight.h"

#include <gtest/gtest.h>

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// Every branch is a product of two or three decimal numbers: exact to a few ulps.
constexpr double kTolerance = 1e-12;

BlockCamera FrameCamera(double pixel_size_um) {
  BlockCamera camera;
  camera.model = CameraModelType::kFrame;
  camera.table.pixel_size_um = pixel_size_um;
  return camera;
}

BlockMark Mark(MarkUnit unit, double units_per_unit) {
  BlockMark mark;
  mark.unit = unit;
  mark.observation_units_per_unit = units_per_unit;
  return mark;
}

MarkSigmaDefaults Defaults(double pixel_px, double film_um) {
  MarkSigmaDefaults defaults;
  defaults.pixel_px = pixel_px;
  defaults.film_um = film_um;
  return defaults;
}

TEST(MarkSigma, OwnAccuracyInItsUnitTimesObservationUnits) {
  // A pixel mark of a frame camera (4.5 um per pixel) stated at 0.3 px: 1.35 um.
  BlockMark pixel = Mark(MarkUnit::kPixel, 4.5);
  pixel.accuracy = 0.3;
  EXPECT_NEAR(MarkSigma(pixel, FrameCamera(4.5), Defaults(1.0, 5.0)), 1.35, kTolerance);
  // A film mark stated at 2 um stays 2 um, whatever the pixel size and defaults.
  BlockMark film = Mark(MarkUnit::kFilm, 1.0);
  film.accuracy = 2.0;
  EXPECT_NEAR(MarkSigma(film, FrameCamera(9.0), Defaults(0.5, 7.0)), 2.0, kTolerance);
}

TEST(MarkSigma, PixelMarkDefaultTimesObservationUnits) {
  // 0.5 px at 6 um per pixel: 3 um on the film of a frame camera.
  EXPECT_NEAR(MarkSigma(Mark(MarkUnit::kPixel, 6.0), FrameCamera(6.0), Defaults(0.5, 2.5)), 3.0,
              kTolerance);
  // A COLMAP camera observes in pixels: 0.5 px.
  BlockCamera colmap;
  colmap.model = CameraModelType::kSimpleRadial;
  EXPECT_NEAR(MarkSigma(Mark(MarkUnit::kPixel, 1.0), colmap, Defaults(0.5, 2.5)), 0.5, kTolerance);
}

TEST(MarkSigma, FilmMarkOfAFrameCameraWithPixelSizeTakesThePixelDefault) {
  // 0.5 px of 9 um: 4.5 um, not the film default of 2.5 um.
  EXPECT_NEAR(MarkSigma(Mark(MarkUnit::kFilm, 1.0), FrameCamera(9.0), Defaults(0.5, 2.5)), 4.5,
              kTolerance);
}

TEST(MarkSigma, FilmMarkWithoutPixelSizeTakesTheFilmDefault) {
  EXPECT_NEAR(MarkSigma(Mark(MarkUnit::kFilm, 1.0), FrameCamera(0.0), Defaults(0.5, 2.5)), 2.5,
              kTolerance);
  // The pixel size of a non-frame camera does not enter.
  BlockCamera colmap = FrameCamera(9.0);
  colmap.model = CameraModelType::kSimpleRadial;
  EXPECT_NEAR(MarkSigma(Mark(MarkUnit::kFilm, 1.0), colmap, Defaults(0.5, 2.5)), 2.5, kTolerance);
}

TEST(MarkSigma, FilmDefaultAsGivenWhenThePixelSizeIsNotToBeUsed) {
  MarkSigmaDefaults defaults = Defaults(0.5, 5.0);
  defaults.film_from_pixel_size = false;
  EXPECT_NEAR(MarkSigma(Mark(MarkUnit::kFilm, 1.0), FrameCamera(9.0), defaults), 5.0, kTolerance);
  // Pixel marks are unaffected: 0.5 px at 9 um per pixel.
  EXPECT_NEAR(MarkSigma(Mark(MarkUnit::kPixel, 9.0), FrameCamera(9.0), defaults), 4.5, kTolerance);
}

// A COLMAP camera (pixels) with a pixel size that must not enter.
BlockCamera ColmapCamera() {
  BlockCamera camera = FrameCamera(9.0);
  camera.model = CameraModelType::kSimpleRadial;
  return camera;
}

MarkSigmaDefaults WithoutPixelSize(MarkSigmaDefaults defaults) {
  defaults.film_from_pixel_size = false;
  return defaults;
}

// A mark, its camera and defaults, and whether it takes the default a test is about.
struct TakesCase {
  BlockMark mark;
  BlockCamera camera;
  MarkSigmaDefaults defaults;
  bool takes;
};

// TakesFilmDefault says exactly when MarkSigma returns film_um: a film default no other value can
// equal (0.123 um) tells.
TEST(TakesFilmDefault, ExactlyWhenMarkSigmaReturnsTheFilmDefault) {
  constexpr double kFilmDefaultUm = 0.123;
  BlockMark own = Mark(MarkUnit::kFilm, 1.0);
  own.accuracy = 2.0;
  const BlockCamera colmap = ColmapCamera();
  const MarkSigmaDefaults no_pixel_size = WithoutPixelSize(Defaults(0.5, kFilmDefaultUm));
  const TakesCase cases[] = {
      {Mark(MarkUnit::kFilm, 1.0), FrameCamera(0.0), Defaults(0.5, kFilmDefaultUm), true},
      {Mark(MarkUnit::kFilm, 1.0), colmap, Defaults(0.5, kFilmDefaultUm), true},
      {Mark(MarkUnit::kFilm, 1.0), FrameCamera(9.0), no_pixel_size, true},
      {Mark(MarkUnit::kFilm, 1.0), FrameCamera(9.0), Defaults(0.5, kFilmDefaultUm), false},
      {own, FrameCamera(0.0), Defaults(0.5, kFilmDefaultUm), false},
      {Mark(MarkUnit::kPixel, 1.0), FrameCamera(0.0), Defaults(0.5, kFilmDefaultUm), false},
  };
  for (const auto& c : cases) {
    EXPECT_EQ(TakesFilmDefault(c.mark, c.camera, c.defaults), c.takes);
    EXPECT_EQ(MarkSigma(c.mark, c.camera, c.defaults) == kFilmDefaultUm, c.takes);
  }
}

// TakesPixelDefault says exactly when MarkSigma depends on the pixel default: two pixel defaults
// give two sigmas for such a mark and one for every other.
TEST(TakesPixelDefault, ExactlyWhenMarkSigmaDependsOnThePixelDefault) {
  BlockMark own = Mark(MarkUnit::kPixel, 1.0);
  own.accuracy = 0.7;
  const BlockCamera colmap = ColmapCamera();
  const MarkSigmaDefaults no_pixel_size = WithoutPixelSize(Defaults(0.5, 2.5));
  const TakesCase cases[] = {
      {Mark(MarkUnit::kPixel, 1.0), colmap, Defaults(0.5, 2.5), true},
      {Mark(MarkUnit::kPixel, 6.0), FrameCamera(6.0), Defaults(0.5, 2.5), true},
      {Mark(MarkUnit::kFilm, 1.0), FrameCamera(9.0), Defaults(0.5, 2.5), true},
      {Mark(MarkUnit::kFilm, 1.0), FrameCamera(0.0), Defaults(0.5, 2.5), false},
      {Mark(MarkUnit::kFilm, 1.0), colmap, Defaults(0.5, 2.5), false},
      {Mark(MarkUnit::kFilm, 1.0), FrameCamera(9.0), no_pixel_size, false},
      {own, colmap, Defaults(0.5, 2.5), false},
  };
  for (const auto& c : cases) {
    MarkSigmaDefaults other = c.defaults;
    other.pixel_px *= 3.0;
    EXPECT_EQ(TakesPixelDefault(c.mark, c.camera, c.defaults), c.takes);
    EXPECT_EQ(MarkSigma(c.mark, c.camera, c.defaults) != MarkSigma(c.mark, c.camera, other),
              c.takes);
  }
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
