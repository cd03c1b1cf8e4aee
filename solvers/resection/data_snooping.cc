#include "solvers/resection/data_snooping.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "core/collinearity.h"
#include "core/statistics.h"

namespace photopose {
namespace {

// A 2 x 2 cofactor block with an eigenvalue below this is treated as singular in that direction:
// the mark is not checked there by the others (redundancy ~0), so there is nothing to test.
constexpr double kMinCofactorEigenvalue = 1e-9;

// e^T M^+ e for a symmetric 2 x 2 M, its eigenvalues below kMinCofactorEigenvalue dropped: the
// closed-form inverse when both are above (the usual case), the eigen-decomposition otherwise.
double PseudoInverseQuadraticForm(const Eigen::Matrix2d& M, const Eigen::Vector2d& e) {
  const double a = M(0, 0), b = 0.5 * (M(0, 1) + M(1, 0)), c = M(1, 1);
  const double half_trace = 0.5 * (a + c);
  const double root = std::sqrt(0.25 * (a - c) * (a - c) + b * b);
  if (half_trace - root > kMinCofactorEigenvalue) {
    const double det = a * c - b * b;
    return (c * e.x() * e.x() - 2.0 * b * e.x() * e.y() + a * e.y() * e.y()) / det;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(M);
  double value = 0.0;
  for (int k = 0; k < 2; ++k) {
    const double lambda = eigen.eigenvalues()[k];
    if (!(lambda > kMinCofactorEigenvalue)) continue;
    const double projection = eigen.eigenvectors().col(k).dot(e);
    value += projection * projection / lambda;
  }
  return value;
}

}  // namespace

bool OutlierTestOptions::IsValid(std::string* why) const {
  if (!(confidence > 0.0 && confidence < 1.0))
    return InvalidBecause(why, "the test confidence must be in (0, 1)");
  return true;
}

double MarkThresholdSigmas(double confidence) { return std::sqrt(SnoopingCriticalValue(confidence)); }

double SnoopingCriticalValue(double confidence) { return -2.0 * std::log1p(-confidence); }

double TauCriticalValue(double confidence, int redundancy) {
  if (redundancy <= 2) return std::numeric_limits<double>::quiet_NaN();
  const double alpha = 1.0 - confidence;
  return redundancy * (1.0 - std::pow(alpha, 2.0 / (redundancy - 2)));
}

double PredictedCriticalValue(double confidence, int redundancy) {
  if (redundancy <= 0) return std::numeric_limits<double>::quiet_NaN();
  // P(F(2, r) <= x) = 1 - (1 + 2 x / r)^(-r / 2).
  const double alpha = 1.0 - confidence;
  return redundancy * (std::pow(alpha, -2.0 / redundancy) - 1.0);
}

double GlobalTestCriticalValue(double confidence, int redundancy) {
  if (redundancy == 2) return SnoopingCriticalValue(confidence);  // closed form
  // The quantile takes a few hundred evaluations of the incomplete gamma function; resection asks
  // for the same few (confidence, r) over and over, so each thread keeps the last ones.
  struct Entry {
    double confidence;
    int redundancy;
    double value;
  };
  thread_local std::array<Entry, 8> cache{};
  thread_local size_t next = 0;
  for (const Entry& entry : cache)
    if (entry.redundancy == redundancy && entry.confidence == confidence) return entry.value;
  const double value = ChiSquaredQuantile(confidence, redundancy);
  cache[next] = Entry{confidence, redundancy, value};
  next = (next + 1) % cache.size();
  return value;
}

namespace {

double ComputeDetectableBiasSigmas(double confidence, double power) {
  const double critical = SnoopingCriticalValue(confidence);
  // P(chi-square(2, lambda) <= x) = sum_j Poisson(j; lambda / 2) P(chi-square(2 + 2 j) <= x), and
  // P(chi-square(2 + 2 j) > x) = e^(-x/2) sum_{m <= j} (x/2)^m / m!; the terms are summed until
  // the Poisson tail is negligible. Power grows with lambda: bisection.
  const auto power_at = [critical](double lambda) {
    const double half = 0.5 * lambda, x = 0.5 * critical;
    double poisson = std::exp(-half), term = std::exp(-x), tail = term, exceed = 0.0, mass = 0.0;
    for (int j = 0; j < 2000 && mass < 1.0 - 1e-15; ++j) {
      if (j > 0) {
        poisson *= half / j;
        term *= x / j;
        tail += term;
      }
      exceed += poisson * std::min(tail, 1.0);
      mass += poisson;
    }
    return exceed;
  };
  double lo = 0.0, hi = 1.0;
  while (power_at(hi) < power) hi *= 2.0;
  for (int k = 0; k < 100; ++k) {
    const double mid = 0.5 * (lo + hi);
    (power_at(mid) < power ? lo : hi) = mid;
  }
  return std::sqrt(0.5 * (lo + hi));
}

}  // namespace

double DetectableBiasSigmas(double confidence, double power) {
  // A bisection over a Poisson series (about 10 us): every image of a batch asks for the
  // same (confidence, power), so each thread keeps the last answer.
  struct Entry {
    double confidence = -1.0;
    double power = -1.0;
    double value = 0.0;
  };
  thread_local Entry last;
  if (last.confidence != confidence || last.power != power)
    last = Entry{confidence, power, ComputeDetectableBiasSigmas(confidence, power)};
  return last.value;
}

bool FailsGlobalTest(double omega, double confidence, int redundancy) {
  // A quantile above the median is above r - 2/3 (> r - 1); the exact quantile (a few hundred
  // evaluations of the incomplete gamma function) is needed only beyond that.
  if (!(omega > redundancy - 1.0)) return false;
  return omega > GlobalTestCriticalValue(confidence, redundancy);
}

double PoseCovarianceFactor(bool accuracy_stated, double omega, int redundancy) {
  if (accuracy_stated || redundancy <= 0) return 1.0;
  return omega / redundancy;
}

double SigmaUpperFactor(double confidence, int redundancy) {
  if (redundancy <= 0) return std::numeric_limits<double>::infinity();
  // The lower quantile through the same cache as the global test's (any p: chi-square(r)).
  return std::sqrt(redundancy / GlobalTestCriticalValue(1.0 - confidence, redundancy));
}

namespace {

// A used mark's reliability for delta0 = 1 (PoseAdjustmentStatistics): the minimal detectable
// blunder 1 / sqrt(q_min) and the largest pose shift it causes, from its cofactor block Qvv and
// its whitened Jacobian rows J_i. Infinite both when the others do not check the mark.
void MarkReliability(const Eigen::Matrix2d& Qvv,
                     const Eigen::Matrix<double, 2, 6, Eigen::RowMajor>& J,
                     const Matrix6d& cofactor, double* detectable_blunder, double* pose_shift) {
  const double q_min =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(Qvv, Eigen::EigenvaluesOnly).eigenvalues()[0];
  if (!(q_min > kMinCofactorEigenvalue)) {
    *detectable_blunder = std::numeric_limits<double>::infinity();
    *pose_shift = std::numeric_limits<double>::infinity();
    return;
  }
  *detectable_blunder = 1.0 / std::sqrt(q_min);
  const Eigen::Matrix2d Qvv_inverse = Qvv.inverse();
  const Eigen::Matrix<double, 2, 6> G = J * cofactor;  // column k: A_i Q e_k
  for (int k = 0; k < 6; ++k) {
    const Eigen::Vector2d g = G.col(k);
    *pose_shift = std::max(*pose_shift, std::sqrt(g.dot(Qvv_inverse * g) / cofactor(k, k)));
  }
}

}  // namespace

Status ComputePoseAdjustmentStatistics(const std::vector<Eigen::Vector2d>& image_plane,
                                       const std::vector<Eigen::Vector3d>& points_in_ground,
                                       const std::vector<double>& sigmas, double focal,
                                       const ExteriorOrientation& eo, const std::vector<char>& used,
                                       PoseAdjustmentStatistics* statistics,
                                       StatisticsScope scope) {
  const size_t n = image_plane.size();
  // Written in place: the resection asks for the statistics of a few sets per image, and fresh
  // vectors each time were a tenth of the batch's allocations.
  PoseAdjustmentStatistics& s = *statistics;
  s.num_used = 0;
  s.redundancy = 0;
  s.omega = 0.0;
  s.normal.setZero();
  s.cofactor.setZero();
  s.determined = false;
  s.whitened_residuals.assign(n, Eigen::Vector2d::Zero());
  s.redundancy_numbers.assign(n, 0.0);
  s.test_statistics.assign(n, 0.0);
  s.in_front.assign(n, 0);
  s.detectable_blunder_per_delta.assign(n, 0.0);
  s.pose_shift_per_delta.assign(n, 0.0);
  thread_local std::vector<Eigen::Matrix<double, 2, 6, Eigen::RowMajor>> jacobians;
  jacobians.resize(n);
  const SeedProjector projector(eo.data(), focal);
  for (size_t i = 0; i < n; ++i) {
    double xy[2];
    Eigen::Matrix<double, 2, 6, Eigen::RowMajor> J;
    if (!projector.Project(points_in_ground[i].data(), xy, J.data(), nullptr, nullptr)) {
      if (used[i])
        return Status::Error("a control point used in the adjustment is behind the camera");
      continue;
    }
    s.in_front[i] = 1;
    s.whitened_residuals[i] = (image_plane[i] - Eigen::Vector2d(xy[0], xy[1])) / sigmas[i];
    jacobians[i] = J / sigmas[i];
    if (!used[i]) continue;
    ++s.num_used;
    s.omega += s.whitened_residuals[i].squaredNorm();
    s.normal.noalias() += jacobians[i].transpose() * jacobians[i];
  }
  if (s.num_used < 3) return Status::Error("fewer than three marks in the adjustment");
  s.redundancy = 2 * s.num_used - 6;
  const Eigen::LDLT<Matrix6d> ldlt(s.normal);
  s.determined = ldlt.info() == Eigen::Success && ldlt.vectorD().minCoeff() > 0.0;
  if (!s.determined) return Status::Ok();
  s.cofactor = ldlt.solve(Matrix6d::Identity());
  for (size_t i = 0; i < n; ++i) {
    if (!s.in_front[i]) continue;
    const Eigen::Matrix2d H = jacobians[i] * s.cofactor * jacobians[i].transpose();
    if (!used[i]) {
      s.test_statistics[i] =
          PseudoInverseQuadraticForm(Eigen::Matrix2d::Identity() + H, s.whitened_residuals[i]);
      continue;
    }
    const Eigen::Matrix2d Qvv = Eigen::Matrix2d::Identity() - H;
    s.redundancy_numbers[i] = 0.5 * Qvv.trace();
    s.test_statistics[i] = PseudoInverseQuadraticForm(Qvv, s.whitened_residuals[i]);
    if (scope == StatisticsScope::kTestsAndReliability)
      MarkReliability(Qvv, jacobians[i], s.cofactor, &s.detectable_blunder_per_delta[i],
                      &s.pose_shift_per_delta[i]);
  }
  return Status::Ok();
}

}  // namespace photopose
