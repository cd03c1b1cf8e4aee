#include "solvers/resection/absolute_pose.h"

#include "solvers/resection/dlt.h"
#include "solvers/resection/point_configuration.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <utility>

#include "core/rotation.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace photopose {
namespace {

// Points scored between early-exit checks in ScoreModel: long enough for the compiler to keep the
// loop tight, short enough that a bad model stops soon after it is rejected.
constexpr int kScoreBlock = 8;
// Sequential test of ScoreModel: the inlier ratio assumed for a wrong pose (a wrong pose puts a
// point within a few pixels of its mark by chance only; a larger true value merely slows the
// rejection) and the likelihood ratio A at which a model is rejected (a model that could beat
// the best is lost with probability <= 1 / A).
constexpr double kSprtBadInlierRatio = 0.05;
constexpr double kSprtThreshold = 1e6;
// Local optimisation fits at most this many inliers, evenly spread over the list: beyond ~100 the
// pose is already far better than the inlier threshold needs, and the cost grows with the count.
// EstimateAbsolutePoseRansac polishes the final pose on all inliers.
constexpr int kMaxLocalOptimizationPoints = 96;
// The DLT of the local optimisation uses at most this many inliers (a 2n x 12 SVD).
constexpr int kMaxDltPoints = 24;
// Gauss-Newton stops when a step moves the projections by an RMS below this fraction of the inlier
// threshold: the next step would be far below the marking noise.
constexpr double kConvergedImageMotion = 1e-4;
// Seed of the fixed scoring order.
constexpr uint64_t kScoringOrderSeed = 0x9e3779b97f4a7c15ull;

// splitmix64 (S. Vigna): a full-period 64-bit mixer, used as a tiny portable generator and hash.
inline uint64_t SplitMix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// A deterministic pseudo-random number from a model's translation bits (the scoring start offset).
inline uint64_t ModelHash(double t0, double t1, double t2) {
  uint64_t h = 0;
  for (const double value : {t0, t1, t2}) {
    uint64_t bits;
    std::memcpy(&bits, &value, sizeof(bits));
    h = SplitMix64(h ^ bits);
  }
  return h;
}

// The body of internal::AddGaussNewtonTerms, inline so that in RefineModel's loop the sums stay in
// registers.
inline bool AddGaussNewtonTermsInline(const Eigen::Vector3d& camera_point, double observed_x_over_c,
                                      double observed_y_over_c, double* normal, double* gradient) {
  const double w = camera_point.z();
  if (!(w < 0.0)) return false;
  // With q = 1 / w and the normalised projection X = x / c = -u / w, Y = -v / w, the rows of
  // ProjectWithJacobians at the identity pose divided by c are (sin 0 = 0, cos 0 = 1 in the seed's
  // equations 17-28):
  //   jx = [q, 0, X q, X Y, -(1 + X^2), -Y],   jy = [0, q, Y q, 1 + Y^2, -X Y, X].
  // J^T J and J^T r are written out with their zeros and common factors folded.
  const double q = 1.0 / w;
  const double X = -camera_point.x() * q;
  const double Y = -camera_point.y() * q;
  const double ex = observed_x_over_c - X;
  const double ey = observed_y_over_c - Y;
  const double XX = X * X, YY = Y * Y, XY = X * Y;
  const double qq = q * q;
  const double one_xx = 1.0 + XX, one_yy = 1.0 + YY, rho = 1.0 + XX + YY;
  normal[0] += qq;                          // (0, 0)
  /* (0, 1) is zero */                      // normal[1]
  normal[2] += X * qq;                      // (0, 2)
  normal[3] += q * XY;                      // (0, 3)
  normal[4] -= q * one_xx;                  // (0, 4)
  normal[5] -= q * Y;                       // (0, 5)
  normal[6] += qq;                          // (1, 1)
  normal[7] += Y * qq;                      // (1, 2)
  normal[8] += q * one_yy;                  // (1, 3)
  normal[9] -= q * XY;                      // (1, 4)
  normal[10] += q * X;                      // (1, 5)
  normal[11] += qq * (XX + YY);             // (2, 2)
  normal[12] += q * Y * rho;                // (2, 3)
  normal[13] -= q * X * rho;                // (2, 4)
  /* (2, 5) is zero */                      // normal[14]
  normal[15] += XY * XY + one_yy * one_yy;  // (3, 3)
  normal[16] -= XY * (rho + 1.0);           // (3, 4)
  normal[17] += X;                          // (3, 5)
  normal[18] += one_xx * one_xx + XY * XY;  // (4, 4)
  normal[19] += Y;                          // (4, 5)
  normal[20] += XX + YY;                    // (5, 5)
  gradient[0] += q * ex;
  gradient[1] += q * ey;
  gradient[2] += q * (X * ex + Y * ey);
  gradient[3] += XY * ex + one_yy * ey;
  gradient[4] -= one_xx * ex + XY * ey;
  gradient[5] += X * ey - Y * ex;
  return true;
}

// A pose prepared for scoring: (u, v, w) = R X + t for the centred X, and the squared inlier
// threshold in whitened units.
struct ScoringPose {
  double r00, r01, r02, r10, r11, r12, r20, r21, r22;
  double t0, t1, t2;
  double cap;
};

// (u, v, w) = R (X - centre) = R X_centred + t with t = -R (centre - origin).
ScoringPose PrepareScoring(const PoseCandidate& model, const Eigen::Vector3d& origin, double cap) {
  const Eigen::Matrix3d& R = model.R_camera_from_ground;
  const Eigen::Vector3d t = -R * (model.center_in_ground - origin);
  return ScoringPose{R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0),
                     R(2, 1), R(2, 2), t[0],    t[1],    t[2],    cap};
}

