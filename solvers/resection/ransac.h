#pragma once
// Robust model fitting: MSAC scoring (P. Torr and A. Zisserman, "MLESAC: A new robust estimator
// with application to estimating image geometry", CVIU 2000) with local optimisation (O. Chum,
// J. Matas and J. Kittler, "Locally optimized RANSAC", DAGM 2003; K. Lebeda, J. Matas and O. Chum,
// "Fixing the locally optimized RANSAC", BMVC 2012) and the adaptive stopping rule of Fischler and
// Bolles (CACM 1981).
//
// The loop, for trial = 1, 2, ...: draw kMinimalSampleSize distinct indices uniformly, generate
// the models of that minimal sample, score each; a model that beats the best so far becomes the
// best and, with local optimisation and more inliers than a minimal sample, is refined on its
// inliers and re-scored, repeatedly while that lowers the score and changes the inlier set. The
// trial budget is then lowered to the number of samples that, at the best model's inlier ratio w,
// contain at least one all-inlier sample with the requested confidence:
//   log(1 - confidence) / log(1 - w^kMinimalSampleSize).
// The loop stops when the budget is reached.
//
// Small data sets are not sampled but enumerated: when the number of distinct minimal samples
// C(n, m) is at most RansacOptions::max_exhaustive_samples, every sample is tried once, in
// lexicographic order, and the adaptive rule is not used. The result is then the same for every
// seed (a surveyor's four to fifteen control points: C(15, 3) = 455). With
// stop_enumeration_when_all_inliers the enumeration ends at the first model that every datum
// fits, as the adaptive rule would.
//
// The Estimator concept (duck-typed; solvers/resection/absolute_pose.h has the resection one):
//
//   struct Estimator {
//     using Model = ...;                           // default-constructible, copyable
//     static constexpr int kMinimalSampleSize = m;  // data per minimal sample
//     int num_data() const;                         // data are indexed 0 .. num_data() - 1
//     // Appends the models of the m distinct data sample[0..m-1] to *models (cleared by the
//     // caller; its capacity is reused, so no allocation in the loop). A degenerate sample
//     // appends none.
//     void GenerateModels(const int* sample, std::vector<Model>* models) const;
//     // MSAC cost, lower is better: sum over all data of min(r_i^2, threshold^2). It may stop
//     // early and return any value >= best_score_so_far once it cannot beat it.
//     double ScoreModel(const Model& model, double best_score_so_far) const;
//     // Resizes *mask to num_data(), sets mask[i] = 1 for inliers (r_i <= threshold), else 0,
//     // and returns the inlier count.
//     int Inliers(const Model& model, std::vector<char>* mask) const;
//     // The local-optimisation step: improves *model from the given inlier indices (a
//     // non-minimal fit, e.g. a few Gauss-Newton iterations), as close to convergence as it can
//     // afford, since local optimisation stops once the inlier set repeats. Leaves it unchanged
//     // when it cannot.
//     void RefineModel(const std::vector<int>& inliers, Model* model) const;
//   };
//
// Reproducibility: the generator is std::mt19937_64 seeded with RansacOptions::seed, and indices
// are drawn with an explicit reduction instead of std::uniform_int_distribution (whose algorithm is
// left to the standard library), so a seed gives the same samples on every platform.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/status.h"

namespace photopose {

struct RansacOptions {
  // Upper bound on the number of minimal samples drawn (trials), >= 1.
  int max_trials = 10000;
  // Lower bound on the number of trials before the adaptive rule may stop, 0 .. max_trials.
  int min_trials = 0;
  // Probability, in (0, 1), of having drawn at least one all-inlier sample when stopping.
  double confidence = 0.9999;
  // Seed of the random generator; the same seed and data give the same result.
  uint64_t seed = 0;
  // Refine each new best model on its inliers (LO-RANSAC).
  bool local_optimization = true;
  // Refine -> re-score rounds per new best model, >= 0; a round that does not lower the score, or
  // after which the inlier set is unchanged, ends the local optimisation early.
  int max_lo_iterations = 4;
  // Enumerate every minimal sample, instead of drawing, when there are at most this many (>= 0;
  // 0 never enumerates). Enumeration ignores max_trials, min_trials and the seed.
  int max_exhaustive_samples = 1000;
  // Stop an enumeration at the first model whose inliers (after local optimisation) are all the
  // data: what the adaptive rule does when drawing (an inlier ratio of 1 needs one trial), since
  // no later sample can have more inliers. The enumeration then returns that model, not the
  // lowest-scoring one of every sample: for a caller that fits all the data by least squares
  // next (solvers/resection/resection.cc), not for one that keeps the consensus pose.
  bool stop_enumeration_when_all_inliers = false;

