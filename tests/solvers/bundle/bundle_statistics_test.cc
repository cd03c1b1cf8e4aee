// The statistics of solvers/bundle/bundle_statistics.cc by selected inversion against the dense
// inverse (the oracle, BundleCovarianceMethod::kDenseInverse), on simulated blocks with every kind
// of datum and of extra unknowns.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/simulation/synthetic_block.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/bundle/taylor_bundle.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// Selected and dense inverses agree to rounding; every figure derived from them to this,
// relative (the bound; measured on these blocks: covariances within 5e-11, redundancy
// numbers 2e-12 absolute, w, nabla and external reliability 6e-11 where r >= 1e-4).
constexpr double kRelative = 1e-8;
// The redundancy numbers add up to n - u to this, relative.
constexpr double kRedundancySum = 1e-6;
// w, the smallest detectable error and the external reliability go as r^-1/2, and r = 1 - h loses
// digits to the cancellation when it is small: h is exact to ~1e-13 absolute in either inverse,
// so below this redundancy number their relative tolerance grows as kSmallRedundancy / r (measured
// in the relative block: r = 3.7e-6, the two inverses 1.7e-8 apart in w).
constexpr double kSmallRedundancy = 1e-4;
// The smallest detectable error and the external reliability are stored in single precision
// (BundleObservationDiagnostics): each side rounded once, so they agree to two float epsilons.
constexpr double kSingle = 2.0 * std::numeric_limits<float>::epsilon();

enum class Datum { kGnss, kControlOnly, kFreeGauge };

struct Scenario {
  std::string name;
  int lines = 4;
  int images_per_line = 5;
  Datum datum = Datum::kGnss;
  bool self_calibration = false;
  bool lever_arm = false;
};

SyntheticBlockOptions BlockOptions(const Scenario& s) {
  SyntheticBlockOptions o;
  o.seed = 11;
  o.num_lines = s.lines;
  o.images_per_line = s.images_per_line;
  o.tie_point_density_per_m2 = 0.02;
  o.gnss = s.datum == Datum::kGnss;
  o.num_control_points = s.datum == Datum::kFreeGauge ? 0 : 8;
  o.num_check_points = s.datum == Datum::kFreeGauge ? 0 : 4;
  o.control_sigma_m = 0.005;
  o.mark_sigma_px = 0.5;
  return o;
}

BundleAdjustmentOptions Options(BundleCovarianceMethod method) {
  BundleAdjustmentOptions options;
  options.statistics.covariances = method;
  options.robustness.max_rejection_rounds = 0;
  options.solver.num_threads = 1;  // the same adjustment bit for bit in both runs
  return options;
}

// |a - b| within kRelative of `scale` (the quantity's own size or its natural yardstick).
void ExpectClose(double sparse, double dense, double scale, const std::string& what) {
  if (std::isinf(dense) || std::isnan(dense)) {
    EXPECT_EQ(std::isinf(sparse), std::isinf(dense)) << what;
    EXPECT_EQ(std::isnan(sparse), std::isnan(dense)) << what;
    return;
  }
  EXPECT_NEAR(sparse, dense, kRelative * scale) << what;
}

void ExpectSameCovariance(const Eigen::MatrixXd& sparse, const Eigen::MatrixXd& dense,
                          const std::string& what) {
  ASSERT_EQ(sparse.rows(), dense.rows());
  for (int r = 0; r < dense.rows(); ++r)
    for (int c = 0; c < dense.cols(); ++c)
      ExpectClose(sparse(r, c), dense(r, c), std::sqrt(std::abs(dense(r, r) * dense(c, c))),
                  what + " (" + std::to_string(r) + "," + std::to_string(c) + ")");
}

