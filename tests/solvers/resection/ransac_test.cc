#include "solvers/resection/ransac.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <string>
#include <vector>

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// ------------------------------------------------------------------ a toy estimator
// Lines y = a x + b in the plane from two points: the smallest estimator that exercises every part
// of the concept (several data per sample, degenerate samples, MSAC early exit, LO by least
// squares).

struct Line {
  double a = 0.0;
  double b = 0.0;
};

class LineEstimator {
 public:
  using Model = Line;
  static constexpr int kMinimalSampleSize = 2;

  LineEstimator(std::vector<Eigen::Vector2d> points, double threshold)
      : points_(std::move(points)), threshold_sq_(threshold * threshold) {}

  int num_data() const { return static_cast<int>(points_.size()); }

  void GenerateModels(const int* sample, std::vector<Model>* models) const {
    const Eigen::Vector2d& p = points_[sample[0]];
    const Eigen::Vector2d& q = points_[sample[1]];
    if (std::abs(q.x() - p.x()) < 1e-12) return;  // vertical: degenerate for y = a x + b
    Line line;
    line.a = (q.y() - p.y()) / (q.x() - p.x());
    line.b = p.y() - line.a * p.x();
    models->push_back(line);
  }

  double ScoreModel(const Model& line, double best) const {
    double sum = 0.0;
    for (const Eigen::Vector2d& p : points_) {
      const double r = p.y() - line.a * p.x() - line.b;
      sum += std::min(r * r, threshold_sq_);
      if (sum >= best) return sum;
    }
    return sum;
  }

  int Inliers(const Model& line, std::vector<char>* mask) const {
    mask->resize(points_.size());
    int count = 0;
    for (size_t i = 0; i < points_.size(); ++i) {
      const double r = points_[i].y() - line.a * points_[i].x() - line.b;
      (*mask)[i] = r * r <= threshold_sq_;
      count += (*mask)[i];
    }
    return count;
  }

  void RefineModel(const std::vector<int>& inliers, Model* line) const {
    Eigen::MatrixXd A(inliers.size(), 2);
    Eigen::VectorXd y(inliers.size());
    for (size_t k = 0; k < inliers.size(); ++k) {
      A(k, 0) = points_[inliers[k]].x();
      A(k, 1) = 1.0;
      y[k] = points_[inliers[k]].y();
    }
    const Eigen::Vector2d ab = A.colPivHouseholderQr().solve(y);
    if (ab.allFinite()) *line = Line{ab[0], ab[1]};
  }

 private:
  std::vector<Eigen::Vector2d> points_;
  double threshold_sq_;
};

// ------------------------------------------------------------------ tolerances
// Noise sigma of the toy data and the inlier threshold (4 sigma of a 1-D residual: 99.994 % of the
// inliers fall within it).
constexpr double kNoise = 0.01;
constexpr double kThreshold = 4.0 * kNoise;
// A least-squares line through ~n (1 - outlier ratio) points with x in [-1, 1] has slope and
// intercept errors of order kNoise / sqrt(n) ~ 1e-3; 6x that.
constexpr double kLineTolerance = 6e-3;
// Fraction of data whose inlier flag must equal the truth (outliers are at least 10 sigma away, so
// only the ~1e-4 inliers beyond 4 sigma can disagree).
constexpr double kMinMaskAgreement = 0.99;

struct LineData {
  std::vector<Eigen::Vector2d> points;
  std::vector<char> is_outlier;
};

// n points on y = 0.7 x - 0.2 with Gaussian noise; a fraction replaced by gross errors of
// 10-100 sigma in y.
LineData MakeLineData(uint64_t seed, int n, double outlier_fraction) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> gaussian(0.0, kNoise);
  LineData data;
  for (int i = 0; i < n; ++i) {
    const double x = 2.0 * unit(rng) - 1.0;
    data.points.emplace_back(x, 0.7 * x - 0.2 + gaussian(rng));
    data.is_outlier.push_back(0);
  }
  const int outliers = static_cast<int>(std::lround(outlier_fraction * n));
  for (int i = 0; i < outliers; ++i) {
    const double error = kNoise * (10.0 + 90.0 * unit(rng)) * (unit(rng) < 0.5 ? -1.0 : 1.0);
    data.points[i].y() += error;
    data.is_outlier[i] = 1;
  }
  return data;
}

