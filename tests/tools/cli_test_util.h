#pragma once
// Runs the photopose executable for end-to-end tests and gives a scratch folder per test.

#include <gtest/gtest.h>

#include "tests/support/temp_dir.h"
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
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
