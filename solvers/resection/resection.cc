// Single-image resection (resection.h): input checks and weights, initial values (approximate pose
// or consensus), adjustment with rejection, the verdict, per-mark statistics, the search for a
// competing pose and the reliability. One file past ~800 lines on purpose: the steps of one
// image's resection in the order they run (ImageResection), and the batch over images.
#include "solvers/resection/resection.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <numeric>
#include <cstdio>
#include <limits>
#include <mutex>
#include <set>
#include <sstream>

#include "core/collinearity.h"
#include "core/mark_weight.h"
#include "core/parallel.h"
#include "core/simulation/portable_random.h"
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
// Fewest marks for which the consensus may stop at a model every mark fits (ResectionOptions).
constexpr size_t kMinMarksToStopConsensus = 6;

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
// Written into *points, whose storage is reused.
void CameraPoints(const ResectionInput& input, const Eigen::Vector3d& center,
                  std::vector<Eigen::Vector3d>* points) {
  *points = input.points_in_ground;
  if (!(input.earth_radius_m > 0.0)) return;
  for (Eigen::Vector3d& p : *points) p.z() -= EarthCurvatureDrop(center, p, input.earth_radius_m);
}

// Least squares over the marks in `indices`, with the earth-curvature correction iterated with the
// centre. On success *points holds the ground points as corrected for the final centre.
bool Adjust(const ResectionOptions& options, const ResectionInput& input,
            const std::vector<double>& sigmas, const std::vector<int>& indices,
            ExteriorOrientation* eo, std::vector<Eigen::Vector3d>* points,
            ResectionSummary* summary) {
  for (int pass = 0; pass < kMaxEccPasses; ++pass) {
    CameraPoints(input, eo->center_in_ground(), points);
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
  CameraPoints(input, eo->center_in_ground(), points);
  ++summary->adjustments;
  return true;
}

// The poses P3P gives for the marks of `triple` (up to four), written into *poses.
void P3PPoses(const ResectionInput& input, const std::array<int, 3>& triple,
              std::vector<ExteriorOrientation>* poses) {
  std::array<Eigen::Vector3d, 3> bearings, points;
  for (int t = 0; t < 3; ++t) {
    const Eigen::Vector2d& xy = input.image_plane[triple[t]];
    bearings[t] = Eigen::Vector3d(xy.x(), xy.y(), -input.focal_length);
    points[t] = input.points_in_ground[triple[t]];
  }
  thread_local std::vector<PoseCandidate> solutions;
  solutions.clear();
  SolveP3P(bearings, points, &solutions);
  poses->resize(solutions.size());
  for (size_t k = 0; k < solutions.size(); ++k) {
    (*poses)[k] = ExteriorOrientation();
    (*poses)[k].set_center_in_ground(solutions[k].center_in_ground);
    (*poses)[k].set_angles_seed_rad(
        AnglesFromRotation(RotationConvention::kSeed, solutions[k].R_camera_from_ground));
  }
}

// Number of distinct poses P3P finds for three marks.
int CountP3PPoses(const ResectionInput& input, const std::vector<int>& indices) {
  std::vector<ExteriorOrientation> poses;
  P3PPoses(input, {indices[0], indices[1], indices[2]}, &poses);
  std::vector<Eigen::Vector3d> distinct;
  for (const ExteriorOrientation& pose : poses) {
    const Eigen::Vector3d center = pose.center_in_ground();
    const double scale = (center - input.points_in_ground[indices[0]]).norm();
    const bool seen = std::any_of(distinct.begin(), distinct.end(), [&](const Eigen::Vector3d& d) {
      return (d - center).norm() <= kSameP3PPose * scale;
    });
    if (!seen) distinct.push_back(center);
  }
  return static_cast<int>(distinct.size());
}

// The indices of the set marks, written into *indices (storage reused).
void Indices(const std::vector<char>& mask, std::vector<int>* indices) {
  indices->clear();
  for (size_t i = 0; i < mask.size(); ++i)
    if (mask[i]) indices->push_back(static_cast<int>(i));
}

std::vector<int> Indices(const std::vector<char>& mask) {
  std::vector<int> indices;
  indices.reserve(mask.size());
  Indices(mask, &indices);
  return indices;
}


// Largest |a - b| over the six parameters in the standard deviations `sigmas` (angles wrapped).
double PoseDistanceSigmas(const ExteriorOrientation& a, const ExteriorOrientation& b,
                          const Vector6d& sigmas) {
  double largest = 0.0;
  for (int k = 0; k < 6; ++k) {
    const double d = k < 3 ? a.parameters[k] - b.parameters[k]
                           : WrapAngle(a.parameters[k] - b.parameters[k]);
    largest = std::max(largest, std::abs(d) / sigmas[k]);
  }
  return largest;
}

// The least squares of the marks in `set` from *eo (written back); false when it fails. *points
// receives the ground points as corrected at the adjusted centre. The index list is kept per
// thread: the ambiguity search adjusts many sets per image.
bool AdjustSet(const ResectionOptions& options, const ResectionInput& input,
               const std::vector<double>& weights, const std::vector<char>& set,
               ExteriorOrientation* eo, std::vector<Eigen::Vector3d>* points) {
  thread_local std::vector<int> indices;
  Indices(set, &indices);
  ResectionSummary ignored;
  return Adjust(options, input, weights, indices, eo, points, &ignored);
}

// Whether the marks in `set` (stated accuracy), adjusted at `eo` with the ground points `points`
// (AdjustSet), pass the global test and, with five or more and `snoop`, no mark's test statistic
// exceeds the snooping value. Only the tests are computed, not the reliability.
bool SetPassesTests(const ResectionOptions& options, const ResectionInput& input,
                    const std::vector<double>& weights, const std::vector<char>& set, bool snoop,
                    const ExteriorOrientation& eo, const std::vector<Eigen::Vector3d>& points) {
  const double confidence = options.test.confidence;
  thread_local PoseAdjustmentStatistics stats;
  if (!ComputePoseAdjustmentStatistics(input.image_plane, points, weights, input.focal_length, eo,
                                       set, &stats, StatisticsScope::kTests)
           .ok() ||
      !stats.determined || FailsGlobalTest(stats.omega, confidence, stats.redundancy))
    return false;
  if (!snoop || stats.num_used < 5) return true;
  for (size_t i = 0; i < set.size(); ++i)
    if (set[i] && stats.test_statistics[i] > SnoopingCriticalValue(confidence)) return false;
  return true;
}

// Whether the marks in `set` (stated accuracy) fit one pose: their least squares from *eo (written
// back, AdjustSet) passes the tests (SetPassesTests).
bool SetFitsItsAccuracy(const ResectionOptions& options, const ResectionInput& input,
                        const std::vector<double>& weights, const std::vector<char>& set,
                        bool snoop, ExteriorOrientation* eo) {
  thread_local std::vector<Eigen::Vector3d> points;
  return AdjustSet(options, input, weights, set, eo, &points) &&
         SetPassesTests(options, input, weights, set, snoop, *eo, points);
}

// A pose supported by a competing consensus set: its marks and the least squares over them.
struct CompetingPose {
  ExteriorOrientation eo;
  std::vector<char> inliers;
  double distance_sigmas = 0.0;  // from the accepted pose, in its standard deviations
};

// Whether at least `min_size` marks lie within `threshold` whitened units of the pose `eo` (in
// front of the camera). When so, *fits flags them (1) and the rest (0). The search asks only
// whether a set can reach the accepted set's size, so the count stops as soon as the marks left
// cannot bring it there (*fits then partly written). Each mark's test is the one of the whole
// set: its ground point lowered by the earth-curvature drop at this centre (CameraPoints), one
// SeedProjector projection, the whitened residual norm against the threshold.
bool ConsensusAt(const ResectionInput& input, const std::vector<double>& weights,
                 const ExteriorOrientation& eo, double threshold, int min_size,
                 std::vector<char>* fits) {
  const int n = static_cast<int>(input.points_in_ground.size());
  fits->resize(n);
  if (min_size > n) return false;
  const bool lowered = input.earth_radius_m > 0.0;
  const Eigen::Vector3d center = eo.center_in_ground();
  const SeedProjector projector(eo.data(), input.focal_length);
  int misses_left = n - min_size;  // marks that may still fail before the set is too small
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d point = input.points_in_ground[i];
    if (lowered) point.z() -= EarthCurvatureDrop(center, point, input.earth_radius_m);
    double xy[2];
    const bool fit =
        projector.Project(point.data(), xy, nullptr, nullptr, nullptr) &&
        (input.image_plane[i] - Eigen::Vector2d(xy[0], xy[1])).norm() / weights[i] <= threshold;
    (*fits)[i] = fit ? 1 : 0;
    if (!fit && --misses_left < 0) return false;
  }
  return true;
}

