// photopose benchmarks, run side by side with their peers in one process (docs/performance.md):
//   - residual + Jacobian evaluation per observation: analytic vs autodiff;
//   - clean resection from approximate values, 10 / 50 / 500 points: Ceres analytic, Ceres autodiff,
//     the Taylor linearisation, and (with OpenCV) solvePnP SQPNP and ITERATIVE;
//   - robust resection of 500 correspondences with 30% / 60% gross errors and no approximate values:
//     photopose (LO-RANSAC + least squares + data snooping) and OpenCV's solvePnPRansac.
// Accuracy and success over the same scenes are reported as counters next to the times, so speed is
// never bought with quality unseen.
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <ctime>
#include <memory>
#include <random>
#include <vector>

#include "core/io/block_tables.h"
#include "core/collinearity.h"
#include "core/simulation/synthetic_scene.h"
#include "cost_functions/collinearity_cost.h"
#include "solvers/resection/resection.h"
#include "solvers/resection/taylor_resection.h"
#include "tools/compare/comparison.h"

#ifdef PHOTOPOSE_HAVE_OPENCV
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#endif

namespace photopose {
namespace {

using cli::RotationErrorArcSeconds;

constexpr int kNumScenes = 16;  // distinct scenes cycled through, so RANSAC luck averages out

// One image of a nadir aerial scene with exactly `num_points` control points.
struct BenchScene {
  FrameCamera camera;
  ExteriorOrientation truth;
  ResectionInput input;
  std::vector<Eigen::Vector2d> pixels;  // observed Column/Row (corner origin)
  std::vector<char> is_outlier;
};

BenchScene MakeBenchScene(int num_points, double outlier_fraction, uint64_t seed) {
  SyntheticSceneOptions options;
  options.scenario = Scenario::kNadir;
  options.seed = seed;
  options.noise_px = 0.5;
  options.outlier_fraction = outlier_fraction;
  options.num_control_points = num_points;
  options.num_check_points = 0;
  SyntheticScene scene;
  Block block;
  std::vector<int> marks;
  BenchScene bench;
  // The library's one assembly: the scene's tables into a block, its image into a resection input.
  if (!MakeSyntheticScene(options, &scene).ok() ||
      !AssembleBlock(SceneBlockTables(scene), &block).ok() ||
      !MakeResectionInput(block, 0, ResectionInputOptions(), &bench.input, &marks).ok())
    std::abort();
  bench.camera = scene.cameras.front();
  bench.truth = scene.true_frames.front().eo;
  for (const int m : marks) {
    bench.pixels.push_back(block.marks[m].measured);
    bench.is_outlier.push_back(scene.mark_is_outlier[m]);
  }
  return bench;
}

const std::vector<BenchScene>& Scenes(int num_points, double outlier_fraction) {
  static std::map<std::pair<int, int>, std::vector<BenchScene>> cache;
  auto& scenes = cache[{num_points, static_cast<int>(std::lround(outlier_fraction * 100))}];
  if (scenes.empty())
    for (int s = 0; s < kNumScenes; ++s) scenes.push_back(MakeBenchScene(num_points, outlier_fraction, 1000 + s));
  return scenes;
}

// A pose is a success when it is within 0.5 m and 60" of the truth (0.5 px noise gives centimetres
// and seconds; a wrong RANSAC model is off by metres and degrees).
constexpr double kSuccessPositionM = 0.5;
constexpr double kSuccessRotationArcSec = 60.0;

struct Quality {
  int successes = 0, trials = 0;
  double position_ssq = 0.0, rotation_ssq = 0.0;
  void Add(const ExteriorOrientation& truth, const Eigen::Matrix3d& R, const Eigen::Vector3d& c, bool ok) {
    ++trials;
    if (!ok) return;
    const double dp = (c - truth.center_in_ground()).norm();
    const double dr = RotationErrorArcSeconds(
        R, RotationFromAngles(RotationConvention::kSeed, truth.angles_seed_rad()));
    if (dp < kSuccessPositionM && dr < kSuccessRotationArcSec) {
      ++successes;
      position_ssq += dp * dp;
      rotation_ssq += dr * dr;
    }
  }
  void Report(benchmark::State& state) const {
    state.counters["success_pct"] = 100.0 * successes / std::max(1, trials);
    state.counters["pos_rmse_m"] = successes ? std::sqrt(position_ssq / successes) : NAN;
    state.counters["rot_rmse_arcsec"] = successes ? std::sqrt(rotation_ssq / successes) : NAN;
  }
};

// ------------------------------------------------------------------ cost evaluation

void BM_PoseCostEvaluation(benchmark::State& state, JacobianType type) {
  const BenchScene& scene = Scenes(50, 0.0).front();
  std::vector<std::unique_ptr<ceres::CostFunction>> costs;
  for (size_t i = 0; i < scene.input.image_plane.size(); ++i)
    costs.emplace_back(CreatePoseCost(type, PoseCostFunctor(scene.input.image_plane[i],
                                                            scene.input.points_in_ground[i],
                                                            scene.input.focal_length, 1.0)));
  const double* parameters[] = {scene.truth.data()};
  double residual[2], jacobian[12];
  double* jacobians[] = {jacobian};
  size_t i = 0;
  for (auto _ : state) {
    costs[i]->Evaluate(parameters, residual, jacobians);
    benchmark::DoNotOptimize(jacobian[11]);
    if (++i == costs.size()) i = 0;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK_CAPTURE(BM_PoseCostEvaluation, analytic, JacobianType::kAnalytic);
BENCHMARK_CAPTURE(BM_PoseCostEvaluation, autodiff, JacobianType::kAutodiff);

// The same with a different pose at every call: the analytic cost's per-thread memo of the pose's
// trigonometry never hits (the worst case; Ceres evaluates all observations at one pose).
void BM_PoseCostEvaluationNewPoseEveryCall(benchmark::State& state, JacobianType type) {
  const BenchScene& scene = Scenes(50, 0.0).front();
  std::unique_ptr<ceres::CostFunction> cost(CreatePoseCost(
      type, PoseCostFunctor(scene.input.image_plane[0], scene.input.points_in_ground[0],
                            scene.input.focal_length, 1.0)));
  ExteriorOrientation poses[2] = {scene.truth, scene.truth};
  poses[1].parameters[5] += 1e-6;
  double residual[2], jacobian[12];
  double* jacobians[] = {jacobian};
  int k = 0;
  for (auto _ : state) {
    const double* parameters[] = {poses[k ^= 1].data()};
    cost->Evaluate(parameters, residual, jacobians);
    benchmark::DoNotOptimize(jacobian[11]);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK_CAPTURE(BM_PoseCostEvaluationNewPoseEveryCall, analytic, JacobianType::kAnalytic);
BENCHMARK_CAPTURE(BM_PoseCostEvaluationNewPoseEveryCall, autodiff, JacobianType::kAutodiff);

// ceres::Problem + ceres::Solve instead of TinySolver: the Problem set-up cost, shown side by side.
void BM_ResectionCeresProblem(benchmark::State& state) {
  const auto& scenes = Scenes(static_cast<int>(state.range(0)), 0.0);
  ResectionOptions options;
  options.refinement.ceres.minimizer = CeresMinimizer::kProblem;
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(ResectImage(options, scenes[i].input));
    if (++i == scenes.size()) i = 0;
  }
}
BENCHMARK(BM_ResectionCeresProblem)->Arg(10)->Arg(50)->Arg(500)->Unit(benchmark::kMicrosecond);

// ------------------------------------------------------------------ clean resection

void BM_Resection(benchmark::State& state, PoseSolver solver, JacobianType jacobian) {
  const auto& scenes = Scenes(static_cast<int>(state.range(0)), 0.0);
  ResectionOptions options;
  options.refinement.solver = solver;
  options.refinement.jacobian = jacobian;
  Quality quality;
  for (const auto& scene : scenes) {
    const ResectionResult r = ResectImage(options, scene.input);
    quality.Add(scene.truth, RotationFromAngles(RotationConvention::kSeed, r.eo.angles_seed_rad()),
                r.eo.center_in_ground(), r.success);
  }
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(ResectImage(options, scenes[i].input));
    if (++i == scenes.size()) i = 0;
  }
  quality.Report(state);
}
BENCHMARK_CAPTURE(BM_Resection, ceres_analytic, PoseSolver::kCeres, JacobianType::kAnalytic)
    ->Arg(10)->Arg(50)->Arg(500)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Resection, ceres_autodiff, PoseSolver::kCeres, JacobianType::kAutodiff)
    ->Arg(10)->Arg(50)->Arg(500)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Resection, taylor, PoseSolver::kTaylor, JacobianType::kAnalytic)
    ->Arg(10)->Arg(50)->Arg(500)->Unit(benchmark::kMicrosecond);

// The Taylor solver alone (no input checks, no statistics pass): the kernel the 15 us target is for.
void BM_TaylorKernel(benchmark::State& state) {
  const auto& scenes = Scenes(static_cast<int>(state.range(0)), 0.0);
  TaylorResectionOptions options;
  std::vector<std::vector<double>> sigmas;
  for (const auto& scene : scenes) sigmas.emplace_back(scene.input.image_plane.size(), 3.0);
  size_t i = 0;
  TaylorResectionResult result;
  for (auto _ : state) {
    const auto& in = scenes[i].input;
    benchmark::DoNotOptimize(TaylorResection(options, in.image_plane, in.points_in_ground,
                                             sigmas[i], in.focal_length, *in.approximate, &result));
    if (++i == scenes.size()) i = 0;
  }
}
BENCHMARK(BM_TaylorKernel)->Arg(10)->Arg(50)->Arg(500)->Unit(benchmark::kMicrosecond);

// ------------------------------------------------------------------ robust resection

void BM_RobustResection(benchmark::State& state) {
  const double outliers = state.range(0) / 100.0;
  const auto& scenes = Scenes(500, outliers);
  // Defaults: consensus threshold 3.72 sigma of the marks' 0.5 px accuracy (1.86 px), least squares
  // with data snooping, Ceres analytic.
  ResectionOptions options;
  std::vector<ResectionInput> inputs;
  for (const auto& scene : scenes) {
    inputs.push_back(scene.input);
    inputs.back().approximate.reset();  // no approximate values: LO-RANSAC + Ceres
  }
  Quality quality;
  double ransac_seconds = 0.0, total_seconds = 0.0;
  for (size_t s = 0; s < scenes.size(); ++s) {
    const ResectionResult r = ResectImage(options, inputs[s]);
    quality.Add(scenes[s].truth, RotationFromAngles(RotationConvention::kSeed, r.eo.angles_seed_rad()),
                r.eo.center_in_ground(), r.success);
    ransac_seconds += r.summary.ransac_seconds;
    total_seconds += r.summary.total_seconds;
  }
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(ResectImage(options, inputs[i]));
    if (++i == inputs.size()) i = 0;
  }
  quality.Report(state);
  state.counters["ransac_share_pct"] = 100.0 * ransac_seconds / total_seconds;
}
BENCHMARK(BM_RobustResection)->Arg(30)->Arg(60)->Unit(benchmark::kMicrosecond);

// ------------------------------------------------------------------ batch throughput

// The batch of `photopose resect` without a frames table: kBatchImages images of 10 control points
// each (0.5 px), no approximate values (the exhaustive consensus of C(10, 3) = 120 samples, then
// least squares, data snooping, the ambiguity search and reliability), every tenth image with one
// gross error (20-200 px). Wall-clock time per batch; items are images, so items_per_second is the
// throughput; cores_busy is the process's CPU time (every thread) over the wall time.
constexpr int kBatchImages = 2000;
constexpr int kBatchPoints = 10;

const std::vector<ResectionInput>& BatchInputs() {
  static const std::vector<ResectionInput> inputs = [] {
    std::vector<ResectionInput> batch;
    for (int i = 0; i < kBatchImages; ++i) {
      BenchScene scene = MakeBenchScene(kBatchPoints, i % 10 == 9 ? 0.1 : 0.0, 50000 + i);
      scene.input.approximate.reset();
      batch.push_back(std::move(scene.input));
    }
    return batch;
  }();
  return inputs;
}

double ProcessCpuSeconds() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

void BM_ResectImagesThroughput(benchmark::State& state) {
  const std::vector<ResectionInput>& inputs = BatchInputs();
  const int threads = static_cast<int>(state.range(0));
  const ResectionOptions options;
  int solved = 0;
  for (const ResectionResult& r : ResectImages(options, inputs, threads)) solved += r.success;
  double cpu = 0.0, wall = 0.0;
  for (auto _ : state) {
    const double cpu_start = ProcessCpuSeconds();
    const auto wall_start = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(ResectImages(options, inputs, threads));
    wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
    cpu += ProcessCpuSeconds() - cpu_start;
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(inputs.size()));
  state.counters["solved_pct"] = 100.0 * solved / inputs.size();
  state.counters["cores_busy"] = wall > 0.0 ? cpu / wall : 0.0;
}
BENCHMARK(BM_ResectImagesThroughput)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);

