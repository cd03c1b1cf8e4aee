#include "solvers/resection/p3p.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "core/types.h"

namespace photopose {
namespace {

// Sine of the angle at which three points (or the two sides of their triangle) count as collinear.
// Below it the triangle has no well-defined plane and the rotation is not determined.
constexpr double kCollinearSine = 1e-9;
// Newton steps on the three distance constraints after the closed form (Lambda Twist uses a
// handful; from the closed form they converge quadratically within two or three).
constexpr int kMaxNewtonIterations = 5;
// A polished solution must satisfy every distance constraint to this fraction of that squared
// distance; anything worse is rounding garbage from a near-degenerate configuration.
constexpr double kMaxRelativeConstraintError = 1e-6;
// Slightly negative discriminants within this fraction of their terms are rounding of a double
// root and are treated as zero.
constexpr double kDiscriminantSlack = 1e-12;

// adj(A), so that adj(A) * A = det(A) * I; its rows are cross products of the columns of A.
inline Eigen::Matrix3d Adjugate(const Eigen::Matrix3d& A) {
  Eigen::Matrix3d adj;
  adj.row(0) = A.col(1).cross(A.col(2)).transpose();
  adj.row(1) = A.col(2).cross(A.col(0)).transpose();
  adj.row(2) = A.col(0).cross(A.col(1)).transpose();
  return adj;
}

// The unit normal of the plane spanned by the rows of a rank-2 3x3 matrix: the largest of the
// three row cross products (the best conditioned pair). Returns false if all rows are parallel.
bool NullVector(const Eigen::Matrix3d& A, Eigen::Vector3d* n) {
  const Eigen::Vector3d c01 = A.row(0).transpose().cross(A.row(1).transpose());
  const Eigen::Vector3d c02 = A.row(0).transpose().cross(A.row(2).transpose());
  const Eigen::Vector3d c12 = A.row(1).transpose().cross(A.row(2).transpose());
  const double n01 = c01.squaredNorm(), n02 = c02.squaredNorm(), n12 = c12.squaredNorm();
  const Eigen::Vector3d& best = n01 >= n02 ? (n01 >= n12 ? c01 : c12) : (n02 >= n12 ? c02 : c12);
  const double norm = best.norm();
  if (!(norm > 0.0)) return false;
  *n = best / norm;
  return true;
}

// Real roots of the monic cubic g^3 + a g^2 + b g + c (trigonometric form for three real roots,
// Cardano's for one), each polished by two Newton steps. Returns the number of roots (1 or 3).
int RealRootsOfMonicCubic(double a, double b, double c, double roots[3]) {
  const double a_third = a / 3.0;
  const double q = (a * a - 3.0 * b) / 9.0;
  const double r = (2.0 * a * a * a - 9.0 * a * b + 27.0 * c) / 54.0;
  const double q3 = q * q * q;
  int count = 0;
  if (r * r < q3) {
    const double sqrt_q = std::sqrt(q);
    const double theta = std::acos(std::clamp(r / (sqrt_q * q), -1.0, 1.0));
    const double two_pi = 2.0 * kPi;
    roots[0] = -2.0 * sqrt_q * std::cos(theta / 3.0) - a_third;
    roots[1] = -2.0 * sqrt_q * std::cos((theta + two_pi) / 3.0) - a_third;
    roots[2] = -2.0 * sqrt_q * std::cos((theta - two_pi) / 3.0) - a_third;
    count = 3;
  } else {
    const double big = -std::copysign(std::cbrt(std::abs(r) + std::sqrt(r * r - q3)), r);
    const double small = big != 0.0 ? q / big : 0.0;
    roots[0] = big + small - a_third;
    count = 1;
  }
  for (int i = 0; i < count; ++i) {
    for (int k = 0; k < 2; ++k) {
      const double g = roots[i];
      const double f = ((g + a) * g + b) * g + c;
      const double df = (3.0 * g + 2.0 * a) * g + b;
      if (df == 0.0) break;
      roots[i] = g - f / df;
    }
  }
  return count;
}

// The orthonormal frame [e1 e2 e3] of a triangle with sides u = p2 - p1, v = p3 - p1: e1 along u,
// e3 normal to the triangle.
Eigen::Matrix3d TriangleFrame(const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
  Eigen::Matrix3d frame;
  const Eigen::Vector3d e1 = u.normalized();
  const Eigen::Vector3d e3 = u.cross(v).normalized();
  frame.col(0) = e1;
  frame.col(1) = e3.cross(e1);
  frame.col(2) = e3;
  return frame;
}

// The quadrics of the three distance constraints, with the squared distances a_ij and the bearing
// terms b_ij: lambda_i^2 + lambda_j^2 + b_ij lambda_i lambda_j = a_ij.
struct P3PConstraints {
  double a12, a13, a23;
  double b12, b13, b23;

