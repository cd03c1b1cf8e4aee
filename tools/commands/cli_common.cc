#include "tools/commands/cli_common.h"

#include <gflags/gflags.h>
#include <signal.h>
#include <sys/stat.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <iterator>
#include <sstream>
#include <string_view>

#include "core/io/csv.h"

namespace photopose::cli {
namespace {

std::atomic<bool> g_solving{false};

// The signal that asked the run to stop (0: none). Written by the signal handler, read by the
// progress hooks on any thread: a lock-free atomic is async-signal-safe (C++17 [support.signal]).
std::atomic<int> g_cancel_signal{0};
static_assert(std::atomic<int>::is_always_lock_free,
              "the cancellation flag is written by a signal handler");

void SetAction(int signal_number, void (*handler)(int)) {
  struct sigaction action = {};
  action.sa_handler = handler;
  sigemptyset(&action.sa_mask);
  // Both signals blocked while the handler runs; interrupted reads and writes restart.
  sigaddset(&action.sa_mask, SIGINT);
  sigaddset(&action.sa_mask, SIGTERM);
  action.sa_flags = SA_RESTART;
  sigaction(signal_number, &action, nullptr);
}

// The signals CancelOnSignals handles: SIGINT and SIGTERM, unless the process started with one of
// them ignored. Written before the handlers are installed, only read by them.
constexpr int kCancelSignals[] = {SIGINT, SIGTERM};
bool g_handled[std::size(kCancelSignals)] = {};

// The first SIGINT or SIGTERM: recorded, and the signals handled get their default action back,
// so that a second one ends the process (sigaction is async-signal-safe).
extern "C" void OnCancelSignal(int signal_number) {
  int none = 0;
  g_cancel_signal.compare_exchange_strong(none, signal_number);
  for (size_t k = 0; k < std::size(kCancelSignals); ++k)
    if (g_handled[k]) SetAction(kCancelSignals[k], SIG_DFL);
}

const char* SignalName(int signal_number) {
  switch (signal_number) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    default:
      return "a signal";
  }
}

bool IsHelp(const std::string& arg) {
  return arg == "--help" || arg == "-h" || arg == "--helpfull" || arg == "-help";
}

bool IsNumericType(const std::string& type) {
  return type == "int32" || type == "int64" || type == "uint32" || type == "uint64" ||
         type == "double";
}

std::string_view TrimBlanks(std::string_view text) {
  const size_t begin = text.find_first_not_of(" \t\r");
  if (begin == std::string_view::npos) return {};
  return text.substr(begin, text.find_last_not_of(" \t\r") - begin + 1);
}

// The user's name of a gflag of the command: the alias that maps to it, or the name without the
// command's prefix.
std::string UserName(const CommandFlags& flags, const std::string& gflag) {
  for (const auto& [user, target] : flags.aliases)
    if (target == gflag) return user;
  return gflag.rfind(flags.prefix, 0) == 0 ? gflag.substr(flags.prefix.size()) : gflag;
}

// The gflags defined for the command, in gflags' order.
std::vector<gflags::CommandLineFlagInfo> CommandGflags(const CommandFlags& flags) {
  std::vector<gflags::CommandLineFlagInfo> all, own;
  gflags::GetAllFlags(&all);
  for (auto& info : all) {
    if (info.filename.find(flags.defined_in) == std::string::npos) continue;
    if (info.name.rfind(flags.prefix, 0) != 0) continue;
    own.push_back(std::move(info));
  }
  return own;
}

// Parses the arguments of the command line or of one flag-file line into the command's gflags.
class FlagParser {
 public:
  FlagParser(const CommandFlags& flags, ParsedFlags* parsed) : flags_(flags), parsed_(parsed) {}

