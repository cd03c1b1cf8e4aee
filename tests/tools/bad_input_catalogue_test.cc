// The bad-input catalogue of issue 9: one test per case of a careless or hostile user, each run
// through the executable. Every test checks the exit status, the first line of the message, that
// the inputs are unchanged and that no output or temporary file is left behind (or, where the run
// succeeds, exactly the expected outputs). Two cases of the issue belong to the resection rules and
// are tested there: points mirrored behind the camera, and ApplyECC.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "tests/test_devices.h"
#include "tests/tools/cli_test_util.h"
#include "tools/compare/comparison.h"

// AddressSanitizer builds (gcc and clang spell it differently).
#if defined(__SANITIZE_ADDRESS__)
#define PHOTOPOSE_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define PHOTOPOSE_TEST_ASAN 1
#endif
#endif

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

namespace fs = std::filesystem;
using testing::CliOptions;
using testing::CliRun;
using testing::FirstLine;
using testing::ReadFile;
using testing::RunCliWith;
using testing::ScratchDir;
using testing::SourcePath;
using testing::WriteFile;

// Everything under a folder: relative path -> kind and contents (symlink target, file bytes).
using Snapshot = std::map<std::string, std::string>;

Snapshot Take(const std::string& folder) {
  Snapshot snapshot;
  for (const auto& entry : fs::recursive_directory_iterator(folder)) {
    const std::string name = entry.path().lexically_relative(folder).string();
    struct stat info;
    lstat(entry.path().c_str(), &info);
    if (S_ISLNK(info.st_mode)) {
      snapshot[name] = "symlink:" + fs::read_symlink(entry.path()).string();
    } else if (S_ISREG(info.st_mode)) {
      snapshot[name] = "file:" + ReadFile(entry.path().string());
    } else if (S_ISDIR(info.st_mode)) {
      snapshot[name] = "folder";
    } else {
      snapshot[name] = "special";
    }
  }
  return snapshot;
}

// Names in `after` that are not in `before`, and names of photopose's temporaries.
std::vector<std::string> NewEntries(const Snapshot& before, const Snapshot& after) {
  std::vector<std::string> added;
  for (const auto& [name, contents] : after)
    if (before.count(name) == 0 || name.find(".photopose-") != std::string::npos)
      added.push_back(name);
  return added;
}

bool IsCleanOneLine(const std::string& text) {
  // One message line: no control character but its line end, nothing that is not UTF-8.
  if (text.empty() || text.back() != '\n') return false;
  for (size_t i = 0; i + 1 < text.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c < 0x20 || c == 0x7F) return false;
  }
  return true;
}

class BadInputCatalogue : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = ScratchDir();
    work_ = root_ + "/work";
    fs::create_directories(work_);
    fs::create_directories(root_ + "/devices");
    for (const char* name : {"cameras.csv", "points.csv", "marks.csv"})
      fs::copy_file(SourcePath("examples/") + name, work_ + "/" + name);
  }

  // Runs photopose in the work folder, with input paths relative to it.
  CliRun Run(const std::string& arguments, const std::string& standard_input = "/dev/null") {
    CliOptions options;
    options.working_dir = work_;
    options.standard_input = standard_input;
    return RunCliWith(arguments, root_, options);
  }

  // Runs a command that must be refused: exit status and first line as expected, one clean line,
  // and the work folder exactly as before (inputs unchanged, no output, no temporary).
  void ExpectRefused(const std::string& arguments, int exit_code, const std::string& first_line,
                     const std::string& standard_input = "/dev/null") {
    const Snapshot before = Take(work_);
    const CliRun run = Run(arguments, standard_input);
    EXPECT_EQ(run.exit_code, exit_code) << arguments << "\n" << run.err;
    EXPECT_EQ(FirstLine(run.err), first_line) << arguments;
    EXPECT_TRUE(IsCleanOneLine(run.err)) << run.err;
    EXPECT_EQ(Take(work_), before) << arguments << ": the work folder changed";
  }

  std::string Resect(const std::string& more) {
    return "resect --cameras=cameras.csv --points=points.csv --marks=marks.csv " + more;
  }

  // Replaces line `line` (1-based) of a work file.
  void ReplaceLine(const std::string& name, int line, const std::string& text) {
    std::string contents = ReadFile(work_ + "/" + name);
    size_t start = 0;
    for (int i = 1; i < line; ++i) start = contents.find('\n', start) + 1;
    contents.replace(start, contents.find('\n', start) - start, text);
    WriteFile(work_ + "/" + name, contents);
  }

  std::string root_;
  std::string work_;
};

// ------------------------------------------------------------------ outputs