// The P3P triples FindCompetingPose tries: those with a mark outside `accepted`, all of them or a
// seeded random max_exhaustive_samples (each drawn with its first mark outside).
std::vector<std::array<int, 3>> CompetitorTriples(const ResectionOptions& options, const std::vector<char>& accepted,
                                                  const std::vector<int>& outside) {
  const int n = static_cast<int>(accepted.size());
  std::vector<std::array<int, 3>> triples;
  const auto has_outside = [&](int i, int j, int k) { return !accepted[i] || !accepted[j] || !accepted[k]; };
  const long long all = static_cast<long long>(n) * (n - 1) * (n - 2) / 6;
  const int limit = options.consensus.ransac.max_exhaustive_samples;
  if (all <= limit) {
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j)
        for (int k = j + 1; k < n; ++k)
          if (has_outside(i, j, k)) triples.push_back({i, j, k});
  } else {
    PortableRandom random(options.consensus.ransac.seed, /*stream=*/0xA3B1);
    while (static_cast<int>(triples.size()) < limit) {
      const int i = outside[random.Below(outside.size())];
      const int j = static_cast<int>(random.Below(n));
      const int k = static_cast<int>(random.Below(n));
      if (i != j && j != k && i != k) triples.push_back({i, j, k});
    }
  }
  return triples;
}

// Settles the consensus set of a P3P hypothesis: its marks within twice the threshold (a
// three-point pose carries the noise of three marks) adjusted, then the marks within the threshold
// of that adjustment, until the set repeats (at most a few passes). A set smaller than `size`, or
// one in *tried (every set met is added), ends it. True with the settled set in *set and its
// least squares in *hypothesis.
bool SettleConsensus(const ResectionOptions& options, const ResectionInput& input,
                     const std::vector<double>& weights, double threshold, int size,
                     ExteriorOrientation* hypothesis, std::set<std::vector<char>>* tried,
                     std::vector<char>* set, std::vector<char>* next) {
  constexpr int kMaxSettlingPasses = 4;
  bool large = ConsensusAt(input, weights, *hypothesis, 2.0 * threshold, size, set);
  bool settled = false;
  for (int pass = 0; pass < kMaxSettlingPasses && !settled; ++pass) {
    if (!large || !tried->insert(*set).second) break;
    thread_local std::vector<Eigen::Vector3d> adjusted_points;
    if (!AdjustSet(options, input, weights, *set, hypothesis, &adjusted_points)) break;
    large = ConsensusAt(input, weights, *hypothesis, threshold, size, next);
    settled = large && *next == *set;
    if (!settled) set->swap(*next);
  }
  return settled;
}