#ifdef PHOTOPOSE_HAVE_OPENCV
// ------------------------------------------------------------------ the OpenCV peer

// The same scene in OpenCV's terms: pixel centres at integers, camera x right, y down, z forward.
struct OpenCvScene {
  std::vector<cv::Point3d> object;
  std::vector<cv::Point2d> image;
  cv::Mat K;
  cv::Mat rvec_guess, tvec_guess;
};

const Eigen::Matrix3d kCvFromSeedCamera = Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();

OpenCvScene ToOpenCv(const BenchScene& scene) {
  OpenCvScene cv_scene;
  const FrameCamera& camera = scene.camera;
  const double f_px = camera.focal_length_um / camera.pixel_size_um;
  const double cx = 0.5 * camera.n_columns + camera.principal_x_um / camera.pixel_size_um - 0.5;
  const double cy = 0.5 * camera.n_rows - camera.principal_y_um / camera.pixel_size_um - 0.5;
  cv_scene.K = (cv::Mat_<double>(3, 3) << f_px, 0, cx, 0, f_px, cy, 0, 0, 1);
  // Large projected coordinates are centred, as a careful OpenCV user would do.
  const Eigen::Vector3d origin = scene.input.points_in_ground.front();
  for (size_t i = 0; i < scene.pixels.size(); ++i) {
    const Eigen::Vector3d p = scene.input.points_in_ground[i] - origin;
    cv_scene.object.emplace_back(p.x(), p.y(), p.z());
    cv_scene.image.emplace_back(scene.pixels[i].x() - 0.5, scene.pixels[i].y() - 0.5);
  }
  const ExteriorOrientation& guess = *scene.input.approximate;
  const Eigen::Matrix3d R = kCvFromSeedCamera * RotationFromAngles(RotationConvention::kSeed, guess.angles_seed_rad());
  const Eigen::Vector3d t = -R * (guess.center_in_ground() - origin);
  cv::Mat Rm(3, 3, CV_64F);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) Rm.at<double>(r, c) = R(r, c);
  cv::Rodrigues(Rm, cv_scene.rvec_guess);
  cv_scene.tvec_guess = (cv::Mat_<double>(3, 1) << t.x(), t.y(), t.z());
  return cv_scene;
}

