#pragma once
// The statistics of a weighted least-squares pose and the tests that decide which marks it may
// keep: the global test, Baarda's data snooping (W. Baarda, "A testing procedure for use in
// geodetic networks", 1968) when the marks' accuracy is known, and Pope's tau test (A. J. Pope,
// "The statistics of residuals and the detection of outliers", NOAA 1976) when sigma0 has to be
// estimated from the same residuals.
//
// A mark is a two-dimensional observation, so each test is of its two coordinates together. With
// e_i = (observed - computed) / sigma_i the whitened residual of mark i (2-vector), A_i its whitened
// 2 x 6 Jacobian, N = sum A_i^T A_i over the marks used, Q = N^-1:
//   - redundancy number of a mark: r_i = trace(Qvv_i) / 2, Qvv_i = I - A_i Q A_i^T (how much of its
//     own error the other marks check; they sum to the redundancy 2n - 6 over 2);
//   - test statistic of a used mark: T_i = e_i^T Qvv_i^-1 e_i, the drop of the weighted sum of
//     squares Omega = sum |e_i|^2 when the mark is left out. Known sigma: T_i ~ chi-square(2), and
//     the mark is rejected when T_i > -2 ln(alpha). Estimated sigma (s0^2 = Omega / r): T_i / Omega
//     ~ Beta(1, (r - 2) / 2) (the two-dimensional tau distribution), rejected when
//     T_i / s0^2 > r (1 - alpha^(2 / (r - 2))), r = 2n - 6 > 2;
//   - test statistic of a mark left out: the predicted residual's T_i = e_i^T (I + A_i Q A_i^T)^-1
//     e_i, chi-square(2) with known sigma; with s0 of the marks used, T_i / s0^2 is 2 F(2, r);
//   - global test (known sigma): Omega ~ chi-square(r).
// With four marks (r = 2) every T_i equals Omega: a blunder can be detected but not localised.
//
// Reliability (Baarda 1968; Foerstner, "Reliability analysis of parameter estimation in linear
// models with applications to mensuration problems in computer vision", CVGIP 1987), for the 2-D
// test of a used mark at level alpha and power beta0: a blunder b (whitened 2-vector) on mark i
// is found with probability beta0 when b^T Qvv_i b >= delta0^2, delta0^2 the non-centrality of
// chi-square(2) that exceeds the test's critical value with probability beta0.
//   - internal reliability: the largest blunder not found (the minimal detectable blunder, MDB)
//     lies along Qvv_i's smallest eigenvalue q_min: |b| = delta0 / sqrt(q_min) standard deviations;
//   - external reliability: such a blunder moves parameter k by Q A_i^T b, at most
//     delta0 sqrt(g^T Qvv_i^-1 g) with g = A_i Q e_k, that is delta0 sqrt(g^T Qvv_i^-1 g / Q_kk) of
//     its own standard deviation; the mark's value is the largest over the six parameters.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/status.h"
#include "core/types.h"

namespace photopose {

struct OutlierTestOptions {
  // 1 - alpha of every test (consensus threshold, data snooping, tau test, global test), in
  // (0, 1). 0.999: a good mark is rejected once in a thousand tests.
  double confidence = 0.999;