// Looks for a consensus set other than `accepted`, at least as large, that passes the tests the
// accepted set passed (global test, no mark beyond the snooping value) and whose least-squares
// pose lies more than options.ambiguous_pose_sigmas of `sigmas` from `eo`. Hypotheses: P3P on
// triples with a mark outside `accepted` (any competitor has one), all of them or a seeded random
// max_exhaustive_samples; each hypothesis's consensus set is settled (SettleConsensus). A set
// smaller than `accepted` ends a hypothesis, and a set met before is not adjusted again: a
// hypothesis costs P3P and a count that stops once the set can no longer reach the accepted size.
bool FindCompetingPose(const ResectionOptions& options, const ResectionInput& input,
                       const std::vector<double>& weights, const std::vector<char>& accepted,
                       const ExteriorOrientation& eo, const Vector6d& sigmas,
                       CompetingPose* competitor) {
  const int n = static_cast<int>(accepted.size());
  const int size = static_cast<int>(std::count(accepted.begin(), accepted.end(), 1));
  std::vector<int> outside;
  for (int i = 0; i < n; ++i)
    if (!accepted[i]) outside.push_back(i);
  if (outside.empty() || size < 4) return false;
  const double threshold = MarkThresholdSigmas(options.test.confidence);
  const std::vector<std::array<int, 3>> triples = CompetitorTriples(options, accepted, outside);
  // Each mark's bearing normalised once (SolveP3P's own normalisation, so the same poses).
  std::vector<Eigen::Vector3d> unit_bearings(n);
  std::vector<char> has_bearing(n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d& xy = input.image_plane[i];
    has_bearing[i] =
        UnitBearing(Eigen::Vector3d(xy.x(), xy.y(), -input.focal_length), &unit_bearings[i]);
  }
  std::set<std::vector<char>> tried = {accepted};
  std::vector<PoseCandidate> solutions;
  solutions.reserve(4);
  std::vector<char> set, next;
  std::vector<Eigen::Vector3d> adjusted_points;
  for (const std::array<int, 3>& triple : triples) {
    if (!has_bearing[triple[0]] || !has_bearing[triple[1]] || !has_bearing[triple[2]]) continue;
    const std::array<Eigen::Vector3d, 3> bearings = {
        unit_bearings[triple[0]], unit_bearings[triple[1]], unit_bearings[triple[2]]};
    const std::array<Eigen::Vector3d, 3> points = {input.points_in_ground[triple[0]],
                                                   input.points_in_ground[triple[1]],
                                                   input.points_in_ground[triple[2]]};
    solutions.clear();
    SolveP3PUnitBearings(bearings, points, &solutions);
    for (const PoseCandidate& solution : solutions) {
      ExteriorOrientation hypothesis;
      hypothesis.set_center_in_ground(solution.center_in_ground);
      hypothesis.set_angles_seed_rad(
          AnglesFromRotation(RotationConvention::kSeed, solution.R_camera_from_ground));
      // The distance is checked before the tests: a pose that went back near `eo` is no
      // competitor whatever they say, and they cost a third of an adjustment.
      if (!SettleConsensus(options, input, weights, threshold, size, &hypothesis, &tried, &set,
                           &next) ||
          !AdjustSet(options, input, weights, set, &hypothesis, &adjusted_points))
        continue;
      const double distance = PoseDistanceSigmas(hypothesis, eo, sigmas);
      if (!(distance > options.ambiguous_pose_sigmas) ||
          !SetPassesTests(options, input, weights, set, /*snoop=*/true, hypothesis,
                          adjusted_points))
        continue;
      // Both sets together passing the global test: the competition is a mark at the margin of
      // the snooping (a false alarm), not two poses; a blunder absorbed by one of the sets makes
      // the union fail.
      std::vector<char> both = set;
      for (int i = 0; i < n; ++i) both[i] = both[i] || accepted[i];
      ExteriorOrientation joint = eo;
      if (!SetFitsItsAccuracy(options, input, weights, both, /*snoop=*/false, &joint)) {
        competitor->eo = hypothesis;
        competitor->inliers = set;
        competitor->distance_sigmas = distance;
        return true;
      }
    }
  }
  return false;
}

// Looks for a second pose that the accepted marks themselves fit: their least squares started
// from each P3P pose of their triples (all of them, or a seeded max_exhaustive_samples), passing
// the same tests with every marked control point in front, more than ambiguous_pose_sigmas of
// `sigmas` from `eo`. Control points nearly on one line, or seen at a grazing angle, leave such a
// second minimum: four points of flat ground seen near the horizon fitted a pose 6.6 km from the
// truth at sigma0 0.37 while the true one fitted at 1.05; the consensus took the better fit, and
// its linearised sigmas (54 m) said nothing of the other.
bool FindOtherMinimum(const ResectionOptions& options, const ResectionInput& input,
                      const std::vector<double>& weights, const std::vector<char>& accepted,
                      const ExteriorOrientation& eo, const Vector6d& sigmas,
                      CompetingPose* competitor) {
  const std::vector<int> set = Indices(accepted);
  const int m = static_cast<int>(set.size());
  if (m < 4) return false;
  std::vector<std::array<int, 3>> triples;
  const long long all = static_cast<long long>(m) * (m - 1) * (m - 2) / 6;
  const int limit = options.consensus.ransac.max_exhaustive_samples;
  if (all <= limit) {
    triples.reserve(static_cast<size_t>(all));
    for (int i = 0; i < m; ++i)
      for (int j = i + 1; j < m; ++j)
        for (int k = j + 1; k < m; ++k) triples.push_back({set[i], set[j], set[k]});
  } else {
    PortableRandom random(options.consensus.ransac.seed, /*stream=*/0xA3B2);
    while (static_cast<int>(triples.size()) < limit) {
      const int i = set[random.Below(m)], j = set[random.Below(m)], k = set[random.Below(m)];
      if (i != j && j != k && i != k) triples.push_back({i, j, k});
    }
  }
  // A second minimum that every accepted mark fits is near one P3P pose of *every* triple of
  // them, so a few triples find it as surely as all: the kOtherMinimumTriples of widest spread on
  // the image (the best-conditioned P3P), ties in index order. All of them cost ~0.5 ms per
  // image at ten marks (a third of the batch throughput).
  constexpr size_t kOtherMinimumTriples = 8;
  if (triples.size() > kOtherMinimumTriples) {
    const auto area = [&](const std::array<int, 3>& t) {
      const Eigen::Vector2d a = input.image_plane[t[1]] - input.image_plane[t[0]];
      const Eigen::Vector2d b = input.image_plane[t[2]] - input.image_plane[t[0]];
      return std::abs(a.x() * b.y() - a.y() * b.x());
    };
    std::vector<double> areas(triples.size());
    for (size_t t = 0; t < triples.size(); ++t) areas[t] = area(triples[t]);
    std::vector<size_t> order(triples.size());
    std::iota(order.begin(), order.end(), size_t{0});
    std::partial_sort(order.begin(), order.begin() + kOtherMinimumTriples, order.end(),
                      [&](size_t a, size_t b) {
                        return areas[a] > areas[b] || (areas[a] == areas[b] && a < b);
                      });
    std::vector<std::array<int, 3>> widest;
    for (size_t t = 0; t < kOtherMinimumTriples; ++t) widest.push_back(triples[order[t]]);
    triples.swap(widest);
  }
  const int n = static_cast<int>(accepted.size());
  const double threshold = MarkThresholdSigmas(options.test.confidence);
  std::vector<char> fits;
  std::vector<Eigen::Vector3d> points;
  std::vector<ExteriorOrientation> starts;
  for (const std::array<int, 3>& triple : triples) {
    P3PPoses(input, triple, &starts);
    for (ExteriorOrientation hypothesis : starts) {
      // A start near the accepted pose goes back to it.
      if (!(PoseDistanceSigmas(hypothesis, eo, sigmas) > options.ambiguous_pose_sigmas)) continue;
      // Only a start that the accepted marks fit within twice the threshold is adjusted (a
      // three-point pose carries the noise of three marks), the rule of FindCompetingPose: the
      // count stops at the first mark that misses, where the least squares cost an adjustment.
      if (!ConsensusAt(input, weights, hypothesis, 2.0 * threshold, m, &fits)) continue;
      bool all_accepted = true;
      for (const int i : set) all_accepted = all_accepted && fits[i];
      if (!all_accepted) continue;
      // Most starts go back to `eo`: the distance first, then the tests (as in FindCompetingPose).
      if (!AdjustSet(options, input, weights, accepted, &hypothesis, &points)) continue;
      const double distance = PoseDistanceSigmas(hypothesis, eo, sigmas);
      if (!(distance > options.ambiguous_pose_sigmas) ||
          !SetPassesTests(options, input, weights, accepted, /*snoop=*/true, hypothesis, points))
        continue;
      std::vector<char> in_front;  // every mark in front of the camera
      if (!ConsensusAt(input, weights, hypothesis, std::numeric_limits<double>::infinity(), n,
                       &in_front))
        continue;
      competitor->eo = hypothesis;
      competitor->inliers = accepted;
      competitor->distance_sigmas = distance;
      return true;
    }
  }
  return false;
}

}  // namespace

