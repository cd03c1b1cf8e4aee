#include "core/statistics.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace photopose {

double RegularizedLowerGamma(double a, double x) {
  if (x <= 0.0) return 0.0;
  const double log_prefactor = -x + a * std::log(x) - std::lgamma(a);
  constexpr double kEpsilon = 1e-16;
  constexpr int kMaxTerms = 100000;
  if (x < a + 1.0) {
    // P = x^a e^-x / Gamma(a) * sum_n x^n / (a (a + 1) ... (a + n)).
    double term = 1.0 / a, sum = term;
    for (int n = 1; n < kMaxTerms; ++n) {
      term *= x / (a + n);
      sum += term;
      if (std::abs(term) < std::abs(sum) * kEpsilon) break;
    }
    return std::min(1.0, sum * std::exp(log_prefactor));
  }
  // Q = x^a e^-x / Gamma(a) * 1 / (x + 1 - a - 1 (1 - a) / (x + 3 - a - 2 (2 - a) / (x + 5 - a
  // ...))), evaluated by the modified Lentz method.
  constexpr double kTiny = 1e-300;
  double b = x + 1.0 - a;
  double c = 1.0 / kTiny;
  double d = 1.0 / b;
  double h = d;
  for (int i = 1; i < kMaxTerms; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < kEpsilon) break;
  }
  return std::max(0.0, 1.0 - std::exp(log_prefactor) * h);
}

double ChiSquaredQuantile(double p, double dof) {
  if (!(p > 0.0 && p < 1.0) || !(dof > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  const double a = 0.5 * dof;
  double low = 0.0, high = dof + 10.0 * std::sqrt(2.0 * dof) + 10.0;
  while (RegularizedLowerGamma(a, 0.5 * high) < p) high *= 2.0;
  for (int i = 0; i < 300 && high - low > 1e-12 * high; ++i) {
    const double middle = 0.5 * (low + high);
    if (RegularizedLowerGamma(a, 0.5 * middle) < p) {
      low = middle;
    } else {
      high = middle;
    }
  }
  return 0.5 * (low + high);
}

double NormalQuantile(double p) {
  double lo = -40.0, hi = 40.0;
  for (int i = 0; i < 200 && hi - lo > 1e-12; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return 0.5 * (lo + hi);
}

}  // namespace photopose
