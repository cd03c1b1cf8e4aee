#include "core/io/output_files.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "tests/test_devices.h"

namespace photopose {
namespace PHOTOPOSE_UNITY_ID {

namespace fs = std::filesystem;

class OutputFilesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::path(::testing::TempDir()) / "photopose_output_XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
    pattern = (fs::path(::testing::TempDir()) / "photopose_devices_XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    devices_ = pattern;
  }
  void TearDown() override {
    fs::remove_all(dir_);
    fs::remove_all(devices_);
  }

  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  std::string Write(const std::string& name, const std::string& contents) {
    std::ofstream(Path(name), std::ios::binary) << contents;
    return Path(name);
  }
  static std::string Read(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }
  // Every entry of the test folder, recursively, as relative paths.
  std::set<std::string> Entries() const {
    std::set<std::string> names;
    for (const auto& entry : fs::recursive_directory_iterator(dir_))
      names.insert(entry.path().lexically_relative(dir_).string());
    return names;
  }
  static ino_t Inode(const std::string& path) {
    struct stat info;
    return stat(path.c_str(), &info) == 0 ? info.st_ino : 0;
  }
  // The pid of a process that has exited: a run that was killed.
  static pid_t DeadPid() {
    const pid_t child = fork();
    if (child == 0) _exit(0);
    int status = 0;
    waitpid(child, &status, 0);
    return child;
  }

  fs::path dir_;
  std::string devices_;  // private device nodes (tests/test_devices.h)
};

// ------------------------------------------------------------------ single files

TEST_F(OutputFilesTest, WriteFileAtomicallyCreatesAndReplacesKeepingTheMode) {
  const std::string path = Path("table.csv");
  ASSERT_TRUE(WriteFileAtomically(path, "old\n").ok());
  EXPECT_EQ(Read(path), "old\n");
  struct stat info;
  ASSERT_EQ(stat(path.c_str(), &info), 0);
  const mode_t mask = umask(0);
  umask(mask);
  EXPECT_EQ(info.st_mode & 0777, 0666u & ~mask);  // a new file: rw-rw-rw- less the umask
  ASSERT_EQ(chmod(path.c_str(), 0640), 0);
  ASSERT_TRUE(WriteFileAtomically(path, "new\n").ok());
  EXPECT_EQ(Read(path), "new\n");
  ASSERT_EQ(stat(path.c_str(), &info), 0);
  EXPECT_EQ(info.st_mode & 0777, 0640u);  // the replaced file's mode is kept
  EXPECT_EQ(Entries(), std::set<std::string>{"table.csv"});
}

TEST_F(OutputFilesTest, MissingFolderIsRefusedBeforeAnythingIsWritten) {
  const std::string path = Path("no_such_folder/table.csv");
  OutputFiles outputs;
  EXPECT_EQ(outputs.AddOutput("--out", path).message(),
            "--out=" + path + ": the folder '" + Path("no_such_folder") + "' does not exist");
  EXPECT_EQ(WriteFileAtomically(path, "data\n").message(),
            path + ": the folder '" + Path("no_such_folder") + "' does not exist");
  EXPECT_TRUE(Entries().empty());
}

TEST_F(OutputFilesTest, AFolderIsNotAnOutputFile) {
  const std::string path = Path("folder");
  fs::create_directory(path);
  EXPECT_EQ(WriteFileAtomically(path, "data\n").message(), path + ": is a folder, not a file");
  EXPECT_EQ(WriteFileAtomically(Path("folder/"), "data\n").message(),
            Path("folder/") + ": is a folder, not a file");
  EXPECT_EQ(Entries(), std::set<std::string>{"folder"});
}

TEST_F(OutputFilesTest, AFailedWriteKeepsTheOldFileAndLeavesNoTemporary) {
  const std::string path = Write("table.csv", "old\n");
  // A file size limit makes write() fail part way, like a full disk (SIGXFSZ ignored so that the
  // call returns EFBIG instead of killing the process).
  rlimit saved;
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &saved), 0);
  const auto old_handler = signal(SIGXFSZ, SIG_IGN);
  rlimit small = saved;
  small.rlim_cur = 4096;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  const Status status = WriteFileAtomically(path, std::string(100000, 'x'));
  setrlimit(RLIMIT_FSIZE, &saved);
  signal(SIGXFSZ, old_handler);
  EXPECT_EQ(status.message(), path + ": cannot write: File too large");
  EXPECT_EQ(Read(path), "old\n");
  EXPECT_EQ(Entries(), std::set<std::string>{"table.csv"});
}