bool ResectionOptions::IsValid(std::string* why) const {
  if (!(ambiguous_pose_sigmas > 0.0) || !(weak_pose_shift_sigmas > 0.0))
    return InvalidBecause(why, "ambiguous_pose_sigmas and weak_pose_shift_sigmas must be positive");
  if (!(detection_power > 0.0 && detection_power < 1.0))
    return InvalidBecause(why, "the detection power must be in (0, 1)");
  return consensus.ransac.IsValid(why) && test.IsValid(why) && refinement.IsValid(why);
}

std::string ResectionSummary::BriefReport() const {
  std::ostringstream os;
  os << EnumName(termination) << ", "
     << (consensus_after_approximate ? "approximate pose abandoned (" + approximate_message + "), " : "")
     << (used_approximate ? "approximate pose given"
                          : (!ransac_exhaustive ? "RANSAC"
                             : ransac_stopped_early
                                 ? "consensus of the minimal samples in order, up to one every mark fits"
                                 : "consensus of every minimal sample"))
     << ", trials " << ransac_trials << ", adjustments " << adjustments << ", iterations "
     << iterations << ", cost " << initial_cost << " -> " << final_cost << ", "
     << total_seconds * 1e3 << " ms";
  if (!message.empty()) os << ": " << message;
  return os.str();
}

namespace {

// The steps of ResectImage (solvers/resection/resection.h, 1-4), over one image. Each step returns
// false when the image is not solved, with the reason in the summary (Fail).
class ImageResection {
 public:
  ImageResection(const ResectionOptions& options, const ResectionInput& input)
      : options_(options), input_(input), n_(input.image_plane.size()), start_(Clock::now()) {}

  // The input's sizes, finiteness and control configuration; the marks' weights.
  bool CheckInput();
  // 1. Initial values and the candidate marks: the approximate pose, or the consensus.
  bool InitialValues();
  // 2. Adjust, take back what fits, reject what the test rejects; until nothing changes.
  bool DecideMarks();
  // 3. The verdict: in front, redundancy, the global test.
  bool Verdict();
  // 4. Statistics per mark: residuals, tests, redundancy numbers, MDB and pose shifts.
  bool Statistics();
  // Another consensus set, as large, that fits a pose beyond a few of this one's sigmas.
  bool NotAmbiguous();
  // An undetected blunder of MDB size on the weakest mark moves the pose by
  // max_pose_shift_sigmas of its standard deviations: weak beyond weak_pose_shift_sigmas.
  bool Reliability();
  ResectionResult Solved();
  ResectionResult Failed() { return std::move(result_); }

 private:
  bool Fail(const std::string& message) {
    ResectionSummary& summary = result_.summary;
    if (summary.termination == SolverTermination::kConverged)
      summary.termination = SolverTermination::kFailure;
    summary.message = message;
    summary.total_seconds = SecondsSince(start_);
    result_.success = false;
    return false;
  }
  std::string Percent() const { return Number(100.0 * options_.test.confidence) + "%"; }
  // The marks left out, each with its residual, for messages.
  std::string LeftOut() const;
  // The names of the marks of a set.
  std::string Names(const std::vector<char>& set) const;
  // A mark's test value: its statistic with stated accuracy, over sigma0^2 otherwise.
  double TestValue(size_t i) const {
    return marks_.stated ? stats_.test_statistics[i] : stats_.test_statistics[i] / s0_squared_;
  }
  bool Readmit();
  bool RejectWorst();

