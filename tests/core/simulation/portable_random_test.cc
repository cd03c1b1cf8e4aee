#include "core/simulation/portable_random.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// Sample size of the moment checks and their tolerances: for N = 200000 draws the standard error
// of a mean is sigma / sqrt(N) = sigma * 0.00224, of a variance about sigma^2 * sqrt(2 / N) =
// 0.0032 sigma^2 (Gaussian); the tolerances are 5 standard errors, and the seed is fixed, so a
// pass is reproducible rather than lucky.
constexpr int kDraws = 200000;
constexpr double kMeanTolerance = 5.0 * 0.00224;
constexpr double kVarianceTolerance = 5.0 * 0.0032;

TEST(PortableRandom, TheEngineIsTheStandardsMt19937_64) {
  // [rand.predef]: the 10000th output of a default-constructed std::mt19937_64 (seed 5489) is
  // 9981545732273789042, on every standard library. Uniform01 keeps its top 53 bits.
  PortableRandom random(5489);
  for (int i = 0; i < 9999; ++i) random.Uniform01();
  const uint64_t expected = 9981545732273789042ULL;
  EXPECT_EQ(random.Uniform01(), static_cast<double>(expected >> 11) * 0x1.0p-53);
}

TEST(PortableRandom, SameSeedSameDrawsOtherSeedOrStreamOtherDraws) {
  PortableRandom a(42), b(42), c(43);
  PortableRandom s0(42, 0), s0_again(42, 0), s1(42, 1);
  int same_c = 0, same_s1 = 0;
  for (int i = 0; i < 1000; ++i) {
    const double x = a.Gaussian();
    EXPECT_EQ(x, b.Gaussian());
    same_c += x == c.Gaussian();
    const uint64_t y = s0.Below(1000000);
    EXPECT_EQ(y, s0_again.Below(1000000));
    same_s1 += y == s1.Below(1000000);
  }
  // Unrelated streams agree by chance only: once in 1e6 per Below draw, never for doubles.
  EXPECT_EQ(same_c, 0);
  EXPECT_LE(same_s1, 2);
}

TEST(PortableRandom, RangesHold) {
  PortableRandom random(7);
  uint64_t below_hits[3] = {0, 0, 0};
  for (int i = 0; i < kDraws; ++i) {
    const double u = random.Uniform01();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    const double v = random.Uniform(-2.0, 3.0);
    ASSERT_GE(v, -2.0);
    ASSERT_LT(v, 3.0);
    const uint64_t k = random.Below(3);
    ASSERT_LT(k, 3u);
    ++below_hits[k];
  }
  EXPECT_EQ(PortableRandom(1).Below(1), 0u);
  // Each of the three values a third of the time: binomial standard deviation
  // sqrt(N / 3 * 2 / 3) = 211; 5 of them allowed.
  for (const uint64_t hits : below_hits)
    EXPECT_NEAR(static_cast<double>(hits), kDraws / 3.0, 1055.0);
}

TEST(PortableRandom, MomentsOfTheDistributions) {
  PortableRandom random(2024);
  double sum_u = 0.0, sum_uu = 0.0, sum_g = 0.0, sum_gg = 0.0, sum_g4 = 0.0;
  for (int i = 0; i < kDraws; ++i) {
    const double u = random.Uniform01();
    sum_u += u;
    sum_uu += u * u;
    const double g = random.Gaussian();
    sum_g += g;
    sum_gg += g * g;
    sum_g4 += g * g * g * g;
  }
  const double n = kDraws;
  // Uniform on [0, 1): mean 1/2, variance 1/12 (sigma 0.289); the standard error of the variance
  // is sqrt((1/80 - 1/144) / N) = 1.67e-4, 5 of them 8.3e-4.
  EXPECT_NEAR(sum_u / n, 0.5, kMeanTolerance * 0.289);
  EXPECT_NEAR(sum_uu / n - std::pow(sum_u / n, 2), 1.0 / 12.0, 8.3e-4);
  // Standard normal: mean 0, variance 1, kurtosis E[g^4] = 3 (standard error sqrt(96 / N) =
  // 0.022 -> 5 of them 0.11); the kurtosis tells a Gaussian from a scaled uniform (1.8).
  EXPECT_NEAR(sum_g / n, 0.0, kMeanTolerance);
  EXPECT_NEAR(sum_gg / n, 1.0, kVarianceTolerance);
  EXPECT_NEAR(sum_g4 / n, 3.0, 0.11);
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
