#pragma once
// Runs the photopose executable for end-to-end tests and gives a scratch folder per test.

#include <gtest/gtest.h>

#include "tests/support/temp_dir.h"
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "core/io/tables.h"
#include "core/rotation.h"
#include "test_data.h"

namespace photopose::testing {

struct CliRun {
  int exit_code = -1;
  std::string out;
  std::string err;
};

inline std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Each group of a `bundle --report` by name: the first axis of its stated accuracy, in the
// group's unit (a prior group's X).
inline std::map<std::string, double> StatedAccuracies(const std::string& report_path) {
  std::map<std::string, double> stated;
  const nlohmann::json report = nlohmann::json::parse(ReadFile(report_path));
  for (const nlohmann::json& group : report.at("groups")) {
    const nlohmann::json& a = group.at("stated_accuracy");
    stated[group.at("name").get<std::string>()] =
        a.is_array() ? a[0].get<double>() : a.get<double>();
  }
  return stated;
}

inline void WriteFile(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
}

// How RunCliWith runs the executable.
struct CliOptions {
  std::string working_dir;  // where it runs (empty: the test's own)
  std::string standard_input = "/dev/null";
  int timeout_seconds = 240;  // a hang is killed and reported as exit code -1
};

// Runs `photopose <arguments>` through the shell; stdout and stderr go to files in `dir`. A run
// that ends on a signal (a crash, or killed by the timeout) has exit_code -1.
inline CliRun RunCliWith(const std::string& arguments, const std::string& dir,
                         const CliOptions& options) {
  const std::string out = dir + "/cli_stdout.txt", err = dir + "/cli_stderr.txt";
  std::string command = "timeout -s KILL " + std::to_string(options.timeout_seconds) + " " +
                        CliPath() + " " + arguments + " >'" + out + "' 2>'" + err + "' <'" +
                        options.standard_input + "'";
  if (!options.working_dir.empty()) command = "cd '" + options.working_dir + "' && " + command;
  const int status = std::system(command.c_str());
  CliRun run;
  // timeout reports a killed child as 128 + 9; the shell reports a signal as 128 + n.
  run.exit_code = WIFEXITED(status) && WEXITSTATUS(status) < 128 ? WEXITSTATUS(status) : -1;
  run.out = ReadFile(out);
  run.err = ReadFile(err);
  return run;
}

inline CliRun RunCli(const std::string& arguments, const std::string& dir) {
  return RunCliWith(arguments, dir, CliOptions());
}

// The executable run in the background, for tests that signal it while it works: stdin from
// /dev/null, stdout to dir/cli_stdout.txt, stderr read through a pipe as it comes.
class BackgroundCli {
 public:
  BackgroundCli(const std::vector<std::string>& arguments, const std::string& dir) {
    int pipe_fds[2];
    if (pipe(pipe_fds) != 0) return;
    const std::string cli = CliPath(), out = dir + "/cli_stdout.txt";
    std::vector<std::string> args = {cli};
    args.insert(args.end(), arguments.begin(), arguments.end());
    std::vector<char*> argv;
    for (std::string& arg : args) argv.push_back(arg.data());
    argv.push_back(nullptr);
    pid_ = fork();
    if (pid_ == 0) {
      const int in = open("/dev/null", O_RDONLY);
      const int stdout_fd = open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (in < 0 || stdout_fd < 0) _exit(127);
      dup2(in, 0);
      dup2(stdout_fd, 1);
      dup2(pipe_fds[1], 2);
      close(pipe_fds[0]);
      // As from a terminal: the test may run where SIGINT is ignored (a script's background job),
      // which the executable would inherit and keep.
      signal(SIGINT, SIG_DFL);
      signal(SIGTERM, SIG_DFL);
      execv(cli.c_str(), argv.data());
      _exit(127);
    }
    close(pipe_fds[1]);
    err_fd_ = pipe_fds[0];
  }
  BackgroundCli(const BackgroundCli&) = delete;
  BackgroundCli& operator=(const BackgroundCli&) = delete;
  ~BackgroundCli() {
    if (pid_ > 0 && !reaped_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
    if (err_fd_ >= 0) close(err_fd_);
  }

  bool started() const { return pid_ > 0 && err_fd_ >= 0; }
  // stderr as read so far.
  const std::string& err() const { return err_; }

  // Reads stderr until a complete line containing `text` has arrived (true), or stderr ends or
  // `timeout_seconds` pass (false).
  bool WaitForLine(const std::string& text, int timeout_seconds) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(timeout_seconds);
    for (;;) {
      for (size_t at = err_.find(text); at != std::string::npos; at = err_.find(text, at + 1))
        if (err_.find('\n', at) != std::string::npos) return true;
      if (!ReadSome(end)) return false;
    }
  }

  void Signal(int signal_number) { kill(pid_, signal_number); }

