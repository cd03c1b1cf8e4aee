#include "solvers/resection/resection.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "core/collinearity.h"
#include "core/parallel.h"
#include "solvers/resection/p3p.h"
#include "solvers/resection/point_configuration.h"

namespace photopose {
namespace {

using Clock = std::chrono::steady_clock;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Earth-curvature iterations stop when the projection centre moves less than this (m); the
// correction changes by D / R per metre of centre motion, ~1e-4 at D = 600 m.
constexpr double kEccCenterTolerance = 1e-4;
constexpr int kMaxEccPasses = 5;
// Two P3P poses closer than this fraction of the distance to the points are one pose.
constexpr double kSameP3PPose = 1e-6;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

std::string Number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.3g", value);
  return buffer;
}


// The marks' data in the form the stages need.
struct Marks {
  size_t n = 0;
  bool stated = false;          // every mark states its accuracy
  std::vector<double> weights;  // standard deviation in the image-plane unit (stated or 1 unit)
  std::vector<double> per_unit; // image-plane units per unit of the mark
  std::vector<MarkUnit> units;
  const std::vector<std::string>* ids = nullptr;  // point ids, for messages
  // 'P7', or #3 when the input names no points.
  std::string name(size_t i) const {
    return ids != nullptr && i < ids->size() ? "'" + (*ids)[i] + "'" : "#" + std::to_string(i + 1);
  }
};

Marks MarksOf(const ResectionInput& input) {
  Marks marks;
  marks.n = input.image_plane.size();
  marks.stated = !input.sigma.empty();
  for (size_t i = 0; i < marks.n; ++i) {
    const double sigma = input.sigma.empty() ? 0.0 : input.sigma[i];
    const double per_unit =
        input.observation_units_per_unit.empty() ? 1.0 : input.observation_units_per_unit[i];
    marks.stated = marks.stated && sigma > 0.0;
    marks.per_unit.push_back(per_unit);
    marks.weights.push_back((sigma > 0.0 ? sigma : 1.0) * per_unit);
    marks.units.push_back(input.units.empty() ? MarkUnit::kPixel : input.units[i]);
  }
  marks.ids = &input.point_ids;
  return marks;
}

// Ground points as the camera at `center` sees them: with ECC, lowered by D^2 / (2 R).
std::vector<Eigen::Vector3d> CameraPoints(const ResectionInput& input,
                                          const Eigen::Vector3d& center) {
  if (!(input.earth_radius_m > 0.0)) return input.points_in_ground;
  std::vector<Eigen::Vector3d> points = input.points_in_ground;
  for (Eigen::Vector3d& p : points) p.z() -= EarthCurvatureDrop(center, p, input.earth_radius_m);
  return points;
}

// Least squares over the marks in `indices`, with the earth-curvature correction iterated with the
// centre. On success *points holds the ground points as corrected for the final centre.
bool Adjust(const ResectionOptions& options, const ResectionInput& input,
            const std::vector<double>& sigmas, const std::vector<int>& indices,
            ExteriorOrientation* eo, std::vector<Eigen::Vector3d>* points,
            ResectionSummary* summary) {
  for (int pass = 0; pass < kMaxEccPasses; ++pass) {
    *points = CameraPoints(input, eo->center_in_ground());
    const Eigen::Vector3d center = eo->center_in_ground();
    PoseRefinementSummary refinement;
    const bool ok = RefinePose(options.refinement, input.image_plane, *points, sigmas,
                               input.focal_length, indices, eo, &refinement);
    if (summary->adjustments == 0 && pass == 0) summary->initial_cost = refinement.initial_cost;
    summary->iterations += refinement.iterations;
    summary->final_cost = refinement.final_cost;
    if (!ok) {
      summary->message = refinement.message;
      summary->termination = refinement.termination == SolverTermination::kNoConvergence
                                 ? SolverTermination::kNoConvergence
                                 : SolverTermination::kFailure;
      return false;
    }
    if (!(input.earth_radius_m > 0.0) ||
        (eo->center_in_ground() - center).norm() < kEccCenterTolerance)
      break;
  }
  *points = CameraPoints(input, eo->center_in_ground());
  ++summary->adjustments;
  return true;
}

// Number of distinct poses P3P finds for three marks.
int CountP3PPoses(const ResectionInput& input, const std::vector<int>& indices) {
  std::array<Eigen::Vector3d, 3> bearings, points;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector2d& xy = input.image_plane[indices[k]];
    bearings[k] = Eigen::Vector3d(xy.x(), xy.y(), -input.focal_length);
    points[k] = input.points_in_ground[indices[k]];
  }
  std::vector<PoseCandidate> solutions;
  SolveP3P(bearings, points, &solutions);
  std::vector<PoseCandidate> distinct;
  for (const PoseCandidate& s : solutions) {
    const double scale = (s.center_in_ground - points[0]).norm();
    const bool seen = std::any_of(distinct.begin(), distinct.end(), [&](const PoseCandidate& d) {
      return (d.center_in_ground - s.center_in_ground).norm() <= kSameP3PPose * scale;
    });
    if (!seen) distinct.push_back(s);
  }
  return static_cast<int>(distinct.size());
}