  const ResectionOptions& options_;
  const ResectionInput& input_;
  const size_t n_;
  const Clock::time_point start_;
  ResectionResult result_;
  Marks marks_;
  double threshold_ = 0.0;  // sigmas
  ExteriorOrientation eo_;
  std::vector<char> candidate_;
  std::vector<char> rejected_;
  std::vector<Eigen::Vector3d> points_;
  PoseAdjustmentStatistics stats_;
  double s0_squared_ = kNaN;
};

bool ImageResection::CheckInput() {
  if (const Status valid = Validate(options_, "invalid options: "); !valid.ok())
    return Fail(valid.message());
  const size_t n = n_;
  const auto sized = [n](size_t size) { return size == 0 || size == n; };
  if (input_.points_in_ground.size() != n || !sized(input_.sigma.size()) ||
      !sized(input_.observation_units_per_unit.size()) || !sized(input_.units.size()))
    return Fail("observations, points, accuracies and units differ in number");
  if (!(input_.focal_length > 0.0) || !std::isfinite(input_.focal_length))
    return Fail("the focal length must be positive");
  for (size_t i = 0; i < n; ++i) {
    if (!input_.image_plane[i].allFinite()) return Fail("an image observation is not finite");
    if (!input_.sigma.empty() && !(input_.sigma[i] >= 0.0 && std::isfinite(input_.sigma[i])))
      return Fail("an observation accuracy is negative or not finite");
    if (!input_.observation_units_per_unit.empty() &&
        !(input_.observation_units_per_unit[i] > 0.0 &&
          std::isfinite(input_.observation_units_per_unit[i])))
      return Fail("an observation unit scale is not positive");
  }
  const Status configuration = CheckControlConfiguration(input_.points_in_ground);
  if (!configuration.ok()) return Fail(configuration.message());
  marks_ = MarksOf(input_);
  result_.accuracy_stated = marks_.stated;
  threshold_ = MarkThresholdSigmas(options_.test.confidence);
  return true;
}

bool ImageResection::InitialValues() {
  ResectionSummary& summary = result_.summary;
  const size_t n = n_;
  candidate_.assign(n, 1);
  if (input_.approximate.has_value()) {
    eo_ = *input_.approximate;
    summary.used_approximate = true;
    if (!eo_.parameters.allFinite()) return Fail("the approximate pose is not finite");
    std::vector<Eigen::Vector3d> points;
    CameraPoints(input_, eo_.center_in_ground(), &points);
    const SeedProjector projector(eo_.data(), input_.focal_length);
    for (size_t i = 0; i < n; ++i) {
      double xy[2];
      if (!projector.Project(points[i].data(), xy, nullptr, nullptr, nullptr))
        return Fail("control point " + marks_.name(i) +
                    " is behind the camera at the approximate pose");
    }
    return true;
  }
  const Clock::time_point ransac_start = Clock::now();
  AbsolutePoseRansacOptions consensus = options_.consensus;
  consensus.inlier_threshold = threshold_;
  consensus.score = marks_.stated ? ConsensusScore::kMsac : ConsensusScore::kLeastMedian;
  // Stopping at a model every mark fits decides nothing only where the all-marks check below
  // speaks for every mark (stated accuracy), and six marks leave a least squares of all marks no
  // second minimum within the threshold of every one of them to fall into from another start.
  consensus.ransac.stop_enumeration_when_all_inliers =
      consensus.ransac.stop_enumeration_when_all_inliers && marks_.stated &&
      n >= kMinMarksToStopConsensus;
  RansacSummary ransac;
  Status status =
      EstimateAbsolutePoseRansac(consensus, input_.image_plane, input_.points_in_ground,
                                 marks_.weights, input_.focal_length, &eo_, &candidate_, &ransac);
  summary.ransac_trials = ransac.num_trials;
  summary.ransac_exhaustive = ransac.exhaustive;
  if (status.ok() && ransac.stopped_early) {
    // Every mark fits the stopping model. The full enumeration ends with all marks as candidates
    // at their least squares too whenever that least squares passes the tests: its best model
    // then fits all, or the all-marks check below takes all back. Otherwise it runs in full.
    ExteriorOrientation all_marks = eo_;
    if (SetFitsItsAccuracy(options_, input_, marks_.weights, std::vector<char>(n, 1),
                           /*snoop=*/true, &all_marks)) {
      candidate_.assign(n, 1);
      eo_ = all_marks;
      summary.ransac_stopped_early = true;
      summary.ransac_seconds = SecondsSince(ransac_start);
      return true;
    }
    consensus.ransac.stop_enumeration_when_all_inliers = false;
    status = EstimateAbsolutePoseRansac(consensus, input_.image_plane, input_.points_in_ground,
                                        marks_.weights, input_.focal_length, &eo_, &candidate_,
                                        &ransac);
    summary.ransac_trials += ransac.num_trials;
  }
  summary.ransac_seconds = SecondsSince(ransac_start);
  if (!status.ok()) return Fail("no initial pose: " + status.message());
  // Four marks and no stated accuracy: the data cannot say which would not fit; all are taken.
  if (!marks_.stated && n == 4) candidate_.assign(n, 1);
  // The pose of a minimal sample carries the noise of three marks, so a good mark may lie
  // beyond the threshold there and also beyond the prediction of the few marks kept; when every
  // mark fits the least squares of all, all are kept.
  ExteriorOrientation all_marks = eo_;
  if (marks_.stated && n >= 4 &&
      std::count(candidate_.begin(), candidate_.end(), 1) < static_cast<long>(n) &&
      SetFitsItsAccuracy(options_, input_, marks_.weights, std::vector<char>(n, 1),
                         /*snoop=*/true, &all_marks)) {
    candidate_.assign(n, 1);
    eo_ = all_marks;
  }
  return true;
}

// Marks left out that fit this solution come back: their predicted residuals pass the test (so
// when every mark fits the least-squares solution of all, all are kept).
bool ImageResection::Readmit() {
  const double confidence = options_.test.confidence;
  const double critical = marks_.stated ? threshold_ * threshold_
                                        : PredictedCriticalValue(confidence, stats_.redundancy);
  bool readmitted = false;
  for (size_t i = 0; i < n_; ++i) {
    if (candidate_[i] || rejected_[i] || !stats_.in_front[i] || !stats_.determined) continue;
    if (TestValue(i) <= critical) {
      candidate_[i] = 1;
      readmitted = true;
    }
  }
  return readmitted;
}

// The test of the worst accepted mark; true when it rejected one.
bool ImageResection::RejectWorst() {
  if (stats_.num_used < 5 || !stats_.determined) return false;
  const double confidence = options_.test.confidence;
  const double critical = marks_.stated ? SnoopingCriticalValue(confidence)
                                        : TauCriticalValue(confidence, stats_.redundancy);
  int worst = -1;
  double worst_value = 0.0;
  for (size_t i = 0; i < n_; ++i) {
    if (!candidate_[i]) continue;
    if (TestValue(i) > worst_value) {
      worst = static_cast<int>(i);
      worst_value = TestValue(i);
    }
  }
  if (worst < 0 || !(worst_value > critical)) return false;
  candidate_[worst] = 0;
  rejected_[worst] = 1;
  return true;
}

bool ImageResection::DecideMarks() {
  const Clock::time_point refine_start = Clock::now();
  rejected_.assign(n_, 0);
  const int max_rounds = 3 * static_cast<int>(n_) + 3;
  for (int round = 0;; ++round) {
    if (round == max_rounds) return Fail("the outlier decisions did not settle");
    if (!Adjust(options_, input_, marks_.weights, Indices(candidate_), &eo_, &points_,
                &result_.summary))
      return Fail(result_.summary.message);
    const Status computed = ComputePoseAdjustmentStatistics(
        input_.image_plane, points_, marks_.weights, input_.focal_length, eo_, candidate_, &stats_);
    if (!computed.ok()) return Fail(computed.message());
    s0_squared_ = stats_.redundancy > 0 ? stats_.omega / stats_.redundancy : kNaN;
    if (Readmit()) continue;
    if (RejectWorst()) continue;
    break;
  }
  result_.summary.refinement_seconds = SecondsSince(refine_start);
  return true;
}

std::string ImageResection::LeftOut() const {
  std::string text;
  for (size_t i = 0; i < n_; ++i) {
    if (candidate_[i]) continue;
    const double residual =
        stats_.whitened_residuals[i].norm() * marks_.weights[i] / marks_.per_unit[i];
    text += std::string(text.empty() ? "" : ", ") + marks_.name(i) + " (" +
            (stats_.in_front[i] ? Number(residual) + " " + EnumName(marks_.units[i]) : "behind") +
            ")";
  }
  return text;
}

std::string ImageResection::Names(const std::vector<char>& set) const {
  std::string text;
  for (size_t i = 0; i < n_; ++i)
    if (set[i]) text += std::string(text.empty() ? "" : ", ") + marks_.name(i);
  return text;
}

bool ImageResection::Verdict() {
  const size_t n = n_;
  const int accepted = stats_.num_used;
  result_.eo = eo_;
  result_.inliers = candidate_;
  result_.num_inliers = accepted;
  result_.degrees_of_freedom = stats_.redundancy;
  result_.sigma0 = stats_.redundancy > 0 ? std::sqrt(s0_squared_) : 0.0;
  for (size_t i = 0; i < n; ++i) {
    if (!stats_.in_front[i])
      return Fail("control point " + marks_.name(i) +
                  " lies behind the camera at the solution: the pose cannot have seen it");
  }
  if (accepted == 3) {
    const std::string what =
        n == 3 ? std::string("three control points determine the pose exactly and nothing checks it")
               : "only 3 of the " + std::to_string(n) + " marks agree (left out: " + LeftOut() +
                     ") and nothing checks the pose they give";
    if (!options_.allow_no_redundancy)
      return Fail("no redundancy: " + what + "; add control points, or allow it explicitly");
    if (!input_.approximate.has_value()) {
      const int poses = CountP3PPoses(input_, Indices(candidate_));
      if (poses > 1)
        return Fail("ambiguous: " + std::to_string(poses) +
                    " poses fit the three accepted marks exactly; give approximate values to "
                    "choose one");
    }
    result_.warnings.push_back("no redundancy: " + what + "; the pose has no standard deviations");
  }
  const double confidence = options_.test.confidence;
  if (accepted >= 4 && marks_.stated && FailsGlobalTest(stats_.omega, confidence, stats_.redundancy)) {
    result_.accuracy_disagrees = true;
    const double critical = GlobalTestCriticalValue(confidence, stats_.redundancy);
    return Fail("sigma0 = " + Number(result_.sigma0) + ": the " + std::to_string(accepted) +
                " accepted marks do not fit their stated accuracy (sum of squared normalized "
                "residuals " + Number(stats_.omega) + " > " + Number(critical) + ", chi-square(" +
                std::to_string(stats_.redundancy) + ") at " + Percent() + "; sigma0 up to " +
                Number(std::sqrt(critical / stats_.redundancy)) + " passes): " +
                (accepted == 4 ? "one of them is a blunder, and four marks cannot show which"
                               : "a blunder the tests cannot isolate, or marks less accurate "
                                 "than stated") +
                (n > static_cast<size_t>(accepted) ? " (left out: " + LeftOut() + ")" : ""));
  }
  if (accepted == 4 && !marks_.stated) {
    result_.warnings.push_back(
        "4 marks without a stated accuracy: a blunder among them cannot be detected (redundancy "
        "2); state their Accuracy to test them");
  }
  return true;
}

bool ImageResection::Statistics() {
  if (!stats_.determined)
    return Fail("the normal matrix is singular: the pose is not determined by these points");
  const size_t n = n_;
  const double confidence = options_.test.confidence;
  if (stats_.redundancy > 0) {
    result_.has_covariance = true;
    result_.covariance_factor =
        PoseCovarianceFactor(marks_.stated, stats_.omega, stats_.redundancy);
    result_.covariance = result_.covariance_factor * stats_.cofactor;
    result_.standard_deviations = result_.covariance.diagonal().cwiseSqrt();
    if (!marks_.stated) {
      result_.sigma_upper_factor = SigmaUpperFactor(kSigmaUpperFactorConfidence, stats_.redundancy);
      if (stats_.redundancy < kMinSigmaDegreesOfFreedom)
        result_.warnings.push_back(
            "uncertain sigmas: without a stated accuracy the standard deviations rest on sigma0 "
            "from " + std::to_string(stats_.redundancy) + " degrees of freedom; at " +
            Number(100.0 * kSigmaUpperFactorConfidence) + "% the true ones may be up to " +
            Number(result_.sigma_upper_factor) + " times larger; state the marks' Accuracy");
    }
  } else {
    result_.sigma_upper_factor = std::numeric_limits<double>::infinity();
  }
  const double critical =
      stats_.num_used >= 5
          ? (marks_.stated ? SnoopingCriticalValue(confidence)
                           : TauCriticalValue(confidence, stats_.redundancy))
          : kNaN;
  result_.critical_normalized_residual = std::sqrt(critical);
  result_.residuals.resize(n);
  result_.normalized_residuals.assign(n, kNaN);
  result_.redundancy_numbers = stats_.redundancy_numbers;
  result_.minimal_detectable_blunders.assign(n, 0.0);
  result_.pose_shifts_sigmas.assign(n, 0.0);
  result_.mark_status.resize(n);
  // The marks' standard deviation in their own unit: stated, or sigma0 times the unit weight.
  const double scale =
      marks_.stated ? 1.0 : (stats_.redundancy > 0 ? std::sqrt(s0_squared_) : kNaN);
  const double delta0 = DetectableBiasSigmas(confidence, options_.detection_power);
  for (size_t i = 0; i < n; ++i) {
    result_.residuals[i] = stats_.whitened_residuals[i] * marks_.weights[i] / marks_.per_unit[i];
    const bool testable = candidate_[i] ? stats_.redundancy_numbers[i] > 1e-6 : true;
    if (testable && stats_.redundancy > (marks_.stated ? 0 : 2))
      result_.normalized_residuals[i] = std::sqrt(TestValue(i));
    result_.mark_status[i] = candidate_[i]  ? MarkStatus::kAccepted
                             : rejected_[i] ? MarkStatus::kRejected
                                            : MarkStatus::kConsensusOutlier;
    if (!candidate_[i] || stats_.redundancy == 0) continue;
    result_.minimal_detectable_blunders[i] = delta0 * stats_.detectable_blunder_per_delta[i] *
                                             scale * marks_.weights[i] / marks_.per_unit[i];
    result_.pose_shifts_sigmas[i] = delta0 * stats_.pose_shift_per_delta[i];
    if (!(result_.pose_shifts_sigmas[i] <= result_.max_pose_shift_sigmas)) {
      result_.max_pose_shift_sigmas = result_.pose_shifts_sigmas[i];
      result_.weakest_mark = static_cast<int>(i);
    }
  }
  return true;
}

bool ImageResection::NotAmbiguous() {
  if (!marks_.stated || !result_.has_covariance) return true;
  CompetingPose competitor;
  const bool other_set = FindCompetingPose(options_, input_, marks_.weights, candidate_, eo_,
                                           result_.standard_deviations, &competitor);
  // The same marks at a second pose: searched where the geometry is weak (a pose strong by its
  // reliability has one minimum within reach) and when no approximate pose chose one.
  const bool weak = result_.max_pose_shift_sigmas > options_.weak_pose_shift_sigmas;
  // Its distance in the a-priori sigmas unless the data say worse: sigma0 near 0 (marks without
  // noise) would make a rounding difference of the same minimum "many sigmas" away.
  const Vector6d sigmas =
      (std::max(1.0, s0_squared_) * stats_.cofactor.diagonal()).cwiseSqrt();
  const bool same_set = !other_set && weak && !input_.approximate.has_value() &&
                        FindOtherMinimum(options_, input_, marks_.weights, candidate_, eo_,
                                         sigmas, &competitor);
  if (!other_set && !same_set) return true;
  result_.ambiguous = true;
  result_.competing_eo = competitor.eo;
  result_.competing_inliers = competitor.inliers;
  const Eigen::Vector3d apart = competitor.eo.center_in_ground() - eo_.center_in_ground();
  if (same_set)
    return Fail("ambiguous: the accepted marks (" + Names(candidate_) + ") fit two poses " +
                Number(apart.norm()) + " m apart (" + Number(competitor.distance_sigmas) +
                " standard deviations), both within their accuracy: the control points' "
                "configuration (nearly on one line, or seen at a grazing angle) does not decide "
                "between them; add control points away from that line, or give approximate "
                "values (--frames) to choose one");
  return Fail("ambiguous: two poses fit as many marks each: " + Names(candidate_) + " give one, " +
              Names(competitor.inliers) + " another " + Number(apart.norm()) + " m away (" +
              Number(competitor.distance_sigmas) +
              " standard deviations); one of the marks is a blunder that the others cannot "
              "single out: check the marks, or add control points");
}

bool ImageResection::Reliability() {
  if (stats_.redundancy == 0) {
    result_.weak = true;
    return true;
  }
  if (!(result_.max_pose_shift_sigmas > options_.weak_pose_shift_sigmas)) return true;
  result_.weak = true;
  const size_t w = static_cast<size_t>(result_.weakest_mark);
  const std::string why =
      "an undetectable blunder of " + Number(result_.minimal_detectable_blunders[w]) + " " +
      std::string(EnumName(marks_.units[w])) + " on mark " + marks_.name(w) +
      " (redundancy number " + Number(stats_.redundancy_numbers[w]) +
      ") would move the pose by " + Number(result_.max_pose_shift_sigmas) +
      " standard deviations (more than " + Number(options_.weak_pose_shift_sigmas) + ")";
  if (options_.refuse_weak) return Fail("weak: " + why);
  result_.warnings.push_back("weak: " + why + "; more control points make it checkable");
  return true;
}

ResectionResult ImageResection::Solved() {
  result_.success = true;
  result_.summary.termination = SolverTermination::kConverged;
  result_.summary.message.clear();
  result_.summary.total_seconds = SecondsSince(start_);
  return std::move(result_);
}

}  // namespace