  // Reads the rest of stderr and reaps the process; after `timeout_seconds` it is killed
  // (SIGKILL). Returns the wait status.
  int Wait(int timeout_seconds) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(timeout_seconds);
    while (ReadSome(end)) {
    }
    if (std::chrono::steady_clock::now() >= end) kill(pid_, SIGKILL);
    int status = 0;
    waitpid(pid_, &status, 0);
    reaped_ = true;
    return status;
  }

 private:
  // One read of stderr, waiting until `end`; false at its end or at the timeout.
  bool ReadSome(std::chrono::steady_clock::time_point end) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        end - std::chrono::steady_clock::now());
    if (left.count() <= 0) return false;
    pollfd poll_fd = {err_fd_, POLLIN, 0};
    if (poll(&poll_fd, 1, static_cast<int>(left.count())) <= 0) return false;
    char buffer[4096];
    const ssize_t n = read(err_fd_, buffer, sizeof(buffer));
    if (n <= 0) return false;
    err_.append(buffer, static_cast<size_t>(n));
    return true;
  }

  pid_t pid_ = -1;
  int err_fd_ = -1;
  bool reaped_ = false;
  std::string err_;
};

// Runs `photopose <arguments>` in the background, sends it `signal_number` once a complete stderr
// line containing `line` has come, and waits for its end (killed after `timeout_seconds` of either
// wait). exit_code is -1 unless it exited (a crash, a signal's default action, never started);
// a run that never printed `line` fails the test.
inline CliRun RunCliAndSignal(const std::vector<std::string>& arguments, const std::string& dir,
                              const std::string& line, int signal_number,
                              int timeout_seconds = 120) {
  BackgroundCli background(arguments, dir);
  CliRun run;
  if (!background.started()) {
    ADD_FAILURE() << "photopose did not start";
    return run;
  }
  if (background.WaitForLine(line, timeout_seconds)) {
    background.Signal(signal_number);
  } else {
    ADD_FAILURE() << "no line '" << line << "' on stderr";
  }
  const int status = background.Wait(timeout_seconds);
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  run.out = ReadFile(dir + "/cli_stdout.txt");
  run.err = background.err();
  return run;
}

// The first line of a text (without its line end).
inline std::string FirstLine(const std::string& text) { return text.substr(0, text.find('\n')); }

// A fresh, empty folder for one test.
inline std::string ScratchDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::filesystem::path dir = testing::ScratchRoot() /
                                    (std::string(info->test_suite_name()) + "." + info->name());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

// A frames table the executable wrote, by raster; a read error fails the test.
// The bundled example's marks with Row counted up from the bottom edge, Row' = NRows - Row (NRows
// 3648), written as dir/marks_up.csv; and as dir/marks_down.csv with Row = NRows - Row' again, as
// the reader counts them down (within an ulp of the example's Row, so that a run on either file
// sees the same numbers). Returns the path of marks_down.csv.
inline std::string WriteExampleMarksWithRowsUp(const std::string& dir) {
  constexpr double kExampleRows = 3648.0;  // examples/cameras.csv NRows
  std::vector<ImageMark> marks;
  EXPECT_TRUE(ReadImageMarks(SourcePath("examples/marks.csv"), &marks).ok());
  for (ImageMark& mark : marks) mark.column_row->y() = kExampleRows - mark.column_row->y();
  EXPECT_TRUE(WriteImageMarks(dir + "/marks_up.csv", marks).ok());
  for (ImageMark& mark : marks) mark.column_row->y() = kExampleRows - mark.column_row->y();
  EXPECT_TRUE(WriteImageMarks(dir + "/marks_down.csv", marks).ok());
  return dir + "/marks_down.csv";
}

inline std::map<std::string, FrameRecord> ReadFrames(
    const std::string& path, RotationConvention convention = RotationConvention::kSeed) {
  std::vector<FrameRecord> frames;
  FramesTableOptions options;
  options.convention = convention;
  const Status status = ReadFramesTable(path, options, &frames);
  EXPECT_TRUE(status.ok()) << status.message();
  std::map<std::string, FrameRecord> by_raster;
  for (FrameRecord& frame : frames) by_raster[frame.raster] = std::move(frame);
  return by_raster;
}

inline int CountLines(const std::string& text) {
  int lines = 0;
  for (char c : text) lines += c == '\n';
  return lines;
}

// The rows of a CSV text, split at line ends and commas: the tables and results the executable
// writes in these tests quote nothing. "a,,b," is {"a", "", "b", ""}; an empty line is {""}.
inline std::vector<std::vector<std::string>> SplitCsvText(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    std::vector<std::string> cells;
    size_t start = 0;
    for (size_t comma; (comma = line.find(',', start)) != std::string::npos; start = comma + 1)
      cells.push_back(line.substr(start, comma - start));
    cells.push_back(line.substr(start));
    rows.push_back(std::move(cells));
  }
  return rows;
}

}  // namespace photopose::testing
