// Leave-one-out cross-validation of the control points (CrossValidateControlPoints,
// solvers/bundle/bundle_adjustment.h), two ways to the adjustment without a point p:
//  - kRefit: the block adjusted again without it, warm-started (BundleAdjust), one per point;
//  - kUpdate: from the full adjustment's reduced camera system S (whitened, the points
//    eliminated; internal/reduced_normals.h) and its selected inverse C = S^-1. Point p's rows
//    (its marks and its prior) put M = A - W V^-1 W^T into S on the e blocks K they touch
//    (A = J_e^T J_e, W = J_e^T J_p, V = J_p^T J_p over its rows; a point held fixed: M = A) and
//    r = J_e^T f - W V^-1 J_p^T f into the reduced gradient g (f the whitened residuals). The
//    problem without it has S - M and g - r, and one Gauss-Newton step from the full solution is
//    delta = -(S - M)^-1 (g - r), where (Woodbury, M nonzero on K alone)
//      (S - M)^-1 = C + C_:K (I - M C_KK)^-1 M C_K:.
//    With C_KK = L L^T and B = L^T M L = U diag(mu) U^T (mu in [0, 1]: the share of the
//    information on each direction of K that p carries), (I - M C_KK)^-1 M = L^-T (I - B)^-1 B
//    L^-1, so on the blocks J (K, and the images and cameras of all of p's marks)
//      C'_JJ = C_JJ + G U diag(mu / (1 - mu)) U^T G^T,   G = C_JK L^-T,
//    and only C_JJ is needed, which lies on S's pattern (every pair of images of one point does).
//    The point is then intersected from its images moved by delta_J by the check points' rule
//    (TabulateCheckPoint), with the covariance s0'^2 (N^-1 + A C'_JJ A^T)
//    (CheckPointSensitivity), s0'^2 the problem's sum of squares without p after the step over
//    its redundancy: what the refit's left-out adjustment computes, after one step instead of
//    its iterations.
#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>
#include <string>
#include <vector>

#include "core/parallel.h"
#include "core/statistics.h"
#include "core/units.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/bundle/check_points.h"
#include "solvers/bundle/internal/bundle_problem.h"
#include "solvers/bundle/internal/bundle_statistics.h"
#include "solvers/bundle/internal/reduced_normals.h"

