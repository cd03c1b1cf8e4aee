#pragma once
// OpenSfM / OpenDroneMap reconstructions (reconstruction.json and tracks.csv) into a Block and
// back. ODM keeps them in <project>/opensfm/.
//
// OpenSfM's conventions (its documentation, "Geometric models", and its opensfm/io.py):
//  - reconstruction.json is a JSON array of reconstructions, the largest first. Each is an object
//    {"cameras": {id: camera}, "shots": {image name: shot}, "points": {track id: point},
//    "reference_lla": {"latitude", "longitude", "altitude"} (optional)}.
//  - a shot's "rotation" (a rotation vector, rad) and "translation" are the world -> camera rigid
//    transformation x_camera = R X + t; OpenSfM's camera frame is x right, y down, z forward, like
//    COLMAP's. "camera" names its camera; "gps_position" (m, the reconstruction's frame) and
//    "gps_dop" (m) are its GNSS position and accuracy when the images had them.
//  - the world frame is topocentric (x east, y north, z up, metres) around reference_lla when the
//    images had GNSS; the reference is in the reconstruction or in reference_lla.json beside it.
//  - cameras project into normalised image coordinates: pixels divided by s = max(width, height),
//    origin at the centre of the image, x right, y down. OpenSfM's pixel (OpenCV's: the centre of
//    the first pixel at (0, 0)) is s x_n + (width - 1) / 2, so in the COLMAP convention of the
//    block (the top-left corner of the image at (0, 0), the centre of the first pixel at (0.5,
//    0.5))
//      column = s x_n + width / 2,   row = s y_n + height / 2      (exactly, no half-pixel term).
//  - tracks.csv: an optional header line "OPENSFM_TRACKS_VERSION_v1" or "_v2" (none: version 0),
//    then one tab-separated line per observation: image, track id, feature id, x, y (normalised),
//    [scale (v1, v2),] r, g, b[, segmentation, instance (v2)].
//
// The block sees them as follows (exactly):
//  - the first reconstruction is read; the others are counted (OpenSfmExtras).
//  - shots -> BlockImage {name = shot id, eo = EoFromComputerVisionPose(R(rotation), translation)
//    (core/rotation.h)}, in the order of their ids.
//  - cameras -> BlockCamera {camera_id = its key, table.n_columns = width, table.n_rows = height}
//    with the COLMAP model (core/camera_models.h) that is the same projection in pixels, s =
//    max(width, height):
//      perspective (focal, k1, k2)               RADIAL (f s, width/2, height/2, k1, k2)
//      brown (focal_x, focal_y, c_x, c_y, k1, k2, p1, p2, k3)
//                                                FULL_OPENCV (focal_x s, focal_y s, width/2 + c_x
//                                                s, height/2 + c_y s, k1, k2, p1, p2, k3, 0, 0, 0)
//      radial (focal_x, focal_y, c_x, c_y, k1, k2), simple_radial (the same without k2)
//                                                OPENCV (fx, fy, cx, cy as brown, k1, k2, 0, 0)
//      fisheye (focal, k1, k2)                   OPENCV_FISHEYE (f s, f s, width/2, height/2, k1,
//                                                k2, 0, 0)
//      fisheye_opencv (focal_x, focal_y, c_x, c_y, k1, k2, k3, k4)
//                                                OPENCV_FISHEYE (fx, fy, cx, cy as brown, k1..k4)
//    A missing projection_type is perspective and a missing coefficient 0, as in OpenSfM; focal
//    lengths, width and height are required. Other projections (spherical, equirectangular, dual,
//    fisheye62, fisheye624) are refused naming the camera and the type.
//  - points -> BlockPoint {id = track id, role tie, position_m = coordinates}, in id order.
//  - tracks.csv -> BlockMark in pixels (unit kPixel, observation = measured = the pixel above, no
//    accuracy, line = its line in tracks.csv), in file order, for every entry whose image is a shot
//    and whose track is a point of the reconstruction; the other entries are counted, not errors.
//
// Errors are one line naming the file and the JSON path ("…/reconstruction.json: shots.\"a.jpg\".
// rotation: expected 3 numbers") or the line of tracks.csv ("…/tracks.csv:12: x: 'abc' is not a
// number"); files are read under ReadTextFile's rules (core/io/csv.h) and absurd values are refused
// as the COLMAP reader refuses them (core/io/tables.h: focal lengths in pixels below
// kMinFocalLengthPx, coordinates, translations and pixels beyond kMaxCoordinate, rotation vector
// components beyond kMaxRotationVectorRad, image sides outside [1, kMaxImageSidePx]).

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "core/block.h"
#include "core/status.h"

