#include "core/pixel_rows.h"

#include <gtest/gtest.h>

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// A few multiplications of numbers below 1e5: rounding stays below 1e-10 um.
constexpr double kFilmUm = 1e-9;

// A 1000 x 1000 scan of 20 um pixels with A0-B2 (pixel -> film) on rows counted down.
FrameCamera ScanCamera() {
  FrameCamera camera;
  camera.camera_id = "scan";
  camera.focal_length_um = 153000.0;
  camera.n_rows = 1000;
  camera.n_columns = 1000;
  camera.has_affine = true;
  camera.affine_a = {-10000.0, 20.0, 0.0};
  camera.affine_b = {10000.0, 0.0, -20.0};
  return camera;
}

TEST(PixelRows, RowCountedDownIsItsOwnInverseForEitherOrigin) {
  EXPECT_EQ(RowCountedDown(650.0, 1000, PixelOrigin::kCorner), 350.0);
  EXPECT_EQ(RowCountedDown(350.0, 1000, PixelOrigin::kCorner), 650.0);
  EXPECT_EQ(RowCountedDown(0.0, 1000, PixelOrigin::kCorner), 1000.0);  // the bottom edge
  // The centre of the bottom pixel: Row 0 counted up, 999 counted down, with (0, 0) at the first
  // pixel's centre; the centre of the top pixel the other way round.
  EXPECT_EQ(RowCountedDown(0.0, 1000, PixelOrigin::kCenter), 999.0);
  EXPECT_EQ(RowCountedDown(999.0, 1000, PixelOrigin::kCenter), 0.0);
  EXPECT_EQ(RowCountedDown(649.5, 1000, PixelOrigin::kCenter), 349.5);
}

// Worked by hand: the scan's film centre at pixel (500, 500), film x right and y up. The film point
// (2000, 3000) um lies at Column 600 and Row 500 - 3000 / 20 = 350 counted down, Row
// 1000 - 350 = 650 counted up. Counting down, y = 10000 - 20 Row; the scanner's software, counting
// rows up, states y = -10000 + 20 Row: B0-B2 = (-10000, 0, 20).
TEST(PixelRows, RowsCountedUpAndDownGiveTheSameFilmPoint) {
  const FrameCamera down = ScanCamera();
  FrameCamera up = down;
  up.affine_b = {-10000.0, 0.0, 20.0};
  Eigen::Vector2d film_down, film_up;
  ASSERT_TRUE(FilmFromPixel(down, {600.0, 350.0}, PixelOrigin::kCorner, &film_down).ok());
  ASSERT_TRUE(FilmFromPixel(up, {600.0, 650.0}, PixelOrigin::kCorner, &film_up).ok());
  EXPECT_EQ(film_down, Eigen::Vector2d(2000.0, 3000.0));
  EXPECT_EQ(film_up, Eigen::Vector2d(2000.0, 3000.0));
  // The reader's turn of the up camera is the down camera; turning again gives the up one back.
  FrameCamera turned = up;
  ASSERT_TRUE(AffineWithRowsFlipped(&turned).ok());
  EXPECT_EQ(turned.affine_a, down.affine_a);
  EXPECT_EQ(turned.affine_b, down.affine_b);
  ASSERT_TRUE(AffineWithRowsFlipped(&turned).ok());
  EXPECT_EQ(turned.affine_b, up.affine_b);
  // The centre origin: the same point is (599.5, 649.5) counted up, (599.5, 349.5) down.
  ASSERT_TRUE(FilmFromPixel(down, {599.5, RowCountedDown(649.5, 1000, PixelOrigin::kCenter)},
                            PixelOrigin::kCenter, &film_down).ok());
  EXPECT_NEAR((film_down - Eigen::Vector2d(2000.0, 3000.0)).norm(), 0.0, kFilmUm);
}

TEST(PixelRows, ATurnedScanTakesA2TimesNRowsIntoA0) {
  FrameCamera up = ScanCamera();
  up.affine_a = {-10000.0, 20.0, 0.1};  // a scan turned a little
  up.affine_b = {-10000.0, -0.1, 20.0};
  FrameCamera turned = up;
  ASSERT_TRUE(AffineWithRowsFlipped(&turned).ok());
  EXPECT_EQ(turned.affine_a[0], -10000.0 + 0.1 * 1000);
  EXPECT_EQ(turned.affine_a[2], -0.1);
  EXPECT_EQ(turned.affine_b[0], -10000.0 + 20.0 * 1000);
  EXPECT_EQ(turned.affine_b[2], -20.0);
  for (const double row_up : {0.0, 123.25, 650.0, 1000.0}) {
    Eigen::Vector2d film_up, film_down;
    ASSERT_TRUE(FilmFromPixel(up, {600.0, row_up}, PixelOrigin::kCorner, &film_up).ok());
    ASSERT_TRUE(FilmFromPixel(turned, {600.0, RowCountedDown(row_up, 1000, PixelOrigin::kCorner)},
                              PixelOrigin::kCorner, &film_down).ok());
    EXPECT_NEAR((film_up - film_down).norm(), 0.0, kFilmUm) << row_up;
  }
}

// AffineDirection -1 (film -> pixel): Column = 500 + x / 20, Row = 500 - y / 20 counted down,
// 500 + y / 20 counted up.
TEST(PixelRows, FilmToPixelAffineTurnsItsRowEquation) {
  FrameCamera down = ScanCamera();
  down.affine_direction = -1;
  down.affine_a = {500.0, 0.05, 0.0};
  down.affine_b = {500.0, 0.0, -0.05};
  FrameCamera up = down;
  up.affine_b = {500.0, 0.0, 0.05};
  FrameCamera turned = up;
  ASSERT_TRUE(AffineWithRowsFlipped(&turned).ok());
  EXPECT_EQ(turned.affine_a, down.affine_a);
  EXPECT_EQ(turned.affine_b, down.affine_b);
  Eigen::Vector2d film;
  ASSERT_TRUE(FilmFromPixel(up, {600.0, 650.0}, PixelOrigin::kCorner, &film).ok());
  EXPECT_NEAR((film - Eigen::Vector2d(2000.0, 3000.0)).norm(), 0.0, kFilmUm);
}

TEST(PixelRows, AffineWithoutNRowsCannotBeTurned) {
  FrameCamera camera = ScanCamera();
  camera.n_rows = 0;
  const Status refused = AffineWithRowsFlipped(&camera);
  EXPECT_EQ(refused.message(),
            "camera 'scan': rows counted up need NRows in the camera table (to turn A0-B2 to rows "
            "counted down)");
  EXPECT_EQ(camera.affine_b, ScanCamera().affine_b);  // unchanged
  // A camera without A0-B2 has nothing to turn.
  camera.has_affine = false;
  EXPECT_TRUE(AffineWithRowsFlipped(&camera).ok());
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