namespace photopose {
namespace {

using Clock = std::chrono::steady_clock;
using internal::BlockRows;
using internal::BundlePlan;
using internal::BundleRound;
using internal::BundleState;
using internal::ReducedNormals;

// kUpdate: a removal that leaves less than this share (unitless) of the information on the worst
// direction of the blocks it touches (1 - max(mu)) leaves that direction undetermined in all but
// rounding: its variance grows by 1 / share, a million times (its sigma a thousand times) at the
// bound. The computed share carries the rounding of C, about 1e-16 times the condition of the
// Jacobi-scaled S, which the statistics' own pivot test (SelectedInversionOptions::
// min_pivot_ratio, 1e-9) keeps far from 1e-6.
constexpr double kMinInformationLeft = 1e-6;

// The block every left-out adjustment of the cross-validation starts from: what the full
// adjustment removed stays out. The marks it rejected (in *rejected) except those of the point left
// out, whose marks are what checks it (a wrong control coordinate makes the full adjustment reject
// them); a control point whose coordinates were rejected is a tie point here, a rejected camera
// position or attitude no prior.
Block CrossValidationBase(const Block& adjusted, const BundleAdjustmentResult& full,
                          std::vector<char>* rejected) {
  *rejected = full.RemovedMarks(adjusted.marks.size());
  Block base = adjusted;
  for (const BundleSnoopingStep& s : full.snooping) {
    if (s.item < 0) continue;
    if (s.group == kControlPoints && s.item < static_cast<int>(base.points.size())) {
      base.points[s.item].role = PointRole::kTie;
      base.points[s.item].surveyed_m.reset();
    } else if (s.group == kCameraPositions && s.item < static_cast<int>(base.images.size())) {
      base.images[s.item].measured_center_m.reset();
    } else if (s.group == kAttitudes && s.item < static_cast<int>(base.images.size())) {
      base.images[s.item].measured_angles_rad.reset();
    }
  }
  base.BuildIndex();
  return base;
}

// The normalized error of a cross-validated point: e^T (C_estimate + C_surveyed)^-1 e against
// chi-square(3) (the refit's rule and the update's).
void SetNormalized(const BlockPoint& surveyed, const Eigen::Matrix3d& covariance_m2,
                   double marker_m, double threshold, BundleCrossValidationPoint* out) {
  const Eigen::Matrix3d C = SurveyedPointErrorCovariance(surveyed, covariance_m2, marker_m);
  out->normalized = out->error_m.dot(C.ldlt().solve(out->error_m));
  out->stands_out = out->normalized > threshold;
}

// Control point p left out (a check point) of an adjustment of `base`: its error against the
// survey and that error normalized by its covariance plus the survey's.
BundleCrossValidationPoint LeaveOneOut(const BundleAdjustmentOptions& one,
                                       const BundleAdjustmentConfig& config, const Block& base,
                                       const std::vector<char>& rejected, const Block& adjusted,
                                       double marker_m, double threshold, int p) {
  BundleCrossValidationPoint out;
  out.point = p;
  Block block = base;
  std::vector<BlockMark> kept;
  for (size_t m = 0; m < base.marks.size(); ++m)
    if (!rejected[m] || base.marks[m].point == p) kept.push_back(base.marks[m]);
  block.marks = std::move(kept);
  block.BuildIndex();
  block.points[p].role = PointRole::kCheck;
  block.points[p].position_m.reset();
  BundleAdjustmentResult left_out;
  const Status status = BundleAdjust(one, config, &block, &left_out);
  if (!status.ok()) {
    out.message = status.message();
    return out;
  }
  if (!left_out.summary.IsSolutionUsable()) {
    out.message = left_out.summary.message;
    return out;
  }
  const BundlePointResult& point = left_out.points[p];
  if (!point.error_m) {
    out.message = point.message;
    return out;
  }
  out.ok = true;
  out.error_m = *point.error_m;
  out.num_images = point.num_observations;
  SetNormalized(adjusted.points[p], point.covariance, marker_m, threshold, &out);
  return out;
}

// kRefit: one adjustment per left-out point, single-threaded (the points run in parallel),
// without blunder removal (the full adjustment's removals are applied in `base`) or diagnostics.
void RefitEachPoint(const BundleAdjustmentOptions& options, const BundleAdjustmentConfig& config,
                    const Block& base, const std::vector<char>& rejected, const Block& adjusted,
                    const std::vector<int>& controls, int num_threads,
                    BundleCrossValidationResult* result) {
  BundleAdjustmentOptions one = options;
  one.solver.num_threads = 1;
  one.solver.progress = nullptr;
  one.robustness.snoop = false;
  one.statistics.estimate_accuracies = false;
  one.robustness.rejection_threshold = 0.0;
  one.statistics.observation_diagnostics = false;
  ParallelFor(controls.size(), num_threads, [&](size_t k) {
    result->points[k] = LeaveOneOut(one, config, base, rejected, adjusted,
                                    options.accuracies.marker_m, result->threshold, controls[k]);
  });
}

// ------------------------------------------------------------------ kUpdate

// What every point's update shares: the full adjustment's last round rebuilt from the adjusted
// block (its plan, values and rows), its reduced system with C, the reduced gradient g there (C g
// and g^T C g), the whitened sum of squares and scalar rows, and per control point its residual
// blocks in the round. Built in place: the round points into the plan and the state.
struct FullRound {
  BundleAdjustmentConfig config;  // with the control points held fixed (WithFixedControlPoints)
  BundlePlan plan;
  BundleState state;
  BundleRound round;
  ReducedNormals reduced;
  Eigen::VectorXd Cg;
  double gCg = 0.0;
  double ssq = 0.0;
  std::vector<std::vector<int>> residuals_of_point;  // per block point (control points only)
  std::mutex solve;                                  // C.Solve: one thread at a time
};

// Point q's rows added to the reduced gradient (their J_e^T f, less W V^-1 J_p^T f) and to *ssq.
bool AddPointGradient(const BundleRound& round, const ReducedNormals& reduced, int q,
                      std::vector<BlockRows>* scratch, Eigen::VectorXd* g, double* ssq) {
  Eigen::MatrixXd W;
  if (!internal::EvaluatePointW(round, reduced, q, scratch, &W)) return false;
  Eigen::Vector3d g_p = Eigen::Vector3d::Zero();
  const int count = reduced.point_residual_start[q + 1] - reduced.point_residual_start[q];
  for (int k = 0; k < count; ++k) {
    const BlockRows& rows = (*scratch)[k];
    const Eigen::Map<const Eigen::VectorXd> f(rows.residuals.data(), rows.rows);
    *ssq += f.squaredNorm();
    g_p += rows.J_p.transpose() * f;
    const Eigen::VectorXd g_e = rows.J_e.transpose() * f;
    for (size_t c = 0; c < rows.e_columns.size(); ++c) (*g)[rows.e_columns[c]] += g_e[c];
  }
  const Eigen::VectorXd eliminated = W * (reduced.V_inverse[q] * g_p);
  internal::SubtractAtPointBlocks(reduced, q, eliminated, *g);
  return true;
}

// The round's reduced gradient g (whitened, the points eliminated; zero at the minimum of the
// full problem within its tolerances) and its sum of squares f^T f: the points in fixed chunks
// on the threads, summed in chunk order (the same figures on any number of threads), then the
// rows without a point. False when a residual block cannot be evaluated.
bool ReducedGradient(const BundleRound& round, const ReducedNormals& reduced, int num_threads,
                     Eigen::VectorXd* g, double* ssq) {
  constexpr int kPointsPerChunk = 1024;
  const int num_points = static_cast<int>(reduced.V_inverse.size());
  const int num_chunks = (num_points + kPointsPerChunk - 1) / kPointsPerChunk;
  const int wave = ResolveThreadCount(num_threads);
  *g = Eigen::VectorXd::Zero(reduced.size);
  *ssq = 0.0;
  bool ok = true;
  for (int first = 0; first < num_chunks && ok; first += wave) {
    const int chunks = std::min(wave, num_chunks - first);
    std::vector<Eigen::VectorXd> chunk_g(chunks, Eigen::VectorXd::Zero(reduced.size));
    std::vector<double> chunk_ssq(chunks, 0.0);
    std::vector<char> chunk_ok(chunks, 1);
    ParallelFor(chunks, num_threads, [&](size_t c) {
      std::vector<BlockRows> scratch;
      const int begin = (first + static_cast<int>(c)) * kPointsPerChunk;
      const int end = std::min(num_points, begin + kPointsPerChunk);
      for (int q = begin; q < end && chunk_ok[c]; ++q)
        chunk_ok[c] = AddPointGradient(round, reduced, q, &scratch, &chunk_g[c], &chunk_ssq[c]);
    });
    for (int c = 0; c < chunks; ++c) {
      ok = ok && chunk_ok[c];
      *g += chunk_g[c];
      *ssq += chunk_ssq[c];
    }
  }
  BlockRows rows;
  for (size_t k = reduced.point_residual_start[num_points]; ok && k < reduced.residual_order.size();
       ++k) {
    ok = internal::EvaluateBlockRows(round, reduced, round.residuals[reduced.residual_order[k]],
                                     &rows);
    if (!ok) break;
    const Eigen::Map<const Eigen::VectorXd> f(rows.residuals.data(), rows.rows);
    *ssq += f.squaredNorm();
    const Eigen::VectorXd g_e = rows.J_e.transpose() * f;
    for (size_t c = 0; c < rows.e_columns.size(); ++c) (*g)[rows.e_columns[c]] += g_e[c];
  }
  return ok;
}

// The full adjustment's last round from `base` with the marks it removed (`rejected`) out, at the
// adjusted values (the estimated lever arm from `full`), its reduced system, C g, and each
// control point's residual blocks. An error when the plan or the reduced system cannot be made
// again (the full adjustment made both).
Status BuildFullRound(const BundleAdjustmentOptions& options, const BundleAdjustmentConfig& config,
                      const Block& base, const std::vector<char>& rejected,
                      const BundleAdjustmentResult& full, int num_threads, FullRound* f) {
  f->config = WithFixedControlPoints(config, base);
  PHOTOPOSE_RETURN_IF_ERROR(internal::MakeBundlePlan(internal::PlanOptionsOf(options, f->config),
                                                     f->config, base, &f->plan));
  for (size_t m = 0; m < base.marks.size(); ++m)
    if (rejected[m]) f->plan.mark_used[m] = 0;
  PHOTOPOSE_RETURN_IF_ERROR(internal::RecheckBundlePlan(f->config, base, &f->plan));
  f->state = internal::StartState(f->config, base);
  if (f->plan.use_lever && full.lever_arm_m) f->state.lever = *full.lever_arm_m;
  internal::BuildBundleRoundRows(options, f->config, base, f->plan, &f->state, &f->round);
  internal::SelectedInversionOptions inversion;
  inversion.dense = options.statistics.covariances == BundleCovarianceMethod::kDenseInverse;
  internal::BuildReducedNormals(f->round, inversion, num_threads, &f->reduced);
  if (!f->reduced.ok)
    return Status::Error("the full adjustment's reduced normal matrix: " + f->reduced.message);
  Eigen::VectorXd g;
  if (!ReducedGradient(f->round, f->reduced, num_threads, &g, &f->ssq))
    return Status::Error(
        "the full adjustment's reduced normal matrix: a residual could not be "
        "evaluated at the solution");
  f->Cg = f->reduced.size > 0 ? Eigen::VectorXd(f->reduced.C.Solve(g)) : Eigen::VectorXd();
  if (!f->Cg.allFinite()) return Status::Error("the full adjustment's gradient: the solve failed");
  f->gCg = g.dot(f->Cg);
  f->residuals_of_point.assign(base.points.size(), {});
  for (size_t r = 0; r < f->round.residuals.size(); ++r) {
    const internal::ResidualInfo& info = f->round.residuals[r];
    const bool mark = info.group == kTieMarks || info.group == kControlMarks;
    if (!mark && info.group != kControlPoints) continue;
    const int p = mark ? base.marks[info.item].point : info.item;
    if (base.points[p].role == PointRole::kControl)
      f->residuals_of_point[p].push_back(static_cast<int>(r));
  }
  return Status::Ok();
}

// Point p's share of the full round: M and r on the e blocks K its rows touch (ascending, their
// columns one after another), its rows' sum of squares and scalar rows, whether it is adjusted
// (an eliminated point) or held fixed.
struct PointShare {
  std::vector<int> K;
  Eigen::MatrixXd M;
  Eigen::VectorXd r;
  double ssq = 0.0;
  int rows = 0;
  bool adjusted = false;
};

// The columns of `blocks` (ascending e blocks) one after another: each block's first column.
std::vector<int> BlockOffsets(const ReducedNormals& reduced, const std::vector<int>& blocks) {
  std::vector<int> offset(blocks.size() + 1, 0);
  for (size_t k = 0; k < blocks.size(); ++k)
    offset[k + 1] = offset[k] + reduced.C.block_size(blocks[k]);
  return offset;
}

// Row block `rows`' columns in the numbering of `blocks` (ascending, offsets `offset`).
std::vector<int> LocalColumns(const std::vector<int>& blocks, const std::vector<int>& offset,
                              const ReducedNormals& reduced, const BlockRows& rows) {
  std::vector<int> columns;
  for (const int b : rows.e_blocks) {
    const size_t k = std::lower_bound(blocks.begin(), blocks.end(), b) - blocks.begin();
    for (int c = 0; c < reduced.C.block_size(b); ++c) columns.push_back(offset[k] + c);
  }
  return columns;
}

bool PointShareOf(const FullRound& f, int p, PointShare* s) {
  const std::vector<int>& residuals = f.residuals_of_point[p];
  std::vector<BlockRows> rows(residuals.size());
  for (size_t k = 0; k < residuals.size(); ++k) {
    if (!internal::EvaluateBlockRows(f.round, f.reduced, f.round.residuals[residuals[k]], &rows[k]))
      return false;
    s->rows += f.round.residuals[residuals[k]].rows;
    s->K.insert(s->K.end(), rows[k].e_blocks.begin(), rows[k].e_blocks.end());
  }
  std::sort(s->K.begin(), s->K.end());
  s->K.erase(std::unique(s->K.begin(), s->K.end()), s->K.end());
  const std::vector<int> offset = BlockOffsets(f.reduced, s->K);
  const int n = offset.back();
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n), W = Eigen::MatrixXd::Zero(n, 3);
  Eigen::Matrix3d V = Eigen::Matrix3d::Zero();
  Eigen::VectorXd g_e = Eigen::VectorXd::Zero(n);
  Eigen::Vector3d g_p = Eigen::Vector3d::Zero();
  for (const BlockRows& br : rows) {
    const Eigen::Map<const Eigen::VectorXd> f_rows(br.residuals.data(), br.rows);
    s->ssq += f_rows.squaredNorm();
    const std::vector<int> columns = LocalColumns(s->K, offset, f.reduced, br);
    const Eigen::MatrixXd JtJ = br.J_e.transpose() * br.J_e;
    const Eigen::VectorXd Jtf = br.J_e.transpose() * f_rows;
    for (size_t a = 0; a < columns.size(); ++a) {
      g_e[columns[a]] += Jtf[a];
      for (size_t b = 0; b < columns.size(); ++b) A(columns[a], columns[b]) += JtJ(a, b);
    }
    if (br.point < 0) continue;
    s->adjusted = true;
    V += br.J_p.transpose() * br.J_p;
    g_p += br.J_p.transpose() * f_rows;
    const Eigen::MatrixXd JtJp = br.J_e.transpose() * br.J_p;
    for (size_t a = 0; a < columns.size(); ++a) W.row(columns[a]) += JtJp.row(a);
  }
  s->M = A;
  s->r = g_e;
  if (s->adjusted) {
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(V);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) return false;
    s->M -= W * ldlt.solve(W.transpose());
    s->r -= W * ldlt.solve(g_p);
  }
  return true;
}

