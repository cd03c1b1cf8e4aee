#include "solvers/georeference/similarity.h"

#include <Eigen/Dense>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <map>

#include "core/simulation/portable_random.h"

namespace photopose {
namespace {

// Weighted Umeyama on the chosen pairs; `spread_ratio` receives the second singular value of the
// centred source over the first (0 for a line).
bool Umeyama(const std::vector<SimilarityCorrespondence>& pairs, const std::vector<int>& chosen,
             Similarity3* similarity, double* spread_ratio) {
  double weight_sum = 0.0;
  Eigen::Vector3d mean_source = Eigen::Vector3d::Zero(), mean_target = Eigen::Vector3d::Zero();
  for (int i : chosen) {
    const double w = 1.0 / (pairs[i].sigma_m * pairs[i].sigma_m);
    weight_sum += w;
    mean_source += w * pairs[i].source;
    mean_target += w * pairs[i].target;
  }
  if (!(weight_sum > 0.0)) return false;
  mean_source /= weight_sum;
  mean_target /= weight_sum;
  Eigen::Matrix3d cross = Eigen::Matrix3d::Zero(), source_scatter = Eigen::Matrix3d::Zero(),
                  target_scatter = Eigen::Matrix3d::Zero();
  double source_variance = 0.0;
  for (int i : chosen) {
    const double w = 1.0 / (pairs[i].sigma_m * pairs[i].sigma_m) / weight_sum;
    const Eigen::Vector3d s = pairs[i].source - mean_source;
    const Eigen::Vector3d t = pairs[i].target - mean_target;
    cross += w * t * s.transpose();
    source_scatter += w * s * s.transpose();
    target_scatter += w * t * t.transpose();
    source_variance += w * s.squaredNorm();
  }
  // Both sides must span a plane: the smaller of the two ratios; and the target's width across
  // its main direction must stand out of the targets' noise (twice their RMS sigma), else the
  // rotation about that direction is noise.
  *spread_ratio = 1.0;
  for (const Eigen::Matrix3d* scatter : {&source_scatter, &target_scatter}) {
    const Eigen::Vector3d values = Eigen::JacobiSVD<Eigen::Matrix3d>(*scatter).singularValues();
    *spread_ratio = std::min(*spread_ratio, values(0) > 0.0 ? std::sqrt(values(1) / values(0)) : 0.0);
  }
  const double target_width = std::sqrt(Eigen::JacobiSVD<Eigen::Matrix3d>(target_scatter).singularValues()(1));
  const double rms_sigma = std::sqrt(static_cast<double>(chosen.size()) / weight_sum);
  if (chosen.size() > 3 && target_width < 2.0 * rms_sigma) *spread_ratio = 0.0;
  if (!(source_variance > 0.0)) return false;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cross, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) S(2, 2) = -1.0;
  similarity->R_target_from_source = svd.matrixU() * S * svd.matrixV().transpose();
  similarity->scale = (svd.singularValues().asDiagonal() * S).trace() / source_variance;
  similarity->translation = mean_target - similarity->scale * similarity->R_target_from_source * mean_source;
  return std::isfinite(similarity->scale) && similarity->scale > 0.0 &&
         similarity->R_target_from_source.allFinite() && similarity->translation.allFinite();
}

constexpr double kMinSpreadRatio = 1e-6;

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const size_t middle = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + middle, values.end());
  return values[middle];
}

}  // namespace

Status FitSimilarity(const std::vector<SimilarityCorrespondence>& pairs,
                     const std::vector<char>* use, Similarity3* similarity) {
  std::vector<int> chosen;
  for (size_t i = 0; i < pairs.size(); ++i) {
    if (use != nullptr && !(*use)[i]) continue;
    if (!(pairs[i].sigma_m > 0.0) || !pairs[i].source.allFinite() || !pairs[i].target.allFinite())
      return Status::Error("similarity: pair " + std::to_string(i) + " has a non-finite point or a sigma that is not positive");
    chosen.push_back(static_cast<int>(i));
  }
  if (chosen.size() < 3)
    return Status::Error("similarity: " + std::to_string(chosen.size()) + " pairs; at least 3 are needed");
  double spread = 0.0;
  Similarity3 fitted;
  if (!Umeyama(pairs, chosen, &fitted, &spread) || spread < kMinSpreadRatio)
    return Status::Error("similarity: the " + std::to_string(chosen.size()) + " points lie on a line (or in one point), within twice their accuracy: the rotation about it is not determined");
  *similarity = fitted;
  return Status::Ok();
}

namespace {

// The pairs' normalised residuals and the cost of a similarity on them, group by group.
class GroupedResiduals {
 public:
  GroupedResiduals(const std::vector<SimilarityCorrespondence>& pairs, int num_groups)
      : pairs_(pairs), num_groups_(num_groups) {}