namespace {

ResectionResult ResectFromItsStart(const ResectionOptions& options, const ResectionInput& input) {
  ImageResection image(options, input);
  if (!image.CheckInput() || !image.InitialValues() || !image.DecideMarks() || !image.Verdict() ||
      !image.Statistics() || !image.NotAmbiguous() || !image.Reliability())
    return image.Failed();
  return image.Solved();
}

}  // namespace

ResectionResult ResectImage(const ResectionOptions& options, const ResectionInput& input) {
  ResectionResult given = ResectFromItsStart(options, input);
  // An approximate pose far off (hundreds of metres, tens of degrees) leads the least squares
  // nowhere or to another minimum; the consensus needs no start. Tried only when the given start
  // did not solve the image with every mark, and taken only when it does better: solved where
  // the given start failed, or with more marks accepted.
  const size_t n = input.image_plane.size();
  if (!options.consensus_after_approximate || !input.approximate.has_value() ||
      (given.success && given.num_inliers == static_cast<int>(n)))
    return given;
  ResectionInput without = input;
  without.approximate.reset();
  ResectionResult consensus = ResectFromItsStart(options, without);
  const bool better =
      consensus.success && (!given.success || consensus.num_inliers > given.num_inliers);
  if (!better) return given;
  ResectionSummary& summary = consensus.summary;
  summary.consensus_after_approximate = true;
  summary.approximate_message = given.success ? "kept " + std::to_string(given.num_inliers) +
                                                    " of " + std::to_string(n) + " marks"
                                              : given.summary.message;
  summary.total_seconds += given.summary.total_seconds;
  consensus.warnings.insert(
      consensus.warnings.begin(),
      "approximate pose abandoned: from it " +
          (given.success ? "the resection " + summary.approximate_message
                         : "the image was not solved (" + given.summary.message + ")") +
          "; solved from the consensus start with " + std::to_string(consensus.num_inliers) +
          " of " + std::to_string(n) + " marks");
  return consensus;
}