std::vector<int> Indices(const std::vector<char>& mask) {
  std::vector<int> indices;
  for (size_t i = 0; i < mask.size(); ++i)
    if (mask[i]) indices.push_back(static_cast<int>(i));
  return indices;
}

}  // namespace

bool ResectionOptions::IsValid(std::string* why) const {
  return consensus.ransac.IsValid(why) && test.IsValid(why) && refinement.IsValid(why);
}

std::string ResectionSummary::BriefReport() const {
  std::ostringstream os;
  os << EnumName(termination) << ", "
     << (used_approximate ? "approximate pose given"
                          : (ransac_exhaustive ? "consensus of every minimal sample" : "RANSAC"))
     << ", trials " << ransac_trials << ", adjustments " << adjustments << ", iterations "
     << iterations << ", cost " << initial_cost << " -> " << final_cost << ", "
     << total_seconds * 1e3 << " ms";
  if (!message.empty()) os << ": " << message;
  return os.str();
}

ResectionResult ResectImage(const ResectionOptions& options, const ResectionInput& input) {
  const Clock::time_point start = Clock::now();
  ResectionResult result;
  ResectionSummary& summary = result.summary;
  auto fail = [&](const std::string& message) {
    if (summary.termination == SolverTermination::kConverged)
      summary.termination = SolverTermination::kFailure;
    summary.message = message;
    summary.total_seconds = SecondsSince(start);
    result.success = false;
    return result;
  };
  std::string why;
  if (!options.IsValid(&why)) return fail("invalid options: " + why);
  const size_t n = input.image_plane.size();
  const auto sized = [n](size_t size) { return size == 0 || size == n; };
  if (input.points_in_ground.size() != n || !sized(input.sigma.size()) ||
      !sized(input.observation_units_per_unit.size()) || !sized(input.units.size()))
    return fail("observations, points, accuracies and units differ in number");
  if (!(input.focal_length > 0.0) || !std::isfinite(input.focal_length))
    return fail("the focal length must be positive");
  for (size_t i = 0; i < n; ++i) {
    if (!input.image_plane[i].allFinite()) return fail("an image observation is not finite");
    if (!input.sigma.empty() && !(input.sigma[i] >= 0.0 && std::isfinite(input.sigma[i])))
      return fail("an observation accuracy is negative or not finite");
    if (!input.observation_units_per_unit.empty() &&
        !(input.observation_units_per_unit[i] > 0.0 &&
          std::isfinite(input.observation_units_per_unit[i])))
      return fail("an observation unit scale is not positive");
  }
  const Status configuration = CheckControlConfiguration(input.points_in_ground);
  if (!configuration.ok()) return fail(configuration.message());
  const Marks marks = MarksOf(input);
  result.accuracy_stated = marks.stated;
  const double confidence = options.test.confidence;
  const double threshold = MarkThresholdSigmas(confidence);  // sigmas
  const auto percent = [confidence]() { return Number(100.0 * confidence) + "%"; };

  // 1. Initial values and the candidate marks.
  ExteriorOrientation eo;
  std::vector<char> candidate(n, 1);
  if (input.approximate.has_value()) {
    eo = *input.approximate;
    summary.used_approximate = true;
    if (!eo.parameters.allFinite()) return fail("the approximate pose is not finite");
    const std::vector<Eigen::Vector3d> points = CameraPoints(input, eo.center_in_ground());
    const SeedProjector projector(eo.data(), input.focal_length);
    for (size_t i = 0; i < n; ++i) {
      double xy[2];
      if (!projector.Project(points[i].data(), xy, nullptr, nullptr, nullptr))
        return fail("control point " + marks.name(i) +
                    " is behind the camera at the approximate pose");
    }
  } else {
    const Clock::time_point ransac_start = Clock::now();
    AbsolutePoseRansacOptions consensus = options.consensus;
    consensus.inlier_threshold = threshold;
    consensus.score = marks.stated ? ConsensusScore::kMsac : ConsensusScore::kLeastMedian;
    RansacSummary ransac;
    const Status status =
        EstimateAbsolutePoseRansac(consensus, input.image_plane, input.points_in_ground,
                                   marks.weights, input.focal_length, &eo, &candidate, &ransac);
    summary.ransac_trials = ransac.num_trials;
    summary.ransac_exhaustive = ransac.exhaustive;
    summary.ransac_seconds = SecondsSince(ransac_start);
    if (!status.ok()) return fail("no initial pose: " + status.message());
    // Four marks and no stated accuracy: the data cannot say which would not fit; all are taken.
    if (!marks.stated && n == 4) candidate.assign(n, 1);
  }

  // 2. Adjust, take back what fits, reject what the test rejects; until nothing changes.
  const Clock::time_point refine_start = Clock::now();
  std::vector<char> rejected(n, 0);
  std::vector<Eigen::Vector3d> points;
  PoseAdjustmentStatistics stats;
  double s0_squared = kNaN;
  const int max_rounds = 3 * static_cast<int>(n) + 3;
  for (int round = 0;; ++round) {
    if (round == max_rounds) return fail("the outlier decisions did not settle");
    if (!Adjust(options, input, marks.weights, Indices(candidate), &eo, &points, &summary))
      return fail(summary.message);
    const Status computed = ComputePoseAdjustmentStatistics(
        input.image_plane, points, marks.weights, input.focal_length, eo, candidate, &stats);
    if (!computed.ok()) return fail(computed.message());
    s0_squared = stats.redundancy > 0 ? stats.omega / stats.redundancy : kNaN;
    // Marks left out that fit this solution come back: their predicted residuals pass the test
    // (so when every mark fits the least-squares solution of all, all are kept).
    bool readmitted = false;
    const double readmit_critical = marks.stated
                                        ? threshold * threshold
                                        : PredictedCriticalValue(confidence, stats.redundancy);
    for (size_t i = 0; i < n; ++i) {
      if (candidate[i] || rejected[i] || !stats.in_front[i] || !stats.determined) continue;
      const double value =
          marks.stated ? stats.test_statistics[i] : stats.test_statistics[i] / s0_squared;
      if (value <= readmit_critical) {
        candidate[i] = 1;
        readmitted = true;
      }
    }
    if (readmitted) continue;
    // The test of the worst accepted mark.
    if (stats.num_used >= 5 && stats.determined) {
      const double critical = marks.stated ? SnoopingCriticalValue(confidence)
                                           : TauCriticalValue(confidence, stats.redundancy);
      int worst = -1;
      double worst_value = 0.0;
      for (size_t i = 0; i < n; ++i) {
        if (!candidate[i]) continue;
        const double value =
            marks.stated ? stats.test_statistics[i] : stats.test_statistics[i] / s0_squared;
        if (value > worst_value) {
          worst = static_cast<int>(i);
          worst_value = value;
        }
      }
      if (worst >= 0 && worst_value > critical) {
        candidate[worst] = 0;
        rejected[worst] = 1;
        continue;
      }
    }
    break;
  }
  summary.refinement_seconds = SecondsSince(refine_start);

  // 3. The verdict.
  const int accepted = stats.num_used;
  // Each mark left out, with its residual, for messages.
  const auto left_out = [&]() {
    std::string text;
    for (size_t i = 0; i < n; ++i) {
      if (candidate[i]) continue;
      const double residual = stats.whitened_residuals[i].norm() * marks.weights[i] / marks.per_unit[i];
      text += std::string(text.empty() ? "" : ", ") + marks.name(i) + " (" +
              (stats.in_front[i] ? Number(residual) + " " + EnumName(marks.units[i]) : "behind") +
              ")";
    }
    return text;
  };
  for (size_t i = 0; i < n; ++i) {
    if (!stats.in_front[i])
      return fail("control point " + marks.name(i) +
                  " lies behind the camera at the solution: the pose cannot have seen it");
  }
  if (accepted == 3) {
    const std::string dropped = left_out();
    const std::string what =
        n == 3 ? std::string("three control points determine the pose exactly and nothing checks it")
               : "only 3 of the " + std::to_string(n) + " marks agree (left out: " + dropped +
                     ") and nothing checks the pose they give";
    if (!options.allow_no_redundancy)
      return fail("no redundancy: " + what + "; add control points, or allow it explicitly");
    if (!input.approximate.has_value()) {
      const int poses = CountP3PPoses(input, Indices(candidate));
      if (poses > 1)
        return fail("ambiguous: " + std::to_string(poses) +
                    " poses fit the three accepted marks exactly; give approximate values to "
                    "choose one");
    }
    result.warnings.push_back("no redundancy: " + what + "; the pose has no standard deviations");
  }
  if (accepted == 4 && marks.stated) {
    const double critical = GlobalTestCriticalValue(confidence, 2);
    if (FailsGlobalTest(stats.omega, confidence, 2))
      return fail("the 4 accepted marks do not fit their stated accuracy (sum of squared "
                  "normalized residuals " + Number(stats.omega) + " > " + Number(critical) +
                  ", chi-square(2) at " + percent() + "): one of them is a blunder, and four marks "
                  "cannot show which" + (n > 4 ? " (left out: " + left_out() + ")" : ""));
  }
  if (accepted == 4 && !marks.stated) {
    result.warnings.push_back(
        "4 marks without a stated accuracy: a blunder among them cannot be detected (redundancy "
        "2); state their Accuracy to test them");
  }
  if (accepted >= 5 && marks.stated && FailsGlobalTest(stats.omega, confidence, stats.redundancy)) {
    result.warnings.push_back(
        "sigma0 = " + Number(std::sqrt(s0_squared)) +
        ": the accepted marks fit worse than their stated accuracy (global test at " + percent() +
        "); the Accuracy values may be too optimistic");
  }

  // 4. Statistics.
  result.eo = eo;
  result.num_inliers = accepted;
  result.degrees_of_freedom = stats.redundancy;
  result.sigma0 = stats.redundancy > 0 ? std::sqrt(s0_squared) : 0.0;
  if (!stats.determined)
    return fail("the normal matrix is singular: the pose is not determined by these points");
  if (stats.redundancy > 0) {
    result.has_covariance = true;
    result.covariance = s0_squared * stats.cofactor;
    result.standard_deviations = result.covariance.diagonal().cwiseSqrt();
  }
  const double critical = accepted >= 5 ? (marks.stated ? SnoopingCriticalValue(confidence)
                                                        : TauCriticalValue(confidence,
                                                                           stats.redundancy))
                                        : kNaN;
  result.critical_normalized_residual = std::sqrt(critical);
  result.residuals.resize(n);
  result.normalized_residuals.assign(n, kNaN);
  result.redundancy_numbers = stats.redundancy_numbers;
  result.mark_status.resize(n);
  result.inliers = candidate;
  for (size_t i = 0; i < n; ++i) {
    result.residuals[i] = stats.whitened_residuals[i] * marks.weights[i] / marks.per_unit[i];
    const bool testable = candidate[i] ? stats.redundancy_numbers[i] > 1e-6 : true;
    if (testable && stats.redundancy > (marks.stated ? 0 : 2)) {
      const double value =
          marks.stated ? stats.test_statistics[i] : stats.test_statistics[i] / s0_squared;
      result.normalized_residuals[i] = std::sqrt(value);
    }
    result.mark_status[i] = candidate[i] ? MarkStatus::kAccepted
                            : rejected[i] ? MarkStatus::kRejected
                                          : MarkStatus::kConsensusOutlier;
  }
  result.success = true;
  summary.termination = SolverTermination::kConverged;
  summary.message.clear();
  summary.total_seconds = SecondsSince(start);
  return result;
}