// For the points [begin, end) of the scoring layout: adds min(w2 r^2, cap) to *sum (cap for a point
// on or behind the camera plane) and the number of outliers (w2 r^2 > cap or w >= 0) to *outliers,
// with r = (x_obs / c + u / w, y_obs / c + v / w) and w2 the datum's squared weight, and writes the
// inlier flags to flags[order[i]] when flags is not null. The SSE2 path (baseline on x86-64) takes
// two points per step with the arithmetic of the scalar loop in the same order; this loop is most
// of the time of RANSAC.
inline void ScoreRange(const ScoringPose& p, const double* x, const double* y, const double* z,
                       const double* ox, const double* oy, const double* w2, int begin, int end,
                       double* sum, int* outliers, const int* order, char* flags) {
  int i = begin;
  double partial = 0.0;
  int count = 0;
#if defined(__SSE2__)
  if (end - begin >= 2) {
    const __m128d r00 = _mm_set1_pd(p.r00), r01 = _mm_set1_pd(p.r01), r02 = _mm_set1_pd(p.r02);
    const __m128d r10 = _mm_set1_pd(p.r10), r11 = _mm_set1_pd(p.r11), r12 = _mm_set1_pd(p.r12);
    const __m128d r20 = _mm_set1_pd(p.r20), r21 = _mm_set1_pd(p.r21), r22 = _mm_set1_pd(p.r22);
    const __m128d t0 = _mm_set1_pd(p.t0), t1 = _mm_set1_pd(p.t1), t2 = _mm_set1_pd(p.t2);
    const __m128d cap = _mm_set1_pd(p.cap), zero = _mm_setzero_pd(), one = _mm_set1_pd(1.0);
    __m128d sums = _mm_setzero_pd();
    for (; i + 1 < end; i += 2) {
      const __m128d X = _mm_loadu_pd(x + i), Y = _mm_loadu_pd(y + i), Z = _mm_loadu_pd(z + i);
      const __m128d u = _mm_add_pd(
          _mm_add_pd(_mm_add_pd(_mm_mul_pd(r00, X), _mm_mul_pd(r01, Y)), _mm_mul_pd(r02, Z)), t0);
      const __m128d v = _mm_add_pd(
          _mm_add_pd(_mm_add_pd(_mm_mul_pd(r10, X), _mm_mul_pd(r11, Y)), _mm_mul_pd(r12, Z)), t1);
      const __m128d w = _mm_add_pd(
          _mm_add_pd(_mm_add_pd(_mm_mul_pd(r20, X), _mm_mul_pd(r21, Y)), _mm_mul_pd(r22, Z)), t2);
      const __m128d inv_w = _mm_div_pd(one, w);
      const __m128d dx = _mm_add_pd(_mm_loadu_pd(ox + i), _mm_mul_pd(u, inv_w));
      const __m128d dy = _mm_add_pd(_mm_loadu_pd(oy + i), _mm_mul_pd(v, inv_w));
      const __m128d r2 =
          _mm_mul_pd(_mm_add_pd(_mm_mul_pd(dx, dx), _mm_mul_pd(dy, dy)), _mm_loadu_pd(w2 + i));
      const __m128d inlier = _mm_and_pd(_mm_cmplt_pd(w, zero), _mm_cmple_pd(r2, cap));
      sums = _mm_add_pd(sums, _mm_or_pd(_mm_and_pd(inlier, r2), _mm_andnot_pd(inlier, cap)));
      const int bits = _mm_movemask_pd(inlier);
      count += 2 - (bits & 1) - (bits >> 1);
      if (flags != nullptr) {
        flags[order[i]] = static_cast<char>(bits & 1);
        flags[order[i + 1]] = static_cast<char>(bits >> 1);
      }
    }
    double lanes[2];
    _mm_storeu_pd(lanes, sums);
    partial = lanes[0] + lanes[1];
  }
#endif
  for (; i < end; ++i) {
    const double u = p.r00 * x[i] + p.r01 * y[i] + p.r02 * z[i] + p.t0;
    const double v = p.r10 * x[i] + p.r11 * y[i] + p.r12 * z[i] + p.t1;
    const double w = p.r20 * x[i] + p.r21 * y[i] + p.r22 * z[i] + p.t2;
    const double inv_w = 1.0 / w;
    const double dx = ox[i] + u * inv_w;
    const double dy = oy[i] + v * inv_w;
    const double r2 = (dx * dx + dy * dy) * w2[i];
    const bool inlier = w < 0.0 && r2 <= p.cap;
    partial += inlier ? r2 : p.cap;
    count += inlier ? 0 : 1;
    if (flags != nullptr) flags[order[i]] = inlier ? 1 : 0;
  }
  *sum += partial;
  *outliers += count;
}
}  // namespace