// The e blocks J of point p's update: K, and the e blocks of the images and cameras of every
// mark of p (its rejected ones too: the intersection uses them), ascending.
std::vector<int> UpdateBlocks(const FullRound& f, const Block& base, int p,
                              const std::vector<int>& K) {
  std::vector<int> J = K;
  for (const int m : base.marks_of_point[p]) {
    const int image = base.marks[m].image;
    for (const double* block :
         {f.state.eo[image].data(), f.state.cameras[base.images[image].camera].data()}) {
      const auto found = f.reduced.e_index.find(block);
      if (found != f.reduced.e_index.end()) J.push_back(found->second);
    }
  }
  std::sort(J.begin(), J.end());
  J.erase(std::unique(J.begin(), J.end()), J.end());
  return J;
}

// C on the blocks J: from the selected inverse where J lies on its pattern (always, unless p has
// marks the full adjustment rejected on images that share no point with its others), else
// through the factor (one solve per column of J).
bool CovarianceOnBlocks(FullRound* f, const std::vector<int>& J, Eigen::MatrixXd* C_JJ) {
  if (f->reduced.C.Blocks(J, C_JJ)) return true;
  const std::vector<int> offset = BlockOffsets(f->reduced, J);
  Eigen::MatrixXd E = Eigen::MatrixXd::Zero(f->reduced.size, offset.back());
  for (size_t k = 0; k < J.size(); ++k)
    for (int c = 0; c < f->reduced.C.block_size(J[k]); ++c)
      E(f->reduced.e_offset[J[k]] + c, offset[k] + c) = 1.0;
  Eigen::MatrixXd CE;
  {
    const std::lock_guard<std::mutex> lock(f->solve);
    CE = f->reduced.C.Solve(E);
  }
  if (!CE.allFinite()) return false;
  *C_JJ = E.transpose() * CE;
  return true;
}

