#pragma once
// COLMAP models, text (cameras.txt, images.txt, points3D.txt) or binary (cameras.bin, images.bin,
// points3D.bin), into a Block and back.
//
// COLMAP's conventions (https://colmap.github.io/format.html): an image's QW QX QY QZ TX TY TZ are
// the world -> camera rigid transformation x_cam = R(q) X + t, with COLMAP's camera frame x right,
// y down, z forward (the optical axis); pixel coordinates have (0, 0) at the top-left corner of
// the image (the centre of the first pixel is (0.5, 0.5)), x right (Column), y down (Row).
//
// The block sees them as follows (exactly, no approximation):
//  - exterior orientation (seed, core/types.h): centre X0 = -R(q)^T t, and the seed's camera frame
//    (u, v, w) = (x_cam, -y_cam, -z_cam), so R_camera_from_ground = diag(1, -1, -1) R(q) and
//    (omega, phi, kappa) = AnglesFromRotation(kSeed, that matrix); writing inverts both steps
//    (the quaternion written has QW >= 0). A read-write round trip keeps R and the centre to
//    1e-12 and more (tests/core/io/colmap_test.cc).
//  - cameras: CAMERA_ID MODEL WIDTH HEIGHT PARAMS[] -> BlockCamera {camera_id = CAMERA_ID as text,
//    the COLMAP model of core/camera_models.h with its parameters in COLMAP's order,
//    table.n_columns = WIDTH, table.n_rows = HEIGHT}. The models core/camera_models.h has are read
//    (SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV, OPENCV_FISHEYE, FULL_OPENCV); any
//    other (FOV, THIN_PRISM_FISHEYE, ...)
//    is an error naming file, line (byte) and model.
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
// The binary files hold the same records (little-endian; COLMAP's src/base/reconstruction.cc):
//  cameras.bin: uint64 count; per camera uint32 CAMERA_ID, int32 MODEL_ID (0 SIMPLE_PINHOLE,
//    1 PINHOLE, 2 SIMPLE_RADIAL, 3 RADIAL, 4 OPENCV, 5 OPENCV_FISHEYE, 6 FULL_OPENCV, 7 FOV,
//    8 SIMPLE_RADIAL_FISHEYE, 9 RADIAL_FISHEYE, 10 THIN_PRISM_FISHEYE), uint64 WIDTH, HEIGHT,
//    double PARAMS[n(model)].
//  images.bin: uint64 count; per image uint32 IMAGE_ID, double QW QX QY QZ TX TY TZ, uint32
//    CAMERA_ID, NAME ending in a NUL byte, uint64 count, per POINTS2D entry double X Y, uint64
//    POINT3D_ID (2^64 - 1 for none, -1 in text).
//  points3D.bin: uint64 count; per point uint64 POINT3D_ID, double X Y Z, uint8 R G B, double
//    ERROR, uint64 track length, per entry uint32 IMAGE_ID, POINT2D_IDX.
// Both formats are parsed into the same records and checked and converted by the same code
// (core/io/internal/colmap_records.h), so a binary model reads as the text model with the same
// numbers, with the same refusals; binary errors read "file: byte N: field: what", N the offset
// of the record (of the entry, in POINTS2D and TRACK lists; of the field for a truncated or
// malformed one). Every count is checked against the bytes left before anything is allocated for
// it, and bytes after the last record are an error.
//
// Reading is linear in the size of the files (ids are looked up in hash maps; lines and numbers
// are parsed in place); docs/performance.md has the figures for a 1.8-million-observation model.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/block.h"
#include "core/enum_names.h"
#include "core/status.h"