namespace internal {

bool AddGaussNewtonTerms(const Eigen::Vector3d& camera_point, double observed_x_over_c,
                         double observed_y_over_c, double* normal, double* gradient) {
  return AddGaussNewtonTermsInline(camera_point, observed_x_over_c, observed_y_over_c, normal,
                                   gradient);
}

}  // namespace internal

bool AbsolutePoseRansacOptions::IsValid(std::string* why) const {
  if (!ransac.IsValid(why)) return false;
  if (!(inlier_threshold > 0.0) || !std::isfinite(inlier_threshold))
    return InvalidBecause(why, "inlier_threshold must be positive and finite");
  if (lo_gauss_newton_iterations < 1)
    return InvalidBecause(why, "lo_gauss_newton_iterations must be >= 1");
  if (final_gauss_newton_iterations < 0)
    return InvalidBecause(why, "final_gauss_newton_iterations must be >= 0");
  return true;
}

AbsolutePoseEstimator::AbsolutePoseEstimator(const std::vector<Eigen::Vector2d>& image_plane_um,
                                             const std::vector<Eigen::Vector3d>& points_in_ground,
                                             double focal_um, double inlier_threshold,
                                             int gauss_newton_iterations,
                                             const std::vector<double>& sigmas,
                                             ConsensusScore score)
    : num_data_(static_cast<int>(points_in_ground.size())),
      threshold_sq_(inlier_threshold * inlier_threshold),
      gauss_newton_iterations_(gauss_newton_iterations),
      score_(score),
      median_rank_(std::max(0, (num_data_ + 4) / 2 - 1)) {
  const int n = num_data_;
  double mean_sigma_sq = 0.0;
  for (int i = 0; i < n; ++i) mean_sigma_sq += sigmas.empty() ? 1.0 : sigmas[i] * sigmas[i];
  if (n > 0) mean_sigma_sq /= n;
  typical_threshold_sq_over_c2_ = threshold_sq_ * mean_sigma_sq / (focal_um * focal_um);
  for (const Eigen::Vector3d& X : points_in_ground) origin_in_ground_ += X;
  if (n > 0) origin_in_ground_ /= n;
  centred_points_.resize(n);
  observed_over_c_.resize(n);
  unit_bearings_.resize(n);
  x_.resize(n);
  y_.resize(n);
  z_.resize(n);
  ox_.resize(n);
  oy_.resize(n);
  w2_.resize(n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d& xy = image_plane_um[i];
    centred_points_[i] = points_in_ground[i] - origin_in_ground_;
    observed_over_c_[i] = xy / focal_um;
    // (x / c, y / c, -1) is along the bearing (never zero: its third coordinate is -1).
    UnitBearing(Eigen::Vector3d(observed_over_c_[i].x(), observed_over_c_[i].y(), -1.0),
                &unit_bearings_[i]);
  }
  // The scoring copy is in a fixed pseudo-random order (a Fisher-Yates shuffle driven by
  // splitmix64 from a constant seed), so the scores are reproducible and the sequential test in
  // ScoreModel sees the points as random draws.
  order_.resize(n);
  for (int i = 0; i < n; ++i) order_[i] = i;
  uint64_t state = kScoringOrderSeed;
  for (int i = n - 1; i > 0; --i) {
    state = SplitMix64(state);
    std::swap(order_[i], order_[static_cast<int>(state % static_cast<uint64_t>(i + 1))]);
  }
  for (int k = 0; k < n; ++k) {
    const int i = order_[k];
    x_[k] = centred_points_[i].x();
    y_[k] = centred_points_[i].y();
    z_[k] = centred_points_[i].z();
    ox_[k] = observed_over_c_[i].x();
    oy_[k] = observed_over_c_[i].y();
    const double sigma = sigmas.empty() ? 1.0 : sigmas[i];
    w2_[k] = focal_um * focal_um / (sigma * sigma);
  }
}