bool ResectionBatchOptions::IsValid(std::string* why) const {
  if (num_threads < 0) return InvalidBecause(why, "num_threads must be >= 0 (0: all cores)");
  if (!(progress_fraction >= 0.0 && progress_fraction <= 1.0))
    return InvalidBecause(why, "progress_fraction must be in [0, 1]");
  if (!(progress_interval_seconds >= 0.0) || !std::isfinite(progress_interval_seconds))
    return InvalidBecause(why, "progress_interval_seconds must be a finite number >= 0");
  return true;
}

std::string ResectionBatchSummary::BriefReport() const {
  std::ostringstream os;
  os << images_total << " images: " << images_solved << " solved, "
     << images_total - images_solved - images_cancelled << " not solved, " << images_cancelled
     << " cancelled" << (cancelled ? " (the batch was cancelled)" : "") << "; " << progress_calls
     << " progress calls; " << Number(total_seconds) << " s";
  return os.str();
}

namespace {

// A batch's side of its progress hook: counts the finished images and calls the hook, throttled
// (ResectionBatchOptions), one call at a time under a mutex. A thread that finds the mutex taken
// goes on resecting; only the thread that finishes the last image waits for it, so that the last
// call reports every image.
class BatchProgress {
 public:
  BatchProgress(const ResectionBatchOptions& options, size_t total, Clock::time_point start)
      : hook_(options.progress),
        total_(static_cast<int>(total)),
        step_(std::max(1, static_cast<int>(std::ceil(options.progress_fraction * total)))),
        // At most 30 years: the nanoseconds stay far inside int64_t.
        interval_ns_(static_cast<int64_t>(std::min(options.progress_interval_seconds, 1e9) * 1e9)),
        start_(start),
        next_done_(step_),
        next_ns_(interval_ns_) {}

