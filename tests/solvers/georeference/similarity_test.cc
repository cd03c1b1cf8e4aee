#include "solvers/georeference/similarity.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "core/simulation/portable_random.h"
#include "tests/support/ordered_draws.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

Similarity3 Truth() {
  Similarity3 s;
  s.scale = 37.5;
  s.R_target_from_source = (Eigen::AngleAxisd(1.1, Eigen::Vector3d(0.2, -0.5, 0.8).normalized())).toRotationMatrix();
  s.translation = Eigen::Vector3d(500000.0, 5300000.0, 420.0);
  return s;
}

std::vector<SimilarityCorrespondence> Pairs(int n, double noise_m, uint64_t seed) {
  PortableRandom random(seed);
  const Similarity3 truth = Truth();
  std::vector<SimilarityCorrespondence> pairs;
  for (int i = 0; i < n; ++i) {
    SimilarityCorrespondence pair;
    pair.source = DrawLastFirst<3>([&](int i) { return i < 2 ? random.Uniform(-5, 5) : random.Uniform(-0.5, 0.5); });
    pair.target = truth.Apply(pair.source) + noise_m * DrawLastFirst<3>([&](int) { return random.Uniform(-1, 1); });
    pair.sigma_m = noise_m > 0 ? noise_m : 0.01;
    pairs.push_back(pair);
  }
  return pairs;
}

TEST(Similarity, ExactPairsGiveTheSimilarityBack) {
  Similarity3 fitted;
  ASSERT_TRUE(FitSimilarity(Pairs(10, 0.0, 1), nullptr, &fitted).ok());
  const Similarity3 truth = Truth();
  EXPECT_NEAR(fitted.scale, truth.scale, 1e-9 * truth.scale);
  EXPECT_LT((fitted.R_target_from_source - truth.R_target_from_source).norm(), 1e-10);
  EXPECT_LT((fitted.translation - truth.translation).norm(), 1e-6);
}

TEST(Similarity, GrossErrorsAreLeftOutAndTheRestFitsToTheirNoise) {
  std::vector<SimilarityCorrespondence> pairs = Pairs(30, 0.05, 2);
  for (int i : {3, 11, 17, 25}) pairs[i].target += Eigen::Vector3d(12.0, -8.0, 5.0);
  Similarity3 fitted;
  RobustSimilaritySummary summary;
  ASSERT_TRUE(RobustSimilarity(RobustSimilarityOptions(), pairs, &fitted, &summary).ok());
  EXPECT_EQ(summary.num_inliers, 26);
  for (int i : {3, 11, 17, 25}) EXPECT_FALSE(summary.inlier[i]) << i;
  EXPECT_LT((fitted.translation - Truth().translation).norm(), 0.2);
  EXPECT_NEAR(fitted.scale, Truth().scale, 0.01);
  // The same answer again: no dependence on a random state.
  Similarity3 again;
  RobustSimilaritySummary summary_again;
  ASSERT_TRUE(RobustSimilarity(RobustSimilarityOptions(), pairs, &again, &summary_again).ok());
  EXPECT_EQ(again.translation, fitted.translation);
}

TEST(Similarity, TooFewOrCollinearPairsAreRefused) {
  std::vector<SimilarityCorrespondence> pairs = Pairs(2, 0.0, 3);
  Similarity3 fitted;
  EXPECT_NE(FitSimilarity(pairs, nullptr, &fitted).message().find("at least 3"), std::string::npos);
  pairs.clear();
  for (int i = 0; i < 8; ++i) {
    SimilarityCorrespondence pair;
    pair.source = Eigen::Vector3d(i, 2 * i, 0);
    pair.target = Truth().Apply(pair.source);
    pairs.push_back(pair);
  }
  const Status line = FitSimilarity(pairs, nullptr, &fitted);
  EXPECT_NE(line.message().find("lie on a line"), std::string::npos) << line.message();
  RobustSimilaritySummary summary;
  EXPECT_FALSE(RobustSimilarity(RobustSimilarityOptions(), pairs, &fitted, &summary).ok());
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