std::vector<ResectionResult> ResectImages(const ResectionOptions& options,
                                          const std::vector<ResectionInput>& inputs,
                                          int num_threads) {
  std::vector<ResectionResult> results(inputs.size());
  ParallelFor(inputs.size(), num_threads, [&](size_t i) {
    ResectionOptions image_options = options;
    // A distinct, reproducible RANSAC stream per image, whatever the thread schedule.
    image_options.consensus.ransac.seed =
        options.consensus.ransac.seed + 0x9E3779B97F4A7C15ull * (i + 1);
    results[i] = ResectImage(image_options, inputs[i]);
  });
  return results;
}

// ------------------------------------------------------------------ from a block

Status MakeResectionInput(const Block& block, int image, const ResectionInputOptions& options,
                          ResectionInput* input, std::vector<int>* marks) {
  if (image < 0 || image >= static_cast<int>(block.images.size()))
    return Status::Error("no image " + std::to_string(image) + " in the block");
  if (block.marks_of_image.size() != block.images.size())
    return Status::Error("the block's index is not built (Block::BuildIndex)");
  const BlockImage& block_image = block.images[image];
  const BlockCamera& camera = block.cameras[block_image.camera];
  const CameraModelData data = camera.data();
  const double focal = CameraModelFocal(camera.model, camera.params.data());
  ResectionInput result;
  result.raster = block_image.name;
  result.focal_length = focal;
  result.approximate = block_image.eo;
  if (camera.model == CameraModelType::kFrame && camera.table.apply_ecc)
    result.earth_radius_m = camera.table.earth_radius_m;
  std::vector<int> used;
  for (const int m : block.marks_of_image[image]) {
    const BlockMark& mark = block.marks[m];
    const BlockPoint& point = block.points[mark.point];
    const bool tie_with_position = options.include_tie_points_with_positions &&
                                   point.role == PointRole::kTie && point.position_m.has_value();
    if (!tie_with_position && (point.role != PointRole::kControl || !point.surveyed_m)) continue;
    Eigen::Vector2d ab;
    const Status status = NormalizedFromObservation(camera.model, camera.params.data(), data,
                                                    mark.observation, &ab);
    if (!status.ok()) {
      return Status::Error(block.marks_source + ":" + std::to_string(mark.line) +
                           ": the mark of point '" + point.id + "' in image '" +
                           block_image.name + "': " + status.message());
    }
    result.image_plane.push_back(focal * ab);
    result.points_in_ground.push_back(tie_with_position ? *point.position_m : *point.surveyed_m);
    result.sigma.push_back(mark.accuracy.value_or(options.default_accuracy));
    result.observation_units_per_unit.push_back(mark.observation_units_per_unit);
    result.units.push_back(mark.unit);
    result.point_ids.push_back(point.id);
    used.push_back(m);
  }
  *input = std::move(result);
  if (marks != nullptr) *marks = std::move(used);
  return Status::Ok();
}

Status MarkResidual(const Block& block, int mark_index, const ExteriorOrientation& eo,
                    Eigen::Vector2d* residual) {
  const BlockMark& mark = block.marks[mark_index];
  const BlockPoint& point = block.points[mark.point];
  if (!point.surveyed_m) return Status::Error("point '" + point.id + "' has no coordinates");
  const BlockCamera& camera = block.cameras[block.images[mark.image].camera];
  Eigen::Vector2d observed;
  PHOTOPOSE_RETURN_IF_ERROR(NormalizedFromObservation(camera.model, camera.params.data(),
                                                      camera.data(), mark.observation, &observed));
  Eigen::Vector3d p = *point.surveyed_m;
  if (camera.model == CameraModelType::kFrame && camera.table.apply_ecc)
    p.z() -= EarthCurvatureDrop(eo.center_in_ground(), p, camera.table.earth_radius_m);
  Eigen::Vector2d computed;
  if (!ProjectToNormalized(eo.data(), p.data(), computed.data()))
    return Status::Error("point '" + point.id + "' is behind the camera");
  const double focal = CameraModelFocal(camera.model, camera.params.data());
  *residual = focal * (observed - computed) / mark.observation_units_per_unit;
  return Status::Ok();
}

}  // namespace photopose
