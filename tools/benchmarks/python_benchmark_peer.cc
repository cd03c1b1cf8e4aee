// The C++ side of tools/benchmarks/python_benchmark.py: the calls the Python module makes, on the
// same tables, measured here without Python (docs/performance.md, "Python module").
//
//   photopose_python_benchmark_peer MODE DIR THREADS OUT
//
// reads the tables of DIR once, prints "ready" and then makes one call for every line "call" it
// reads on stdin (the script alternates the peer's calls with its own), until stdin ends:
//   resect                  DIR/cameras.csv, points.csv, marks.csv; one resection input per image
//                           with marks (MakeResectionInput, default accuracies); ResectImages
//                           (default options, THREADS threads).
//   resect_progress         the same with a progress hook that counts its calls (default throttle).
//   bundle                  also DIR/frames.csv; BundleAdjust (default options, THREADS threads) on
//                           a fresh copy of the block (copied before the call is measured).
//   bundle_no_diagnostics   the same without the per-observation diagnostics.
// After each call it writes that call's poses to OUT (one line per image: its index and X0 Y0 Z0
// omega phi kappa, m and rad, seed, 17 significant digits, or "nan") and then prints one line
//   "call: WALL_S CPU_S PROGRESS_CALLS"
// WALL_S the call's wall time (steady clock), CPU_S the CPU time of the whole process during the
// call, user + system of every thread (getrusage RUSAGE_SELF, as the script measures its own side),
// PROGRESS_CALLS the hook's calls (0 without a hook). Neither measure includes the copy of the
// block before the call or the freeing of the previous call's result.
//
// At start it also prints "hardware counters: available" or "hardware counters: unavailable
// (REASON)": whether perf_event_open gives this process its user-space instructions (a VM without
// a virtual PMU does not, whatever /proc/sys/kernel/perf_event_paranoid says); the script then
// states why it measures CPU time rather than instructions and cycles.

#include <linux/perf_event.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "core/block.h"
#include "core/io/block_tables.h"
#include "solvers/bundle/bundle_adjustment.h"
#include "solvers/resection/resection.h"

namespace {

using Clock = std::chrono::steady_clock;
using Poses = std::vector<std::optional<photopose::ExteriorOrientation>>;

int Fail(const std::string& message) {
  std::fprintf(stderr, "photopose_python_benchmark_peer: %s\n", message.c_str());
  return 2;
}

bool WritePoses(const std::string& path, const Poses& poses) {
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

// CPU time of the whole process so far, every thread's user + system time (s).
double ProcessCpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const auto seconds = [](const timeval& t) { return t.tv_sec + 1e-6 * t.tv_usec; };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

// Whether perf_event_open counts this process's user-space instructions; empty when it does, else
// the reason.
std::string HardwareCountersUnavailable() {
  perf_event_attr attr{};
  attr.size = sizeof(attr);
  attr.type = PERF_TYPE_HARDWARE;
  attr.config = PERF_COUNT_HW_INSTRUCTIONS;
  attr.disabled = 1;
  attr.inherit = 1;
  attr.exclude_kernel = 1;
  attr.exclude_hv = 1;
  const long fd = syscall(SYS_perf_event_open, &attr, 0, -1, -1, 0);
  if (fd < 0) return std::string("perf_event_open: ") + std::strerror(errno);
  close(static_cast<int>(fd));
  return "";
}

// One measured call: its wall and CPU time (s) and its poses.
struct Call {
  double wall_seconds = 0.0;
  double cpu_seconds = 0.0;
  int progress_calls = 0;
  Poses poses;
};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 5)
    return Fail(
        "usage: resect|resect_progress|bundle|bundle_no_diagnostics DIR THREADS OUT (calls: 'call' "
        "lines on stdin)");
  const std::string mode = argv[1], dir = argv[2], out = argv[4];
  const int threads = std::atoi(argv[3]);
  if (threads < 0) return Fail("THREADS must be >= 0");
  const bool resect = mode == "resect" || mode == "resect_progress";
  const bool bundle = mode == "bundle" || mode == "bundle_no_diagnostics";
  if (!resect && !bundle)
    return Fail("unknown mode '" + mode +
                "': resect, resect_progress, bundle or bundle_no_diagnostics");