double MaskAgreement(const std::vector<char>& mask, const std::vector<char>& is_outlier) {
  int agree = 0;
  for (size_t i = 0; i < mask.size(); ++i) agree += (mask[i] != 0) == (is_outlier[i] == 0);
  return static_cast<double>(agree) / static_cast<double>(mask.size());
}

// ------------------------------------------------------------------ tests

TEST(RansacOptionsTest, Validation) {
  std::string why;
  EXPECT_TRUE(RansacOptions().IsValid(&why));
  RansacOptions options;
  options.max_trials = 0;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("max_trials"), std::string::npos);
  options = RansacOptions();
  options.min_trials = options.max_trials + 1;
  EXPECT_FALSE(options.IsValid(&why));
  options = RansacOptions();
  options.confidence = 1.0;
  EXPECT_FALSE(options.IsValid(&why));
  options.confidence = 0.0;
  EXPECT_FALSE(options.IsValid(nullptr));
  options = RansacOptions();
  options.max_lo_iterations = -1;
  EXPECT_FALSE(options.IsValid(&why));
}

TEST(RansacTest, RequiredTrialsByHand) {
  // log(1 - 0.99) / log(1 - 0.5^3) = -4.6052 / -0.13353 = 34.49 -> 35.
  EXPECT_EQ(internal::RequiredTrials(0.5, 3, 0.99, 10000), 35);
  // log(1e-4) / log(1 - 0.7^3) = -9.2103 / -0.42007 = 21.93 -> 22.
  EXPECT_EQ(internal::RequiredTrials(0.7, 3, 0.9999, 10000), 22);
  EXPECT_EQ(internal::RequiredTrials(1.0, 3, 0.9999, 10000), 1);
  EXPECT_EQ(internal::RequiredTrials(0.0, 3, 0.9999, 10000), 10000);
  EXPECT_EQ(internal::RequiredTrials(0.01, 3, 0.9999, 500), 500);  // capped
}

TEST(RansacTest, SamplerDrawsDistinctIndices) {
  for (int n : {2, 3, 5, 11, 1000}) {
    internal::UniformSampler sampler(123, n, 2);
    std::vector<int> hits(n, 0);
    for (int k = 0; k < 2000; ++k) {
      int sample[2];
      sampler.Sample(sample);
      ASSERT_NE(sample[0], sample[1]);
      for (int i : sample) {
        ASSERT_GE(i, 0);
        ASSERT_LT(i, n);
        ++hits[i];
      }
    }
    if (n <= 11)  // every index is drawn
      for (int h : hits) EXPECT_GT(h, 0);
  }
  internal::UniformSampler all(9, 3, 3);  // m == n: always a permutation
  for (int k = 0; k < 50; ++k) {
    int sample[3];
    all.Sample(sample);
    EXPECT_EQ(std::set<int>(sample, sample + 3), (std::set<int>{0, 1, 2}));
  }
}

TEST(RansacTest, RecoversLineWithOutliers) {
  for (double outlier_fraction : {0.3, 0.6}) {
    SCOPED_TRACE(outlier_fraction);
    const LineData data = MakeLineData(1, 500, outlier_fraction);
    const LineEstimator estimator(data.points, kThreshold);
    RansacOptions options;
    options.seed = 5;
    Line line;
    std::vector<char> mask;
    const RansacSummary summary = Ransac(options, estimator, &line, &mask);
    ASSERT_TRUE(summary.success) << summary.BriefReport();
    EXPECT_NEAR(line.a, 0.7, kLineTolerance);
    EXPECT_NEAR(line.b, -0.2, kLineTolerance);
    ASSERT_EQ(mask.size(), data.points.size());
    EXPECT_GE(MaskAgreement(mask, data.is_outlier), kMinMaskAgreement);
    EXPECT_EQ(summary.num_inliers, std::count(mask.begin(), mask.end(), 1));
    EXPECT_GT(summary.num_lo_steps, 0);
    EXPECT_GE(summary.num_models, 1);
    // The adaptive rule stops well before max_trials: for m = 2 at 0.9999 confidence the budget is
    // 14 trials at 30 % outliers and 53 at 60 %; a slightly low inlier estimate adds a few.
    EXPECT_LE(summary.num_trials, outlier_fraction < 0.5 ? 40 : 120);
    EXPECT_NE(summary.BriefReport().find("succeeded"), std::string::npos);
  }
}