TEST_F(OutputFilesTest, ASymlinkKeepsPointingToTheFileItNamesWhichIsReplaced) {
  const std::string target = Write("target.csv", "old\n");
  fs::create_symlink("target.csv", Path("link.csv"));
  ASSERT_TRUE(WriteFileAtomically(Path("link.csv"), "new\n").ok());
  EXPECT_TRUE(fs::is_symlink(Path("link.csv")));
  EXPECT_EQ(fs::read_symlink(Path("link.csv")), "target.csv");
  EXPECT_EQ(Read(target), "new\n");
  // A dangling symlink: the file it names is created.
  fs::create_symlink("created.csv", Path("dangling.csv"));
  ASSERT_TRUE(WriteFileAtomically(Path("dangling.csv"), "made\n").ok());
  EXPECT_TRUE(fs::is_symlink(Path("dangling.csv")));
  EXPECT_EQ(Read(Path("created.csv")), "made\n");
  EXPECT_EQ(Entries(),
            (std::set<std::string>{"target.csv", "link.csv", "dangling.csv", "created.csv"}));
}

TEST_F(OutputFilesTest, DevicesAreWrittenInPlaceNeverReplaced) {
  const std::string null = testing::TestDevice(devices_, "null");
  const std::string full = testing::TestDevice(devices_, "full");
  if (null.empty() || full.empty()) GTEST_SKIP() << "root cannot make a private device node here";
  ASSERT_TRUE(WriteFileAtomically(null, "discarded\n").ok());
  struct stat info;
  ASSERT_EQ(stat(null.c_str(), &info), 0);
  EXPECT_TRUE(S_ISCHR(info.st_mode));
  // A full disk, as a device: the error names the output.
  EXPECT_EQ(WriteFileAtomically(full, "data\n").message(),
            full + ": cannot write: No space left on device");
  ASSERT_EQ(stat(full.c_str(), &info), 0);
  EXPECT_TRUE(S_ISCHR(info.st_mode));
  // The same device twice is no conflict.
  OutputFiles outputs;
  ASSERT_TRUE(outputs.AddOutput("--out", null).ok());
  ASSERT_TRUE(outputs.AddOutput("--report", null).ok());
  ASSERT_TRUE(outputs.Stage(null, "a").ok());
  ASSERT_TRUE(outputs.Stage(null, "b").ok());
  EXPECT_TRUE(outputs.Commit().ok());
}

TEST_F(OutputFilesTest, AFifoIsWrittenInPlaceAndOneWithoutReaderIsAnErrorNotAHang) {
  const std::string fifo = Path("fifo");
  ASSERT_EQ(mkfifo(fifo.c_str(), 0644), 0);
  EXPECT_EQ(WriteFileAtomically(fifo, "data\n").message(),
            fifo + ": no process is reading the FIFO");
  std::string received;
  std::thread reader([&] {
    std::ifstream in(fifo);  // blocks until the writer opens
    std::stringstream ss;
    ss << in.rdbuf();
    received = ss.str();
  });
  // The reader must have the FIFO open before the non-blocking open for writing.
  Status status;
  for (int attempt = 0; attempt < 500; ++attempt) {
    status = WriteFileAtomically(fifo, "through the fifo\n");
    if (status.ok()) break;
    usleep(10000);
  }
  reader.join();
  EXPECT_TRUE(status.ok()) << status.message();
  EXPECT_EQ(received, "through the fifo\n");
  struct stat info;
  ASSERT_EQ(lstat(fifo.c_str(), &info), 0);
  EXPECT_TRUE(S_ISFIFO(info.st_mode));
  EXPECT_EQ(Entries(), std::set<std::string>{"fifo"});
}

TEST_F(OutputFilesTest, AnOutputThatIsAnInputIsRefusedAfterSymlinksAndByInode) {
  const std::string input = Write("marks.csv", "data\n");
  fs::create_symlink("marks.csv", Path("alias.csv"));
  ASSERT_EQ(link(input.c_str(), Path("hard.csv").c_str()), 0);
  for (const std::string& output :
       {input, Path("alias.csv"), Path("hard.csv"), (dir_ / "." / "marks.csv").string()}) {
    OutputFiles outputs;
    ASSERT_TRUE(outputs.AddInput("--marks", input).ok());
    EXPECT_EQ(outputs.AddOutput("--out", output).message(),
              "--out=" + output + " is the input --marks=" + input +
                  "; photopose never writes over an input: choose another output file");
  }
  // An input given through a symlink is the file it names.
  OutputFiles outputs;
  ASSERT_TRUE(outputs.AddInput("--marks", Path("alias.csv")).ok());
  EXPECT_FALSE(outputs.AddOutput("--out", input).ok());
  EXPECT_EQ(Read(input), "data\n");
}

