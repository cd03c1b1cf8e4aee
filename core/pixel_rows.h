#pragma once
// Which way pixel rows count, and the turn from one way to the other (docs/conventions.md, "Rows
// counted up"). The house counts Row down from the top edge of the image (core/camera.h); some
// photogrammetric software and film scanners count it up from the bottom edge. The readers
// (AssembleBlock, core/io/block_tables.h) turn rows counted up into rows counted down -- the marks',
// the measured fiducials' and the camera table's A0-B2 alike -- so that everything after them sees
// rows counted down.

#include "core/camera.h"
#include "core/enum_names.h"
#include "core/status.h"

namespace photopose {

// kDown: Row 0 at the top edge, growing down (the house convention); kUp: Row 0 at the bottom
// edge, growing up.
enum class PixelRows { kDown, kUp };
inline constexpr EnumNameEntry<PixelRows> kPixelRowsNames[] = {{PixelRows::kDown, "down"},
                                                              {PixelRows::kUp, "up"}};
constexpr EnumNameTable<PixelRows> EnumNames(PixelRows) {
  return EnumNameTable<PixelRows>(kPixelRowsNames);
}

// A Row counted up as a Row counted down, and back (the map is its own inverse), in an image of
// n_rows rows: n_rows - row with PixelOrigin::kCorner, n_rows - 1 - row with kCenter (the bottom
// edge is Row 0 counted up and Row n_rows counted down at the corner origin).
double RowCountedDown(double row, int n_rows, PixelOrigin origin);

// The camera's A0-B2 for rows counted the other way (its own inverse; the affine acts on corner
// coordinates, FilmFromPixel, so the origin does not enter): with AffineDirection +1 (pixel ->
// film) A0 += A2 NRows, A2 = -A2, B0 += B2 NRows, B2 = -B2; with -1 (film -> pixel)
// B0 = NRows - B0, B1 = -B1, B2 = -B2. A camera without A0-B2 is unchanged; one with A0-B2 needs
// NRows (an error naming the camera otherwise).
Status AffineWithRowsFlipped(FrameCamera* camera);

}  // namespace photopose