// The problem without p on the blocks J: its inverse C'_JJ, the step delta_J, the decrease of the
// sum of squares by the step (x^T C' x, x = g - r the gradient without p), and the share of the
// information left on K's worst direction (1 when p touches no e block).
struct LeftOut {
  std::vector<int> J;
  std::vector<int> offset;
  Eigen::MatrixXd C;
  Eigen::VectorXd delta;
  double decrease = 0.0;
  double information_left = 1.0;
};

// The update of the header's comment. False when C_JJ cannot be had.
bool UpdateOnBlocks(FullRound* f, const PointShare& s, LeftOut* out) {
  const ReducedNormals& reduced = f->reduced;
  out->offset = BlockOffsets(reduced, out->J);
  Eigen::MatrixXd C_JJ;
  if (!CovarianceOnBlocks(f, out->J, &C_JJ)) return false;
  // K's columns among J's; C x on J for x = g - r (r on K).
  std::vector<int> k_columns;
  Eigen::VectorXd Cx(out->offset.back());
  for (size_t j = 0; j < out->J.size(); ++j) {
    const int b = out->J[j], size = reduced.C.block_size(b);
    Cx.segment(out->offset[j], size) = f->Cg.segment(reduced.e_offset[b], size);
    if (std::binary_search(s.K.begin(), s.K.end(), b))
      for (int c = 0; c < size; ++c) k_columns.push_back(out->offset[j] + c);
  }
  const int k = static_cast<int>(k_columns.size());
  Eigen::MatrixXd C_JK(C_JJ.rows(), k), C_KK(k, k);
  for (int c = 0; c < k; ++c) C_JK.col(c) = C_JJ.col(k_columns[c]);
  for (int c = 0; c < k; ++c) C_KK.row(c) = C_JK.row(k_columns[c]);
  Cx -= C_JK * s.r;
  Eigen::VectorXd Cx_K(k);
  for (int c = 0; c < k; ++c) Cx_K[c] = Cx[k_columns[c]];
  // x^T C x = g^T C g - 2 r^T (C g)_K + r^T C_KK r.
  const Eigen::VectorXd Cg_K = Cx_K + C_KK * s.r;
  out->decrease = f->gCg - 2.0 * s.r.dot(Cg_K) + s.r.dot(C_KK * s.r);
  out->C = C_JJ;
  out->delta = -Cx;
  if (k == 0) return true;
  const Eigen::LLT<Eigen::MatrixXd> llt(C_KK);
  if (llt.info() != Eigen::Success) return false;
  const Eigen::MatrixXd L = llt.matrixL();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(L.transpose() * s.M * L);
  const Eigen::VectorXd mu = eigen.eigenvalues();
  out->information_left = 1.0 - mu.maxCoeff();
  if (!(out->information_left >= kMinInformationLeft)) return true;
  // G U = C_JK L^-T U, D = mu / (1 - mu), w = U^T L^-1 (C x)_K.
  const Eigen::MatrixXd GU =
      llt.matrixL().solve(C_JK.transpose()).transpose() * eigen.eigenvectors();
  const Eigen::VectorXd D = mu.array() / (1.0 - mu.array());
  const Eigen::VectorXd w = eigen.eigenvectors().transpose() * llt.matrixL().solve(Cx_K);
  out->C += GU * D.asDiagonal() * GU.transpose();
  out->delta -= GU * D.cwiseProduct(w);
  out->decrease += w.dot(D.cwiseProduct(w));
  return true;
}