  // `where` starts every message: "" on the command line, "file:line: " in a flag file.
  bool Parse(const std::vector<std::string>& args, const std::string& where) {
    for (size_t i = 0; i < args.size(); ++i) {
      const std::string& arg = args[i];
      if (IsHelp(arg)) {
        parsed_->help = true;
        continue;
      }
      if (arg.size() < 2 || arg[0] != '-') {
        return Fail(where + "unexpected argument '" + arg + "' (flags are --name=value)");
      }
      const std::string body = arg.substr(arg[1] == '-' ? 2 : 1);
      const size_t equals = body.find('=');
      std::string name = body.substr(0, equals);
      const bool has_value = equals != std::string::npos;
      std::string value = has_value ? body.substr(equals + 1) : "";
      if (name == "flagfile") {
        if (!has_value) {
          if (i + 1 >= args.size()) return Fail(where + "flag --flagfile needs a value");
          value = args[++i];
        }
        if (!ReadFlagFile(value, where)) return false;
        continue;
      }
      std::string gflag;
      gflags::CommandLineFlagInfo info;
      if (!Lookup(name, &gflag, &info)) {
        // --noflag for booleans.
        if (name.rfind("no", 0) == 0 && !has_value && Lookup(name.substr(2), &gflag, &info) &&
            info.type == "bool") {
          name = name.substr(2);
          value = "false";
        } else {
          return Fail(where + "unknown flag --" + name + " (see photopose " + flags_.command +
                      " --help)");
        }
      } else if (!has_value) {
        if (info.type == "bool") {
          value = "true";
        } else if (i + 1 < args.size()) {
          value = args[++i];
        } else {
          return Fail(where + "flag --" + name + " needs a value");
        }
      }
      if (gflags::SetCommandLineOption(gflag.c_str(), value.c_str()).empty()) {
        return Fail(where + "invalid value '" + value + "' for --" + name + " (" + info.type +
                    " expected)");
      }
    }
    return true;
  }

  // Every numeric flag inside its range, whether given or not.
  bool CheckRanges() {
    for (const gflags::CommandLineFlagInfo& info : CommandGflags(flags_)) {
      if (!IsNumericType(info.type)) continue;
      const FlagRange* range = flags_.RangeOf(UserName(flags_, info.name));
      if (range == nullptr) continue;  // NumericFlagsWithoutRange keeps this list empty
      double value = 0.0;
      std::string why;
      if (!ParseFiniteNumber(info.current_value, &value, &why) || !range->Contains(value))
        return Fail(range->Refusal(info.current_value));
    }
    return true;
  }

 private:
  bool Fail(const std::string& message) {
    BadInput(flags_.command, message);
    return false;
  }

  bool Lookup(const std::string& name, std::string* gflag, gflags::CommandLineFlagInfo* info) {
    *gflag = flags_.prefix + name;
    for (const auto& [user, target] : flags_.aliases)
      if (user == name) *gflag = target;
    return gflags::GetCommandLineFlagInfo(gflag->c_str(), info) &&
           info->filename.find(flags_.defined_in) != std::string::npos;
  }

  bool ReadFlagFile(const std::string& path, const std::string& where) {
    const std::string flag = where + "--flagfile=" + path + ": ";
    struct stat info;
    if (stat(path.c_str(), &info) != 0) {
      std::string text;
      return Fail(where + ReadTextFile(path, &text).message());  // "path: cannot open: ..."
    }
    std::string chain;
    for (const OpenFile& open : open_files_) chain += open.path + " -> ";
    for (const OpenFile& open : open_files_) {
      if (open.device == info.st_dev && open.inode == info.st_ino) {
        return Fail(flag + "the flag file includes itself (" + chain + path +
                    "); a flag file may not read itself again");
      }
    }
    if (open_files_.size() >= static_cast<size_t>(kMaxFlagFileDepth)) {
      return Fail(flag + "flag files nest deeper than " + std::to_string(kMaxFlagFileDepth) +
                  " levels (" + chain + path + ")");
    }
    std::string text;
    Status status = ReadTextFile(path, &text);
    if (status.ok()) status = CheckTextInput(text, path);
    if (!status.ok()) return Fail(where + status.message());
    parsed_->flag_files.push_back(path);
    open_files_.push_back({path, info.st_dev, info.st_ino});
    size_t start = 0;
    for (int line = 1; start < text.size(); ++line) {
      size_t end = text.find('\n', start);
      if (end == std::string::npos) end = text.size();
      const std::string_view content =
          TrimBlanks(std::string_view(text).substr(start, end - start));
      start = end + 1;
      if (content.empty() || content.front() == '#') continue;
      const std::string here = path + ":" + std::to_string(line) + ": ";
      if (content.front() != '-') {
        return Fail(here + "'" + std::string(content) +
                    "' is not a flag (a flag file holds one --name=value per line)");
      }
      std::vector<std::string> args;
      const size_t blank = content.find_first_of(" \t");
      if (blank != std::string_view::npos && content.find('=') > blank) {
        args.emplace_back(content.substr(0, blank));  // "--name value"
        args.emplace_back(TrimBlanks(content.substr(blank)));
      } else {
        args.emplace_back(content);
      }
      if (!Parse(args, here)) return false;
    }
    open_files_.pop_back();
    return true;
  }