void AbsolutePoseEstimator::GenerateModels(const int* sample, std::vector<Model>* models) const {
  const std::array<Eigen::Vector3d, 3> bearings = {
      unit_bearings_[sample[0]], unit_bearings_[sample[1]], unit_bearings_[sample[2]]};
  const std::array<Eigen::Vector3d, 3> points = {
      centred_points_[sample[0]], centred_points_[sample[1]], centred_points_[sample[2]]};
  const size_t first = models->size();
  SolveP3PUnitBearings(bearings, points, models);
  for (size_t k = first; k < models->size(); ++k)
    (*models)[k].center_in_ground += origin_in_ground_;
}

void AbsolutePoseEstimator::WhitenedSquares(const Model& model,
                                            std::vector<double>* squares) const {
  squares->assign(num_data_, std::numeric_limits<double>::infinity());
  const ScoringPose pose = PrepareScoring(model, origin_in_ground_, 0.0);
  for (int k = 0; k < num_data_; ++k) {
    const double u = pose.r00 * x_[k] + pose.r01 * y_[k] + pose.r02 * z_[k] + pose.t0;
    const double v = pose.r10 * x_[k] + pose.r11 * y_[k] + pose.r12 * z_[k] + pose.t1;
    const double w = pose.r20 * x_[k] + pose.r21 * y_[k] + pose.r22 * z_[k] + pose.t2;
    if (!(w < 0.0)) continue;
    const double dx = ox_[k] + u / w, dy = oy_[k] + v / w;
    (*squares)[order_[k]] = (dx * dx + dy * dy) * w2_[k];
  }
}

double AbsolutePoseEstimator::RobustSigma(const Model& model) const {
  std::vector<double> squares;
  WhitenedSquares(model, &squares);
  std::nth_element(squares.begin(), squares.begin() + median_rank_, squares.end());
  const double h = median_rank_ + 1.0;
  // |r|^2 / sigma^2 of a 2-D Gaussian residual is chi-square(2): its p-quantile is -2 ln(1 - p).
  const double quantile = -2.0 * std::log(1.0 - h / (num_data_ + 1.0));
  const double correction = 1.0 + 5.0 / std::max(1, num_data_ - kMinimalSampleSize);
  // Noise-free data would give 0; a scale of 1e-9 of c (in whitened units) stands for rounding.
  const double floor = 1e-9 * std::sqrt(*std::min_element(w2_.begin(), w2_.end()));
  return std::max(correction * std::sqrt(squares[median_rank_] / quantile), floor);
}

