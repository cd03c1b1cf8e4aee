#pragma once
// Shared plumbing of the photopose subcommands: exit codes, flag parsing that never exits on its
// own and checks every flag wherever it comes from, one-line error reporting, and the phase of a
// run that main's top-level guard reads.

#include <chrono>
#include <cstddef>
#include <mutex>
#include <optional>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "core/enum_names.h"
#include "core/io/output_files.h"
#include "core/status.h"

namespace photopose::cli {

// Exit status of every subcommand.
constexpr int kExitSuccess = 0;     // every image solved
constexpr int kExitSomeFailed = 1;  // some image could not be solved (each says why)
constexpr int kExitBadInput = 2;    // bad input or usage

// Flag files may include further flag files down to this depth (the command line is depth 0).
constexpr int kMaxFlagFileDepth = 4;

// The pixel and film conventions, printed in every subcommand's --help.
extern const char kConventionsHelp[];

// The values a numeric flag may take: [min, max], each end excluded when open. Every numeric flag
// of a command has one; a value outside (or not finite) is refused before any work.
struct FlagRange {
  FlagRange(std::string name, double min, double max, bool open_min = false, bool open_max = false,
            std::string unit = "")
      : name(std::move(name)),
        min(min),
        max(max),
        open_min(open_min),
        open_max(open_max),
        unit(std::move(unit)) {}

  std::string name;  // the user's flag name, without dashes
  double min;
  double max;
  bool open_min;     // min itself excluded
  bool open_max;     // max itself excluded
  std::string unit;  // "px", "m", "degrees", or empty

  // "[0, 1000] px", "(0, 1)".
  std::string Text() const;
  // Whether `value` is finite and inside.
  bool Contains(double value) const;
  // "--name=<text> is outside (0, 1000] px" or "--name=<text> is not a finite number; ...".
  std::string Refusal(const std::string& text) const;
};

// How a subcommand's flags are registered. The user writes --<name>; the gflag behind it is
// prefix + name (or the alias's target), defined in the source file `defined_in`.
struct CommandFlags {
  std::string command;     // "resect": messages read "photopose resect: ..."
  std::string defined_in;  // "resect_command": flags defined in this file belong to the command
  std::string prefix;      // "compare_" for compare, empty otherwise
  // User name -> gflag name for the flags registered under another name ("seed" -> "sim_seed").
  std::vector<std::pair<std::string, std::string>> aliases;
  std::vector<FlagRange> ranges;  // one per numeric flag of the command (user names)