void AddOpenCvQuality(const BenchScene& scene, const cv::Mat& rvec, const cv::Mat& tvec, bool ok,
                      Quality* quality) {
  Eigen::Matrix3d R_seed = Eigen::Matrix3d::Identity();
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  if (ok) {
    cv::Mat Rm;
    cv::Rodrigues(rvec, Rm);
    Eigen::Matrix3d R_cv;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) R_cv(r, c) = Rm.at<double>(r, c);
    const Eigen::Vector3d t(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
    R_seed = kCvFromSeedCamera * R_cv;
    center = -R_cv.transpose() * t + scene.input.points_in_ground.front();
  }
  quality->Add(scene.truth, R_seed, center, ok);
}

void BM_OpenCvSolvePnP(benchmark::State& state, int flags) {
  const auto& scenes = Scenes(static_cast<int>(state.range(0)), 0.0);
  std::vector<OpenCvScene> cv_scenes;
  for (const auto& s : scenes) cv_scenes.push_back(ToOpenCv(s));
  const bool use_guess = flags == cv::SOLVEPNP_ITERATIVE;
  Quality quality;
  for (size_t s = 0; s < scenes.size(); ++s) {
    cv::Mat rvec = cv_scenes[s].rvec_guess.clone(), tvec = cv_scenes[s].tvec_guess.clone();
    const bool ok = cv::solvePnP(cv_scenes[s].object, cv_scenes[s].image, cv_scenes[s].K, cv::noArray(),
                                 rvec, tvec, use_guess, flags);
    AddOpenCvQuality(scenes[s], rvec, tvec, ok, &quality);
  }
  size_t i = 0;
  for (auto _ : state) {
    cv::Mat rvec = cv_scenes[i].rvec_guess.clone(), tvec = cv_scenes[i].tvec_guess.clone();
    benchmark::DoNotOptimize(cv::solvePnP(cv_scenes[i].object, cv_scenes[i].image, cv_scenes[i].K,
                                          cv::noArray(), rvec, tvec, use_guess, flags));
    if (++i == cv_scenes.size()) i = 0;
  }
  quality.Report(state);
}
BENCHMARK_CAPTURE(BM_OpenCvSolvePnP, sqpnp, static_cast<int>(cv::SOLVEPNP_SQPNP))
    ->Arg(10)->Arg(50)->Arg(500)->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_OpenCvSolvePnP, iterative_from_guess, static_cast<int>(cv::SOLVEPNP_ITERATIVE))
    ->Arg(10)->Arg(50)->Arg(500)->Unit(benchmark::kMicrosecond);