// The adjusted values moved by the step: each e block of J (an image's orientation or a camera's
// parameters) through its manifold; into *eo (pointers to the state's values, or to *moved_eo
// for a moved image) and *cameras (the adjusted cameras, moved).
void MoveByStep(const FullRound& f, const Block& base, const LeftOut& left,
                std::vector<Vector6d>* moved_eo, std::vector<const Vector6d*>* eo,
                std::vector<BlockCamera>* cameras) {
  eo->assign(base.images.size(), nullptr);
  for (size_t i = 0; i < base.images.size(); ++i) (*eo)[i] = &f.state.eo[i];
  *cameras = base.cameras;
  for (size_t c = 0; c < cameras->size(); ++c) (*cameras)[c].params = f.state.cameras[c];
  moved_eo->assign(base.images.size(), Vector6d::Zero());
  for (size_t j = 0; j < left.J.size(); ++j) {
    const int b = left.J[j];
    const double* x = f.round.e_blocks[b];
    std::vector<double> moved(f.round.e_ambient_sizes[b]);
    const ceres::Manifold* manifold = f.round.e_manifolds[b];
    const double* step = left.delta.data() + left.offset[j];
    if (manifold != nullptr) {
      manifold->Plus(x, step, moved.data());
    } else {
      for (size_t a = 0; a < moved.size(); ++a) moved[a] = x[a] + step[a];
    }
    for (size_t i = 0; i < base.images.size(); ++i) {
      if (f.state.eo[i].data() != x) continue;
      (*moved_eo)[i] = Eigen::Map<const Vector6d>(moved.data());
      (*eo)[i] = &(*moved_eo)[i];
    }
    for (size_t c = 0; c < cameras->size(); ++c)
      if (f.state.cameras[c].data() == x) (*cameras)[c].params = moved;
  }
}

