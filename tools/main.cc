// photopose: space resection and its tools on the photogrammetric collinearity equations.
#include <gflags/gflags.h>
#include <glog/logging.h>

#include <cstring>
#include <iostream>
#include <string>

#include "tools/cli_common.h"
#include "tools/commands.h"

namespace {

constexpr char kUsage[] =
    "photopose: camera poses from the photogrammetric collinearity equations.\n\n"
    "Usage: photopose <command> [--flag=value ...]\n\n"
    "Commands:\n"
    "  resect    resect every image that has marks (robust: RANSAC + Ceres, or the Taylor\n"
    "            linearisation of the seed lecture)\n"
    "  simulate  write a synthetic dataset (camera table, frames, points, marks) with its truth\n"
    "  compare   the solvers side by side: Monte-Carlo sweeps against truth, or a dataset\n\n"
    "Run 'photopose <command> --help' for the flags of a command, 'photopose --version' for the\n"
    "version.\n";

}  // namespace

int main(int argc, char** argv) {
  google::InitGoogleLogging(argv[0]);
  FLAGS_logtostderr = true;
  // The subcommands report every problem themselves, one line each; Ceres' own log lines would
  // only repeat them.
  FLAGS_minloglevel = 3;
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
  if (command == "resect") return photopose::cli::RunResect(argc - 2, argv + 2);
  if (command == "simulate") return photopose::cli::RunSimulate(argc - 2, argv + 2);
  if (command == "compare") return photopose::cli::RunCompare(argc - 2, argv + 2);
  std::cerr << "photopose: unknown command '" << command << "'\n" << kUsage;
  return photopose::cli::kExitBadInput;
}