void BM_OpenCvSolvePnPRansac(benchmark::State& state) {
  const double outliers = state.range(0) / 100.0;
  const auto& scenes = Scenes(500, outliers);
  std::vector<OpenCvScene> cv_scenes;
  for (const auto& s : scenes) cv_scenes.push_back(ToOpenCv(s));
  // Same threshold (3.72 sigma of 0.5 px marks) and confidence (0.9999) as photopose; enough
  // iterations for 60% outliers.
  const ResectionOptions ours;
  const float threshold =
      static_cast<float>(MarkThresholdSigmas(ours.test.confidence) * scenes.front().input.sigma[0]);
  const double confidence = ours.consensus.ransac.confidence;
  const int iterations = ours.consensus.ransac.max_trials;
  Quality quality;
  for (size_t s = 0; s < scenes.size(); ++s) {
    cv::Mat rvec, tvec;
    const bool ok = cv::solvePnPRansac(cv_scenes[s].object, cv_scenes[s].image, cv_scenes[s].K,
                                       cv::noArray(), rvec, tvec, false, iterations, threshold, confidence);
    AddOpenCvQuality(scenes[s], rvec, tvec, ok, &quality);
  }
  size_t i = 0;
  for (auto _ : state) {
    cv::Mat rvec, tvec;
    benchmark::DoNotOptimize(cv::solvePnPRansac(cv_scenes[i].object, cv_scenes[i].image, cv_scenes[i].K,
                                                cv::noArray(), rvec, tvec, false, iterations, threshold,
                                                confidence));
    if (++i == cv_scenes.size()) i = 0;
  }
  quality.Report(state);
}
BENCHMARK(BM_OpenCvSolvePnPRansac)->Arg(30)->Arg(60)->Unit(benchmark::kMicrosecond);
#endif

}  // namespace
}  // namespace photopose

BENCHMARK_MAIN();