  // The three constraints' residuals at the depths L.
  Eigen::Vector3d Residual(const Eigen::Vector3d& L) const {
    return Eigen::Vector3d(L[0] * L[0] + L[1] * L[1] + b12 * L[0] * L[1] - a12,
                           L[0] * L[0] + L[2] * L[2] + b13 * L[0] * L[2] - a13,
                           L[1] * L[1] + L[2] * L[2] + b23 * L[1] * L[2] - a23);
  }
};

// Step 1: the member D0 of the pencil D1 + g D2 that is degenerate (det = 0) and farthest from a
// double line, with the sum of its principal 2x2 minors in *minor_sum. False when no real root
// gives a real pair of planes.
bool DegeneratePencilMember(const Eigen::Matrix3d& D1, const Eigen::Matrix3d& D2, Eigen::Matrix3d* D0,
                            double* minor_sum) {
  // det(D1 + g D2) = c3 g^3 + c2 g^2 + c1 g + c0. A real root gives a degenerate member D0 of the
  // pencil. The cubic is solved in g = gamma or, when det(D2) is the smaller end coefficient, in
  // its reciprocal (D0 = D2 + mu D1), so the leading coefficient is never the vanishing one.
  const Eigen::Matrix3d adj1 = Adjugate(D1);
  const Eigen::Matrix3d adj2 = Adjugate(D2);
  const double c0 = D1.determinant();
  const double c3 = D2.determinant();
  const double c1 = adj1.cwiseProduct(D2).sum();  // trace(adj(D1) D2), both symmetric
  const double c2 = adj2.cwiseProduct(D1).sum();  // trace(adj(D2) D1)
  const bool in_gamma = std::abs(c3) >= std::abs(c0);
  const Eigen::Matrix3d& first = in_gamma ? D1 : D2;
  const Eigen::Matrix3d& second = in_gamma ? D2 : D1;
  double roots[3];
  int num_roots = 0;
  if (in_gamma ? c3 == 0.0 : c0 == 0.0) {
    roots[0] = 0.0;  // both ends vanish: D1 itself is degenerate
    num_roots = 1;
  } else if (in_gamma) {
    num_roots = RealRootsOfMonicCubic(c2 / c3, c1 / c3, c0 / c3, roots);
  } else {
    num_roots = RealRootsOfMonicCubic(c1 / c0, c2 / c0, c3 / c0, roots);
  }

  // Of the real roots keep the D0 that is farthest from a double line: the product of its two
  // non-zero eigenvalues (the sum of its principal 2x2 minors, trace(adj D0)) must be negative for
  // a real pair of planes, and the most negative relative to |D0|^2 factors most stably.
  double best_quality = -1.0;
  for (int i = 0; i < num_roots; ++i) {
    const Eigen::Matrix3d candidate = first + roots[i] * second;
    const double candidate_minor_sum = Adjugate(candidate).trace();
    const double quality = -candidate_minor_sum / candidate.squaredNorm();
    if (std::isfinite(quality) && quality > best_quality) {
      best_quality = quality;
      *minor_sum = candidate_minor_sum;
      *D0 = candidate;
    }
  }
  return best_quality > -kDiscriminantSlack;
}

// Step 2: D0 = sigma1 e1 e1^T + sigma2 e2 e2^T with null vector n0 factors as
// Lambda^T D0 Lambda = sigma1 (e1.L - s e2.L)(e1.L + s e2.L): two planes through the origin, with
// normals e1 -+ s e2. sigma1 + sigma2 = trace, sigma1 sigma2 = minor sum; sigma1 is taken as the
// larger in magnitude, whose eigenvector is better defined. False when D0 does not factor.
bool PlanesOfDegenerateMember(const Eigen::Matrix3d& D0, double minor_sum, Eigen::Vector3d* n0,
                              Eigen::Vector3d* e1, Eigen::Vector3d* e2, double* s) {
  if (!NullVector(D0, n0)) return false;
  const double half_trace = 0.5 * D0.trace();
  const double root_disc = std::sqrt(std::max(0.0, half_trace * half_trace - minor_sum));
  const double sigma1 = half_trace + std::copysign(root_disc, half_trace);
  if (sigma1 == 0.0) return false;
  const double sigma2 = minor_sum / sigma1;
  if (!NullVector(D0 - sigma1 * Eigen::Matrix3d::Identity(), e1)) return false;
  *e2 = n0->cross(*e1).normalized();
  *s = std::sqrt(std::max(0.0, -sigma2 / sigma1));
  return true;
}

// Step 3: the rays (up to two) in the plane spanned by n0 and q that the quadrics cut out. Returns
// their number.
int RaysInPlane(const Eigen::Matrix3d& D1, const Eigen::Matrix3d& D2, const Eigen::Vector3d& n0,
                const Eigen::Vector3d& q, Eigen::Vector3d rays[2]) {
  // On the plane D1 and D2 are proportional, so either quadric cuts out the same rays. The one
  // with the larger restriction is better conditioned.
  double S11 = n0.dot(D1 * n0), S12 = n0.dot(D1 * q), S22 = q.dot(D1 * q);
  const double T11 = n0.dot(D2 * n0), T12 = n0.dot(D2 * q), T22 = q.dot(D2 * q);
  if (std::abs(T11) + std::abs(T12) + std::abs(T22) >
      std::abs(S11) + std::abs(S12) + std::abs(S22)) {
    S11 = T11;
    S12 = T12;
    S22 = T22;
  }
  // S11 al^2 + 2 S12 al be + S22 be^2 = 0. With k = -S12 - sign(S12) sqrt(disc) the two roots
  // are (al, be) = (k, S11) and (S22, k), free of cancellation.
  double disc = S12 * S12 - S11 * S22;
  if (disc < 0.0) {
    if (disc < -kDiscriminantSlack * (S12 * S12 + std::abs(S11 * S22))) return 0;
    disc = 0.0;
  }
  const double k = -S12 - std::copysign(std::sqrt(disc), S12);
  if (k == 0.0) {
    // S12 = 0 and S11 S22 = 0: one double ray on the axis whose coefficient vanishes.
    rays[0] = std::abs(S11) <= std::abs(S22) ? n0 : q;
    return 1;
  }
  rays[0] = k * n0 + S11 * q;
  rays[1] = S22 * n0 + k * q;
  return 2;
}

// Step 4: the depths on a ray, scaled so that the constraints hold and polished by Newton's
// method (a step kept only when it reduces the error). False when a depth is not positive or a
// constraint is not met to kMaxRelativeConstraintError.
bool DepthsOnRay(const P3PConstraints& k, const Eigen::Vector3d& ray, Eigen::Vector3d* depths) {
  Eigen::Vector3d lambda = ray;
  if (lambda.sum() < 0.0) lambda = -lambda;
  // Scale so the constraints hold: every Lambda^T M_ij Lambda / a_ij is the same on the ray.
  const double l1 = lambda[0], l2 = lambda[1], l3 = lambda[2];
  const double m_sum = (l1 * l1 + l2 * l2 + k.b12 * l1 * l2) +
                       (l1 * l1 + l3 * l3 + k.b13 * l1 * l3) +
                       (l2 * l2 + l3 * l3 + k.b23 * l2 * l3);
  if (!(m_sum > 0.0)) return false;
  lambda *= std::sqrt((k.a12 + k.a13 + k.a23) / m_sum);
  if (!(lambda.minCoeff() > 0.0)) return false;

  Eigen::Vector3d f = k.Residual(lambda);
  double error = f.cwiseAbs().maxCoeff();
  for (int iteration = 0; iteration < kMaxNewtonIterations && error > 0.0; ++iteration) {
    Eigen::Matrix3d J;
    J << 2.0 * lambda[0] + k.b12 * lambda[1], 2.0 * lambda[1] + k.b12 * lambda[0], 0.0,  //
        2.0 * lambda[0] + k.b13 * lambda[2], 0.0, 2.0 * lambda[2] + k.b13 * lambda[0],   //
        0.0, 2.0 * lambda[1] + k.b23 * lambda[2], 2.0 * lambda[2] + k.b23 * lambda[1];
    const double det = J.determinant();
    if (!(std::abs(det) > 0.0) || !std::isfinite(det)) break;
    const Eigen::Vector3d next = lambda - Adjugate(J) * f / det;
    const Eigen::Vector3d next_f = k.Residual(next);
    const double next_error = next_f.cwiseAbs().maxCoeff();
    if (!(next_error < error)) break;
    lambda = next;
    f = next_f;
    error = next_error;
  }
  if (!(lambda.minCoeff() > 0.0)) return false;
  if (!(std::abs(f[0]) <= kMaxRelativeConstraintError * k.a12 &&
        std::abs(f[1]) <= kMaxRelativeConstraintError * k.a13 &&
        std::abs(f[2]) <= kMaxRelativeConstraintError * k.a23))
    return false;
  *depths = lambda;
  return true;
}

// Step 5: the pose that carries the ground triangle x_i onto the camera-frame triangle
// lambda_i y_i, congruent to it: the rotation maps the frame of one onto the frame of the other.
// False when the camera-frame triangle is degenerate.
bool PoseFromDepths(const std::array<Eigen::Vector3d, 3>& y, const std::array<Eigen::Vector3d, 3>& x,
                    const Eigen::Matrix3d& ground_frame, const Eigen::Vector3d& lambda, PoseCandidate* pose) {
  const Eigen::Vector3d p1 = lambda[0] * y[0];
  const Eigen::Vector3d p2 = lambda[1] * y[1];
  const Eigen::Vector3d p3 = lambda[2] * y[2];
  const Eigen::Vector3d c12 = p2 - p1;
  const Eigen::Vector3d c13 = p3 - p1;
  if (!(c12.cross(c13).norm() > kCollinearSine * c12.norm() * c13.norm())) return false;
  pose->R_camera_from_ground = TriangleFrame(c12, c13) * ground_frame.transpose();
  // X = center + R^T p for each point; the mean of the three spreads the rounding.
  pose->center_in_ground = (x[0] + x[1] + x[2] - pose->R_camera_from_ground.transpose() * (p1 + p2 + p3)) / 3.0;
  return true;
}

}  // namespace

int SolveP3P(const std::array<Eigen::Vector3d, 3>& bearings,
             const std::array<Eigen::Vector3d, 3>& points_in_ground,
             std::vector<PoseCandidate>* solutions) {
  std::array<Eigen::Vector3d, 3> unit;
  for (int i = 0; i < 3; ++i) {
    if (!UnitBearing(bearings[i], &unit[i])) return 0;
  }
  return SolveP3PUnitBearings(unit, points_in_ground, solutions);
}

bool UnitBearing(const Eigen::Vector3d& bearing, Eigen::Vector3d* unit) {
  const double norm = bearing.norm();
  if (!(norm > 0.0) || !std::isfinite(norm)) return false;
  *unit = bearing / norm;
  return true;
}

int SolveP3PUnitBearings(const std::array<Eigen::Vector3d, 3>& y,
                         const std::array<Eigen::Vector3d, 3>& points_in_ground,
                         std::vector<PoseCandidate>* solutions) {
  const Eigen::Vector3d& x1 = points_in_ground[0];
  const Eigen::Vector3d& x2 = points_in_ground[1];
  const Eigen::Vector3d& x3 = points_in_ground[2];
  const Eigen::Vector3d d12 = x2 - x1;
  const Eigen::Vector3d d13 = x3 - x1;
  const Eigen::Vector3d d23 = x3 - x2;
  P3PConstraints k;
  k.a12 = d12.squaredNorm();
  k.a13 = d13.squaredNorm();
  k.a23 = d23.squaredNorm();
  // Collinear or coincident points (this also rejects NaN through the negated comparison).
  if (!(d12.cross(d13).norm() > kCollinearSine * std::sqrt(k.a12 * k.a13))) return 0;
  k.b12 = -2.0 * y[0].dot(y[1]);
  k.b13 = -2.0 * y[0].dot(y[2]);
  k.b23 = -2.0 * y[1].dot(y[2]);

  // Lambda^T M_ij Lambda is the left side of constraint ij. The quadrics
  //   D1 = a23 M12 - a12 M23,  D2 = a23 M13 - a13 M23
  // vanish on every solution ray, whatever its scale. The squared distances are divided by their
  // mean so the matrix entries are of order one in any ground unit.
  const double a_mean = (k.a12 + k.a13 + k.a23) / 3.0;
  const double n12 = k.a12 / a_mean, n13 = k.a13 / a_mean, n23 = k.a23 / a_mean;
  Eigen::Matrix3d D1, D2;
  D1 << n23, 0.5 * n23 * k.b12, 0.0,                     //
      0.5 * n23 * k.b12, n23 - n12, -0.5 * n12 * k.b23,  //
      0.0, -0.5 * n12 * k.b23, -n12;
  D2 << n23, 0.0, 0.5 * n23 * k.b13,  //
      0.0, -n13, -0.5 * n13 * k.b23,  //
      0.5 * n23 * k.b13, -0.5 * n13 * k.b23, n23 - n13;

  Eigen::Matrix3d D0;
  double minor_sum = 0.0;
  if (!DegeneratePencilMember(D1, D2, &D0, &minor_sum)) return 0;
  Eigen::Vector3d n0, e1, e2;
  double s = 0.0;
  if (!PlanesOfDegenerateMember(D0, minor_sum, &n0, &e1, &e2, &s)) return 0;

  // The ground triangle's frame, the same for every solution.
  const Eigen::Matrix3d ground_frame = TriangleFrame(d12, d13);
  const int num_before = static_cast<int>(solutions->size());
  const int num_planes = s > 0.0 ? 2 : 1;
  for (int plane = 0; plane < num_planes; ++plane) {
    const Eigen::Vector3d normal =
        plane == 0 ? Eigen::Vector3d(e1 - s * e2) : Eigen::Vector3d(e1 + s * e2);
    // The plane is spanned by n0 and q.
    const Eigen::Vector3d q = n0.cross(normal).normalized();
    Eigen::Vector3d rays[2];
    const int num_rays = RaysInPlane(D1, D2, n0, q, rays);
    for (int r = 0; r < num_rays; ++r) {
      Eigen::Vector3d lambda;
      PoseCandidate pose;
      if (DepthsOnRay(k, rays[r], &lambda) && PoseFromDepths(y, points_in_ground, ground_frame, lambda, &pose))
        solutions->push_back(pose);
    }
  }
  return static_cast<int>(solutions->size()) - num_before;
}

}  // namespace photopose