TEST_F(OutputFilesTest, StandardInputIsOneInputOnly) {
  OutputFiles outputs;
  EXPECT_TRUE(outputs.AddInput("--points", "-").ok());
  EXPECT_EQ(outputs.AddInput("--marks", "-").message(),
            "--marks=-: standard input is already read as --points=-; only one input can be '-'");
}

TEST_F(OutputFilesTest, TwoOutputsInOneFileAreRefused) {
  Write("x.csv", "old\n");
  fs::create_symlink("x.csv", Path("y.csv"));
  for (const std::string& second : {Path("x.csv"), Path("y.csv")}) {
    OutputFiles outputs;
    ASSERT_TRUE(outputs.AddOutput("--out", Path("x.csv")).ok());
    EXPECT_EQ(outputs.AddOutput("--report", second).message(),
              "--report=" + second + " is the same file as --out=" + Path("x.csv") +
                  "; every output needs a file of its own");
  }
  // Also when the file does not exist yet.
  OutputFiles outputs;
  ASSERT_TRUE(outputs.AddOutput("--out", Path("new.csv")).ok());
  EXPECT_FALSE(outputs.AddOutput("--report", (dir_ / "." / "new.csv").string()).ok());
}

TEST_F(OutputFilesTest, NothingIsReplacedUnlessEveryOutputIsWritten) {
  const std::string first = Write("frames.csv", "old frames\n");
  const std::string full = testing::TestDevice(devices_, "full");
  if (!full.empty()) {
    OutputFiles outputs;
    ASSERT_TRUE(outputs.AddOutput("--out", first).ok());
    ASSERT_TRUE(outputs.AddOutput("--report", full).ok());
    ASSERT_TRUE(outputs.Stage(first, "new frames\n").ok());
    ASSERT_TRUE(outputs.Stage(full, "report\n").ok());
    EXPECT_EQ(outputs.Commit().message(),
              "--report=" + full + ": cannot write: No space left on device");
  }
  EXPECT_EQ(Read(first), "old frames\n");
  EXPECT_EQ(Entries(), std::set<std::string>{"frames.csv"});
  {
    // Staged but never committed (an error in between): the destructor removes the temporary.
    OutputFiles outputs;
    ASSERT_TRUE(outputs.AddOutput("--out", first).ok());
    ASSERT_TRUE(outputs.Stage(first, "new frames\n").ok());
    EXPECT_EQ(Entries().size(), 2u);
  }
  EXPECT_EQ(Read(first), "old frames\n");
  EXPECT_EQ(Entries(), std::set<std::string>{"frames.csv"});
  // An output that was never staged makes Commit fail without touching anything.
  OutputFiles outputs;
  ASSERT_TRUE(outputs.AddOutput("--out", first).ok());
  ASSERT_TRUE(outputs.AddOutput("--report", Path("report.json")).ok());
  ASSERT_TRUE(outputs.Stage(first, "new frames\n").ok());
  EXPECT_FALSE(outputs.Commit().ok());
  EXPECT_EQ(Read(first), "old frames\n");
  EXPECT_EQ(Entries(), std::set<std::string>{"frames.csv"});
}

TEST_F(OutputFilesTest, StageWithHandsOutATemporaryAndNamesTheTargetInMessages) {
  const std::string path = Write("frames.csv", "old\n");
  OutputFiles outputs;
  ASSERT_TRUE(outputs.AddOutput("--out", path).ok());
  std::string temporary;
  const Status failed = outputs.StageWith(path, [&](const std::string& temp) {
    temporary = temp;
    return Status::Error(temp + ": raster 'a': X: value is not finite");
  });
  EXPECT_EQ(failed.message(), path + ": raster 'a': X: value is not finite");
  EXPECT_EQ(fs::path(temporary).parent_path(), dir_);
  EXPECT_FALSE(fs::exists(temporary));
  ASSERT_TRUE(
      outputs
          .StageWith(path,
                     [](const std::string& temp) { return WriteFileAtomically(temp, "new\n"); })
          .ok());
  ASSERT_TRUE(outputs.Commit().ok());
  EXPECT_EQ(Read(path), "new\n");
  EXPECT_EQ(Entries(), std::set<std::string>{"frames.csv"});
}