// Control point p left out by the update: the plan's checks (datum, marks per image) as the
// refit's, the step, the intersection from the moved images.
BundleCrossValidationPoint UpdateOnePoint(const BundleAdjustmentOptions& options, FullRound* f,
                                          const Block& base, const Block& adjusted,
                                          double threshold, int p) {
  BundleCrossValidationPoint out;
  out.point = p;
  BundlePlan plan = f->plan;
  for (const int m : base.marks_of_point[p]) plan.mark_used[m] = 0;
  plan.point_in_problem[p] = plan.point_prior[p] = 0;
  const Status planned = internal::RecheckBundlePlan(f->config, base, &plan);
  if (!planned.ok()) {
    out.message = planned.message();
    return out;
  }
  PointShare share;
  LeftOut left;
  if (!PointShareOf(*f, p, &share)) {
    out.message = "its rows could not be evaluated at the solution";
    return out;
  }
  left.J = UpdateBlocks(*f, base, p, share.K);
  if (!UpdateOnBlocks(f, share, &left)) {
    out.message = "the covariance of its images could not be computed";
    return out;
  }
  if (!(left.information_left >= kMinInformationLeft)) {
    out.message = "the normal matrix without it is singular: it carries all but " +
                  FormatSignificant(left.information_left, 2) +
                  " of the information on a combination of its images' parameters (no datum "
                  "without it)";
    return out;
  }
  std::vector<Vector6d> moved_eo;
  std::vector<const Vector6d*> eo;
  std::vector<BlockCamera> cameras;
  MoveByStep(*f, base, left, &moved_eo, &eo, &cameras);
  // The problem without p: its redundancy, sigma0^2 after the step, the w-test's critical value.
  const int redundancy = f->round.redundancy() - share.rows + (share.adjusted ? 3 : 0);
  const double ssq = f->ssq - share.ssq - left.decrease;
  const double variance_factor = redundancy > 0 ? std::max(ssq, 0.0) / redundancy : 1.0;
  const double critical = internal::SnoopingCriticalValue(
      options.statistics, f->round.num_observations - share.rows, nullptr);
  const internal::CheckPointCovariance covariance = [&](const std::vector<RayObservation>& rays,
                                                        const std::vector<int>& marks,
                                                        const TriangulationResult& intersection) {
    Eigen::Matrix3d N_inverse;
    Eigen::MatrixXd A;
    internal::CheckPointSensitivity(base, f->state, f->round, f->reduced, rays, marks, intersection,
                                    &N_inverse, &A);
    Eigen::MatrixXd A_J(3, left.offset.back());
    for (size_t j = 0; j < left.J.size(); ++j) {
      const int size = f->reduced.C.block_size(left.J[j]);
      A_J.middleCols(left.offset[j], size) = A.middleCols(f->reduced.e_offset[left.J[j]], size);
    }
    return Eigen::Matrix3d(N_inverse + A_J * left.C * A_J.transpose());
  };
  BundlePointResult table;
  std::vector<BundleRejectedCheckMark> rejected;
  if (!internal::TabulateCheckPoint(
          base, p, eo, cameras, internal::GroupMarkDefaults(options.accuracies, kControlMarks), 1.0,
          variance_factor, critical, covariance, &table, &rejected)) {
    out.message = table.message;
    return out;
  }
  out.ok = true;
  out.error_m = *table.error_m;
  out.num_images = table.num_observations;
  SetNormalized(adjusted.points[p], table.covariance, options.accuracies.marker_m, threshold, &out);
  return out;
}

