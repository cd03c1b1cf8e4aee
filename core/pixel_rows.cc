#include "core/pixel_rows.h"

namespace photopose {

double RowCountedDown(double row, int n_rows, PixelOrigin origin) {
  // The centre origin sits half a pixel inside each edge: n_rows - 1/2 - (row + 1/2) - 1/2 + ...
  // collapses to n_rows - 1 - row.
  return n_rows - (origin == PixelOrigin::kCenter ? 1.0 : 0.0) - row;
}

Status AffineWithRowsFlipped(FrameCamera* camera) {
  if (!camera->has_affine) return Status::Ok();
  if (camera->n_rows <= 0)
    return Status::Error("camera '" + camera->camera_id +
                         "': rows counted up need NRows in the camera table (to turn A0-B2 to rows "
                         "counted down)");
  const double rows = camera->n_rows;
  auto& a = camera->affine_a;
  auto& b = camera->affine_b;
  if (camera->affine_direction > 0) {
    // film = A0 + A1 col + A2 (NRows - row'): the constant takes A2 NRows, the row term turns.
    a[0] += a[2] * rows;
    a[2] = -a[2];
    b[0] += b[2] * rows;
    b[2] = -b[2];
  } else {
    // row' = NRows - (B0 + B1 x + B2 y).
    b = {rows - b[0], -b[1], -b[2]};
  }
  return Status::Ok();
}

}  // namespace photopose
