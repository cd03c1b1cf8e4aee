#pragma once
// COLMAP text models (cameras.txt, images.txt, points3D.txt) into a Block and back.
//
// COLMAP's conventions (https://colmap.github.io/format.html): an image's QW QX QY QZ TX TY TZ are
// the world -> camera rigid transformation x_cam = R(q) X + t, with COLMAP's camera frame x right,
// y down, z forward (the optical axis); pixel coordinates have (0, 0) at the top-left corner of
// the image (the centre of the first pixel is (0.5, 0.5)), x right (Column), y down (Row).
//
// The block sees them as follows (exactly, no approximation):
//  - exterior orientation (seed, core/types.h): EoFromComputerVisionPose(R(q), t) of
//    core/rotation.h: centre X0 = -R(q)^T t, and the seed's camera frame (u, v, w) = (x_cam,
//    -y_cam, -z_cam), so R_camera_from_ground = diag(1, -1, -1) R(q) and (omega, phi, kappa) =
//    AnglesFromRotation(kSeed, that matrix); writing inverts both steps (the quaternion written has
//    QW >= 0). A read-write round trip keeps R and the centre to
//    1e-12 and more (tests/core/io/colmap_test.cc).
//  - cameras: CAMERA_ID MODEL WIDTH HEIGHT PARAMS[] -> BlockCamera {camera_id = CAMERA_ID as text,
//    the COLMAP model of core/camera_models.h with its parameters in COLMAP's order, table.n_columns
//    = WIDTH, table.n_rows = HEIGHT}. SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV,
//    FULL_OPENCV and OPENCV_FISHEYE are read; any other model (FISHEYE, ...) is an error naming
//    file, line and model.
//  - images: IMAGE_ID ... CAMERA_ID NAME -> BlockImage {name = NAME (the rest of the line), eo};
//    their POINTS2D[] as (X, Y, POINT3D_ID): every entry with a POINT3D_ID becomes a BlockMark in
//    pixels (unit kPixel, observation = measured = (X, Y), no accuracy; line = the line of the
//    POINTS2D row); entries with POINT3D_ID -1 (keypoints without a 3D point) are no marks but are
//    kept in ColmapModelExtras::unmatched, so that a model written back has every entry, at its
//    index.
//  - points3D: POINT3D_ID X Y Z R G B ERROR TRACK[] -> BlockPoint {id = POINT3D_ID as text, role
//    tie, position_m = (X, Y, Z)}; R G B and ERROR go to ColmapModelExtras. Every TRACK entry
//    (IMAGE_ID, POINT2D_IDX) must name a POINTS2D entry that names this point, and every such entry
//    must be in the point's track (else an error naming file and line).
// Marks are in images.txt order (image by image, POINT2D index ascending).
//
// Reading is linear in the size of the files (ids are looked up in hash maps; lines and numbers
// are parsed in place); docs/performance.md has the figures for a 1.8-million-observation model.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/block.h"
#include "core/status.h"

namespace photopose {

// A POINTS2D entry without a 3D point (POINT3D_ID -1).
struct ColmapKeypoint {
  int image = -1;                                 // index into Block::images
  int index = 0;                                  // POINT2D_IDX in its image's POINTS2D list
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();   // pixels, COLMAP convention
};

// What a COLMAP model holds beyond the block, parallel to the block's vectors. Optional on
// writing: without it, images are numbered 1..n, cameras and points keep their ids when all are
// plain whole numbers (else 1..n), and each image's marks become its POINTS2D list in block order.
struct ColmapModelExtras {
  std::vector<long long> image_ids;         // per Block::images: IMAGE_ID
  std::vector<int> mark_keypoint_index;     // per Block::marks: its POINT2D_IDX in its image
  std::vector<int> num_keypoints;           // per Block::images: length of POINTS2D
  std::vector<ColmapKeypoint> unmatched;    // POINTS2D entries with POINT3D_ID -1
  std::vector<std::array<unsigned char, 3>> point_rgb;  // per Block::points: R G B
  std::vector<double> point_error_px;       // per Block::points: ERROR as read (px)
};

// Reads directory/cameras.txt, images.txt and points3D.txt into *block (replacing it; index
// built) and, when `extras` is not null, *extras. Errors read "file:line: field: what". Each file
// is read under ReadTextFile's rules (core/io/csv.h), and absurd values are refused at their line
// before any work: a focal length (f, fx, fy) below kMinFocalLengthPx or above kMaxCoordinate, a
// principal point, POINTS2D entry, translation or point coordinate beyond kMaxCoordinate in
// magnitude, a quaternion of norm 0 or above 1e12 (core/io/tables.h; docs/formats.md, "Limits and
// refusals").
Status ReadColmapModel(const std::string& directory, Block* block,
                       ColmapModelExtras* extras = nullptr);

// Writes the block as directory/cameras.txt, images.txt and points3D.txt (the directory is
// created when missing; each file written to a temporary file and renamed, after all three have
// been formatted, so that bad data leave nothing behind). `extras`, when given, must be the one
// read with this block (same sizes) and restores ids, keypoint indices, unmatched keypoints and
// colours. ERROR of each point is its mean reprojection error computed from the block
// (MeanReprojectionErrors), -1 when it cannot be computed.
// Cameras: COLMAP models as they are; a kFrame camera only when it is exactly a pinhole (no
// distortion, affinity or skew, a film <-> pixel mapping without rotation or shear): it is written
// as SIMPLE_PINHOLE (square pixels) or PINHOLE. Every image needs an exterior orientation. A point
// without a position is left out of points3D.txt and its marks are written with POINT3D_ID -1.
// Roles (control / check) and accuracies have no place in a COLMAP model and are not written.
Status WriteColmapModel(const std::string& directory, const Block& block,
                        const ColmapModelExtras* extras = nullptr);

// The three files of a COLMAP text model as WriteColmapModel writes them, formatted in memory (for
// callers that write them with other outputs as one transaction, core/io/output_files.h).
struct ColmapModelText {
  std::string cameras;   // cameras.txt
  std::string images;    // images.txt
  std::string points3D;  // points3D.txt
};
Status FormatColmapModel(const Block& block, const ColmapModelExtras* extras,
                         ColmapModelText* text);
// Whether FormatColmapModel can write the block's cameras and images (the errors it would give
// for them, at the cost of a look at each camera and image): to refuse an output before the work
// that would fill it.
Status CheckColmapModelWritable(const Block& block, const ColmapModelExtras* extras);
// ReadColmapModel on the three texts of a model; `directory` names them in messages.
Status ParseColmapModel(const ColmapModelText& text, const std::string& directory, Block* block,
                        ColmapModelExtras* extras = nullptr);

// The COLMAP camera (model and parameters, pixels with COLMAP's conventions) of a block camera:
// COLMAP models unchanged; a kFrame camera as described for WriteColmapModel, else an error.
Status ColmapCameraFromBlockCamera(const BlockCamera& camera, CameraModelType* model,
                                   std::vector<double>* params);

// The reprojection error of every mark (px: the norm of the residual of core/camera_models.h,
// divided by the mark's observation units per pixel for pixel marks), NaN when its image has no
// exterior orientation, its point no position, or the point is not in front of the camera.
void MarkReprojectionErrors(const Block& block, std::vector<double>* error_px);
// Per point, the mean of its marks' reprojection errors (px), COLMAP's ERROR column; -1 when any
// of its marks has none (see above) or it has no marks.
void MeanReprojectionErrors(const Block& block, std::vector<double>* point_error_px);

}  // namespace photopose