// kUpdate: the full round once, then every point's update (in parallel: C's blocks are read
// concurrently, a solve through the factor one at a time).
Status UpdateEachPoint(const BundleAdjustmentOptions& options, const BundleAdjustmentConfig& config,
                       const Block& base, const std::vector<char>& rejected, const Block& adjusted,
                       const BundleAdjustmentResult& full, const std::vector<int>& controls,
                       int num_threads, BundleCrossValidationResult* result) {
  FullRound f;
  PHOTOPOSE_RETURN_IF_ERROR(BuildFullRound(options, config, base, rejected, full, num_threads, &f));
  ParallelFor(controls.size(), num_threads, [&](size_t k) {
    result->points[k] = UpdateOnePoint(options, &f, base, adjusted, result->threshold, controls[k]);
  });
  return Status::Ok();
}

}  // namespace

Status CrossValidateControlPoints(const BundleAdjustmentOptions& options,
                                  const BundleAdjustmentConfig& config, const Block& adjusted,
                                  const BundleAdjustmentResult& full, int num_threads,
                                  BundleCrossValidationResult* result) {
  const Clock::time_point start = Clock::now();
  *result = BundleCrossValidationResult();
  result->method = options.statistics.cross_validation;
  PHOTOPOSE_RETURN_IF_ERROR(Validate(options, "invalid options: "));
  if (options.statistics.covariances == BundleCovarianceMethod::kNone)
    return Status::Error(
        "invalid options: cross-validation needs the statistics: a left-out control point's "
        "normalized error weighs its error by the intersection's covariance, which takes the "
        "images' own from the covariances, and statistics.covariances is none");
  if (config.lever_arm_m && !config.lever_arm_m->allFinite())
    return Status::Error("invalid options: the lever arm must be finite");
  std::vector<char> rejected;
  const Block base = CrossValidationBase(adjusted, full, &rejected);
  std::vector<int> controls;
  for (size_t p = 0; p < base.points.size(); ++p)
    if (base.points[p].role == PointRole::kControl && !base.marks_of_point[p].empty())
      controls.push_back(static_cast<int>(p));
  result->points.assign(controls.size(), BundleCrossValidationPoint());
  // The normalized error of a point is chi-square with 3 degrees of freedom.
  result->threshold = ChiSquaredQuantile(1.0 - options.statistics.snooping_alpha, 3.0);
  if (result->method == BundleCrossValidationMethod::kRefit) {
    RefitEachPoint(options, config, base, rejected, adjusted, controls, num_threads, result);
  } else {
    PHOTOPOSE_RETURN_IF_ERROR(UpdateEachPoint(options, config, base, rejected, adjusted, full,
                                              controls, num_threads, result));
  }

  Eigen::Vector3d ssq = Eigen::Vector3d::Zero();
  for (const BundleCrossValidationPoint& point : result->points) {
    if (!point.ok) continue;
    ++result->count;
    ssq += point.error_m.cwiseAbs2();
  }
  if (result->count > 0) {
    result->rmse_m = (ssq / result->count).cwiseSqrt();
    result->rmse_total_m = std::sqrt(ssq.sum() / result->count);
  }
  result->time_seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return Status::Ok();
}

}  // namespace photopose
