#include "tools/jobs/resection_job.h"

#include <cmath>
#include <cstdio>

#include "core/io/block_tables.h"
#include "core/io/tables.h"

namespace photopose::cli {

Status PrepareResectionJob(const ResectionJobOptions& options, ResectionJob* job) {
  Block block;
  PHOTOPOSE_RETURN_IF_ERROR(ReadBlock(options.files, &block));
  return PrepareResectionJob(std::move(block), options.input, job);
}

Status PrepareResectionJob(Block block, const ResectionInputOptions& options, ResectionJob* job) {
  ResectionJob result;
  result.block = std::move(block);
  const Block& b = result.block;
  for (size_t i = 0; i < b.images.size(); ++i) {
    if (b.marks_of_image[i].empty()) continue;  // a frames row only: nothing to resect
    ResectionInput input;
    std::vector<int> marks;
    PHOTOPOSE_RETURN_IF_ERROR(MakeResectionInput(b, static_cast<int>(i), options, &input, &marks));
    std::vector<int> checks;
    for (const int m : b.marks_of_image[i]) {
      const BlockPoint& point = b.points[b.marks[m].point];
      if (point.role == PointRole::kCheck) checks.push_back(m);
      if (point.role == PointRole::kTie) ++result.num_tie_marks;
    }
    result.images.push_back(static_cast<int>(i));
    result.inputs.push_back(std::move(input));
    result.input_marks.push_back(std::move(marks));
    result.check_marks.push_back(std::move(checks));
  }
  *job = std::move(result);
  return Status::Ok();
}

std::vector<CheckResidual> CheckResiduals(const ResectionJob& job, size_t input,
                                          const ExteriorOrientation& eo) {
  std::vector<CheckResidual> residuals;
  for (const int m : job.check_marks[input]) {
    CheckResidual check;
    check.mark = m;
    if (MarkResidual(job.block, m, eo, &check.residual).ok()) residuals.push_back(check);
  }
  return residuals;
}

Eigen::Vector3d OutputAnglesDeg(const ResectionJob& job, size_t input, RotationConvention rotation,
                                const ExteriorOrientation& eo) {
  return ConventionAnglesFromSeed(rotation, job.camera(input).table.angle_flags(),
                                  eo.angles_seed_rad()) *
         kDegreesPerRadian;
}

std::optional<Eigen::Vector3d> OutputAngleSigmasDeg(const ResectionJob& job, size_t input,
                                                    RotationConvention rotation,
                                                    const ResectionResult& result) {
  if (!result.has_covariance) return std::nullopt;
  const Eigen::Matrix3d J = ConventionFromSeedJacobian(
      rotation, job.camera(input).table.angle_flags(), result.eo.angles_seed_rad());
  const Eigen::Matrix3d covariance =
      J * result.covariance.bottomRightCorner<3, 3>() * J.transpose();
  return Eigen::Vector3d(covariance.diagonal().cwiseMax(0.0).cwiseSqrt() * kDegreesPerRadian);
}

const char* ResectionVerdictName(const ResectionResult& result) {
  if (result.success) return result.weak ? "weak" : "solved";
  if (result.ambiguous) return "ambiguous";
  if (result.accuracy_disagrees) return "accuracy_disagrees";
  return "not_solved";
}

std::string Sigma0Unit(const ResectionJob& job, size_t input, const ResectionResult& result) {
  if (result.accuracy_stated) return "";
  const std::vector<MarkUnit>& units = job.inputs[input].units;
  if (units.empty()) return "px";
  for (const MarkUnit unit : units)
    if (unit != units.front()) return "mark units";
  return EnumName(units.front());
}

}  // namespace photopose::cli
