// The C++ side of tools/benchmarks/python_benchmark.py: the calls the Python module makes, on the
// same tables, timed here without Python (docs/performance.md, "Python module").
//
//   photopose_python_benchmark_peer resect DIR THREADS REPEATS OUT
//       reads DIR/cameras.csv, points.csv, marks.csv; one resection input per image with marks
//       (MakeResectionInput, default accuracies); times ResectImages (default options) REPEATS
//       times; writes the poses of the last run to OUT.
//   photopose_python_benchmark_peer resect_progress DIR THREADS REPEATS OUT
//       the same with a progress hook that counts its calls (default throttle), printed as
//       "progress calls: N" (of the last run).
//   photopose_python_benchmark_peer bundle DIR THREADS REPEATS OUT
//       reads DIR/cameras.csv, points.csv, marks.csv, frames.csv; times BundleAdjust (default
//       options, THREADS threads) on a fresh copy of the block REPEATS times; writes the adjusted
//       poses of the last run to OUT.
//   photopose_python_benchmark_peer bundle_no_diagnostics DIR THREADS REPEATS OUT
//       the same without the per-observation diagnostics (observation_diagnostics off).
// Prints "seconds: t1 t2 ..." (each run's time of the call alone). OUT has one line per image:
// its index and X0 Y0 Z0 omega phi kappa (m, rad, seed) with 17 significant digits, or "nan".

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/block.h"
#include "core/io/block_tables.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/resection/resection.h"

namespace {

using Clock = std::chrono::steady_clock;

int Fail(const std::string& message) {
  std::fprintf(stderr, "photopose_python_benchmark_peer: %s\n", message.c_str());
  return 2;
}

bool WritePoses(const std::string& path, const std::vector<std::optional<photopose::ExteriorOrientation>>& poses) {
  FILE* out = std::fopen(path.c_str(), "w");
  if (out == nullptr) return false;
  for (size_t i = 0; i < poses.size(); ++i) {
    std::fprintf(out, "%zu", i);
    for (int k = 0; k < 6; ++k) {
      if (poses[i]) {
        std::fprintf(out, " %.17g", poses[i]->parameters[k]);
      } else {
        std::fprintf(out, " nan");
      }
    }
    std::fprintf(out, "\n");
  }
  return std::fclose(out) == 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 6)
    return Fail("usage: resect|resect_progress|bundle|bundle_no_diagnostics DIR THREADS REPEATS OUT");
  const std::string mode = argv[1], dir = argv[2], out = argv[5];
  const int threads = std::atoi(argv[3]), repeats = std::atoi(argv[4]);
  if (threads < 0 || repeats < 1) return Fail("THREADS must be >= 0 and REPEATS >= 1");

  photopose::BlockFiles files;
  files.cameras = dir + "/cameras.csv";
  files.points = dir + "/points.csv";
  files.marks = dir + "/marks.csv";
  const bool bundle = mode == "bundle" || mode == "bundle_no_diagnostics";
  if (bundle) files.frames = dir + "/frames.csv";
  photopose::Block block;
  const photopose::Status read = photopose::ReadBlock(files, &block);
  if (!read.ok()) return Fail(read.message());

  std::vector<double> seconds;
  std::vector<std::optional<photopose::ExteriorOrientation>> poses(block.images.size());
  if (mode == "resect" || mode == "resect_progress") {
    std::vector<int> images;
    std::vector<photopose::ResectionInput> inputs;
    for (size_t i = 0; i < block.images.size(); ++i) {
      if (block.marks_of_image[i].empty()) continue;
      photopose::ResectionInput input;
      const photopose::Status made = photopose::MakeResectionInput(
          block, static_cast<int>(i), photopose::ResectionInputOptions(), &input, nullptr);
      if (!made.ok()) return Fail(made.message());
      images.push_back(static_cast<int>(i));
      inputs.push_back(std::move(input));
    }
    std::vector<photopose::ResectionResult> results;
    photopose::ResectionBatchOptions batch;
    batch.num_threads = threads;
    int calls = 0;
    if (mode == "resect_progress")
      batch.progress = [&calls](const photopose::ResectionProgress&) { return ++calls > 0; };
    for (int r = 0; r < repeats; ++r) {
      calls = 0;
      const auto start = Clock::now();
      const photopose::Status status =
          photopose::ResectImages(photopose::ResectionOptions(), inputs, batch, &results);
      seconds.push_back(std::chrono::duration<double>(Clock::now() - start).count());
      if (!status.ok()) return Fail(status.message());
    }
    if (batch.progress) std::printf("progress calls: %d\n", calls);
    for (size_t k = 0; k < images.size(); ++k)
      if (results[k].success) poses[images[k]] = results[k].eo;
  } else if (bundle) {
    photopose::BundleAdjustmentOptions options;
    options.solver.num_threads = threads;
    options.statistics.observation_diagnostics = mode == "bundle";
    photopose::Block adjusted;
    for (int r = 0; r < repeats; ++r) {
      adjusted = block;
      photopose::BundleAdjustmentResult result;
      const auto start = Clock::now();
      const photopose::Status status =
          photopose::BundleAdjust(options, photopose::BundleAdjustmentConfig(), &adjusted, &result);
      seconds.push_back(std::chrono::duration<double>(Clock::now() - start).count());
      if (!status.ok()) return Fail(status.message());
      if (!result.summary.IsSolutionUsable()) return Fail("no convergence: " + result.summary.message);
    }
    for (size_t i = 0; i < adjusted.images.size(); ++i) poses[i] = adjusted.images[i].eo;
  } else {
    return Fail("unknown mode '" + mode + "': resect, resect_progress, bundle or bundle_no_diagnostics");
  }
  if (!WritePoses(out, poses)) return Fail("cannot write " + out);
  std::printf("seconds:");
  for (const double s : seconds) std::printf(" %.6f", s);
  std::printf("\n");
  return 0;
}