TEST_F(BadInputCatalogue, AnOutputThatIsAnInputIsRefusedBeforeAnyWork) {
  ExpectRefused(Resect("--out=marks.csv"), 2,
                "photopose resect: --out=marks.csv is the input --marks=marks.csv; photopose "
                "never writes over an input: choose another output file");
  ExpectRefused(Resect("--out=frames.csv --report=points.csv"), 2,
                "photopose resect: --report=points.csv is the input --points=points.csv; "
                "photopose never writes over an input: choose another output file");
  ExpectRefused(Resect("--out=./sub/../cameras.csv"), 2,
                "photopose resect: --out=./sub/../cameras.csv: the folder './sub/..' does not "
                "exist");
  fs::create_symlink("marks.csv", work_ + "/alias.csv");
  ExpectRefused(Resect("--out=alias.csv"), 2,
                "photopose resect: --out=alias.csv is the input --marks=marks.csv; photopose "
                "never writes over an input: choose another output file");
  ExpectRefused(
      "compare --cameras=cameras.csv --points=points.csv --marks=marks.csv "
      "--csv=points.csv",
      2,
      "photopose compare: --csv=points.csv is the input --points=points.csv; photopose "
      "never writes over an input: choose another output file");
}

TEST_F(BadInputCatalogue, TwoOutputsInOneFileAreRefused) {
  ExpectRefused(Resect("--out=x.csv --report=x.csv"), 2,
                "photopose resect: --report=x.csv is the same file as --out=x.csv; every output "
                "needs a file of its own");
  WriteFile(work_ + "/x.csv", "previous frames\n");
  ExpectRefused(Resect("--out=x.csv --report=./x.csv"), 2,
                "photopose resect: --report=./x.csv is the same file as --out=x.csv; every output "
                "needs a file of its own");
  // 'block' is a scenario of its own kind: named with others it is explained, not "unknown".
  ExpectRefused("compare --trials=1 --scenarios=block,nadir --csv=r.csv", 2,
                "photopose compare: --scenarios: 'block' compares the block solvers and runs alone "
                "(--scenarios=block); the single-image scenarios (" + std::string(EnumChoices<Scenario>()) +
                ") go in another run");
  ExpectRefused("compare --trials=1 --scenarios=nadir --csv=r.txt --markdown=r.txt", 2,
                "photopose compare: --markdown=r.txt is the same file as --csv=r.txt; every output "
                "needs a file of its own");
}

TEST_F(BadInputCatalogue, AnUnwritableReportLeavesTheOtherOutputUntouched) {
  WriteFile(work_ + "/frames.csv", "previous frames\n");
  // A missing folder is found before any work.
  ExpectRefused(Resect("--out=frames.csv --report=missing/report.json"), 2,
                "photopose resect: --report=missing/report.json: the folder 'missing' does not "
                "exist");
  // A full disk is found while writing: nothing has been replaced yet.
  const std::string full = testing::TestDevice(root_ + "/devices", "full");
  if (full.empty()) GTEST_SKIP() << "root cannot make a private device node here";
  ExpectRefused(Resect("--out=frames.csv --report=" + full), 2,
                "photopose resect: --report=" + full + ": cannot write: No space left on device");
  // compare finds it after its trials: a slow run (a sanitizer build) has printed progress lines
  // before it, so the error is the last line, not the only one.
  const Snapshot before = Take(work_);
  const CliRun run = Run("compare --trials=1 --scenarios=nadir --csv=r.csv --html=" + full);
  EXPECT_EQ(run.exit_code, 2) << run.err;
  std::string err = run.err;
  while (!err.empty() && err.back() == '\n') err.pop_back();
  EXPECT_EQ(err.substr(err.rfind('\n') + 1),
            "photopose compare: --html=" + full + ": cannot write: No space left on device")
      << run.err;
  for (size_t start = 0, end; start < err.size(); start = end + 1) {
    end = std::min(err.find('\n', start), err.size());
    const std::string line = err.substr(start, end - start);
    if (end < err.size())  // every line before the error is a progress line
      EXPECT_EQ(line.rfind("photopose compare: ", 0), 0u) << line;
  }
  EXPECT_EQ(Take(work_), before) << "the work folder changed";
}