// A file of three pieces and a half: written as it is formatted, never held whole, the same bytes.
TEST_F(OutputFilesTest, StageInPiecesWritesTheTextAPieceAtATime) {
  const std::string path = Path("images.txt");
  OutputFiles outputs;
  ASSERT_TRUE(outputs.AddOutput("--out_colmap", path).ok());
  std::string expected;
  size_t largest_held = 0, pieces_written = 0;
  const Status staged = outputs.StageInPieces(path, [&](TextPieces* out) {
    EXPECT_TRUE(out->writes_file());
    for (int line = 0; expected.size() < 7 * TextPieces::kPieceBytes / 2; ++line) {
      const std::string text =
          "line " + std::to_string(line) + " " + std::string(line % 97, 'x') + "\n";
      out->text() += text;
      expected += text;
      largest_held = std::max(largest_held, out->text().size());
      const size_t before = out->text().size();
      PHOTOPOSE_RETURN_IF_ERROR(out->Piece());
      if (out->text().size() < before) ++pieces_written;
    }
    return out->Write("the end\n");
  });
  expected += "the end\n";
  ASSERT_TRUE(staged.ok()) << staged.message();
  EXPECT_EQ(pieces_written, 3u);
  EXPECT_LT(largest_held, TextPieces::kPieceBytes + 200);
  EXPECT_FALSE(fs::exists(path));  // not before Commit
  ASSERT_TRUE(outputs.Commit().ok());
  EXPECT_EQ(Read(path), expected);
  EXPECT_EQ(Entries(), std::set<std::string>{"images.txt"});
}

// A format that fails after pieces were written: the old file kept, no temporary left.
TEST_F(OutputFilesTest, StageInPiecesThatFailsLeavesTheOldFileAndNoTemporary) {
  const std::string path = Write("points3D.txt", "old\n");
  OutputFiles outputs;
  ASSERT_TRUE(outputs.AddOutput("--out_colmap", path).ok());
  const Status staged = outputs.StageInPieces(path, [&](TextPieces* out) {
    out->text() = std::string(TextPieces::kPieceBytes + 1, 'a');
    PHOTOPOSE_RETURN_IF_ERROR(out->Piece());
    EXPECT_TRUE(out->text().empty());
    return Status::Error(path + ": point 7: X: value is not finite");
  });
  EXPECT_EQ(staged.message(), path + ": point 7: X: value is not finite");
  EXPECT_EQ(Read(path), "old\n");
  EXPECT_EQ(Entries(), std::set<std::string>{"points3D.txt"});
}

// Collected whole by a TextPieces of one's own (the in-memory formats).
TEST(TextPiecesTest, CollectsTheWholeTextWhenItWritesNoFile) {
  TextPieces whole;
  EXPECT_FALSE(whole.writes_file());
  whole.text() = std::string(TextPieces::kPieceBytes + 5, 'b');
  ASSERT_TRUE(whole.Piece().ok());
  ASSERT_TRUE(whole.Write("c").ok());
  EXPECT_EQ(whole.text().size(), TextPieces::kPieceBytes + 6);
  EXPECT_EQ(whole.text().back(), 'c');
}

TEST_F(OutputFilesTest, TemporariesOfKilledRunsAreRemovedLiveOnesKept) {
  const std::string path = Write("frames.csv", "old\n");
  const std::string dead = std::to_string(DeadPid());
  const std::string alive = std::to_string(getppid());
  Write(".frames.csv.photopose-" + dead + "-a1b2c3", "half\n");
  Write("..frames.csv.photopose-" + dead + "-a1b2c3.photopose-" + dead + "-d4e5f6", "nested\n");
  Write(".frames.csv.photopose-" + alive + "-a1b2c3", "another run\n");
  Write(".other.csv.photopose-" + dead + "-a1b2c3", "another target\n");
  ASSERT_TRUE(WriteFileAtomically(path, "new\n").ok());
  EXPECT_EQ(Entries(),
            (std::set<std::string>{"frames.csv", ".frames.csv.photopose-" + alive + "-a1b2c3",
                                   ".other.csv.photopose-" + dead + "-a1b2c3"}));
}

// ------------------------------------------------------------------ folders

std::vector<FolderFile> Dataset(const std::string& version) {
  return {{"a.csv", "a " + version + "\n"}, {"truth/b.csv", "b " + version + "\n"}};
}

TEST_F(OutputFilesTest, AFolderIsCreatedWithItsParents) {
  const std::string folder = Path("deep/er/data");
  ASSERT_TRUE(WriteFolderAtomically("--out_dir", folder, Dataset("1")).ok());
  EXPECT_EQ(Read(folder + "/a.csv"), "a 1\n");
  EXPECT_EQ(Read(folder + "/truth/b.csv"), "b 1\n");
  EXPECT_EQ(Entries(),
            (std::set<std::string>{"deep", "deep/er", "deep/er/data", "deep/er/data/a.csv",
                                   "deep/er/data/truth", "deep/er/data/truth/b.csv"}));
}