  struct OpenFile {
    std::string path;
    dev_t device;
    ino_t inode;
  };
  const CommandFlags& flags_;
  ParsedFlags* parsed_;
  std::vector<OpenFile> open_files_;  // the flag files being read, outermost first
};

}  // namespace

const char kConventionsHelp[] =
    "Conventions: pixel coordinates are Column/Row with (0,0) at the top-left corner of the image\n"
    "and Row down (the centre of the first pixel is 0.5,0.5). Film coordinates are micrometres "
    "from\n"
    "the fiducial centre, x right and y up (FilmCoordinateSystem 1) unless the camera table says\n"
    "otherwise. Angles in tables are decimal degrees; --rotation names their convention: rxryrz\n"
    "(R = Rx(omega) Ry(phi) Rz(kappa) maps ground to camera, the seed lecture's equation 1; 'seed'\n"
    "is accepted as an alias), opk (Wolf & Dewitt / PATB, the transpose of rxryrz for the same\n"
    "numbers) or pok (Y-primary phi-omega-kappa); the camera's AngleDirection applies. A mark's\n"
    "Accuracy is in its own unit: pixels for Column/Row, micrometres for FilmX/FilmY. Ground units\n"
    "are metres. See docs/conventions.md and docs/formats.md.\n";

namespace {

// An end of a range as written in help and messages; the uint64 seeds end at 2^64 - 1, which a
// double cannot hold.
std::string RangeEnd(double value) {
  return value >= 18446744073709551615.0 ? "18446744073709551615" : FormatPlainNumber(value);
}

}  // namespace

std::string FlagRange::Text() const {
  return std::string(open_min ? "(" : "[") + RangeEnd(min) + ", " + RangeEnd(max) +
         (open_max ? ")" : "]") + (unit.empty() ? "" : " " + unit);
}

bool FlagRange::Contains(double value) const {
  return std::isfinite(value) && (open_min ? value > min : value >= min) &&
         (open_max ? value < max : value <= max);
}

std::string FlagRange::Refusal(const std::string& text) const {
  double value = 0.0;
  std::string why;
  const bool finite = ParseFiniteNumber(text, &value, &why);
  return "--" + name + "=" + text +
         (finite ? " is outside " + Text() : " is not a finite number; the range is " + Text());
}

const FlagRange* CommandFlags::RangeOf(const std::string& name) const {
  for (const FlagRange& range : ranges)
    if (range.name == name) return &range;
  return nullptr;
}

bool ParseFlags(int argc, char** argv, const CommandFlags& flags, ParsedFlags* parsed) {
  *parsed = ParsedFlags();
  FlagParser parser(flags, parsed);
  return parser.Parse(std::vector<std::string>(argv, argv + argc), "") && parser.CheckRanges();
}

std::optional<int> StartCommand(int argc, char** argv, const std::string& usage,
                                const CommandFlags& flags, ParsedFlags* parsed) {
  if (!ParseFlags(argc, argv, flags, parsed)) return kExitBadInput;
  if (!parsed->help) return std::nullopt;
  PrintHelp(usage, flags);
  return kExitSuccess;
}