TEST_F(BadInputCatalogue, DevicesFifosAndSymlinksAreWrittenThroughNeverReplaced) {
  // A device: written in place.
  const std::string null = testing::TestDevice(root_ + "/devices", "null");
  CliRun run;
  struct stat info;
  if (!null.empty()) {
    run = Run(Resect("--out=" + null + " --report=" + null));
    EXPECT_EQ(run.exit_code, 0) << run.err;
    ASSERT_EQ(stat(null.c_str(), &info), 0);
    EXPECT_TRUE(S_ISCHR(info.st_mode));
  }
  // Standard output: the frames follow the lines the run printed.
  for (const std::string stdout_path : {"/dev/fd/1", "/dev/stdout"}) {
    if (stdout_path == "/dev/stdout" && !testing::MayWriteDevStdout()) continue;
    run = Run(Resect("--out=" + stdout_path));
    EXPECT_EQ(run.exit_code, 0) << run.err;
    EXPECT_NE(run.out.find("img_0012: X="), std::string::npos);
    EXPECT_GT(run.out.find("Raster,CameraID,PerspectiveX"), run.out.find("img_0012: X="));
  }
  // A symlink: the file it names is replaced, the link stays.
  WriteFile(work_ + "/target.csv", "previous frames\n");
  fs::create_symlink("target.csv", work_ + "/link.csv");
  run = Run(Resect("--out=link.csv"));
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(fs::is_symlink(work_ + "/link.csv"));
  EXPECT_EQ(FirstLine(ReadFile(work_ + "/target.csv")).rfind("Raster,CameraID", 0), 0u);
  // A FIFO that nobody reads: an error, not a hang.
  const std::string fifo = work_ + "/fifo";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0644), 0);
  ExpectRefused(Resect("--out=fifo"), 2,
                "photopose resect: --out=fifo: no process is reading the FIFO");
  // A FIFO with a reader receives the table and stays a FIFO.
  std::string received;
  std::thread reader([&] { received = ReadFile(fifo); });
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  run = Run(Resect("--out=fifo"));
  if (run.exit_code != 0) close(open(fifo.c_str(), O_WRONLY | O_NONBLOCK));  // free the reader
  reader.join();
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(FirstLine(received).rfind("Raster,CameraID", 0), 0u);
  ASSERT_EQ(lstat(fifo.c_str(), &info), 0);
  EXPECT_TRUE(S_ISFIFO(info.st_mode));
  // Nothing else was written.
  const Snapshot after = Take(work_);
  EXPECT_EQ(after.size(), 6u) << "cameras, points, marks, target, link, fifo";
}

// ------------------------------------------------------------------ flags

TEST_F(BadInputCatalogue, AFlagFileThatIncludesItselfIsRefusedBeforeGflagsSeesIt) {
  WriteFile(work_ + "/self.flags", "--flagfile=self.flags\n");
  ExpectRefused("resect --flagfile=self.flags", 2,
                "photopose resect: self.flags:1: --flagfile=self.flags: the flag file includes "
                "itself (self.flags -> self.flags); a flag file may not read itself again");
  WriteFile(work_ + "/a.flags", "# a cycle through a second file\n--flagfile b.flags\n");
  WriteFile(work_ + "/b.flags", "--out=frames.csv\n--flagfile=./a.flags\n");
  ExpectRefused("resect --flagfile=a.flags", 2,
                "photopose resect: b.flags:2: --flagfile=./a.flags: the flag file includes itself "
                "(a.flags -> b.flags -> ./a.flags); a flag file may not read itself again");
  for (int level = 1; level <= 5; ++level)
    WriteFile(work_ + "/d" + std::to_string(level) + ".flags",
              "--flagfile=d" + std::to_string(level + 1) + ".flags\n");
  WriteFile(work_ + "/d5.flags", "--threads=1\n");
  ExpectRefused("resect --flagfile=d1.flags", 2,
                "photopose resect: d4.flags:1: --flagfile=d5.flags: flag files nest deeper than 4 "
                "levels (d1.flags -> d2.flags -> d3.flags -> d4.flags -> d5.flags)");
  ExpectRefused("simulate --flagfile=/dev/zero --out_dir=sim", 2,
                "photopose simulate: /dev/zero: is a character device, not a regular file; "
                "photopose reads regular files, or standard input for '-'");
}

TEST_F(BadInputCatalogue, AnUnknownFlagInsideAFlagFileIsRefused) {
  WriteFile(work_ + "/extra.flags", "--out=frames.csv\n--bogus=1\n");
  ExpectRefused(Resect("--flagfile=extra.flags"), 2,
                "photopose resect: extra.flags:2: unknown flag --bogus (see photopose resect "
                "--help)");
  WriteFile(work_ + "/other.flags", "--noise_px 3\n");
  ExpectRefused(Resect("--out=frames.csv --flagfile=other.flags"), 2,
                "photopose resect: other.flags:1: unknown flag --noise_px (see photopose resect "
                "--help)");
  WriteFile(work_ + "/compare.flags", "--trials=2\n--csv_file=r.csv\n");
  ExpectRefused("compare --flagfile=compare.flags", 2,
                "photopose compare: compare.flags:2: unknown flag --csv_file (see photopose "
                "compare --help)");
  WriteFile(work_ + "/prose.flags", "trials=2\n");
  ExpectRefused("compare --flagfile=prose.flags", 2,
                "photopose compare: prose.flags:1: 'trials=2' is not a flag (a flag file holds "
                "one --name=value per line)");
}