  bool IsValid(std::string* why) const {
    if (max_trials < 1) return InvalidBecause(why, "max_trials must be >= 1");
    if (min_trials < 0 || min_trials > max_trials)
      return InvalidBecause(why, "min_trials must be in [0, max_trials]");
    if (!(confidence > 0.0 && confidence < 1.0))
      return InvalidBecause(why, "confidence must be in (0, 1)");
    if (max_lo_iterations < 0) return InvalidBecause(why, "max_lo_iterations must be >= 0");
    if (max_exhaustive_samples < 0)
      return InvalidBecause(why, "max_exhaustive_samples must be >= 0");
    return true;
  }
};

struct RansacSummary {
  int num_trials = 0;   // minimal samples drawn
  int num_models = 0;   // models generated from them (and scored)
  int num_inliers = 0;  // inliers of the returned model
  double score = std::numeric_limits<double>::infinity();  // its MSAC cost (data units squared)
  int num_lo_steps = 0;                                    // RefineModel calls
  bool exhaustive = false;  // the minimal samples were enumerated (no random draws): all of them,
                            // unless stopped_early
  bool stopped_early = false;  // the enumeration stopped at a model with every datum an inlier
  bool success = false;  // a model with >= kMinimalSampleSize inliers was found
  std::string message;   // why it failed, or a note on success

  std::string BriefReport() const {
    std::ostringstream out;
    out << "RANSAC " << (success ? "succeeded" : "failed") << ": " << num_inliers << " inliers, "
        << num_trials << " trials, " << num_models << " models, " << num_lo_steps
        << " LO steps, score " << score << (exhaustive ? ", exhaustive" : "")
        << (stopped_early ? " (stopped at a model with every datum an inlier)" : "");
    if (!message.empty()) out << " (" << message << ")";
    return out.str();
  }
};

namespace internal {

// Number of trials that draw an all-inlier sample of size m with probability `confidence` when a
// fraction inlier_ratio of the data are inliers, capped at `cap`.
inline int RequiredTrials(double inlier_ratio, int m, double confidence, int cap) {
  const double p_good = std::pow(inlier_ratio, m);
  if (p_good >= 1.0) return 1;
  if (!(p_good > 0.0)) return cap;
  const double denominator = std::log1p(-p_good);
  if (!(denominator < 0.0)) return cap;  // p_good below rounding of 1 - p_good
  const double trials = std::ceil(std::log(1.0 - confidence) / denominator);
  if (!(trials < static_cast<double>(cap))) return cap;
  return trials < 1.0 ? 1 : static_cast<int>(trials);
}

// C(n, m), or cap + 1 when it exceeds cap (no overflow).
inline long long CappedBinomial(int n, int m, long long cap) {
  if (m < 0 || m > n) return 0;
  long long value = 1;
  for (int k = 1; k <= m; ++k) {
    value = value * (n - m + k) / k;  // exact: C(n - m + k, k) at every step
    if (value > cap) return cap + 1;
  }
  return value;
}

// Every m-subset of [0, n) once, in lexicographic order.
class CombinationSampler {
 public:
  CombinationSampler(int n, int m) : n_(n), m_(m), current_(m) {
    for (int k = 0; k < m_; ++k) current_[k] = k;
  }
  // Writes the next subset; false (nothing written) after the last one.
  bool Sample(int* sample) {
    if (done_) return false;
    for (int k = 0; k < m_; ++k) sample[k] = current_[k];
    int k = m_ - 1;
    while (k >= 0 && current_[k] == n_ - m_ + k) --k;
    if (k < 0) {
      done_ = true;
    } else {
      ++current_[k];
      for (int j = k + 1; j < m_; ++j) current_[j] = current_[j - 1] + 1;
    }
    return true;
  }

