// The shared flag handling of the subcommands: ranges, flag files, help.
#include "tools/commands/cli_common.h"

#include <gflags/gflags.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <cstdlib>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "tests/tools/cli_test_util.h"

DEFINE_int32(clitest_count, 1, "A count for the tests of StartCommand.");

namespace photopose::cli {
namespace PHOTOPOSE_UNITY_ID {

using testing::CliRun;
using testing::RunCli;
using testing::ScratchDir;
using testing::SourcePath;
using testing::WriteFile;

TEST(ProgressLineTest, PrintsWhenDueAndTheEndOnlyAfterALine) {
  // Due at once and after every call: a line each, the estimate of what is left in all but the
  // last.
  std::ostringstream every;
  ProgressLine every_call("resect", "images", &every, 0.0, 0.0);
  every_call(1, 4);
  every_call(4, 4);
  const std::string text = every.str();
  EXPECT_EQ(text.rfind("photopose resect: 1 of 4 images (25%), 0 s, about 0 s left\n", 0), 0u)
      << text;
  EXPECT_NE(text.find("\nphotopose resect: 4 of 4 images (100%), 0 s\n"), std::string::npos)
      << text;
  // Never due within the test: no line, and so no last line either.
  std::ostringstream quiet;
  ProgressLine later("compare", "trials", &quiet, 3600.0, 5.0);
  later(1, 2);
  later(2, 2);
  EXPECT_EQ(quiet.str(), "");
}

// Both signals with their default action, as a program started from a terminal has them (a test
// may run where SIGINT is ignored: a script's background job).
void DefaultSignalActions() {
  signal(SIGINT, SIG_DFL);
  signal(SIGTERM, SIG_DFL);
}

// Cancellation by signals, each case in a child process of its own (the handlers and the flag are
// the process's): the first SIGINT or SIGTERM only sets the flag the hooks read; the run reports
// it in one line and exits 128 + the signal; a second signal ends the process by its default
// action; a signal ignored from the start stays ignored.
TEST(CancelTest, TheFirstSignalSetsTheFlagAndTheSecondEndsTheProcess) {
  for (const auto& [signal_number, exit_code, name] :
       {std::tuple<int, int, const char*>{SIGINT, 130, "SIGINT"}, {SIGTERM, 143, "SIGTERM"}}) {
    SCOPED_TRACE(name);
    EXPECT_EQ(CancelledExitCode(signal_number), exit_code);
    EXPECT_EXIT(
        {
          DefaultSignalActions();
          CancelOnSignals();
          if (CancelRequested()) std::_Exit(3);
          raise(signal_number);  // handled: the process goes on
          if (!CancelRequested()) std::_Exit(4);
          std::_Exit(ReportCancelled("bundle", "during the adjustment"));
        },
        ::testing::ExitedWithCode(exit_code),
        std::string("photopose bundle: cancelled by ") + name +
            " during the adjustment; nothing written");
    EXPECT_EXIT(
        {
          DefaultSignalActions();
          CancelOnSignals();
          raise(signal_number);
          raise(signal_number == SIGINT ? SIGTERM : SIGINT);  // the second, either of the two
          std::_Exit(5);
        },
        ::testing::KilledBySignal(signal_number == SIGINT ? SIGTERM : SIGINT), "");
    EXPECT_EXIT(
        {
          DefaultSignalActions();
          signal(signal_number, SIG_IGN);
          CancelOnSignals();
          raise(signal_number);  // ignored: no cancellation
          std::_Exit(CancelRequested() ? 6 : 7);
        },
        ::testing::ExitedWithCode(7), "");
  }
}

// A transaction is committed unless a signal asked the run to stop: then nothing is written and
// no temporary is left.
TEST(CancelTest, CommitUnlessCancelledWritesNothingOnceCancelled) {
  const std::string dir = ScratchDir();
  const std::string path = dir + "/out.csv";
  WriteFile(path, "old\n");
  EXPECT_EXIT(
      {
        DefaultSignalActions();
        CancelOnSignals();
        OutputFiles outputs;
        if (!outputs.AddOutput("--out", path).ok() || !outputs.Stage(path, "new\n").ok())
          std::_Exit(3);
        raise(SIGTERM);
        const Status committed = CommitUnlessCancelled(&outputs);
        std::_Exit(committed.ok() ? 4 : ReportCancelled("resect", "before writing"));
      },
      ::testing::ExitedWithCode(143), "cancelled by SIGTERM before writing; nothing written");
  EXPECT_EQ(testing::ReadFile(path), "old\n");
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    EXPECT_EQ(entry.path().filename().string(), "out.csv") << "left behind: " << entry.path();
  // Without a signal the same transaction is written.
  OutputFiles outputs;
  ASSERT_TRUE(outputs.AddOutput("--out", path).ok());
  ASSERT_TRUE(outputs.Stage(path, "new\n").ok());
  ASSERT_TRUE(CommitUnlessCancelled(&outputs).ok());
  EXPECT_EQ(testing::ReadFile(path), "new\n");
}

TEST(FlagRangeTest, StatesItsEndsAndRefusesWhatLiesOutside) {
  const FlagRange threshold("ransac_threshold", 0.0, 1000.0, true, false, "px");
  EXPECT_EQ(threshold.Text(), "(0, 1000] px");
  EXPECT_FALSE(threshold.Contains(0.0));
  EXPECT_TRUE(threshold.Contains(1e-300));
  EXPECT_TRUE(threshold.Contains(1000.0));
  EXPECT_FALSE(threshold.Contains(std::numeric_limits<double>::infinity()));
  EXPECT_FALSE(threshold.Contains(std::nan("")));
  EXPECT_EQ(threshold.Refusal("1e9"), "--ransac_threshold=1e9 is outside (0, 1000] px");
  EXPECT_EQ(threshold.Refusal("inf"),
            "--ransac_threshold=inf is not a finite number; the range is (0, 1000] px");
  const FlagRange fraction("outlier_fraction", 0.0, 1.0, false, true);
  EXPECT_EQ(fraction.Text(), "[0, 1)");
  EXPECT_TRUE(fraction.Contains(0.0));
  EXPECT_FALSE(fraction.Contains(1.0));
}

// Every numeric flag of every command states a finite range in its --help (and is checked
// against it before any work, see bad_input_catalogue_test.cc).
TEST(CliCommonTest, EveryNumericFlagOfEveryCommandHasARange) {
  const std::string dir = ScratchDir();
  for (const std::string command : {"resect", "simulate", "compare", "bundle"}) {
    const CliRun run = RunCli(command + " --help", dir);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    std::istringstream help(run.out);
    int numeric = 0;
    for (std::string line; std::getline(help, line);) {
      if (line.rfind("  --", 0) != 0) continue;
      std::string description;
      std::getline(help, description);
      const bool is_numeric = line.find("(int32,") != std::string::npos ||
                              line.find("(uint64,") != std::string::npos ||
                              line.find("(double,") != std::string::npos;
      if (!is_numeric) continue;
      ++numeric;
      EXPECT_NE(description.find(" Range: "), std::string::npos) << command << ": " << line;
    }
    EXPECT_GE(numeric, 5) << command;
  }
}

TEST(CliCommonTest, FlagFilesTakeBothFormsCommentsAndNestedFiles) {
  const std::string dir = ScratchDir();
  WriteFile(dir + "/inputs.flags", "# the example\n--cameras " +
                                       SourcePath("examples/cameras.csv") +
                                       "\n\n   --points=" + SourcePath("examples/points.csv") +
                                       "  \r\n--marks=" + SourcePath("examples/marks.csv") + "\n");
  WriteFile(dir + "/run.flags", "--flagfile=" + dir + "/inputs.flags\n--out " + dir +
                                    "/frames.csv\n--norandom_flag_that_is_not_there\n");
  CliRun run = RunCli("resect --flagfile=" + dir + "/run.flags", dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_EQ(run.err, "photopose resect: " + dir +
                         "/run.flags:3: unknown flag --norandom_flag_that_is_not_there (see "
                         "photopose resect --help)\n");
  WriteFile(dir + "/run.flags", "--flagfile=" + dir + "/inputs.flags\n--out " + dir +
                                    "/frames.csv\n--nopixel_center_origin\n");
  run = RunCli("resect --flagfile=" + dir + "/run.flags", dir);
  EXPECT_EQ(run.exit_code, 0) << run.err;
  // The same flag file twice in a row is no cycle.
  run = RunCli("resect --flagfile=" + dir + "/inputs.flags --flagfile=" + dir +
                   "/inputs.flags --out=" + dir + "/frames.csv",
               dir);
  EXPECT_EQ(run.exit_code, 0) << run.err;
  // A flag file is an input: no output may overwrite it.
  run = RunCli("resect --flagfile=" + dir + "/inputs.flags --out=" + dir + "/inputs.flags", dir);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_EQ(run.err, "photopose resect: --out=" + dir +
                         "/inputs.flags is the input --flagfile=" + dir +
                         "/inputs.flags; photopose never writes over an input: choose "
                         "another output file\n");
}

// StartCommand: the opening of every Run*. A command of this file's own flags (defined_in
// "cli_common_test").
const CommandFlags& TestFlags() {
  static const CommandFlags* const kFlags =
      new CommandFlags{"test", "cli_common_test", "clitest_", {}, {{"count", 0.0, 10.0}}};
  return *kFlags;
}

std::optional<int> Start(std::vector<std::string> args, ParsedFlags* parsed) {
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  return StartCommand(static_cast<int>(argv.size()), argv.data(), "usage: photopose test",
                      TestFlags(), parsed);
}

TEST(CliCommonTest, StartCommandParsesAnswersHelpOrRefuses) {
  ParsedFlags parsed;
  ::testing::internal::CaptureStdout();
  ::testing::internal::CaptureStderr();
  const std::optional<int> go_on = Start({"--count=7"}, &parsed);
  EXPECT_FALSE(go_on.has_value());
  EXPECT_EQ(FLAGS_clitest_count, 7);
  EXPECT_FALSE(parsed.help);
  EXPECT_EQ(::testing::internal::GetCapturedStdout(), "");
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");

  ::testing::internal::CaptureStdout();
  const std::optional<int> help = Start({"--count=3", "--help"}, &parsed);
  const std::string help_text = ::testing::internal::GetCapturedStdout();
  ASSERT_TRUE(help.has_value());
  EXPECT_EQ(*help, kExitSuccess);
  EXPECT_EQ(help_text.rfind("usage: photopose test\n", 0), 0u) << help_text;
  EXPECT_NE(help_text.find("  --count (int32, default: \"1\")"), std::string::npos) << help_text;

  ::testing::internal::CaptureStdout();
  ::testing::internal::CaptureStderr();
  const std::optional<int> refused = Start({"--count=11"}, &parsed);
  EXPECT_EQ(::testing::internal::GetCapturedStdout(), "");
  EXPECT_EQ(::testing::internal::GetCapturedStderr(),
            "photopose test: --count=11 is outside [0, 10]\n");
  ASSERT_TRUE(refused.has_value());
  EXPECT_EQ(*refused, kExitBadInput);
  FLAGS_clitest_count = 1;
}

TEST(CliCommonTest, LoggingFlagsOfTheLibrariesAreNotTheCommandsFlags) {
  // glog's flags would write log files outside the run's outputs; gflags' would read flags from
  // the environment. Neither is a photopose flag.
  const std::string dir = ScratchDir();
  for (const std::string flag : {"--logtostderr=false", "--log_dir=/tmp", "--fromenv=cameras"}) {
    const CliRun run = RunCli("simulate --out_dir=" + dir + "/sim " + flag, dir);
    EXPECT_EQ(run.exit_code, 2) << flag;
    EXPECT_EQ(run.err.rfind("photopose simulate: unknown flag --", 0), 0u) << run.err;
  }
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose::cli
