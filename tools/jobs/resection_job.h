#pragma once
// From a block to resection inputs, and what every output of a solved input shows (its check
// residuals, angles in the asked convention, verdict): used by `photopose resect` and
// `photopose compare` (tools/compare). The tables and the JSON report of `resect` are written by
// tools/report/resection_report.h. The block (core/block.h) is the one assembly of the tables;
// every image with marks becomes one resection input (MakeResectionInput,
// solvers/resection/resection.h).

#include <string>
#include <vector>

#include "core/block.h"
#include "core/io/block_tables.h"
#include "core/rotation.h"
#include "core/status.h"
#include "solvers/resection/resection.h"

namespace photopose::cli {

struct ResectionJobOptions {
  BlockFiles files;              // the tables, their rotation convention and pixel origin
  ResectionInputOptions input;   // accuracy of marks without one
  ResectionOptions resection;
};

// The block and, per image that has marks (block order), its resection input.
struct ResectionJob {
  Block block;
  std::vector<int> images;                 // block image of each input
  std::vector<ResectionInput> inputs;
  std::vector<std::vector<int>> input_marks;  // block mark of each observation of each input
  std::vector<std::vector<int>> check_marks;  // block marks of the check points of each input
  int num_tie_marks = 0;                      // marks of tie points, left out of resection

  // The camera of input `input`'s image.
  const BlockCamera& camera(size_t input) const {
    return block.cameras[block.images[images[input]].camera];
  }
};

// Reads the tables (ReadBlock) and prepares the inputs.
Status PrepareResectionJob(const ResectionJobOptions& options, ResectionJob* job);
// The same from an assembled block.
Status PrepareResectionJob(Block block, const ResectionInputOptions& options, ResectionJob* job);

// The residual of one check mark (own unit, image-plane axes).
struct CheckResidual {
  int mark = -1;  // block mark
  Eigen::Vector2d residual = Eigen::Vector2d::Zero();
};
// Check-point residuals of a solved input (marks behind the camera are left out).
std::vector<CheckResidual> CheckResiduals(const ResectionJob& job, size_t input,
                                          const ExteriorOrientation& eo);

// The angles every output of a solved image shows: the convention asked for, the camera's
// AngleDirection applied (ConventionAnglesFromSeed), degrees.
Eigen::Vector3d OutputAnglesDeg(const ResectionJob& job, size_t input, RotationConvention rotation,
                                const ExteriorOrientation& eo);
// Their standard deviations (degrees) as the frames table writes them (empty without covariance).
std::optional<Eigen::Vector3d> OutputAngleSigmasDeg(const ResectionJob& job, size_t input,
                                                    RotationConvention rotation,
                                                    const ResectionResult& result);

// "solved", "weak" (solved, flagged), "ambiguous", "accuracy_disagrees" (the global test) or
// "not_solved" (any other reason; the message says it).
const char* ResectionVerdictName(const ResectionResult& result);

// The unit of sigma0 of a result: "" when the accuracy was stated (unitless), else the marks'.
std::string Sigma0Unit(const ResectionJob& job, size_t input, const ResectionResult& result);

}  // namespace photopose::cli