 private:
  int n_, m_;
  std::vector<int> current_;
  bool done_ = false;
};

// Draws m distinct indices in [0, n), uniformly over subsets, from a seeded mt19937_64.
class UniformSampler {
 public:
  UniformSampler(uint64_t seed, int n, int m) : rng_(seed), n_(n), m_(m) {
    // Rejection of repeats is cheap when m is small against n; otherwise a partial shuffle.
    if (n_ < 4 * m_) {
      pool_.resize(n_);
      for (int i = 0; i < n_; ++i) pool_[i] = i;
    }
  }

  void Sample(int* sample) {
    if (!pool_.empty()) {
      for (int k = 0; k < m_; ++k) {
        const int j = k + UniformBelow(n_ - k);
        std::swap(pool_[k], pool_[j]);
        sample[k] = pool_[k];
      }
      return;
    }
    for (int k = 0; k < m_; ++k) {
      int candidate;
      bool repeated;
      do {
        candidate = UniformBelow(n_);
        repeated = false;
        for (int j = 0; j < k; ++j) repeated |= sample[j] == candidate;
      } while (repeated);
      sample[k] = candidate;
    }
  }

 private:
  // Uniform in [0, bound) for 0 < bound < 2^31: the high half of (top 32 random bits) x bound, a
  // multiply-shift reduction (D. Lemire, "Fast random integer generation in an interval", 2019)
  // without its rejection step; the bias, below bound / 2^32, is immaterial for sampling.
  int UniformBelow(int bound) {
    const uint64_t high = rng_() >> 32;
    return static_cast<int>((high * static_cast<uint64_t>(bound)) >> 32);
  }

  std::mt19937_64 rng_;
  int n_;
  int m_;
  std::vector<int> pool_;
};

// The best model of a Ransac run so far, with its score and inliers: what its loop keeps between
// trials.
template <typename Estimator>
struct RansacBest {
  using Model = typename Estimator::Model;

  explicit RansacBest(int n) : mask(n, 0) {
    inliers.reserve(n);
    previous_inliers.reserve(n);
  }

  // Gathers the indices of the inliers of `model` into `inliers` (and `mask`), sets num_inliers.
  void CollectInliers(const Estimator& estimator) {
    num_inliers = estimator.Inliers(model, &mask);
    inliers.clear();
    const int n = static_cast<int>(mask.size());
    for (int i = 0; i < n; ++i)
      if (mask[i]) inliers.push_back(i);
  }

