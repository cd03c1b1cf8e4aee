#pragma once
// Distribution functions for the statistical tests of photopose (outlier tests of resection, data
// snooping and cross-validation of the bundle adjustment, the NEES intervals of the comparison
// tool): the one home of every quantile photopose uses. Plain double functions, no state.

namespace photopose {

// Regularized lower incomplete gamma function P(a, x) = gamma(a, x) / Gamma(a) for a > 0, x >= 0:
// its series below x = a + 1, 1 - Q by the modified Lentz continued fraction above (Numerical
// Recipes 6.2), to a relative 1e-16.
double RegularizedLowerGamma(double a, double x);

// The p-quantile of the chi-square distribution with `dof` degrees of freedom (p in (0, 1),
// dof > 0) by bisection on P(dof / 2, x / 2), to a relative 1e-12. NaN outside the domain.
double ChiSquaredQuantile(double p, double dof);

// The p-quantile of the standard normal distribution, Phi^-1(p) for p in (0, 1), by bisection on
// Phi(x) = erfc(-x / sqrt 2) / 2 over [-40, 40] to 1e-12 (absolute).
double NormalQuantile(double p);

}  // namespace photopose
