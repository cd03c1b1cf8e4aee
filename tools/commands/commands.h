#pragma once
// The photopose subcommands. Each parses its own flags (argv without the program and command
// names) and returns the process exit status (tools/commands/cli_common.h).

namespace photopose::cli {

int RunResect(int argc, char** argv);
int RunSimulate(int argc, char** argv);
int RunCompare(int argc, char** argv);
int RunBundle(int argc, char** argv);

}  // namespace photopose::cli