TEST_F(BadInputCatalogue, NumericFlagsOutsideTheirRangeAreBadUsageBeforeAnyWork) {
  ExpectRefused(Resect("--out=frames.csv --confidence=inf"), 2,
                "photopose resect: --confidence=inf is not a finite number; the range is "
                "[0.5, 1)");
  ExpectRefused(Resect("--out=frames.csv --loss_scale=nan"), 2,
                "photopose resect: --loss_scale=nan is not a finite number; the range is (0, "
                "1000] standard deviations");
  ExpectRefused(Resect("--out=frames.csv --confidence=1"), 2,
                "photopose resect: --confidence=1 is outside [0.5, 1)");
  ExpectRefused(Resect("--out=frames.csv --threads=100000"), 2,
                "photopose resect: --threads=100000 is outside [0, 1024]");
  ExpectRefused("compare --trials=10 --success_sigmas=-inf", 2,
                "photopose compare: --success_sigmas=-inf is not a finite number; the range is "
                "(0, 1000000]");
  ExpectRefused("simulate --outlier_fraction=1 --out_dir=sim", 2,
                "photopose simulate: --outlier_fraction=1 is outside [0, 1)");
}

TEST_F(BadInputCatalogue, HugeCountsAreRefusedNotAllocated) {
  ExpectRefused("compare --trials=1e9", 2,
                "photopose compare: invalid value '1e9' for --trials (int32 expected)");
  ExpectRefused("compare --trials=1000000000", 2,
                "photopose compare: --trials=1000000000 is outside [1, 100000]");
  ExpectRefused("simulate --control_points=1e8 --out_dir=sim", 2,
                "photopose simulate: invalid value '1e8' for --control_points (int32 expected)");
  ExpectRefused("simulate --control_points=100000000 --out_dir=sim", 2,
                "photopose simulate: --control_points=100000000 is outside [0, 10000]");
  // A grid of long lists: counted in 64 bits, never built.
  std::string list = "1";
  for (int i = 2; i <= 100; ++i) list += "," + std::to_string(i);
  ExpectRefused("compare --sweep=grid --trials=100000 --noise_px=" + list +
                    " --control_points=" + list.substr(list.find(",3") + 1) +
                    " --outlier_fractions=0 --initial_errors=5:2",
                2,
                "photopose compare: the sweep asks for 11760000000 solves (19600 settings x "
                "100000 trials x 6 solvers); at most 10000000 per run");
}

TEST_F(BadInputCatalogue, SimulateWithTheLargestIntIsRefusedWithoutOverflow) {
  ExpectRefused("simulate --control_points=2147483647 --out_dir=sim", 2,
                "photopose simulate: --control_points=2147483647 is outside [0, 10000]");
  ExpectRefused("simulate --control_points=10000 --check_points=2147483647 --out_dir=sim", 2,
                "photopose simulate: --check_points=2147483647 is outside [0, 10000]");
}

TEST_F(BadInputCatalogue, SimulateThatFailsLeavesThePreviousDatasetWhole) {
  CliRun run = Run("simulate --scenario=nadir --seed=3 --out_dir=sim");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  ExpectRefused("simulate --scenario=nadir --noise_px=1e308 --out_dir=sim", 2,
                "photopose simulate: --noise_px=1e+308 is outside [0, 1000] px");
  // A folder that cannot be replaced as a whole is refused before any work.
  fs::create_directory(work_ + "/sim/keep");
  ExpectRefused("simulate --scenario=nadir --seed=4 --out_dir=sim", 2,
                "photopose simulate: --out_dir=sim: holds the folder 'keep'; photopose replaces "
                "the output folder as a whole and carries over files only: give a folder of its "
                "own to the dataset");
}

TEST_F(BadInputCatalogue, KillDuringSimulateLeavesTheOldOrTheNewDatasetNeverAMix) {
  const std::string common =
      "simulate --scenario=uav_block --control_points=2000 --check_points=0 --noise_px=0.5 ";
  // The two complete datasets, made apart for comparison.
  ASSERT_EQ(Run(common + "--seed=1 --out_dir=../seed1").exit_code, 0);
  const auto started = std::chrono::steady_clock::now();
  ASSERT_EQ(Run(common + "--seed=2 --out_dir=../seed2").exit_code, 0);
  const double run_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started).count();
  const Snapshot datasets[2] = {Take(root_ + "/seed1"), Take(root_ + "/seed2")};
  ASSERT_NE(datasets[0], datasets[1]);
  fs::copy(root_ + "/seed1", work_ + "/data", fs::copy_options::recursive);

  int current = 0, killed_mid_run = 0;
  for (int k = 0; k < 12; ++k) {
    const int next = 1 - current;
    const std::string seed = "--seed=" + std::to_string(next + 1);
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      if (chdir(work_.c_str()) != 0) _exit(99);
      const int null = open("/dev/null", O_RDWR);
      dup2(null, 1);
      dup2(null, 2);
      const std::string cli = testing::CliPath();
      execl(cli.c_str(), cli.c_str(), "simulate", "--scenario=uav_block", "--control_points=2000",
            "--check_points=0", "--noise_px=0.5", seed.c_str(), "--out_dir=data",
            static_cast<char*>(nullptr));
      _exit(98);
    }
    // Kill at a different moment of the run each time, from the start to its end.
    std::this_thread::sleep_for(
        std::chrono::microseconds(static_cast<int64_t>(run_ms * 1000.0 * k / 11.0)));
    kill(child, SIGKILL);
    int status = 0;
    waitpid(child, &status, 0);
    killed_mid_run += WIFSIGNALED(status);
    const Snapshot now = Take(work_ + "/data");
    ASSERT_TRUE(now == datasets[current] || now == datasets[next])
        << "kill after " << run_ms * k / 11.0 << " ms left a mixed dataset";
    if (now == datasets[next]) current = next;
  }
  EXPECT_GT(killed_mid_run, 0);
  // A complete run removes what the killed ones left beside the folder.
  ASSERT_EQ(Run(common + "--seed=1 --out_dir=data").exit_code, 0);
  EXPECT_EQ(Take(work_ + "/data"), datasets[0]);
  for (const auto& entry : fs::directory_iterator(work_))
    EXPECT_EQ(entry.path().filename().string().find(".photopose-"), std::string::npos)
        << entry.path();
}