double AbsolutePoseEstimator::ScoreModel(const Model& model, double best_score_so_far) const {
  if (score_ == ConsensusScore::kLeastMedian) {
    std::vector<double> squares;
    WhitenedSquares(model, &squares);
    std::nth_element(squares.begin(), squares.begin() + median_rank_, squares.end());
    return squares[median_rank_];
  }
  // Work in image-plane units divided by c: x / c = -u / w, so the residual over c is
  // x_obs / c + u / w, and one reciprocal of w serves both coordinates; the squared weights whiten.
  const ScoringPose pose = PrepareScoring(model, origin_in_ground_, threshold_sq_);
  const double limit = best_score_so_far;

  // Sequential probability ratio test (J. Matas and O. Chum, "Randomized RANSAC with sequential
  // probability ratio test", ICCV 2005). A model that beats the best has fewer than
  // best / threshold^2 outliers, so an inlier ratio of at least eps = 1 - best / (n threshold^2).
  // Against a bad model (inlier ratio kSprtBadInlierRatio) the log likelihood ratio gains
  // log((1 - delta) / (1 - eps)) per outlier and log(delta / eps) per inlier; past log(A) the model
  // is rejected, which by Wald's bound happens to a model with inlier ratio >= eps with probability
  // <= 1 / A. A bad model is thus dropped after a dozen or so points instead of the ~n (1 - eps)
  // that the exact bound (sum >= best) needs.
  // The best score changes rarely (every model of a RANSAC run is scored against it): its two
  // logarithms are kept from the last call.
  if (!(sprt_best_score_ == best_score_so_far)) {
    const double eps = 1.0 - best_score_so_far / (num_data_ * threshold_sq_);
    const bool sprt = eps > 2.0 * kSprtBadInlierRatio && eps < 1.0;
    sprt_best_score_ = best_score_so_far;
    sprt_log_per_inlier_ = sprt ? std::log(kSprtBadInlierRatio / eps) : 0.0;
    sprt_log_per_outlier_ = sprt ? std::log((1.0 - kSprtBadInlierRatio) / (1.0 - eps)) : 0.0;
  }
  const double log_per_inlier = sprt_log_per_inlier_;
  const double log_per_outlier = sprt_log_per_outlier_;
  const double log_threshold = std::log(kSprtThreshold);

  double sum = 0.0;
  double log_ratio = 0.0;
  // Points are stored in a pseudo-random order (the test needs random draws, whatever the
  // caller's order), and each model starts at its own pseudo-random offset so that one unlucky
  // run of the order cannot reject every good model.
  const int start =
      static_cast<int>(ModelHash(pose.t0, pose.t1, pose.t2) % static_cast<uint64_t>(num_data_));
  for (int pass = 0; pass < 2; ++pass) {
    const int first = pass == 0 ? start : 0;
    const int last = pass == 0 ? num_data_ : start;
    for (int begin = first; begin < last; begin += kScoreBlock) {
      const int end = std::min(begin + kScoreBlock, last);
      int outliers = 0;
      ScoreRange(pose, x_.data(), y_.data(), z_.data(), ox_.data(), oy_.data(), w2_.data(), begin,
                 end, &sum, &outliers, nullptr, nullptr);
      if (sum >= limit) return std::max(sum, best_score_so_far);
      log_ratio += outliers * log_per_outlier + (end - begin - outliers) * log_per_inlier;
      if (log_ratio > log_threshold) return std::numeric_limits<double>::infinity();
    }
  }
  return sum;
}

int AbsolutePoseEstimator::Inliers(const Model& model, std::vector<char>* mask) const {
  mask->resize(num_data_);
  if (score_ == ConsensusScore::kLeastMedian) {
    const double sigma = RobustSigma(model);
    std::vector<double> squares;
    WhitenedSquares(model, &squares);
    int count = 0;
    for (int i = 0; i < num_data_; ++i) {
      (*mask)[i] = squares[i] <= threshold_sq_ * sigma * sigma ? 1 : 0;
      count += (*mask)[i];
    }
    return count;
  }
  double sum = 0.0;
  int outliers = 0;
  const ScoringPose pose = PrepareScoring(model, origin_in_ground_, threshold_sq_);
  ScoreRange(pose, x_.data(), y_.data(), z_.data(), ox_.data(), oy_.data(), w2_.data(), 0,
             num_data_, &sum, &outliers, order_.data(), mask->data());
  return num_data_ - outliers;
}