void CompareWithOracle(const Scenario& s) {
  SCOPED_TRACE(s.name);
  Block block;
  SyntheticBlockTruth truth;
  ASSERT_TRUE(MakeSyntheticBlock(BlockOptions(s), &block, &truth).ok());
  BundleAdjustmentConfig config;
  if (s.self_calibration)
    ASSERT_TRUE(
        BundleAdjustmentConfig::FromCalibrationNames(block, {"FocalLength", "K1"}, &config).ok());
  if (s.lever_arm) {
    config.lever_arm_m = Eigen::Vector3d(0.0, 0.0, 0.1);
    config.estimate_lever_arm = true;
  }
  Block sparse_block = block, dense_block = block;
  BundleAdjustmentResult sparse, dense;
  ASSERT_TRUE(BundleAdjust(Options(BundleCovarianceMethod::kSelectedInversion), config,
                           &sparse_block, &sparse)
                  .ok());
  ASSERT_TRUE(
      BundleAdjust(Options(BundleCovarianceMethod::kDenseInverse), config, &dense_block, &dense)
          .ok());
  ASSERT_TRUE(sparse.summary.IsSolutionUsable()) << sparse.summary.BriefReport();
  ASSERT_TRUE(dense.summary.IsSolutionUsable()) << dense.summary.BriefReport();
  EXPECT_EQ(sparse.summary.sigma0, dense.summary.sigma0);
  // The selected inverse is not the dense one.
  EXPECT_LT(sparse.summary.covariance_entries, dense.summary.covariance_entries);

  int images_with_covariance = 0;
  for (size_t i = 0; i < block.images.size(); ++i) {
    ASSERT_EQ(sparse.images[i].has_covariance, dense.images[i].has_covariance);
    if (!dense.images[i].has_covariance) continue;
    ++images_with_covariance;
    ExpectSameCovariance(sparse.images[i].covariance, dense.images[i].covariance,
                         "image " + std::to_string(i));
  }
  EXPECT_GE(images_with_covariance, static_cast<int>(block.images.size()) - 1);
  int points_with_covariance = 0;
  for (size_t p = 0; p < block.points.size(); ++p) {
    ASSERT_EQ(sparse.points[p].has_covariance, dense.points[p].has_covariance);
    if (!dense.points[p].has_covariance) continue;
    ++points_with_covariance;
    ExpectSameCovariance(sparse.points[p].covariance, dense.points[p].covariance,
                         "point " + std::to_string(p));
  }
  if (s.datum != Datum::kFreeGauge) EXPECT_GT(points_with_covariance, 0);

  ASSERT_EQ(sparse.observations.size(), dense.observations.size());
  ASSERT_FALSE(dense.observations.empty());
  double redundancy = 0.0;
  for (size_t k = 0; k < dense.observations.size(); ++k) {
    const BundleObservationDiagnostics& a = sparse.observations[k];
    const BundleObservationDiagnostics& b = dense.observations[k];
    const std::string what = "observation " + std::to_string(k);
    ASSERT_EQ(a.group, b.group);
    ASSERT_EQ(a.item, b.item);
    ExpectClose(a.redundancy, b.redundancy, 1.0, what + " redundancy");
    const double conditioning = std::max(1.0, kSmallRedundancy / b.redundancy);
    ExpectClose(a.normalized, b.normalized, conditioning * (std::abs(b.normalized) + 1.0),
                what + " w");
    const double single = std::max(conditioning, kSingle / kRelative);
    ExpectClose(a.mdb, b.mdb, single * b.mdb, what + " mdb");
    ExpectClose(a.external_m, b.external_m, single * b.external_m, what + " external");
    EXPECT_EQ(a.rejected, b.rejected) << what;
    redundancy += a.redundancy;
  }
  EXPECT_NEAR(redundancy, sparse.summary.redundancy, kRedundancySum * sparse.summary.redundancy);
  EXPECT_EQ(sparse.num_uncontrolled, dense.num_uncontrolled);

  ASSERT_EQ(sparse.groups.size(), dense.groups.size());
  for (size_t g = 0; g < dense.groups.size(); ++g) {
    ExpectClose(sparse.groups[g].redundancy_share, dense.groups[g].redundancy_share, 1.0,
                std::string(EnumName(dense.groups[g].group)) + " share");
    EXPECT_EQ(sparse.groups[g].overfit, dense.groups[g].overfit);
  }
  ASSERT_EQ(sparse.calibration.size(), dense.calibration.size());
  for (size_t c = 0; c < dense.calibration.size(); ++c) {
    ASSERT_EQ(sparse.calibration[c].sigmas.size(), dense.calibration[c].sigmas.size());
    ASSERT_FALSE(dense.calibration[c].sigmas.empty());
    for (size_t k = 0; k < dense.calibration[c].sigmas.size(); ++k) {
      ExpectClose(sparse.calibration[c].sigmas[k], dense.calibration[c].sigmas[k],
                  dense.calibration[c].sigmas[k], "calibration sigma");
      for (size_t l = 0; l < dense.calibration[c].sigmas.size(); ++l)
        ExpectClose(sparse.calibration[c].correlation(k, l), dense.calibration[c].correlation(k, l),
                    1.0, "calibration correlation");
    }
  }
}