// ------------------------------------------------------------------ inputs

TEST_F(BadInputCatalogue, EndlessOrSpecialInputsAreRefusedNotRead) {
  ExpectRefused(Resect("--points=/dev/zero --out=frames.csv"), 2,
                "photopose resect: /dev/zero: is a character device, not a regular file; "
                "photopose reads regular files, or standard input for '-'");
  ExpectRefused(Resect("--points=- --out=frames.csv"), 2,
                "photopose resect: <stdin>: is larger than 268435456 bytes, the largest input "
                "photopose reads",
                "/dev/zero");
  ExpectRefused(Resect("--points=. --out=frames.csv"), 2,
                "photopose resect: .: is a folder, not a regular file; photopose reads regular "
                "files, or standard input for '-'");
  // Standard input is a documented input.
  const CliRun run = Run(Resect("--points=- --out=frames.csv"), work_ + "/points.csv");
  EXPECT_EQ(run.exit_code, 0) << run.err;
}

TEST_F(BadInputCatalogue, AbsurdlyWideHeadersAreRefusedAtOnce) {
  std::string header;
  for (int i = 0; i < 100000; ++i) header += (i ? ",C" : "C") + std::to_string(i);
  WriteFile(work_ + "/wide.csv", header + "\n");
  ExpectRefused(Resect("--points=wide.csv --out=frames.csv"), 2,
                "photopose resect: wide.csv:1: the line is longer than 65536 bytes, the longest "
                "line photopose reads");
  header.resize(header.find(",C5000"));
  WriteFile(work_ + "/wide.csv", header + "\n");
  ExpectRefused(Resect("--points=wide.csv --out=frames.csv"), 2,
                "photopose resect: wide.csv:1: the header has more than 1000 fields; photopose "
                "reads at most 1000 columns");
}

TEST_F(BadInputCatalogue, CoordinatesBeyondAHundredThousandKilometresAreRefusedAtTheirLine) {
  ReplaceLine("points.csv", 3, "P0002,1e308,4099988.12000357,33.70307312975029,,,,control");
  ExpectRefused(Resect("--out=frames.csv"), 2,
                "photopose resect: points.csv:3: X: '1e308' is outside [-100000000, 100000000] m");
  fs::copy_file(SourcePath("examples/points.csv"), work_ + "/points.csv",
                fs::copy_options::overwrite_existing);
  ReplaceLine("marks.csv", 2, "img_0001,P0001,279.1,-1e308,,,0.5,UAV_8.8mm");
  ExpectRefused(Resect("--out=frames.csv"), 2,
                "photopose resect: marks.csv:2: Row: '-1e308' is outside [-100000000, 100000000] "
                "px");
}

TEST_F(BadInputCatalogue, BinaryBytesAreNamedEscapedNeverEchoed) {
  std::string points = ReadFile(work_ + "/points.csv");
  points.replace(points.find("P0003"), 5, std::string("P\0\x1b[2J", 6));
  WriteFile(work_ + "/points.csv", points);
  ExpectRefused(Resect("--out=frames.csv"), 2,
                "photopose resect: points.csv:4: character 2: NUL byte: photopose reads UTF-8 text "
                "(is this a binary file, or UTF-16 without a byte order mark?)");
  points.replace(points.find(std::string("P\0", 2)), 2, "P\xff\xfe");
  WriteFile(work_ + "/points.csv", points);
  ExpectRefused(Resect("--out=frames.csv"), 2,
                "photopose resect: points.csv:4: character 2: byte 0xFF is not UTF-8; photopose "
                "reads UTF-8 text");
  points.replace(points.find("P\xff\xfe"), 3, "P");
  WriteFile(work_ + "/points.csv", points);
  ExpectRefused(Resect("--out=frames.csv"), 2,
                "photopose resect: points.csv:4: character 2: control character 0x1B: photopose "
                "reads plain UTF-8 text");
  // Bytes on the command line are escaped too.
  ExpectRefused(Resect("--out=frames.csv --rotation=\"$(printf '\\033[2Jx')\""), 2,
                "photopose resect: --rotation must be rxryrz (alias seed), opk or pok, not "
                "'\\x1B[2Jx'");
}