void AbsolutePoseEstimator::RefineModel(const std::vector<int>& inliers, Model* model) const {
  // The non-minimal solver of the local optimisation (Lebeda et al. 2012): with six or more inliers
  // the DLT (solvers/resection/dlt.h) on an evenly spread subset of them proposes a second start; both starts
  // are polished by Gauss-Newton and the better-scoring one is kept. Coplanar inliers (flat
  // terrain) make the DLT decline, and the Gauss-Newton refinement of the sample's model remains.
  Model refined = *model;
  GaussNewton(inliers, kMaxLocalOptimizationPoints, gauss_newton_iterations_, &refined);
  const int size = static_cast<int>(inliers.size());
  if (size >= kDltMinimumPoints) {
    // The DLT start, its Gauss-Newton polish and its score depend on the inliers alone, and local
    // optimisation meets the same inlier set again and again: they are kept for the last set.
    const double infinity = std::numeric_limits<double>::infinity();
    if (!dlt_.valid || dlt_.inliers != inliers) {
      dlt_.valid = true;
      dlt_.inliers = inliers;
      const int count = std::min(size, kMaxDltPoints);
      dlt_.bearings.resize(count);
      dlt_.points.resize(count);
      for (int k = 0; k < count; ++k) {
        const int i = inliers[static_cast<size_t>(k) * size / count];
        dlt_.bearings[k] =
            Eigen::Vector3d(observed_over_c_[i].x(), observed_over_c_[i].y(), -1.0).normalized();
        dlt_.points[k] = centred_points_[i];
      }
      dlt_.solved = SolveDlt(dlt_.bearings, dlt_.points, &dlt_.model).ok();
      if (dlt_.solved) {
        dlt_.model.center_in_ground += origin_in_ground_;
        GaussNewton(inliers, kMaxLocalOptimizationPoints, gauss_newton_iterations_, &dlt_.model);
        dlt_.score = ScoreModel(dlt_.model, infinity);
      }
    }
    if (dlt_.solved && dlt_.score < ScoreModel(refined, infinity)) refined = dlt_.model;
  }
  *model = refined;
}

void AbsolutePoseEstimator::Polish(const std::vector<int>& inliers, int iterations,
                                   Model* model) const {
  GaussNewton(inliers, static_cast<int>(inliers.size()), iterations, model);
}

void AbsolutePoseEstimator::GaussNewton(const std::vector<int>& indices, int max_points,
                                        int iterations, Model* model) const {
  const int size = static_cast<int>(indices.size());
  const int count = std::min(size, max_points);
  if (count < kMinimalSampleSize) return;
  Eigen::Matrix3d R = model->R_camera_from_ground;
  Eigen::Vector3d center = model->center_in_ground - origin_in_ground_;
  // In the normalised units of AddGaussNewtonTerms (image plane / c).
  const double converged_motion_sq =
      kConvergedImageMotion * kConvergedImageMotion * typical_threshold_sq_over_c2_;
  // Each iteration linearises about the current pose in a local ground frame X' = R (X - centre),
  // where the pose is the zero vector: the increments (dX0', d_omega, d_phi, d_kappa) are then the
  // eo partials of the collinearity equations at zero angles (AddGaussNewtonTerms, no
  // trigonometry per point), with no Euler-angle singularity, and
  // R <- R_seed(d_angles) R, centre <- centre + R^T dX0'.
  for (int iteration = 0; iteration < iterations; ++iteration) {
    double normal[21] = {};
    double gradient[6] = {};
    int used = 0;
    for (int k = 0; k < count; ++k) {
      // An even spread over the list when it is subsampled (the inliers come in data order).
      const int i = count == size
                        ? indices[k]
                        : indices[static_cast<int>(static_cast<int64_t>(k) * size / count)];
      const Eigen::Vector3d local = R * (centred_points_[i] - center);
      if (AddGaussNewtonTermsInline(local, observed_over_c_[i].x(), observed_over_c_[i].y(), normal,
                                    gradient))
        ++used;
    }
    if (used < kMinimalSampleSize) return;
    Matrix6d N;
    for (int r = 0, k = 0; r < 6; ++r)
      for (int c = r; c < 6; ++c, ++k) N(r, c) = N(c, r) = normal[k];
    const Vector6d g = Eigen::Map<const Vector6d>(gradient);
    const Vector6d step = N.ldlt().solve(g);
    if (!step.allFinite()) return;
    center += R.transpose() * step.head<3>();
    double R_step[9];
    SeedRotationMatrix(step[3], step[4], step[5], R_step);
    R = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(R_step) * R;
    // step^T J^T J step is the summed squared motion of the projections; once its RMS is
    // negligible the next step would be smaller still.
    if (step.dot(N * step) <= converged_motion_sq * used) break;
  }
  model->R_camera_from_ground = R;
  model->center_in_ground = center + origin_in_ground_;
}