namespace photopose {

class OutputFiles;  // core/io/output_files.h

// A POINTS2D entry without a 3D point (POINT3D_ID -1).
struct ColmapKeypoint {
  int image = -1;                                // index into Block::images
  int index = 0;                                 // POINT2D_IDX in its image's POINTS2D list
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();  // pixels, COLMAP convention
};

// What a COLMAP model holds beyond the block, parallel to the block's vectors. Optional on
// writing: without it, images are numbered 1..n, cameras and points keep their ids when all are
// plain whole numbers (else 1..n), and each image's marks become its POINTS2D list in block order.
struct ColmapModelExtras {
  std::vector<long long> image_ids;       // per Block::images: IMAGE_ID
  std::vector<int> mark_keypoint_index;   // per Block::marks: its POINT2D_IDX in its image
  std::vector<int> num_keypoints;         // per Block::images: length of POINTS2D
  std::vector<ColmapKeypoint> unmatched;  // POINTS2D entries with POINT3D_ID -1
  std::vector<std::array<unsigned char, 3>> point_rgb;  // per Block::points: R G B
  std::vector<double> point_error_px;                   // per Block::points: ERROR as read (px)
};

// The two file formats of a COLMAP model.
enum class ColmapFormat { kText, kBinary };
inline constexpr EnumNameEntry<ColmapFormat> kColmapFormatNames[] = {
    {ColmapFormat::kText, "text"}, {ColmapFormat::kBinary, "binary"}};
constexpr EnumNameTable<ColmapFormat> EnumNames(ColmapFormat) {
  return EnumNameTable<ColmapFormat>(kColmapFormatNames, NameMatch::kIgnoreCase);
}
// The names of the three files of a model: {"cameras.txt", "images.txt", "points3D.txt"} or the
// .bin ones.
std::array<const char*, 3> ColmapFileNames(ColmapFormat format);

// The format of the model in `directory`: binary when cameras.bin, images.bin and points3D.bin are
// all there (COLMAP's own preference), else text when the three .txt files are; else an error
// naming the folder and the files missing.
Status DetectColmapFormat(const std::string& directory, ColmapFormat* format);

// Reads the model in `directory` (DetectColmapFormat) into *block (replacing it; index built)
// and, when not null, *extras and *format (the format read). Errors read "file:line: field: what"
// (text) or "file: byte N: field: what" (binary). Each file is read under ReadTextFile's rules
// (core/io/csv.h: regular files only, at most kMaxInputBytes), and absurd values are refused at
// their record before any work: a focal length (f, fx, fy) below kMinFocalLengthPx or above
// kMaxCoordinate, a principal point, POINTS2D entry, translation or point coordinate beyond
// kMaxCoordinate in magnitude, a quaternion of norm 0 or above 1e12, a number that is not finite,
// an image size outside [1, 2^31 - 1] (core/io/tables.h; docs/formats.md, "Limits and refusals").
Status ReadColmapModel(const std::string& directory, Block* block,
                       ColmapModelExtras* extras = nullptr, ColmapFormat* format = nullptr);

// How a block is written as a COLMAP model.
struct ColmapWriteOptions {
  ColmapFormat format = ColmapFormat::kText;  // the three .txt files, or the three .bin files
  // Per Block::marks (or empty): the marks to leave out of the tracks (e.g. those a bundle
  // adjustment rejected). Each is written as a keypoint without a 3D point (POINT3D_ID -1) at its
  // POINT2D index, so that the indices of the others stay; a point that loses a mark this way and
  // keeps fewer than 2 is left out of points3D, its other marks written the same way. ERROR is
  // the mean over the marks kept.
  std::vector<char> marks_left_out;
};

// Writes the block as the three files of `options.format` in `directory` (created when missing;
// each file written to a temporary file and renamed, after all three have been formatted, so
// that bad data leave nothing behind). `extras`, when given, must be the one read with this block
// (same sizes) and restores ids, keypoint indices, unmatched keypoints and colours. ERROR of each
// point is its mean reprojection error computed from the block (MeanReprojectionErrors), -1 when
// it cannot be computed.
// Cameras: COLMAP models as they are; a kFrame camera only when it is exactly a pinhole (no
// distortion, affinity or skew, a film <-> pixel mapping without rotation or shear): it is written
// as SIMPLE_PINHOLE (square pixels) or PINHOLE. Every image needs an exterior orientation. A point
// without a position is left out of points3D and its marks are written with POINT3D_ID -1.
// Roles (control / check) and accuracies have no place in a COLMAP model and are not written.
// Binary ids: a CAMERA_ID above 2^32 - 1 (possible in text) makes all cameras numbered 1..n.
// The other format's files in the folder are left as they are (binary ones are read first).
Status WriteColmapModel(const std::string& directory, const Block& block,
                        const ColmapModelExtras* extras = nullptr,
                        const ColmapWriteOptions& options = ColmapWriteOptions());

// The three files of a COLMAP model (text, or the bytes of the binary files), in memory.
struct ColmapModelFiles {
  ColmapFormat format = ColmapFormat::kText;
  std::string cameras;   // cameras.txt / cameras.bin
  std::string images;    // images.txt / images.bin
  std::string points3D;  // points3D.txt / points3D.bin
};
// The files as WriteColmapModel writes them (for callers that write them with other outputs as
// one transaction, core/io/output_files.h).
Status FormatColmapModel(const Block& block, const ColmapModelExtras* extras,
                         const ColmapWriteOptions& options, ColmapModelFiles* files);
// FormatColmapModel's files staged in `outputs` as directory/cameras.txt ... (or .bin; added to
// `outputs` when not there yet), each written to its temporary file in pieces
// (core/io/output_files.h TextPieces): the model is never held whole as text (84 MB at a
// thousand images). For callers that write the model with other outputs as one transaction.
Status StageColmapModel(const Block& block, const ColmapModelExtras* extras,
                        const ColmapWriteOptions& options, const std::string& directory,
                        OutputFiles* outputs);
// Whether FormatColmapModel can write the block's cameras and images (the errors it would give
// for them, at the cost of a look at each camera and image): to refuse an output before the work
// that would fill it.
Status CheckColmapModelWritable(const Block& block, const ColmapModelExtras* extras);
// Whether the block's cameras stay COLMAP cameras when the parameters `calibrated_params` names
// (per camera, indices into BlockCamera::params; shorter or empty: none) are estimated: a kFrame
// camera is written as a pinhole, so its distortion, affinity and skew must stay 0. With
// CheckColmapModelWritable's camera checks, to refuse before any work a self-calibration whose
// result no COLMAP model could hold.
Status CheckColmapCamerasWritable(const Block& block,
                                  const std::vector<std::vector<int>>& calibrated_params);
// ReadColmapModel on the files of a model in memory (their format is files.format); `directory`
// names them in messages.
Status ParseColmapModel(const ColmapModelFiles& files, const std::string& directory, Block* block,
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
