#pragma once
// A block read from and written as photopose's tables (docs/formats.md). Reading: ReadBlock reads
// the files (core/io/tables.h) and AssembleBlock pairs their records into a Block (core/block.h).
// Writing: the camera table, the ground points, the image marks and the frames table, so that
// `photopose bundle --cameras --points --marks --frames` reads back the same block.
//
//  - cameras: the kFrame cameras' camera-table rows with their current parameters
//    (SetFrameModelParams: affinity and skew folded into A0-B2). A block with a COLMAP-model camera
//    cannot be written as tables (write it as a COLMAP model, core/io/colmap.h).
//  - points: control and check points with their surveyed coordinates, AccuracyX/Y/Z when they
//    have one, and Role; tie points with a position as Role tie rows (approximate values) unless
//    BlockTableWriteOptions::write_tie_points is false.
//  - marks: Raster, PointID, Column/Row (pixel marks, in the block's pixel origin) or FilmX/FilmY
//    (film marks), Accuracy (pixels; a film mark's accuracy divided by the pixel size), CameraID.
//  - frames: one row per image that has a measured centre or an exterior orientation:
//    PerspectiveX/Y/Z = the measured centre (GNSS) when there is one, else the orientation's
//    centre (an approximate value); Omega/Phi/Kappa = the measured attitude when there is one, else
//    the orientation's angles (degrees, in options.rotation); and the extra columns AccuracyX,
//    AccuracyY, AccuracyZ (m) where the image has a centre accuracy and AccuracyOmega,
//    AccuracyPhi, AccuracyKappa (deg, seed angles; written only with the seed convention) where
//    it has an attitude accuracy. An image with neither centre nor angles gets no row.
// The block is checked (CheckBlock) and converted into the tables' records before the first table
// is written, so bad data leave nothing behind; each table is written to a temporary file and
// renamed (core/io/tables.h).

#include <string>
#include <vector>

#include "core/block.h"
#include "core/rotation.h"
#include "core/status.h"
#include "core/fiducials.h"
#include "core/pixel_rows.h"
#include "core/io/tables.h"

namespace photopose {

// ------------------------------------------------------------------ from the tables

// The tables of a block, as read by core/io/tables.h, and how to combine them.
struct BlockTables {
  std::vector<FrameCamera> cameras;
  std::vector<GroundPoint> points;
  std::vector<ImageMark> marks;
  std::vector<FrameRecord> frames;  // may be empty
  std::vector<MeasuredFiducial> fiducials;  // scanned film, may be empty
  std::string crs;                  // e.g. the gcp_list header
  RotationConvention frames_rotation = RotationConvention::kSeed;  // of the frames' accuracy angles
  // File names for messages ("file:line: column: what").
  std::string cameras_file, points_file, marks_file, frames_file, fiducials_file;
  PixelOrigin pixel_origin = PixelOrigin::kCorner;
  // Which way the marks', the measured fiducials' and the camera table's A0-B2 Row counts. Rows
  // counted up are turned to rows counted down here (RowCountedDown, AffineWithRowsFlipped), with
  // the camera's NRows: the block holds rows counted down.
  PixelRows pixel_rows = PixelRows::kDown;
  // A pixel mark farther outside its image than this fraction of the image size (per axis) is
  // refused (when the camera gives the size): it cannot be a measurement in that image.
  double max_outside_fraction = kMarkOutsideImageFraction;
  // Largest residual of a measured fiducial after the affine fit (um).
  double max_fiducial_residual_um = 30.0;
};

// Pairs marks with points, images with cameras and frames, converts every mark into its camera
// model's observation unit, and gives every point a role (marks of points without a row are tie
// points). Errors read "file:line: column: what is wrong".
//  - Images: in the order they first appear in the marks, then the frames-table images without
//    marks. The camera of an image is its marks' CameraID, else its frames row's, else the only
//    camera of the table. A frames row gives the initial eo and the measured centre (and angles)
//    with its AccuracyX/Y/Z (m) and AccuracyOmega/Phi/Kappa (degrees in the file's convention,
//    turned into seed-angle sigmas through the convention's Jacobian, correlations dropped).
//  - Points: the points-table rows in file order (control, check or tie as their Role says), then
//    the tie points that only marks name, in the order of their first mark.
//  - Marks: film marks are the observation as they are; pixel marks go through FilmFromPixel of
//    PixelToFilmCamera (their image's fiducial affine, or the camera table's map), and
//    observation_units_per_unit is the local um per pixel of that map (FilmUmPerPixel). A pixel mark
//    of a camera without PixelSize/NRows/NColumns (or A0-B2) is refused at its own line, as is one
//    farther than max_outside_fraction outside its image.
//  - Rows counted up (pixel_rows kUp): every pixel mark's and measured fiducial's Row is counted
//    down with its camera's NRows (refused at its line, field Row, when the camera has none), and
//    every camera's A0-B2 are turned to rows counted down (a camera with A0-B2 and no NRows is
//    refused); Block::marks[].measured and the cameras' tables then count rows down.
// Outputs are written only on success.
Status AssembleBlock(const BlockTables& tables, Block* block);

// The files of a block and how to read them; ReadBlock reads them (core/io/tables.h) and assembles.
struct BlockFiles {
  std::string cameras;   // camera table (required)
  std::string points;    // ground points (or gcp_list)
  std::string marks;     // image marks (or gcp_list)
  std::string gcp_list;  // OpenDroneMap gcp_list.txt instead of points + marks
  std::string frames;    // optional frames table
  std::string fiducials;  // optional measured fiducials of scanned film (core/fiducials.h)
  RotationConvention rotation = RotationConvention::kSeed;  // of the frames table
  PixelOrigin pixel_origin = PixelOrigin::kCorner;          // of the marks' Column/Row
  // Of the marks', fiducials' and A0-B2's Row (see BlockTables); rows counted up are refused with
  // a gcp_list, whose format counts them down.
  PixelRows pixel_rows = PixelRows::kDown;
  double max_fiducial_residual_um = 30.0;                   // see BlockTables
};
Status ReadBlock(const BlockFiles& files, Block* block);

// ------------------------------------------------------------------ to the tables

// Paths of the tables to write; an empty path leaves that table out.
struct BlockTableFiles {
  std::string cameras;
  std::string points;
  std::string marks;
  std::string frames;
};

struct BlockTableWriteOptions {
  RotationConvention rotation = RotationConvention::kSeed;  // of the frames table's angles
  bool write_tie_points = true;  // tie points with a position as Role tie rows
};

Status WriteBlockTables(const Block& block, const BlockTableFiles& files,
                        const BlockTableWriteOptions& options = BlockTableWriteOptions());

// The tables' records of a block (what WriteBlockTables writes), for callers that write them
// elsewhere or change them first.
struct BlockTableRecords {
  std::vector<FrameCamera> cameras;
  std::vector<GroundPoint> points;
  std::vector<ImageMark> marks;
  std::vector<FrameRecord> frames;
};
Status BlockToTableRecords(const Block& block, const BlockTableWriteOptions& options,
                           BlockTableRecords* records);

// The four tables' contents as WriteBlockTables writes them, formatted in memory (for callers that
// write them with other files as one transaction).
struct BlockTableText {
  std::string cameras;
  std::string points;
  std::string marks;
  std::string frames;
};
Status FormatBlockTables(const Block& block, const BlockTableWriteOptions& options,
                         BlockTableText* text);

}  // namespace photopose
