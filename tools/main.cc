// photopose: space resection and its tools on the photogrammetric collinearity equations.
#include <gflags/gflags.h>
#include <glog/logging.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <iostream>
#include <new>
#include <string>

#include "core/io/csv.h"
#include "tools/commands/cli_common.h"
#include "tools/commands/commands.h"

#ifdef PHOTOPOSE_JEMALLOC_CONF
// jemalloc's options, read at its start (MALLOC_CONF in the environment still overrides them).
// A freed page goes back to the system after 1 s instead of jemalloc's 10: the steps of a large
// adjustment free hundreds of MB (the rounds' structures, the statistics' factor) just before the
// next allocates as much, and pages kept dirty for 10 s add to the next step's peak (the Taylor
// path on the 1000-image COLMAP model: 612 -> 593 MiB, the same CPU time; docs/performance.md).
// 0 would purge on every free: 574 MiB, but twice the time, the statistics' scratch being
// faulted in again and again.
extern "C" {
extern const char* malloc_conf;
const char* malloc_conf = "dirty_decay_ms:1000";
}
#endif

namespace {

constexpr char kUsage[] =
    "photopose: camera poses from the photogrammetric collinearity equations.\n\n"
    "Usage: photopose <command> [--flag=value ...]\n\n"
    "Commands:\n"
    "  resect    resect every image that has marks (robust: RANSAC + Ceres, or the Taylor\n"
    "            linearisation of the seed lecture)\n"
    "  bundle    the weighted bundle adjustment of a block (tables, a COLMAP model or a BAL file):\n"
    "            control, check and tie points, GNSS priors, self-calibration, diagnostics\n"
    "  simulate  write a synthetic dataset (camera table, frames, points, marks) with its truth\n"
    "  compare   the solvers side by side: Monte-Carlo sweeps against truth, or a dataset\n\n"
    "Run 'photopose <command> --help' for the flags of a command, 'photopose --version' for the\n"
    "version.\n";

// The running command, for the guard's messages ("photopose resect: ..."); a fixed buffer so that
// reporting needs no memory.
char g_command[16] = "";

// The last resort: one line on stderr and the exit status of the phase (2, or 1 while solving),
// without unwinding and without allocating (memory may be what ran out). Temporary output files
// left behind carry the pid and are removed by the next run that writes the same target.
[[noreturn]] void Die(const char* what) {
  std::fflush(stdout);
  std::fprintf(stderr, "photopose%s%s: %s\n", g_command[0] != '\0' ? " " : "", g_command, what);
  std::fflush(stderr);
  std::_Exit(photopose::cli::ExitCodeForUnexpectedFailure());
}

// An exception that escaped a worker thread or a noexcept function.
void OnTerminate() {
  if (const std::exception_ptr failure = std::current_exception()) {
    try {
      std::rethrow_exception(failure);
    } catch (const std::bad_alloc&) {
      Die("out of memory");
    } catch (const std::exception& e) {
      Die(e.what());
    } catch (...) {
    }
  }
  Die("internal error: the program was terminated");
}

// A failed CHECK in a library: glog has printed it on the line above.
// glog wants the function type itself to carry the noreturn attribute.
__attribute__((noreturn)) void OnFatalCheck() {
  Die("internal error: a consistency check failed (see the line above)");
}

int Run(int argc, char** argv) {
  // --version anywhere on the command line (of the tool or of a command) prints the version.
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--version") == 0) {
      std::cout << "photopose " << PHOTOPOSE_VERSION << "\n";
      return photopose::cli::kExitSuccess;
    }
  }
  if (argc < 2 || std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0 ||
      std::strcmp(argv[1], "help") == 0) {
    std::cout << kUsage;
    return argc < 2 ? photopose::cli::kExitBadInput : photopose::cli::kExitSuccess;
  }
  const std::string command = argv[1];
  if (command.size() < sizeof(g_command)) std::strcpy(g_command, command.c_str());
  if (command == "resect") return photopose::cli::RunResect(argc - 2, argv + 2);
  if (command == "simulate") return photopose::cli::RunSimulate(argc - 2, argv + 2);
  if (command == "compare") return photopose::cli::RunCompare(argc - 2, argv + 2);
  if (command == "bundle") return photopose::cli::RunBundle(argc - 2, argv + 2);
  g_command[0] = '\0';
  std::cerr << "photopose: unknown command '" << photopose::EscapeForMessage(command) << "'\n"
            << kUsage;
  return photopose::cli::kExitBadInput;
}

}  // namespace

int main(int argc, char** argv) {
  // A closed pipe or FIFO is a write error to report, not a signal that kills the run.
  std::signal(SIGPIPE, SIG_IGN);
  std::set_terminate(&OnTerminate);
  google::InitGoogleLogging(argv[0]);
  google::InstallFailureFunction(&OnFatalCheck);
  FLAGS_logtostderr = true;
  // The subcommands report every problem themselves, one line each; Ceres' own log lines would
  // only repeat them. GLOG_minloglevel in the environment keeps them (with GLOG_v=3 Ceres times
  // each linear solve's Schur elimination, factorisation and back-substitution:
  // tools/benchmarks/bundle_scaling.sh).
  if (std::getenv("GLOG_minloglevel") == nullptr) FLAGS_minloglevel = 3;
  // One guard for everything the commands did not catch: a one-line message and exit status 2
  // (1 while solving), never an abort.
  try {
    return Run(argc, argv);
  } catch (const std::bad_alloc&) {
    Die("out of memory");
  } catch (const std::exception& e) {
    const std::string what = "unexpected error: " + photopose::EscapeForMessage(e.what());
    Die(what.c_str());
  } catch (...) {
    Die("unexpected error");
  }
}