  photopose::BlockFiles files;
  files.cameras = dir + "/cameras.csv";
  files.points = dir + "/points.csv";
  files.marks = dir + "/marks.csv";
  if (bundle) files.frames = dir + "/frames.csv";
  photopose::Block block;
  const photopose::Status read = photopose::ReadBlock(files, &block);
  if (!read.ok()) return Fail(read.message());

  // The batch's inputs, made once (the script makes its own once too).
  std::vector<int> images;
  std::vector<photopose::ResectionInput> inputs;
  if (resect) {
    for (size_t i = 0; i < block.images.size(); ++i) {
      if (block.marks_of_image[i].empty()) continue;
      photopose::ResectionInput input;
      const photopose::Status made = photopose::MakeResectionInput(
          block, static_cast<int>(i), photopose::ResectionInputOptions(), &input, nullptr);
      if (!made.ok()) return Fail(made.message());
      images.push_back(static_cast<int>(i));
      inputs.push_back(std::move(input));
    }
  }
  photopose::ResectionBatchOptions batch;
  batch.num_threads = threads;
  int progress_calls = 0;
  if (mode == "resect_progress")
    batch.progress = [&progress_calls](const photopose::ResectionProgress&) {
      return ++progress_calls > 0;
    };
  photopose::BundleAdjustmentOptions options;
  options.solver.num_threads = threads;
  options.statistics.observation_diagnostics = mode == "bundle";

  const std::string no_counters = HardwareCountersUnavailable();
  std::printf("hardware counters: %s\n",
              no_counters.empty() ? "available" : ("unavailable (" + no_counters + ")").c_str());
  std::printf("ready\n");
  std::fflush(stdout);

  std::string line;
  while (std::getline(std::cin, line)) {
    if (line != "call") return Fail("expected 'call' on stdin, got '" + line + "'");
    Call call;
    call.poses.assign(block.images.size(), std::nullopt);
    progress_calls = 0;
    if (resect) {
      std::vector<photopose::ResectionResult> results;
      const double cpu_start = ProcessCpuSeconds();
      const auto start = Clock::now();
      const photopose::Status status =
          photopose::ResectImages(photopose::ResectionOptions(), inputs, batch, &results);
      call.wall_seconds = std::chrono::duration<double>(Clock::now() - start).count();
      call.cpu_seconds = ProcessCpuSeconds() - cpu_start;
      if (!status.ok()) return Fail(status.message());
      for (size_t k = 0; k < images.size(); ++k)
        if (results[k].success) call.poses[images[k]] = results[k].eo;
    } else {
      photopose::Block adjusted = block;
      photopose::BundleAdjustmentResult result;
      const double cpu_start = ProcessCpuSeconds();
      const auto start = Clock::now();
      const photopose::Status status =
          photopose::BundleAdjust(options, photopose::BundleAdjustmentConfig(), &adjusted, &result);
      call.wall_seconds = std::chrono::duration<double>(Clock::now() - start).count();
      call.cpu_seconds = ProcessCpuSeconds() - cpu_start;
      if (!status.ok()) return Fail(status.message());
      if (!result.summary.IsSolutionUsable())
        return Fail("no convergence: " + result.summary.message);
      for (size_t i = 0; i < adjusted.images.size(); ++i) call.poses[i] = adjusted.images[i].eo;
    }
    call.progress_calls = progress_calls;
    if (!WritePoses(out, call.poses)) return Fail("cannot write " + out);
    std::printf("call: %.6f %.6f %d\n", call.wall_seconds, call.cpu_seconds, call.progress_calls);
    std::fflush(stdout);
  }
  return 0;
}