std::vector<std::string> NumericFlagsWithoutRange(const CommandFlags& flags) {
  std::vector<std::string> missing;
  for (const gflags::CommandLineFlagInfo& info : CommandGflags(flags)) {
    const std::string name = UserName(flags, info.name);
    if (IsNumericType(info.type) && flags.RangeOf(name) == nullptr) missing.push_back(name);
  }
  return missing;
}

void PrintHelp(const std::string& usage, const CommandFlags& flags) {
  std::cout << usage << "\n" << kConventionsHelp << "\nFlags:\n";
  for (const gflags::CommandLineFlagInfo& info : CommandGflags(flags)) {
    const std::string name = UserName(flags, info.name);
    std::cout << "  --" << name << " (" << info.type << ", default: \"" << info.default_value
              << "\")\n      " << info.description;
    if (const FlagRange* range = flags.RangeOf(name))
      std::cout << " Range: " << range->Text() << ".";
    std::cout << "\n";
  }
  std::cout << "  --flagfile=F\n      Reads further flags from the file F, one per line "
               "(--name=value or --name value; '#' starts a comment line); a flag file may "
               "include others, "
            << kMaxFlagFileDepth << " levels deep at most.\n";
}

bool FlagGiven(const char* gflag) {
  gflags::CommandLineFlagInfo info;
  return gflags::GetCommandLineFlagInfo(gflag, &info) && !info.is_default;
}

int BadInput(const std::string& subcommand, const std::string& message) {
  std::cerr << "photopose " << subcommand << ": " << EscapeForMessage(message) << "\n";
  return kExitBadInput;
}

ProgressLine::ProgressLine(std::string command, std::string items, std::ostream* out,
                           double first_seconds, double every_seconds)
    : command_(std::move(command)),
      items_(std::move(items)),
      out_(out != nullptr ? out : &std::cerr),
      every_seconds_(every_seconds),
      next_seconds_(first_seconds) {}

void ProgressLine::operator()(size_t done, size_t total) {
  const std::lock_guard<std::mutex> lock(mutex_);
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const bool last = done == total;
  if (last ? !printed_ : elapsed < next_seconds_) return;
  next_seconds_ = std::max(elapsed, next_seconds_) + every_seconds_;
  printed_ = true;
  char line[160];
  std::snprintf(line, sizeof(line), "photopose %s: %zu of %zu %s (%.0f%%), %.0f s",
                command_.c_str(), done, total, items_.c_str(),
                100.0 * done / std::max<size_t>(total, 1), elapsed);
  *out_ << line;
  if (!last && done > 0)
    *out_ << ", about " << static_cast<long>(elapsed * (total - done) / done + 0.5) << " s left";
  *out_ << "\n";
}

void CancelOnSignals() {
  // A signal ignored from the start stays ignored: a background job of a script is meant to be
  // immune to Ctrl-C (POSIX shells start it with SIGINT ignored).
  for (size_t k = 0; k < std::size(kCancelSignals); ++k) {
    struct sigaction current = {};
    g_handled[k] = sigaction(kCancelSignals[k], nullptr, &current) != 0 ||
                   current.sa_handler != SIG_IGN;
  }
  for (size_t k = 0; k < std::size(kCancelSignals); ++k)
    if (g_handled[k]) SetAction(kCancelSignals[k], &OnCancelSignal);
}

bool CancelRequested() { return g_cancel_signal.load() != 0; }

int CancelledExitCode(int signal_number) { return 128 + signal_number; }

int ReportCancelled(const std::string& command, const std::string& when) {
  const int signal_number = g_cancel_signal.load();
  std::cerr << "photopose " << command << ": cancelled by " << SignalName(signal_number)
            << (when.empty() ? "" : " ") << when << "; nothing written\n";
  return CancelledExitCode(signal_number);
}

Status CommitUnlessCancelled(OutputFiles* outputs) {
  if (CancelRequested()) {
    outputs->Abort();
    return Status::Error("cancelled before the outputs were written");
  }
  return outputs->Commit();
}

void SetSolving(bool solving) { g_solving = solving; }

int ExitCodeForUnexpectedFailure() { return g_solving ? kExitSomeFailed : kExitBadInput; }

}  // namespace photopose::cli