TEST_F(BadInputCatalogue, Utf16FilesAreRecognisedAndNamed) {
  const std::string points = ReadFile(work_ + "/points.csv");
  std::string utf16 = "\xFF\xFE";
  for (const char c : points) utf16 += std::string{c, '\0'};
  WriteFile(work_ + "/points.csv", utf16);
  ExpectRefused(Resect("--out=frames.csv"), 2,
                "photopose resect: points.csv: is UTF-16 (little-endian byte order mark); "
                "photopose reads UTF-8 text: save the file as UTF-8");
}

TEST_F(BadInputCatalogue, AbsurdCamerasAndMarksAreRefusedWithTheirLine) {
  const std::string camera = FirstLine(ReadFile(SourcePath("examples/cameras.csv")));
  const std::string row =
      FirstLine(ReadFile(SourcePath("examples/cameras.csv")).substr(camera.size() + 1));
  const auto with = [&](const std::string& from, const std::string& to) {
    std::string changed = row;
    changed.replace(changed.find(from), from.size(), to);
    WriteFile(work_ + "/cameras.csv", camera + "\n" + changed + "\n");
  };
  with(",3648,5472,", ",1,1,");
  ExpectRefused(Resect("--out=frames.csv"), 2,
                "photopose resect: cameras.csv:2: NRows: 1 is outside [2, 1000000] pixels");
  with("0;-0.00012;2e-07;0", "0;-1;0;0");
  ExpectRefused(Resect("--out=frames.csv"), 2,
                "photopose resect: cameras.csv:2: Radial: the distortion correction scales the "
                "radius by 3.035 at 1.426 mm from the principal point; inside the image (7.939 mm "
                "to its farthest corner) it may change it by a factor of 3 at most");
  with(",2.41,3648,5472,3,,,1,,,,,,,1,", ",,3648,5472,3,,,1,0,4.9e-324,0,0,0,-2.41,1,");
  ExpectRefused(Resect("--out=frames.csv"), 2,
                "photopose resect: cameras.csv:2: A1: the affine is singular: A1 B2 - A2 B1 = "
                "-1e-323 is negligible against its coefficients (up to 2.41); the rows of A and B "
                "must not be parallel");
  fs::copy_file(SourcePath("examples/cameras.csv"), work_ + "/cameras.csv",
                fs::copy_options::overwrite_existing);
  ReplaceLine("marks.csv", 2, "img_0001,P0001,25472,2397.6,,,0.5,UAV_8.8mm");
  ExpectRefused(Resect("--out=frames.csv"), 2,
                "photopose resect: marks.csv:2: Column: the mark of point 'P0001' in image "
                "'img_0001' lies 20000 pixels outside the 5472 x 3648 image of camera 'UAV_8.8mm' "
                "(at most 5% of the image size is allowed)");
}

// ------------------------------------------------------------------ readers of other tools

// A BAL problem of one camera, one point and one observation, and a COLMAP model of one image.
constexpr char kBal[] = "1 1 1\n0 0 1 2\n0 0 0 0 0 -10 100 0 0\n1 2 3\n";
constexpr char kColmapCameras[] = "1 SIMPLE_RADIAL 100 80 100 50 40 0.01\n";
constexpr char kColmapImages[] = "1 1 0 0 0 0 0 0 1 a.jpg\n60 60 3\n";
constexpr char kColmapPoints[] = "3 1 2 10 10 20 30 0.5 1 0\n";

TEST_F(BadInputCatalogue, FifosAndHugeFilesGivenAsBalOrColmapAreRefusedAtOnce) {
  ASSERT_EQ(mkfifo((work_ + "/fifo.txt").c_str(), 0644), 0);
  ExpectRefused("bundle --bal=fifo.txt --report=r.json", 2,
                "photopose bundle: fifo.txt: is a FIFO (named pipe), not a regular file; "
                "photopose reads regular files, or standard input for '-'");
  fs::create_directory(work_ + "/model");
  WriteFile(work_ + "/model/cameras.txt", kColmapCameras);
  WriteFile(work_ + "/model/images.txt", kColmapImages);
  ASSERT_EQ(mkfifo((work_ + "/model/points3D.txt").c_str(), 0644), 0);
  ExpectRefused("bundle --colmap_model=model --report=r.json", 2,
                "photopose bundle: model/points3D.txt: is a FIFO (named pipe), not a regular file; "
                "photopose reads regular files, or standard input for '-'");
  // 280 MB, sparse (no disk used), outside the work folder (whose snapshot reads every file).
  const std::string big = root_ + "/big.txt";
  WriteFile(big, kBal);
  fs::resize_file(big, uint64_t{280} << 20);
  ExpectRefused("bundle --bal=" + big + " --report=r.json", 2,
                "photopose bundle: " + big +
                    ": is larger than 268435456 bytes, the largest input photopose reads");
}