  // The range of the user's flag `name`, or nullptr.
  const FlagRange* RangeOf(const std::string& name) const;
};

// What parsing found besides the flag values.
struct ParsedFlags {
  bool help = false;                    // --help, -h, --helpfull
  std::vector<std::string> flag_files;  // every --flagfile read: inputs of the run
};

// Parses --name=value, --name value, --bool_flag, --nobool_flag and --flagfile=F into the gflags of
// `flags`. A flag file holds one flag per line ("--name=value" or "--name value"; blank lines and
// lines starting with '#' skipped) and is read with the limits of every input (core/io/csv.h); it may
// include other flag files down to kMaxFlagFileDepth, never itself (compared by inode). Unknown
// flags, flags of other commands, unparsable values and, once everything is read, numeric values
// outside their FlagRange are reported on stderr as one line ("photopose resect: f.txt:3: unknown
// flag --bogus") and give false: the caller exits with kExitBadInput before any work. gflags never
// sees a flag file.
bool ParseFlags(int argc, char** argv, const CommandFlags& flags, ParsedFlags* parsed);

// The opening of every subcommand's Run*: ParseFlags, then --help answered with PrintHelp(usage).
// Returns the exit status when the run ends here (kExitBadInput after bad flags, kExitSuccess
// after --help), nothing when the command goes on with `parsed`.
std::optional<int> StartCommand(int argc, char** argv, const std::string& usage,
                                const CommandFlags& flags, ParsedFlags* parsed);

// The numeric flags of `flags` (user names) that have no FlagRange: empty when the command is
// complete (a test holds every command to it).
std::vector<std::string> NumericFlagsWithoutRange(const CommandFlags& flags);

// Prints the usage text and the command's flags with their help texts and ranges.
void PrintHelp(const std::string& usage, const CommandFlags& flags);

// Whether the gflag (its internal name: "bundle_jacobian", "loss") was given on the command line
// or in a flag file, whatever its value: a flag the chosen path cannot use is refused only when
// the user gave it, never for its default.
bool FlagGiven(const char* gflag);


// The refusal of an enumerated flag's value, naming the accepted ones from the enum's table
// (core/enum_names.h): "--rotation must be rxryrz (alias seed), opk or pok, not 'x'".
template <typename Enum>
std::string EnumFlagError(const std::string& flag, const std::string& value) {
  return flag + " must be " + EnumChoices<Enum>() + ", not '" + value + "'";
}

// Prints "photopose <subcommand>: <message>" on stderr as one line (control characters and bytes
// that are not UTF-8 escaped) and returns kExitBadInput.
int BadInput(const std::string& subcommand, const std::string& message);

// The phase of the run, for main's guard: an unexpected failure (out of memory, an exception)
// while solving exits kExitSomeFailed, at any other time kExitBadInput.
void SetSolving(bool solving);
int ExitCodeForUnexpectedFailure();

// A progress line on stderr for runs longer than a couple of seconds: the first after
// first_seconds, then every every_seconds, and the last when the run is done (if any was printed):
// "photopose compare: 120 of 400 trials (30%), 7 s, about 16 s left". Thread-safe: the workers of
// a run may call it.
class ProgressLine {
 public:
  // "photopose <command>: ... <items>" on *out (stderr by default; the clock starts here).
  ProgressLine(std::string command, std::string items, std::ostream* out = nullptr,
               double first_seconds = 2.0, double every_seconds = 5.0);
  void operator()(size_t done, size_t total);

 private:
  const std::string command_, items_;
  std::ostream* const out_;
  const double every_seconds_;
  const std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::mutex mutex_;
  double next_seconds_;  // when the next line is due (s since start_)
  bool printed_ = false;
};

// Cancellation by SIGINT (Ctrl-C) and SIGTERM (docs/cli.md, "Cancelling a run"). A command whose
// long steps have progress hooks calls CancelOnSignals() once, before its work: the first SIGINT or
// SIGTERM then only records the signal in a lock-free atomic that the hooks read (CancelRequested)
// and gives both signals back their default action, so that a second one ends the process at once.
// The command stops at the next hook (or at the end of a step without one), writes nothing (no
// output replaced, no temporary left) and returns ReportCancelled(). A command that does not call
// CancelOnSignals keeps the default action: a signal ends it at once. A signal the process started
// with ignored (SIGINT in a script's background job) stays ignored.
void CancelOnSignals();
// Whether a signal asked the run to stop (async-signal-safe, any thread).
bool CancelRequested();
// Prints "photopose <command>: cancelled by SIGINT <when>; nothing written" on stderr (one line;
// `when` may be empty) and returns the exit status of the signal: 128 + its number, 130 for
// SIGINT and 143 for SIGTERM, as a shell reports a process that the signal ended.
int ReportCancelled(const std::string& command, const std::string& when);
// Commits `outputs` unless a signal asked the run to stop, in which case every temporary is
// removed, nothing is written and the status is an error (the caller reports the cancellation).
// A signal that arrives during the renames themselves is too late: the run ends as written.
Status CommitUnlessCancelled(OutputFiles* outputs);
// The exit status of a cancelled run (128 + the signal's number), for tests.
int CancelledExitCode(int signal_number);

// Marks the run as solving for its lifetime.
class ScopedSolving {
 public:
  ScopedSolving() { SetSolving(true); }
  ~ScopedSolving() { SetSolving(false); }
  ScopedSolving(const ScopedSolving&) = delete;
  ScopedSolving& operator=(const ScopedSolving&) = delete;
};

}  // namespace photopose::cli
