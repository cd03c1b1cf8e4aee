#pragma once
// Bundle-adjustment problems of the computer-vision benchmarks into a Block:
//  - BAL ("Bundle Adjustment in the Large", Agarwal et al. 2010) problem files: a header
//    "num_cameras num_points num_observations", the observations "camera point x y", then 9
//    numbers per camera (Rodrigues rotation r, translation t, focal f, radial k1, k2) and 3 per
//    point, all separated by any white space;
//  - Bundler v0.3 .out files (Snavely): "# Bundle file v0.3", "num_cameras num_points", per camera
//    "f k1 k2", the three rows of R and t, per point its position, colour and view list
//    "n (camera key x y) x n".
//
// Both share one camera: P = R X + t (world -> camera, the camera looking down -z, x right, y up),
// p = -P / P.z, predicted = f (1 + k1 |p|^2 + k2 |p|^4) p, in pixels from the image centre with y
// UP; R = exp([r]x) for BAL (angle-axis), given for Bundler.
//
// Exactly, in the block:
//  - the camera frame (x right, y up, looking down -z) is the seed's (u, v, w): R_camera_from_ground
//    = R, centre X0 = -R^T t, (omega, phi, kappa) = AnglesFromRotation(kSeed, R) (Bundler's R,
//    printed with ten digits, is first made exactly orthonormal: its nearest rotation by SVD);
//    then (a, b) = (-u / w, -v / w) = p;
//  - each BAL / Bundler camera becomes one image and one COLMAP RADIAL camera (f, cx = 0, cy = 0,
//    k1, k2): COLMAP's pixel is f (1 + k1 r^2 + k2 r^4) (a, -b) + (cx, cy), so an observation
//    (x, y) becomes the mark (x, -y): pixels from the image centre (not the corner: cx = cy = 0),
//    y down. The residual of core/camera_models.h is then (-(predicted_x - x), predicted_y - y):
//    BAL's residual "predicted - observed" with its x component negated, the same squared norm
//    (tests/core/io/bal_test.cc checks it on the shared data at the files' initial values).
//  - names: image i and camera i are called "i" (the file's index), point j "j"; every point a
//    tie point with position_m from the file. A Bundler camera with f = 0 (not reconstructed) is
//    left out (its index is skipped in the names); a view of it is an error.
// Errors read "file:line: field: what". Reading is linear in the file size (no string per number).

#include <string>
#include <string_view>

#include "core/block.h"
#include "core/status.h"

namespace photopose {

// Values are refused at their line, before any work, when absurd: observations and coordinates
// (t, points) beyond kMaxCoordinate in magnitude, a rotation vector component beyond
// kMaxRotationVectorRad, a focal length below kMinFocalLengthPx or above kMaxCoordinate in
// magnitude (core/io/tables.h; docs/formats.md, "Limits and refusals").
Status ReadBalProblem(const std::string& path, Block* block);
// The same for the text of a BAL problem; `path` names it in messages.
Status ParseBalProblem(std::string_view text, const std::string& path, Block* block);

// `num_unregistered`, when not null, receives the number of cameras left out (f = 0).
Status ReadBundlerFile(const std::string& path, Block* block, int* num_unregistered = nullptr);

// BAL's cost at the block's current values: 1/2 sum over the marks of the squared residual of
// core/camera_models.h (pixels^2 for the COLMAP models), with (a, b) = (-u / w, -v / w) as BAL
// computes it even for a point behind its camera (counted in *num_behind when not null). Images
// without an exterior orientation or points without a position are an error.
Status ReprojectionCost(const Block& block, double* cost, int* num_behind = nullptr);

}  // namespace photopose