TEST_F(BadInputCatalogue, LongTokensAndBinaryAreEchoedCutToAFewDozenCharacters) {
  WriteFile(work_ + "/token.txt", std::string(1 << 20, '7') + "x 1 1\n");
  ExpectRefused("bundle --bal=token.txt --report=r.json", 2,
                "photopose bundle: token.txt:1: num_cameras: '" + std::string(40, '7') +
                    "\u2026(1048577 bytes)' is not a number");
  WriteFile(work_ + "/binary.txt", std::string(2 << 20, '\xff'));
  std::string escaped;
  for (int i = 0; i < 40; ++i) escaped += "\\xFF";
  ExpectRefused("bundle --bal=binary.txt --report=r.json", 2,
                "photopose bundle: binary.txt:1: num_cameras: '" + escaped +
                    "\u2026(2097152 bytes)' is not a number");
}

TEST_F(BadInputCatalogue, AbsurdValuesAreRefusedAtTheReaderWithFileLineAndField) {
  WriteFile(work_ + "/p.txt", "1 1 1\n0 0 1 2\n0 0 0 0 0 -10 100 0 0\n1 2 -1e300\n");
  ExpectRefused("bundle --bal=p.txt --report=r.json", 2,
                "photopose bundle: p.txt:4: point coordinate: '-1e300' is outside [-100000000, "
                "100000000]");
  fs::create_directory(work_ + "/model");
  WriteFile(work_ + "/model/cameras.txt", "1 SIMPLE_RADIAL 100 80 -6000 50 40 0.01\n");
  WriteFile(work_ + "/model/images.txt", kColmapImages);
  WriteFile(work_ + "/model/points3D.txt", kColmapPoints);
  ExpectRefused("bundle --colmap_model=model --report=r.json", 2,
                "photopose bundle: model/cameras.txt:1: PARAMS f: -6000 is no focal length: it "
                "must be at least 0.001 px");
  WriteFile(work_ + "/model/cameras.txt", kColmapCameras);
  WriteFile(work_ + "/model/images.txt", "1 1e300 0 0 0 0 0 0 1 a.jpg\n60 60 3\n");
  ExpectRefused("bundle --colmap_model=model --report=r.json", 2,
                "photopose bundle: model/images.txt:1: QW: the quaternion (QW, QX, QY, QZ) has "
                "norm 1e+300; COLMAP's is a unit quaternion (one with a norm between 1e-12 and "
                "1000000000000 is normalised)");
  const std::string cameras = ReadFile(work_ + "/cameras.csv");
  const size_t focal = cameras.find(",8800,");
  ASSERT_NE(focal, std::string::npos);
  WriteFile(work_ + "/cameras.csv", cameras.substr(0, focal) + ",1e-300," + cameras.substr(focal + 6));
  ExpectRefused(Resect("--out=frames.csv"), 2,
                "photopose resect: cameras.csv:2: FocalLength: '1e-300' is outside [1, 100000000] "
                "um");
}