TEST_F(OutputFilesTest, AFolderIsReplacedAsAWholeKeepingTheOtherFiles) {
  const std::string folder = Path("data");
  ASSERT_TRUE(WriteFolderAtomically("--out_dir", folder, Dataset("1")).ok());
  Write("data/README.md", "mine\n");
  Write("data/truth/notes.txt", "also mine\n");
  fs::create_symlink("README.md", Path("data/link"));
  const ino_t readme = Inode(Path("data/README.md"));
  ASSERT_TRUE(WriteFolderAtomically("--out_dir", folder, Dataset("2")).ok());
  EXPECT_EQ(Read(folder + "/a.csv"), "a 2\n");
  EXPECT_EQ(Read(folder + "/truth/b.csv"), "b 2\n");
  EXPECT_EQ(Read(folder + "/README.md"), "mine\n");
  EXPECT_EQ(Inode(folder + "/README.md"), readme);  // carried over as a hard link
  EXPECT_EQ(Read(folder + "/truth/notes.txt"), "also mine\n");
  EXPECT_EQ(fs::read_symlink(folder + "/link"), "README.md");
  EXPECT_EQ(Entries(),
            (std::set<std::string>{"data", "data/a.csv", "data/truth", "data/truth/b.csv",
                                   "data/README.md", "data/truth/notes.txt", "data/link"}));
}

TEST_F(OutputFilesTest, AFolderReachedThroughASymlinkIsReplacedTheSymlinkKept) {
  ASSERT_TRUE(WriteFolderAtomically("", Path("real"), Dataset("1")).ok());
  fs::create_directory_symlink("real", Path("alias"));
  ASSERT_TRUE(WriteFolderAtomically("", Path("alias"), Dataset("2")).ok());
  EXPECT_TRUE(fs::is_symlink(Path("alias")));
  EXPECT_EQ(Read(Path("real/a.csv")), "a 2\n");
}

TEST_F(OutputFilesTest, FoldersThatCannotBeReplacedAsAWholeAreRefusedUntouched) {
  const std::string folder = Path("data");
  ASSERT_TRUE(WriteFolderAtomically("--out_dir", folder, Dataset("1")).ok());
  fs::create_directory(Path("data/sub"));
  EXPECT_EQ(WriteFolderAtomically("--out_dir", folder, Dataset("2")).message(),
            "--out_dir=" + folder +
                ": holds the folder 'sub'; photopose replaces the output folder as a whole and "
                "carries over files only: give a folder of its own to the dataset");
  fs::remove(Path("data/sub"));
  ASSERT_EQ(mkfifo(Path("data/pipe").c_str(), 0644), 0);
  EXPECT_EQ(WriteFolderAtomically("--out_dir", folder, Dataset("2")).message(),
            "--out_dir=" + folder +
                ": holds 'pipe', a FIFO, which cannot be carried over into the new folder");
  fs::remove(Path("data/pipe"));
  EXPECT_EQ(Read(folder + "/a.csv"), "a 1\n");
  Write("file", "x");
  EXPECT_EQ(WriteFolderAtomically("--out_dir", Path("file"), Dataset("2")).message(),
            "--out_dir=" + Path("file") + ": exists and is not a folder");
  // The current folder (or one that contains it) would be swapped away under the user's feet.
  const fs::path saved = fs::current_path();
  fs::current_path(Path("data/truth"));
  const Status status = WriteFolderAtomically("--out_dir", "..", Dataset("2"));
  fs::current_path(saved);
  EXPECT_EQ(status.message(),
            "--out_dir=..: is the current folder or contains it; photopose replaces the output "
            "folder as a whole: give another folder");
  EXPECT_EQ(Entries(), (std::set<std::string>{"data", "data/a.csv", "data/truth",
                                              "data/truth/b.csv", "file"}));
}

TEST_F(OutputFilesTest, StaleFoldersOfKilledRunsAreRemoved) {
  const std::string dead = std::to_string(DeadPid());
  fs::create_directories(Path(".data.photopose-" + dead + "-x1y2z3/truth"));
  Write(".data.photopose-" + dead + "-x1y2z3/a.csv", "half\n");
  ASSERT_TRUE(WriteFolderAtomically("--out_dir", Path("data"), Dataset("1")).ok());
  EXPECT_EQ(Entries(),
            (std::set<std::string>{"data", "data/a.csv", "data/truth", "data/truth/b.csv"}));
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose
