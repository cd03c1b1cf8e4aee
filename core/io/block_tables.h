#pragma once
// A block written as photopose's tables (docs/formats.md): the camera table, the ground points,
// the image marks and the frames table, so that `photopose bundle --cameras --points --marks
// --frames` reads back the same block.
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
#include "core/io/tables.h"

namespace photopose {

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