namespace photopose {

// The origin of OpenSfM's topocentric frame (WGS84).
struct OpenSfmReferenceLla {
  double latitude_deg = 0.0;
  double longitude_deg = 0.0;
  double altitude_m = 0.0;  // ellipsoidal height, as OpenSfM takes it from the images
};

// What a tracks.csv entry holds beyond the mark.
struct OpenSfmFeature {
  long long feature_id = 0;
  double scale = 0.0;  // feature size, normalised image units (v0: none, 0)
  std::array<double, 3> rgb = {0.0, 0.0, 0.0};
  long long segmentation = -1;  // v2
  long long instance = -1;      // v2
};

// What a reconstruction holds beyond the block, parallel to the block's vectors, and what reading
// left out. Optional on writing.
struct OpenSfmExtras {
  std::optional<OpenSfmReferenceLla> reference_lla;
  // The file the reference came from (reconstruction.json or reference_lla.json), empty without.
  std::string reference_lla_source;
  std::vector<std::string> projection_types;  // per Block::cameras: OpenSfM's projection_type
  // Per Block::images: the shot's GNSS position (m, the reconstruction's frame) and gps_dop (m).
  std::vector<std::optional<Eigen::Vector3d>> gps_position_m;
  std::vector<std::optional<double>> gps_dop_m;
  std::vector<std::array<double, 3>> point_rgb;  // per Block::points: "color"
  std::vector<OpenSfmFeature> mark_features;     // per Block::marks
  int tracks_version = 0;                        // 0, 1 or 2 as read
  // Reconstructions of reconstruction.json after the first, not read.
  int further_reconstructions = 0;
  // tracks.csv entries that are no marks: their image is not a shot / their track not a point of
  // the reconstruction read.
  long long tracks_of_other_images = 0;
  long long tracks_of_other_points = 0;
};

// Reads an OpenSfM reconstruction: `path` is reconstruction.json (or another file of that format,
// e.g. reconstruction.topocentric.json) or the folder holding reconstruction.json; tracks.csv must
// be beside it, reference_lla.json is read when it is there and the reconstruction has no
// reference_lla. Replaces *block (index built) and, when not null, *extras.
Status ReadOpenSfmReconstruction(const std::string& path, Block* block,
                                 OpenSfmExtras* extras = nullptr);

// The texts of a reconstruction, as read or as written.
struct OpenSfmText {
  std::string reconstruction_json;
  std::string tracks_csv;
  std::optional<std::string> reference_lla_json;  // reading only; absent: no such file
};
// ReadOpenSfmReconstruction on texts: `reconstruction_path` names reconstruction.json in
// messages, and tracks.csv and reference_lla.json are named as files beside it.
Status ParseOpenSfmReconstruction(const OpenSfmText& text, const std::string& reconstruction_path,
                                  Block* block, OpenSfmExtras* extras = nullptr);

// The block as reconstruction.json (one reconstruction, with reference_lla when the extras have
// one) and tracks.csv (version 2). Cameras: the projection type of the extras when the camera still
// is one exactly (e.g. perspective while the principal point stays at the centre and fx = fy),
// else the first of perspective, brown, fisheye, fisheye_opencv that is; a camera none of them is
// (FULL_OPENCV with k4..k6, any kFrame camera) is an error naming it. Every image
// needs an exterior orientation and a name without tab or line break; points without a position
// are left out with their marks. Marks keep feature id, scale, colour, segmentation and instance of
// the extras (without: feature id = index of the mark in its image, scale 0, colour 0 0 0,
// segmentation and instance -1), and points their colour (without: 0 0 0). tracks.csv entries that
// were no marks are not written.
Status FormatOpenSfmReconstruction(const Block& block, const OpenSfmExtras* extras,
                                   OpenSfmText* text);
// Writes directory/reconstruction.json and directory/tracks.csv as one transaction
// (core/io/output_files.h); the directory must exist.
Status WriteOpenSfmReconstruction(const std::string& directory, const Block& block,
                                  const OpenSfmExtras* extras = nullptr);

}  // namespace photopose
