#pragma once
// Shared plumbing of the photopose subcommands: exit codes, flag parsing that never exits on its
// own, and one-line error reporting.

#include <string>

#include "core/status.h"

namespace photopose::cli {

// Exit status of every subcommand.
constexpr int kExitSuccess = 0;        // every image solved
constexpr int kExitSomeFailed = 1;     // some image could not be solved (each says why)
constexpr int kExitBadInput = 2;       // bad input or usage

// The pixel and film conventions, printed in every subcommand's --help.
extern const char kConventionsHelp[];

// Parses --name=value / --name value / --bool_flag / --noflag and --flagfile=F into the gflags
// registered by the subcommand. Unknown flags and unparsable values are reported on stderr as one
// line and give false (the caller exits with kExitBadInput). Sets *help_requested for --help.
bool ParseFlags(int argc, char** argv, const std::string& subcommand, bool* help_requested);

// Prints the usage text and the subcommand's flags (those defined in `flags_file`, e.g.
// "resect_command") with their help texts.
void PrintHelp(const std::string& usage, const std::string& flags_file);

// Refuses, before any work, an output path whose folder does not exist or is not a folder:
// "<flag>: folder '<dir>' does not exist". An empty path is fine (the output is not asked for).
Status CheckOutputFolder(const std::string& flag, const std::string& path);

// Prints "photopose <subcommand>: <message>" on stderr and returns kExitBadInput.
int BadInput(const std::string& subcommand, const std::string& message);

}  // namespace photopose::cli