Status EstimateAbsolutePoseRansac(const AbsolutePoseRansacOptions& options,
                                  const std::vector<Eigen::Vector2d>& image_plane_um,
                                  const std::vector<Eigen::Vector3d>& points_in_ground,
                                  double focal_um, ExteriorOrientation* eo,
                                  std::vector<char>* inlier_mask, RansacSummary* summary) {
  return EstimateAbsolutePoseRansac(options, image_plane_um, points_in_ground, {}, focal_um, eo,
                                    inlier_mask, summary);
}

Status EstimateAbsolutePoseRansac(const AbsolutePoseRansacOptions& options,
                                  const std::vector<Eigen::Vector2d>& image_plane_um,
                                  const std::vector<Eigen::Vector3d>& points_in_ground,
                                  const std::vector<double>& sigmas, double focal_um,
                                  ExteriorOrientation* eo, std::vector<char>* inlier_mask,
                                  RansacSummary* summary) {
  RansacSummary local_summary;
  RansacSummary& out = summary != nullptr ? *summary : local_summary;
  out = RansacSummary();
  auto fail = [&out](const std::string& message) {
    out.success = false;
    out.message = message;
    return Status::Error("absolute pose RANSAC: " + message);
  };

  if (const Status valid = Validate(options, "invalid options: "); !valid.ok())
    return fail(valid.message());
  const int n = static_cast<int>(points_in_ground.size());
  if (image_plane_um.size() != points_in_ground.size())
    return fail(std::to_string(image_plane_um.size()) + " image points for " + std::to_string(n) +
                " ground points");
  if (!(focal_um > 0.0) || !std::isfinite(focal_um))
    return fail("the principal distance must be positive and finite");
  if (n < AbsolutePoseEstimator::kMinimalSampleSize)
    return fail("needs at least 3 points, got " + std::to_string(n));
  if (!sigmas.empty() && static_cast<int>(sigmas.size()) != n)
    return fail(std::to_string(sigmas.size()) + " standard deviations for " + std::to_string(n) +
                " points");
  for (int i = 0; i < n; ++i) {
    if (!image_plane_um[i].allFinite() || !points_in_ground[i].allFinite())
      return fail("correspondence " + std::to_string(i) + " is not finite");
    if (!sigmas.empty() && !(sigmas[i] > 0.0 && std::isfinite(sigmas[i])))
      return fail("the standard deviation of correspondence " + std::to_string(i) +
                  " is not positive and finite");
  }

  // All points on one line (or one point): the pose is not determined, so fail before sampling.
  if (ComputePointSpread(points_in_ground).collinear())
    return fail("all ground points are collinear (or coincide); the pose is not determined");

  const AbsolutePoseEstimator estimator(image_plane_um, points_in_ground, focal_um,
                                        options.inlier_threshold,
                                        options.lo_gauss_newton_iterations, sigmas, options.score);
  PoseCandidate pose;
  std::vector<char> mask;
  out = Ransac(options.ransac, estimator, &pose, &mask);
  if (!out.success) return fail(out.message);

  // Polish on all inliers; kept only if it does not worsen the MSAC score, and then the inliers
  // are those of the polished pose.
  if (options.final_gauss_newton_iterations > 0) {
    std::vector<int> inliers;
    inliers.reserve(out.num_inliers);
    for (int i = 0; i < n; ++i)
      if (mask[i]) inliers.push_back(i);
    PoseCandidate polished = pose;
    estimator.Polish(inliers, options.final_gauss_newton_iterations, &polished);
    const double score = estimator.ScoreModel(polished, std::numeric_limits<double>::infinity());
    if (score <= out.score) {
      pose = polished;
      out.score = score;
      out.num_inliers = estimator.Inliers(pose, &mask);
    }
  }

  // Inliers are in front of the camera by definition, so a pose with at least three of them has
  // three points in front; anything less is the all-behind failure.
  if (out.num_inliers < AbsolutePoseEstimator::kMinimalSampleSize)
    return fail("fewer than 3 points are in front of the camera of the best pose");

  eo->set_center_in_ground(pose.center_in_ground);
  eo->set_angles_seed_rad(AnglesFromRotation(RotationConvention::kSeed, pose.R_camera_from_ground));
  if (inlier_mask != nullptr) *inlier_mask = std::move(mask);
  return Status::Ok();
}

}  // namespace photopose