TEST(RansacTest, SameSeedSameResultDifferentSeedsBothSucceed) {
  const LineData data = MakeLineData(2, 300, 0.5);
  const LineEstimator estimator(data.points, kThreshold);
  RansacOptions options;
  options.seed = 77;
  Line first, second;
  std::vector<char> first_mask, second_mask;
  const RansacSummary a = Ransac(options, estimator, &first, &first_mask);
  const RansacSummary b = Ransac(options, estimator, &second, &second_mask);
  ASSERT_TRUE(a.success && b.success);
  EXPECT_EQ(first.a, second.a);
  EXPECT_EQ(first.b, second.b);
  EXPECT_EQ(first_mask, second_mask);
  EXPECT_EQ(a.num_trials, b.num_trials);
  EXPECT_EQ(a.num_models, b.num_models);
  EXPECT_EQ(a.score, b.score);

  options.seed = 78;
  Line other;
  std::vector<char> other_mask;
  const RansacSummary c = Ransac(options, estimator, &other, &other_mask);
  ASSERT_TRUE(c.success);
  EXPECT_NEAR(other.a, 0.7, kLineTolerance);
  EXPECT_NEAR(other.b, -0.2, kLineTolerance);
}

TEST(RansacTest, FewDataAreEnumeratedAndDoNotDependOnTheSeed) {
  EXPECT_EQ(internal::CappedBinomial(15, 3, 1000), 455);
  EXPECT_EQ(internal::CappedBinomial(4, 3, 1000), 4);
  EXPECT_EQ(internal::CappedBinomial(100, 3, 1000), 1001);  // capped, no overflow
  EXPECT_EQ(internal::CappedBinomial(2, 3, 1000), 0);
  internal::CombinationSampler combinations(4, 2);
  std::vector<std::pair<int, int>> pairs;
  int sample[2];
  while (combinations.Sample(sample)) pairs.emplace_back(sample[0], sample[1]);
  EXPECT_EQ(pairs, (std::vector<std::pair<int, int>>{{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}}));
  // 30 points, 40 % of them outliers: C(30, 2) = 435 pairs, every one tried, whatever the seed.
  const LineData data = MakeLineData(3, 30, 0.4);
  const LineEstimator estimator(data.points, kThreshold);
  RansacOptions options;
  Line first;
  std::vector<char> first_mask;
  const RansacSummary a = Ransac(options, estimator, &first, &first_mask);
  ASSERT_TRUE(a.success);
  EXPECT_TRUE(a.exhaustive);
  EXPECT_EQ(a.num_trials, 435);
  for (uint64_t seed : {1, 99, 12345}) {
    options.seed = seed;
    Line other;
    std::vector<char> other_mask;
    const RansacSummary b = Ransac(options, estimator, &other, &other_mask);
    EXPECT_EQ(other.a, first.a);
    EXPECT_EQ(other.b, first.b);
    EXPECT_EQ(other_mask, first_mask);
    EXPECT_EQ(b.score, a.score);
  }
}

// stop_enumeration_when_all_inliers: an enumeration ends at the first model every datum fits (as
// the adaptive rule does when drawing), and runs in full while none does.
TEST(RansacTest, EnumerationStopsAtTheFirstModelEveryDatumFits) {
  RansacOptions options;
  options.stop_enumeration_when_all_inliers = true;
  // 30 points, no outlier, the noise shrunk to a tenth (0.025 of the threshold), so that a good
  // pair's line, refined, fits every point.
  LineData clean = MakeLineData(6, 30, 0.0);
  for (Eigen::Vector2d& p : clean.points) p.y() = 0.7 * p.x() - 0.2 + 0.1 * (p.y() - 0.7 * p.x() + 0.2);
  const LineEstimator estimator(clean.points, kThreshold);
  Line line;
  std::vector<char> mask;
  RansacSummary summary = Ransac(options, estimator, &line, &mask);
  ASSERT_TRUE(summary.success);
  EXPECT_TRUE(summary.exhaustive);
  EXPECT_TRUE(summary.stopped_early);
  EXPECT_LT(summary.num_trials, 435);
  EXPECT_EQ(summary.num_inliers, 30);
  EXPECT_EQ(std::count(mask.begin(), mask.end(), 1), 30);
  EXPECT_NE(summary.BriefReport().find("stopped"), std::string::npos) << summary.BriefReport();
  // Off (the default): every one of the C(30, 2) = 435 pairs.
  summary = Ransac(RansacOptions(), estimator, &line, &mask);
  EXPECT_FALSE(summary.stopped_early);
  EXPECT_EQ(summary.num_trials, 435);
  // With an outlier no model fits every datum: the enumeration runs in full, as without the stop.
  const LineData dirty = MakeLineData(7, 30, 0.1);
  const LineEstimator with_outliers(dirty.points, kThreshold);
  Line full;
  std::vector<char> full_mask;
  const RansacSummary reference = Ransac(RansacOptions(), with_outliers, &full, &full_mask);
  summary = Ransac(options, with_outliers, &line, &mask);
  EXPECT_FALSE(summary.stopped_early);
  EXPECT_EQ(summary.num_trials, 435);
  EXPECT_EQ(line.a, full.a);
  EXPECT_EQ(line.b, full.b);
  EXPECT_EQ(mask, full_mask);
  EXPECT_EQ(summary.score, reference.score);
}

