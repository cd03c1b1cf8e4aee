#include "core/statistics.h"

#include <gtest/gtest.h>

#include <cmath>

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

// Chi-square quantiles are tabulated to 4-5 significant digits.
constexpr double kTableTolerance = 2e-3;

TEST(Statistics, ChiSquaredQuantilesMatchTables) {
  // Abramowitz & Stegun table 26.8 / any chi-square table.
  EXPECT_NEAR(ChiSquaredQuantile(0.95, 1), 3.8415, kTableTolerance);
  EXPECT_NEAR(ChiSquaredQuantile(0.999, 2), 13.8155, kTableTolerance);
  EXPECT_NEAR(ChiSquaredQuantile(0.025, 6), 1.2373, kTableTolerance);
  EXPECT_NEAR(ChiSquaredQuantile(0.975, 6), 14.449, kTableTolerance);
  EXPECT_NEAR(ChiSquaredQuantile(0.005, 6), 0.6757, kTableTolerance);
  EXPECT_NEAR(ChiSquaredQuantile(0.995, 6), 18.548, kTableTolerance);
  EXPECT_NEAR(ChiSquaredQuantile(0.5, 100), 99.334, kTableTolerance);
  EXPECT_NEAR(ChiSquaredQuantile(0.99, 100), 135.807, kTableTolerance);
  EXPECT_TRUE(std::isnan(ChiSquaredQuantile(1.0, 6)));
  EXPECT_TRUE(std::isnan(ChiSquaredQuantile(0.5, 0.0)));
}

TEST(Statistics, RegularizedLowerGammaOfTwoDegreesIsClosedForm) {
  // P(1, x) = 1 - exp(-x): the chi-square(2) distribution function at 2x, on both branches.
  for (double x : {0.1, 0.9, 2.5, 7.0, 30.0})
    EXPECT_NEAR(RegularizedLowerGamma(1.0, x), 1.0 - std::exp(-x), 1e-14) << x;
  EXPECT_EQ(RegularizedLowerGamma(3.0, 0.0), 0.0);
}

TEST(Statistics, NormalQuantilesMatchTables) {
  // The bisection stops at 1e-12; tabulated values to 15 digits.
  constexpr double kBisection = 1e-11;
  EXPECT_NEAR(NormalQuantile(0.5), 0.0, kBisection);
  EXPECT_NEAR(NormalQuantile(0.975), 1.959963984540054, kBisection);
  EXPECT_NEAR(NormalQuantile(0.999), 3.090232306167814, kBisection);
  EXPECT_NEAR(NormalQuantile(0.8), 0.841621233572914, kBisection);
  EXPECT_NEAR(NormalQuantile(0.1), -NormalQuantile(0.9), kBisection);
}

TEST(Statistics, ChiSquaredQuantileOfThreeDegreesInvertsTheClosedForm) {
  // F(x) = erf(sqrt(x / 2)) - sqrt(2 x / pi) exp(-x / 2) for 3 degrees of freedom.
  const double pi = std::acos(-1.0);
  for (const double p : {0.5, 0.95, 0.999}) {
    const double x = ChiSquaredQuantile(p, 3.0);
    EXPECT_NEAR(std::erf(std::sqrt(x / 2.0)) - std::sqrt(2.0 * x / pi) * std::exp(-x / 2.0), p,
                1e-11)
        << p;
  }
  EXPECT_NEAR(ChiSquaredQuantile(0.999, 3.0), 16.266, kTableTolerance);
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