  bool IsValid(std::string* why) const;
};

// The consensus threshold: the largest |e_i| (standard deviations) of a mark that fits, the
// chi-square(2) quantile's square root sqrt(-2 ln(1 - confidence)) (3.72 at 0.999).
double MarkThresholdSigmas(double confidence);
// Critical value of T_i with known sigma: -2 ln(1 - confidence).
double SnoopingCriticalValue(double confidence);
// Critical value of T_i / s0^2 with sigma estimated from redundancy r > 2: r (1 - alpha^(2/(r-2))).
// NaN for r <= 2 (nothing can be localised).
double TauCriticalValue(double confidence, int redundancy);
// Critical value of a left-out mark's T_i / s0^2 with sigma estimated from redundancy r > 0: twice
// the F(2, r) quantile, r (alpha^(-2/r) - 1) (it tends to -2 ln alpha as r grows). NaN for r <= 0.
double PredictedCriticalValue(double confidence, int redundancy);
// Critical value of Omega with known sigma: the chi-square(r) quantile at `confidence`.
double GlobalTestCriticalValue(double confidence, int redundancy);
// delta0 of the 2-D test of a mark (above): sqrt of the non-centrality lambda with
// P(chi-square(2, lambda) > SnoopingCriticalValue(confidence)) = power; 4.434 at 0.999 and 0.8.
double DetectableBiasSigmas(double confidence, double power);
// Omega > GlobalTestCriticalValue, without computing the quantile when Omega is below r - 1 (a
// quantile at confidence >= 0.5 never is).
bool FailsGlobalTest(double omega, double confidence, int redundancy);

// The factor f of a pose's covariance f N^-1 (N the whitened normal matrix): the one rule of every
// resection's covariance (ResectImage, TaylorResection, the comparison's NEES). With the marks'
// accuracy stated, 1: the a-priori covariance, sigma0 = 1, whose estimate sigma0_hat^2 = Omega / r
// is tested by the global test and reported beside, not multiplied in (Foerstner and Wrobel,
// Photogrammetric Computer Vision, 2016: the estimated variance factor serves the test; at two to
// four degrees of freedom it scatters by factors of several, and sigmas scaled by it go with it:
// with noise exactly as stated, 45 of 1200 four- and five-point poses lay beyond 5 of such sigmas).
// Without a stated accuracy sigma0_hat^2 = Omega / r, the only figure there is (r > 0); 1 without
// redundancy.
double PoseCovarianceFactor(bool accuracy_stated, double omega, int redundancy);
// Fewest degrees of freedom whose sigma0_hat the standard deviations may rest on without a warning
// (count): at 5 the true sigmas may still be up to SigmaUpperFactor = 2.1 times those reported.
inline constexpr int kMinSigmaDegreesOfFreedom = 5;
// Confidence of SigmaUpperFactor (one-sided).
inline constexpr double kSigmaUpperFactorConfidence = 0.95;
// With sigma0 estimated from r degrees of freedom (r sigma0_hat^2 / sigma^2 ~ chi-square(r)): the
// factor by which the true standard deviations may exceed the reported ones at `confidence`
// (one-sided), sqrt(r / q), q the chi-square(r) quantile at 1 - confidence: 4.4 at r = 2, 2.4 at
// r = 4, 1.6 at r = 10 (0.95). Infinite for r <= 0.
double SigmaUpperFactor(double confidence, int redundancy);

struct PoseAdjustmentStatistics {
  int num_used = 0;
  int redundancy = 0;   // 2 num_used - 6
  double omega = 0.0;   // sum over the used marks of |e_i|^2 (unitless)
  Matrix6d normal = Matrix6d::Zero();    // N (whitened), m^-2 and rad^-2 units
  Matrix6d cofactor = Matrix6d::Zero();  // N^-1
  bool determined = false;               // N is positive definite
  // Per mark (one entry per observation): whitened residual, redundancy number (0 for marks not
  // used), T_i (squared whitened units; for marks not used, of the predicted residual), and
  // whether the mark is in front of the camera (a mark behind has no residual).
  std::vector<Eigen::Vector2d> whitened_residuals;
  std::vector<double> redundancy_numbers;
  std::vector<double> test_statistics;
  std::vector<char> in_front;
  // Per used mark, for delta0 = 1 (multiply by DetectableBiasSigmas): the minimal detectable
  // blunder in the mark's standard deviations, 1 / sqrt(q_min), and the largest shift of one pose
  // parameter it causes in that parameter's standard deviations (sigma0 = 1). Infinite for a mark
  // the others do not check (q_min ~ 0), 0 for marks not used.
  std::vector<double> detectable_blunder_per_delta;
  std::vector<double> pose_shift_per_delta;
};

// What ComputePoseAdjustmentStatistics computes beyond the tests. A caller that only asks whether
// a set of marks fits (the global test, the snooping) needs no reliability: its 2 x 2
// eigenvalue and inverse per mark are a third of the statistics' time.
enum class StatisticsScope {
  kTestsAndReliability,  // every field
  kTests,                // detectable_blunder_per_delta and pose_shift_per_delta left at zero
};

// The statistics of the pose `eo` for observations image_plane[i] of points_in_ground[i] with
// standard deviations sigmas[i] (unit of image_plane and focal), the marks with used[i] != 0
// forming the adjustment. Errors: fewer than three used marks, a used mark behind the camera
// (*statistics is then partly written). A singular N leaves determined = false and the test
// statistics at zero. *statistics' vectors are reused (no allocation when it held as many marks).
Status ComputePoseAdjustmentStatistics(
    const std::vector<Eigen::Vector2d>& image_plane,
    const std::vector<Eigen::Vector3d>& points_in_ground, const std::vector<double>& sigmas,
    double focal, const ExteriorOrientation& eo, const std::vector<char>& used,
    PoseAdjustmentStatistics* statistics,
    StatisticsScope scope = StatisticsScope::kTestsAndReliability);

}  // namespace photopose