TEST(BundleStatistics, GnssBlockEqualsTheDenseOracle) {
  CompareWithOracle({"gnss 20 images", 4, 5, Datum::kGnss});
}

TEST(BundleStatistics, ControlOnlyBlockEqualsTheDenseOracle) {
  CompareWithOracle({"control only 30 images", 3, 10, Datum::kControlOnly});
}

TEST(BundleStatistics, FreeGaugeBlockEqualsTheDenseOracle) {
  // Relative: COLMAP's gauge (first image held, one coordinate of the second), as the dense path.
  CompareWithOracle({"relative 20 images", 4, 5, Datum::kFreeGauge});
}

TEST(BundleStatistics, SelfCalibrationEqualsTheDenseOracle) {
  Scenario s{"self-calibration 24 images", 4, 6, Datum::kGnss};
  s.self_calibration = true;
  CompareWithOracle(s);
}

TEST(BundleStatistics, LeverArmEqualsTheDenseOracle) {
  Scenario s{"lever arm 24 images", 4, 6, Datum::kGnss};
  s.lever_arm = true;
  CompareWithOracle(s);
}

TEST(BundleStatistics, HundredImageBlockEqualsTheDenseOracle) {
  CompareWithOracle({"gnss 100 images", 5, 20, Datum::kGnss});
}

TEST(BundleStatistics, ThreeHundredImageBlockEqualsTheDenseOracle) {
  CompareWithOracle({"control only 300 images", 10, 30, Datum::kControlOnly});
}

TEST(BundleStatistics, TaylorCovariancesEqualTheDenseOracle) {
  Block block;
  SyntheticBlockTruth truth;
  Scenario s{"taylor 24 images", 4, 6, Datum::kGnss};
  ASSERT_TRUE(MakeSyntheticBlock(BlockOptions(s), &block, &truth).ok());
  TaylorBundleOptions options;
  TaylorBundleOptions oracle_options;
  oracle_options.statistics.covariances = BundleCovarianceMethod::kDenseInverse;
  Block sparse_block = block, dense_block = block;
  TaylorBundleResult sparse_result, dense_result;
  ASSERT_TRUE(
      TaylorBundleAdjust(options, BundleAdjustmentConfig(), &sparse_block, &sparse_result).ok());
  ASSERT_TRUE(
      TaylorBundleAdjust(oracle_options, BundleAdjustmentConfig(), &dense_block, &dense_result)
          .ok());
  ASSERT_TRUE(sparse_result.summary.IsSolutionUsable()) << sparse_result.summary.BriefReport();
  const BundleAdjustmentResult& sparse = sparse_result.adjustment;
  const BundleAdjustmentResult& dense = dense_result.adjustment;
  int compared = 0;
  for (size_t i = 0; i < block.images.size(); ++i) {
    ASSERT_TRUE(sparse.images[i].has_covariance);
    ExpectSameCovariance(sparse.images[i].covariance, dense.images[i].covariance, "taylor image");
    ++compared;
  }
  for (size_t p = 0; p < block.points.size(); ++p) {
    if (!dense.points[p].has_covariance) continue;
    ExpectSameCovariance(sparse.points[p].covariance, dense.points[p].covariance, "taylor point");
    ++compared;
  }
  EXPECT_GT(compared, static_cast<int>(block.images.size()));
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