TEST_F(BadInputCatalogue, BundleRefusesInputsItDoesNotReadAndOutputsItCannotWriteBeforeAnyWork) {
  WriteFile(work_ + "/p.txt", kBal);
  ExpectRefused("bundle --bal=p.txt --points=points.csv --report=r.json", 2,
                "photopose bundle: --bal holds its own points and poses: --geo, --gcp_list, "
                "--points and --frames are read with the tables or --colmap_model");
  // With a COLMAP model, --points and --frames georeference it: in a stated CRS, which a points
  // table cannot state itself.
  ExpectRefused("bundle --colmap_model=model --points=points.csv --marks=marks.csv --report=r.json", 2,
                "photopose bundle: --crs is needed: a points table has no SRS column, so --points "
                "carry no coordinate system (e.g. --crs=EPSG:32632)");
  // A frames table states its own in its SRS column: read, and refused when --crs names another,
  // when its rows name two, or when neither it nor --crs names one.
  fs::create_directory(work_ + "/model");
  WriteFile(work_ + "/model/cameras.txt", kColmapCameras);
  WriteFile(work_ + "/model/images.txt", kColmapImages);
  WriteFile(work_ + "/model/points3D.txt", kColmapPoints);
  WriteFile(work_ + "/gnss.csv",
            "Raster,CameraID,PerspectiveX,PerspectiveY,PerspectiveZ,Omega,Phi,Kappa,SRS\n"
            "a.jpg,1,500000,5300000,600,0,0,0,EPSG:32632\n"
            "b.jpg,1,500010,5300000,600,0,0,0,EPSG:32633\n");
  ExpectRefused("bundle --colmap_model=model --frames=gnss.csv --crs=EPSG:32633 --report=r.json", 2,
                "photopose bundle: --frames gnss.csv:2: SRS: 'EPSG:32632' is another CRS than "
                "--crs=EPSG:32633: the positions of a frames table are in one CRS");
  ExpectRefused("bundle --colmap_model=model --frames=gnss.csv --report=r.json", 2,
                "photopose bundle: --frames gnss.csv:3: SRS: 'EPSG:32633' is another CRS than "
                "line 2's 'EPSG:32632': the positions of a frames table are in one CRS");
  WriteFile(work_ + "/gnss.csv",
            "Raster,CameraID,PerspectiveX,PerspectiveY,PerspectiveZ,Omega,Phi,Kappa,SRS\n"
            "a.jpg,1,500000,5300000,600,0,0,0,\n");
  ExpectRefused("bundle --colmap_model=model --frames=gnss.csv --report=r.json", 2,
                "photopose bundle: --frames gnss.csv: no SRS column value and no --crs: the "
                "coordinate system of the positions is unknown");
  ExpectRefused("bundle --cameras=c.csv --marks=m.csv --geo=geo.txt --report=r.json", 2,
                "photopose bundle: --geo and --gcp_list georeference a --colmap_model; with the "
                "tables give --frames and --points");
  ExpectRefused("bundle --bal=p.txt --out_colmap=model --report=r.json", 2,
                "photopose bundle: --out_colmap: a BAL problem has no image size and counts "
                "pixels from the image centre, which a COLMAP model cannot hold; write --out, "
                "--out_points or --report");
  ExpectRefused("bundle --bal=p.txt --out_cameras=c.csv --report=r.json", 2,
                "photopose bundle: --out_cameras writes a camera table of frame cameras; with "
                "--colmap_model or --bal use --out_colmap");
  // A camera with distortion is no COLMAP camera: refused after reading, before the adjustment
  // (no iteration line on stderr).
  const Snapshot before = Take(work_);
  const CliRun run = Run("bundle --cameras=cameras.csv --marks=marks.csv --points=points.csv "
                         "--out_colmap=../model --report=r.json");
  EXPECT_EQ(run.exit_code, 2) << run.err;
  EXPECT_EQ(run.err.find("iteration"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("photopose bundle: --out_colmap: camera 'UAV_8.8mm' has K1 = -0.00012: "
                         "only a frame camera without distortion, affinity and skew is a COLMAP "
                         "pinhole camera\n"),
            std::string::npos)
      << run.err;
  EXPECT_EQ(Take(work_), before);
  EXPECT_TRUE(fs::is_empty(root_ + "/model"));
}

// A CRS PROJ does not know: one line that says so (PROJ's own words are "Unknown error (code
// 4096)") and names where it was given: the flag, or the file and line (the first line of a
// geo.txt or gcp_list.txt).
TEST_F(BadInputCatalogue, BundleNamesAnUnknownCrsAndWhereItWasGiven) {
  fs::create_directory(work_ + "/model");
  WriteFile(work_ + "/model/cameras.txt", kColmapCameras);
  WriteFile(work_ + "/model/images.txt", kColmapImages);
  WriteFile(work_ + "/model/points3D.txt", kColmapPoints);
  WriteFile(work_ + "/unknown_geo.txt", "EPSG:999999\na.jpg 600000 5300000 500\n");
  WriteFile(work_ + "/unknown_gcp_list.txt", "EPSG:999999\n600000 5300000 500 60 60 a.jpg G1\n");
  WriteFile(work_ + "/geo.txt", "EPSG:32632\na.jpg 600000 5300000 500\n");
  const std::string model = "bundle --colmap_model=model --report=r.json ";
  const std::string unknown = ": CRS 'EPSG:999999' is not known to PROJ (proj.db)";
  ExpectRefused(model + "--geo=unknown_geo.txt", 2, "photopose bundle: unknown_geo.txt:1" + unknown);
  ExpectRefused(model + "--gcp_list=unknown_gcp_list.txt", 2,
                "photopose bundle: unknown_gcp_list.txt:1" + unknown);
  ExpectRefused(model + "--geo=geo.txt --out_crs=EPSG:999999", 2, "photopose bundle: --out_crs" + unknown);
  ExpectRefused(model + "--frames=frames.csv --crs=EPSG:999999", 2, "photopose bundle: --crs" + unknown);
  ExpectRefused(model + "--images=. --exif_crs=EPSG:999999", 2, "photopose bundle: --exif_crs" + unknown);
}

// ------------------------------------------------------------------ guard

TEST_F(BadInputCatalogue, RunningOutOfMemoryIsOneLineNotAnAbort) {
#if defined(PHOTOPOSE_TEST_ASAN)
  GTEST_SKIP() << "AddressSanitizer reserves more address space than the limit allows";
#else
  // 200 MB of address space: the executable starts, the scene of 240 000 points does not fit.
  const Snapshot before = Take(work_);
  const std::string command = "cd '" + work_ + "' && ulimit -v 200000 && " + testing::CliPath() +
                              " simulate --scenario=uav_block --control_points=10000 "
                              "--check_points=10000 --out_dir=sim >'" +
                              root_ + "/out' 2>'" + root_ + "/err'";
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  const std::string err = ReadFile(root_ + "/err");
  EXPECT_EQ(err, "photopose simulate: out of memory\n");
  EXPECT_EQ(Take(work_), before);
#endif
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