  Model model{};
  bool found = false;
  double score = std::numeric_limits<double>::infinity();  // MSAC cost of `model`
  int num_inliers = 0;
  std::vector<char> mask;  // the inliers of `model`, filled whenever it changed
  std::vector<int> inliers, previous_inliers;
};

// Scores the models of one minimal sample; each that beats the best so far becomes the best.
// Returns whether one did.
template <typename Estimator>
bool TakeBetterModel(const Estimator& estimator, const std::vector<typename Estimator::Model>& models,
                     RansacBest<Estimator>* best) {
  bool improved = false;
  for (const typename Estimator::Model& model : models) {
    const double score = estimator.ScoreModel(model, best->score);
    if (!(score < best->score)) continue;
    best->model = model;
    best->score = score;
    best->found = true;
    improved = true;
  }
  return improved;
}

// Local optimisation of a new best model (its inliers collected): refined on its inliers and
// re-scored, repeatedly while that lowers the score and changes the inlier set, at most
// max_lo_iterations times. Counts the RefineModel calls in *num_lo_steps.
template <typename Estimator>
void LocallyOptimize(const RansacOptions& options, const Estimator& estimator, RansacBest<Estimator>* best,
                     int* num_lo_steps) {
  for (int round = 0; round < options.max_lo_iterations; ++round) {
    if (best->num_inliers < Estimator::kMinimalSampleSize) break;
    typename Estimator::Model refined = best->model;
    estimator.RefineModel(best->inliers, &refined);
    ++*num_lo_steps;
    const double score = estimator.ScoreModel(refined, best->score);
    if (!(score < best->score)) break;
    best->model = refined;
    best->score = score;
    // A converged refinement on the same inliers would return the same model: stop when the
    // inlier set repeats.
    best->previous_inliers.swap(best->inliers);
    best->CollectInliers(estimator);
    if (best->inliers == best->previous_inliers) break;
  }
}

}  // namespace internal

// Robustly fits estimator's model. On success writes *best_model and *inlier_mask (num_data()
// entries, 1 for inliers) and returns success = true. On failure (invalid options, fewer data than
// a minimal sample, no model with at least kMinimalSampleSize inliers) leaves both outputs
// untouched and returns success = false with a message.
template <typename Estimator>
RansacSummary Ransac(const RansacOptions& options, const Estimator& estimator,
                     typename Estimator::Model* best_model, std::vector<char>* inlier_mask) {
  using Model = typename Estimator::Model;
  constexpr int kSampleSize = Estimator::kMinimalSampleSize;
  static_assert(kSampleSize >= 1, "kMinimalSampleSize must be positive");

  RansacSummary summary;
  if (const Status valid = Validate(options, "invalid RansacOptions: "); !valid.ok()) {
    summary.message = valid.message();
    return summary;
  }
  const int n = estimator.num_data();
  if (n < kSampleSize) {
    summary.message =
        "needs at least " + std::to_string(kSampleSize) + " data, got " + std::to_string(n);
    return summary;
  }

  const long long num_subsets =
      internal::CappedBinomial(n, kSampleSize, options.max_exhaustive_samples);
  summary.exhaustive = num_subsets <= options.max_exhaustive_samples;
  internal::UniformSampler sampler(options.seed, n, kSampleSize);
  internal::CombinationSampler combinations(n, kSampleSize);
  int sample[kSampleSize];
  std::vector<Model> models;
  models.reserve(16);
  internal::RansacBest<Estimator> best(n);
  int trial_budget = options.max_trials;

  while (summary.exhaustive || summary.num_trials < std::max(options.min_trials, trial_budget)) {
    if (summary.exhaustive) {
      if (!combinations.Sample(sample)) break;
    } else {
      sampler.Sample(sample);
    }
    ++summary.num_trials;
    models.clear();
    estimator.GenerateModels(sample, &models);
    summary.num_models += static_cast<int>(models.size());
    if (!internal::TakeBetterModel(estimator, models, &best)) continue;

    best.CollectInliers(estimator);
    // A model supported by no more than its own minimal sample has nothing to be refined on (and
    // in practice is a wrong model found before any good one): local optimisation would only
    // spend a full scoring pass on it.
    if (options.local_optimization && best.num_inliers > kSampleSize)
      internal::LocallyOptimize(options, estimator, &best, &summary.num_lo_steps);
    if (summary.exhaustive && options.stop_enumeration_when_all_inliers && best.num_inliers == n) {
      summary.stopped_early = true;
      break;
    }
    trial_budget = internal::RequiredTrials(static_cast<double>(best.num_inliers) / n, kSampleSize,
                                            options.confidence, options.max_trials);
  }

  summary.score = best.score;
  summary.num_inliers = best.num_inliers;
  if (!best.found || best.num_inliers < kSampleSize) {
    summary.message = best.found ? "no model with at least " + std::to_string(kSampleSize) +
                                       " inliers (best has " + std::to_string(best.num_inliers) + ")"
                                 : "no model could be generated from " +
                                       std::to_string(summary.num_trials) + " samples";
    return summary;
  }
  summary.success = true;
  *best_model = best.model;
  *inlier_mask = std::move(best.mask);
  return summary;
}

}  // namespace photopose
