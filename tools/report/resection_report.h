#pragma once
// The outputs of `photopose resect`: the frames table of the solved images and the JSON report of
// every image (its verdict, pose, sigmas, marks and check residuals), from the job
// (tools/jobs/resection_job.h) and its results.

#include <string>
#include <vector>

#include "core/status.h"
#include "solvers/resection/resection.h"
#include "tools/jobs/resection_job.h"

namespace photopose::cli {

Status WriteResectionFrames(const std::string& path, const ResectionJobOptions& options,
                            const ResectionJob& job, const std::vector<ResectionResult>& results);
// `written` names the files of the run for the report's summary.
Status WriteResectionReport(const std::string& path, const ResectionJobOptions& options,
                            const ResectionJob& job, const std::vector<ResectionResult>& results,
                            const std::vector<std::string>& written);

}  // namespace photopose::cli