  // |target - s(source)| / sigma of every pair.
  void Normalised(const Similarity3& s, std::vector<double>* r) const {
    const int n = static_cast<int>(pairs_.size());
    r->resize(n);
    for (int i = 0; i < n; ++i) (*r)[i] = (pairs_[i].target - s.Apply(pairs_[i].source)).norm() / pairs_[i].sigma_m;
  }
  // The median of the normalised residuals in each group.
  std::vector<double> GroupMedians(const std::vector<double>& r) const {
    std::vector<std::vector<double>> by_group(num_groups_);
    for (size_t i = 0; i < pairs_.size(); ++i) by_group[pairs_[i].group].push_back(r[i]);
    std::vector<double> medians(num_groups_, 0.0);
    for (int g = 0; g < num_groups_; ++g) medians[g] = Median(by_group[g]);
    return medians;
  }
  // The sum of the groups' medians: the cost of a sample.
  double Cost(const std::vector<double>& r) const {
    double total = 0.0;
    for (double m : GroupMedians(r)) total += m;
    return total;
  }

 private:
  const std::vector<SimilarityCorrespondence>& pairs_;
  int num_groups_;
};

// The minimal sample (a triple) whose similarity costs least, starting from `all` (the fit of
// every pair): every triple, or a fixed seeded sequence of max_samples of them. Counts the samples
// tried in *num_samples.
Similarity3 BestMinimalSample(const RobustSimilarityOptions& options,
                              const std::vector<SimilarityCorrespondence>& pairs,
                              const GroupedResiduals& residuals_of, const Similarity3& all, int* num_samples) {
  const int n = static_cast<int>(pairs.size());
  Similarity3 best = all;
  std::vector<double> residuals;
  residuals_of.Normalised(all, &residuals);
  double best_cost = residuals_of.Cost(residuals);
  const long long triples = static_cast<long long>(n) * (n - 1) * (n - 2) / 6;
  auto try_sample = [&](int a, int b, int c) {
    Similarity3 candidate;
    double spread = 0.0;
    if (!Umeyama(pairs, {a, b, c}, &candidate, &spread) || spread < 1e-3) return;
    ++*num_samples;
    residuals_of.Normalised(candidate, &residuals);
    const double c_cost = residuals_of.Cost(residuals);
    if (c_cost < best_cost) {
      best_cost = c_cost;
      best = candidate;
    }
  };
  if (triples <= options.max_samples) {
    for (int a = 0; a < n; ++a)
      for (int b = a + 1; b < n; ++b)
        for (int c = b + 1; c < n; ++c) try_sample(a, b, c);
  } else {
    PortableRandom random(20261125);
    for (int k = 0; k < options.max_samples; ++k) {
      const int a = static_cast<int>(random.Below(n));
      const int b = static_cast<int>(random.Below(n));
      const int c = static_cast<int>(random.Below(n));
      if (a == b || b == c || a == c) continue;
      try_sample(a, b, c);
    }
  }
  return best;
}

// From `start`: inliers by each group's robust scale, then least squares on them, repeated until
// the inliers repeat. Writes the inliers and the group scales into *result.
Similarity3 RefineOnInliers(const RobustSimilarityOptions& options, const std::vector<SimilarityCorrespondence>& pairs,
                            const GroupedResiduals& residuals_of, const Similarity3& start,
                            RobustSimilaritySummary* result) {
  const int n = static_cast<int>(pairs.size());
  const int num_groups = static_cast<int>(result->group_scale.size());
  Similarity3 current = start;
  std::vector<double> residuals;
  for (int round = 0; round < options.refinement_rounds; ++round) {
    residuals_of.Normalised(current, &residuals);
    const std::vector<double> medians = residuals_of.GroupMedians(residuals);
    std::vector<char> inlier(n, 0);
    for (int g = 0; g < num_groups; ++g) result->group_scale[g] = 1.4826 * medians[g];
    for (int i = 0; i < n; ++i) {
      const double scale = std::max(result->group_scale[pairs[i].group], 1.0);
      inlier[i] = residuals[i] <= options.outlier_sigmas * scale;
    }
    Similarity3 refit;
    if (!FitSimilarity(pairs, &inlier, &refit).ok()) break;
    current = refit;
    const bool same = inlier == result->inlier;
    result->inlier = inlier;
    if (same && round > 0) break;
  }
  return current;
}

}  // namespace

Status RobustSimilarity(const RobustSimilarityOptions& options,
                        const std::vector<SimilarityCorrespondence>& pairs,
                        Similarity3* similarity, RobustSimilaritySummary* summary) {
  RobustSimilaritySummary result;
  const int n = static_cast<int>(pairs.size());
  result.inlier.assign(n, 1);
  result.residual_m.assign(n, 0.0);
  int num_groups = 0;
  for (const SimilarityCorrespondence& pair : pairs) num_groups = std::max(num_groups, pair.group + 1);
  result.group_scale.assign(num_groups, 0.0);
  // Consistent input first: every pair must be usable.
  Similarity3 all;
  const Status fit_all = FitSimilarity(pairs, nullptr, &all);
  if (!fit_all.ok()) {
    result.message = fit_all.message();
    *summary = result;
    return fit_all;
  }
  const GroupedResiduals residuals_of(pairs, num_groups);
  const Similarity3 best = BestMinimalSample(options, pairs, residuals_of, all, &result.num_samples);
  const Similarity3 current = RefineOnInliers(options, pairs, residuals_of, best, &result);
  for (int i = 0; i < n; ++i) result.residual_m[i] = (pairs[i].target - current.Apply(pairs[i].source)).norm();
  result.num_inliers = static_cast<int>(std::count(result.inlier.begin(), result.inlier.end(), 1));
  result.success = true;
  *similarity = current;
  *summary = result;
  return Status::Ok();
}

}  // namespace photopose