TEST(RansacTest, TrialBounds) {
  const LineData clean = MakeLineData(3, 200, 0.0);
  const LineEstimator estimator(clean.points, kThreshold);
  Line line;
  std::vector<char> mask;
  RansacOptions options;
  // Outlier-free: the first sample's inlier ratio ~1 gives a budget of a trial or two.
  RansacSummary summary = Ransac(options, estimator, &line, &mask);
  ASSERT_TRUE(summary.success);
  EXPECT_LE(summary.num_trials, 3);
  // min_trials forces more.
  options.min_trials = 50;
  summary = Ransac(options, estimator, &line, &mask);
  EXPECT_EQ(summary.num_trials, 50);
  // max_trials caps the loop even when the adaptive rule wants more.
  const LineData dirty = MakeLineData(4, 200, 0.8);
  const LineEstimator hard(dirty.points, kThreshold);
  options = RansacOptions();
  options.max_trials = 5;
  summary = Ransac(options, hard, &line, &mask);
  EXPECT_LE(summary.num_trials, 5);
}

TEST(RansacTest, WithoutLocalOptimization) {
  const LineData data = MakeLineData(5, 400, 0.3);
  const LineEstimator estimator(data.points, kThreshold);
  RansacOptions options;
  options.local_optimization = false;
  Line line;
  std::vector<char> mask;
  const RansacSummary summary = Ransac(options, estimator, &line, &mask);
  ASSERT_TRUE(summary.success);
  EXPECT_EQ(summary.num_lo_steps, 0);
  // A line through two noisy points only: a looser check (20 sigma over the unit interval).
  EXPECT_NEAR(line.a, 0.7, 20 * kNoise);
  EXPECT_NEAR(line.b, -0.2, 20 * kNoise);
}

TEST(RansacTest, FailsCleanly) {
  Line line{1.0, 2.0};
  std::vector<char> mask = {7};
  // Fewer data than a minimal sample.
  const LineEstimator one({Eigen::Vector2d(0, 0)}, kThreshold);
  RansacSummary summary = Ransac(RansacOptions(), one, &line, &mask);
  EXPECT_FALSE(summary.success);
  EXPECT_NE(summary.message.find("at least 2"), std::string::npos) << summary.message;
  // Every sample degenerate (all points on a vertical line): no model at all.
  const LineEstimator vertical(
      {Eigen::Vector2d(1, 0), Eigen::Vector2d(1, 1), Eigen::Vector2d(1, 2)}, kThreshold);
  // Three data have three pairs: each is tried once.
  RansacOptions options;
  summary = Ransac(options, vertical, &line, &mask);
  EXPECT_FALSE(summary.success);
  EXPECT_TRUE(summary.exhaustive);
  EXPECT_EQ(summary.num_trials, 3);
  EXPECT_EQ(summary.num_models, 0);
  // Drawn instead: the trial budget.
  options.max_trials = 100;
  options.max_exhaustive_samples = 0;
  summary = Ransac(options, vertical, &line, &mask);
  EXPECT_FALSE(summary.success);
  EXPECT_FALSE(summary.exhaustive);
  EXPECT_EQ(summary.num_trials, 100);
  EXPECT_EQ(summary.num_models, 0);
  EXPECT_FALSE(summary.message.empty());
  // Invalid options.
  options.confidence = 2.0;
  summary = Ransac(options, one, &line, &mask);
  EXPECT_FALSE(summary.success);
  EXPECT_NE(summary.message.find("confidence"), std::string::npos);
  // Outputs untouched on failure.
  EXPECT_EQ(line.a, 1.0);
  EXPECT_EQ(line.b, 2.0);
  EXPECT_EQ(mask, std::vector<char>{7});
  EXPECT_NE(summary.BriefReport().find("failed"), std::string::npos);
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
