#include "tools/cli_common.h"

#include <gflags/gflags.h>

#include <sys/stat.h>

#include <iostream>
#include <vector>

namespace photopose::cli {

const char kConventionsHelp[] =
    "Conventions: pixel coordinates are Column/Row with (0,0) at the top-left corner of the image\n"
    "and Row down (the centre of the first pixel is 0.5,0.5). Film coordinates are micrometres from\n"
    "the fiducial centre, x right and y up (FilmCoordinateSystem 1) unless the camera table says\n"
    "otherwise. Angles in tables are decimal degrees; --rotation names their convention: rxryrz\n"
    "(R = Rx(omega) Ry(phi) Rz(kappa) maps ground to camera, the seed lecture's equation 1; 'seed'\n"
    "is accepted as an alias), opk (Wolf & Dewitt / PATB, the transpose of rxryrz for the same\n"
    "numbers) or pok (Y-primary phi-omega-kappa); the camera's AngleDirection applies. A mark's\n"
    "Accuracy is in its own unit: pixels for Column/Row, micrometres for FilmX/FilmY. Ground units\n"
    "are metres. See docs/conventions.md and docs/formats.md.\n";

bool ParseFlags(int argc, char** argv, const std::string& subcommand, bool* help_requested) {
  *help_requested = false;
  for (int i = 0; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "--help" || arg == "-h" || arg == "--helpfull" || arg == "-help") {
      *help_requested = true;
      continue;
    }
    if (arg.rfind("--", 0) != 0 && arg.rfind("-", 0) != 0) {
      std::cerr << "photopose " << subcommand << ": unexpected argument '" << arg
                << "' (flags are --name=value)\n";
      return false;
    }
    arg = arg.substr(arg[1] == '-' ? 2 : 1);
    std::string name = arg, value;
    bool has_value = false;
    const size_t equals = arg.find('=');
    if (equals != std::string::npos) {
      name = arg.substr(0, equals);
      value = arg.substr(equals + 1);
      has_value = true;
    }
    // A flag of another subcommand is as unknown here as a misspelt one; glog's own flags (--v,
    // --logtostderr, ...) and --flagfile are accepted everywhere.
    auto own_flag = [&subcommand](const std::string& flag, gflags::CommandLineFlagInfo* info) {
      return gflags::GetCommandLineFlagInfo(flag.c_str(), info) &&
             (info->filename.find(subcommand + "_command") != std::string::npos ||
              info->filename.find("logging") != std::string::npos || flag == "flagfile");
    };
    gflags::CommandLineFlagInfo info;
    if (!own_flag(name, &info)) {
      // --noflag for booleans.
      if (name.rfind("no", 0) == 0 && !has_value && own_flag(name.substr(2), &info) &&
          info.type == "bool") {
        gflags::SetCommandLineOption(name.substr(2).c_str(), "false");
        continue;
      }
      std::cerr << "photopose " << subcommand << ": unknown flag --" << name
                << " (see photopose " << subcommand << " --help)\n";
      return false;
    }
    if (!has_value) {
      if (info.type == "bool") {
        value = "true";
      } else if (i + 1 < argc) {
        value = argv[++i];
      } else {
        std::cerr << "photopose " << subcommand << ": flag --" << name << " needs a value\n";
        return false;
      }
    }
    if (gflags::SetCommandLineOption(name.c_str(), value.c_str()).empty()) {
      std::cerr << "photopose " << subcommand << ": invalid value '" << value << "' for --" << name
                << " (" << info.type << " expected)\n";
      return false;
    }
  }
  return true;
}

void PrintHelp(const std::string& usage, const std::string& flags_file) {
  std::cout << usage << "\n" << kConventionsHelp << "\nFlags:\n";
  std::vector<gflags::CommandLineFlagInfo> flags;
  gflags::GetAllFlags(&flags);
  for (const auto& flag : flags) {
    if (flag.filename.find(flags_file) == std::string::npos) continue;
    std::cout << "  --" << flag.name << " (" << flag.type << ", default: \""
              << flag.default_value << "\")\n      " << flag.description << "\n";
  }
  std::cout << "  --flagfile=F\n      Reads further flags, one per line, from the file F.\n";
}

Status CheckOutputFolder(const std::string& flag, const std::string& path) {
  if (path.empty()) return Status::Ok();
  const size_t slash = path.find_last_of('/');
  const std::string folder = slash == std::string::npos ? "." : slash == 0 ? "/" : path.substr(0, slash);
  struct stat info;
  if (stat(folder.c_str(), &info) != 0)
    return Status::Error(flag + ": folder '" + folder + "' does not exist");
  if (!S_ISDIR(info.st_mode)) return Status::Error(flag + ": '" + folder + "' is not a folder");
  return Status::Ok();
}

int BadInput(const std::string& subcommand, const std::string& message) {
  std::cerr << "photopose " << subcommand << ": " << message << "\n";
  return kExitBadInput;
}

}  // namespace photopose::cli