  bool cancelled() const { return cancelled_.load(std::memory_order_acquire); }
  int calls() const { return calls_; }

  // After an image's result is written.
  void ImageDone() {
    const int done = done_.fetch_add(1, std::memory_order_acq_rel) + 1;
    if (done == total_) {
      const std::lock_guard<std::mutex> lock(mutex_);
      Report();
      return;
    }
    if (done < next_done_.load(std::memory_order_relaxed) &&
        NanosecondsSinceStart() < next_ns_.load(std::memory_order_relaxed))
      return;
    const std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
    if (lock.owns_lock()) Report();
  }

 private:
  int64_t NanosecondsSinceStart() const {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - start_).count();
  }
  // With mutex_ held: the hook with every image finished by now, unless that was reported already
  // or the batch is cancelled; then the next due count and time.
  void Report() {
    const int done = done_.load(std::memory_order_acquire);
    if (done <= reported_ || cancelled()) return;
    const bool go_on = hook_(ResectionProgress{done, total_, SecondsSince(start_)});
    ++calls_;
    reported_ = done;
    next_done_.store(done + step_, std::memory_order_relaxed);
    next_ns_.store(NanosecondsSinceStart() + interval_ns_, std::memory_order_relaxed);
    if (!go_on) cancelled_.store(true, std::memory_order_release);
  }

  const ResectionProgressHook& hook_;
  const int total_;
  const int step_;            // images between two calls (count)
  const int64_t interval_ns_;  // time between two calls (ns)
  const Clock::time_point start_;
  std::atomic<int> done_{0};
  std::atomic<bool> cancelled_{false};
  // When the next call is due: images finished, ns since start_ (written under mutex_).
  std::atomic<int> next_done_;
  std::atomic<int64_t> next_ns_;
  std::mutex mutex_;
  int reported_ = 0;  // images_done of the last call (under mutex_)
  int calls_ = 0;     // under mutex_; read after the threads joined
};

ResectionResult CancelledResult() {
  ResectionResult result;
  result.cancelled = true;
  result.summary.termination = SolverTermination::kCancelled;
  result.summary.message = "cancelled: the batch was cancelled by its progress hook before this "
                           "image started";
  return result;
}

// The batch on its threads; with progress null exactly as without a hook.
void ResectBatch(const ResectionOptions& options, const std::vector<ResectionInput>& inputs,
                 int num_threads, size_t chunk_size, BatchProgress* progress,
                 std::vector<ResectionResult>* results) {
  results->assign(inputs.size(), ResectionResult());
  ParallelForChunks(inputs.size(), num_threads, chunk_size, [&](size_t i) {
    if (progress != nullptr && progress->cancelled()) {
      (*results)[i] = CancelledResult();
      return;
    }
    ResectionOptions image_options = options;
    // A distinct, reproducible RANSAC stream per image, whatever the thread schedule.
    image_options.consensus.ransac.seed =
        options.consensus.ransac.seed + 0x9E3779B97F4A7C15ull * (i + 1);
    (*results)[i] = ResectImage(image_options, inputs[i]);
    if (progress != nullptr) progress->ImageDone();
  });
}

}  // namespace

Status ResectImages(const ResectionOptions& options, const std::vector<ResectionInput>& inputs,
                    const ResectionBatchOptions& batch, std::vector<ResectionResult>* results,
                    ResectionBatchSummary* summary) {
  PHOTOPOSE_RETURN_IF_ERROR(Validate(batch, "invalid batch options: "));
  PHOTOPOSE_RETURN_IF_ERROR(Validate(options, "invalid resection options: "));
  if (inputs.size() > static_cast<size_t>(std::numeric_limits<int>::max()))
    return Status::Error("a batch holds at most " +
                         std::to_string(std::numeric_limits<int>::max()) + " images");
  const Clock::time_point start = Clock::now();
  std::optional<BatchProgress> progress;
  if (batch.progress) progress.emplace(batch, inputs.size(), start);
  ResectBatch(options, inputs, batch.num_threads, batch.chunk_size,
              progress ? &*progress : nullptr, results);
  if (summary != nullptr) {
    *summary = ResectionBatchSummary();
    summary->images_total = static_cast<int>(results->size());
    for (const ResectionResult& r : *results) {
      summary->images_solved += r.success;
      summary->images_cancelled += r.cancelled;
    }
    summary->cancelled = progress && progress->cancelled();
    summary->progress_calls = progress ? progress->calls() : 0;
    summary->total_seconds = SecondsSince(start);
  }
  return Status::Ok();
}

std::vector<ResectionResult> ResectImages(const ResectionOptions& options,
                                          const std::vector<ResectionInput>& inputs,
                                          int num_threads, size_t chunk_size) {
  std::vector<ResectionResult> results;
  ResectBatch(options, inputs, num_threads, chunk_size, /*progress=*/nullptr, &results);
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
  result.earth_radius_m = camera.earth_curvature_radius_m();
  MarkSigmaDefaults defaults;
  defaults.pixel_px = options.default_accuracy;
  defaults.film_um = options.default_film_accuracy_um;
  defaults.film_from_pixel_size = false;  // a film default in um, whatever the PixelSize
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
    // MarkSigma gives image-plane units; the input keeps each mark's own unit.
    result.sigma.push_back(
        options.default_accuracy > 0.0
            ? MarkSigma(mark, camera, defaults) / mark.observation_units_per_unit
            : mark.accuracy.value_or(0.0));
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
  if (camera.earth_curvature_radius_m() > 0.0)
    p.z() -= EarthCurvatureDrop(eo.center_in_ground(), p, camera.earth_curvature_radius_m());
  Eigen::Vector2d computed;
  if (!ProjectToNormalized(eo.data(), p.data(), computed.data()))
    return Status::Error("point '" + point.id + "' is behind the camera");
  const double focal = CameraModelFocal(camera.model, camera.params.data());
  *residual = focal * (observed - computed) / mark.observation_units_per_unit;
  return Status::Ok();
}

}  // namespace photopose
