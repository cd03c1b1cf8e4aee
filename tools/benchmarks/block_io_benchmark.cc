// Block I/O at scale (docs/performance.md, issue 10 section 2): generates issue 10's synthetic
// block (25 lines x 40 images of a 24 mm / 4 um / 6000 x 4000 camera at 100 m, 13 m forward and
// 30 m side spacing, 120 000 tie points: about 1.8 million marks), writes it as the project's
// tables and as a COLMAP text and binary model, reads them back (the tables one by one, then
// assembled into a block, then all at once with ReadBlock as `photopose bundle` does; the COLMAP
// model is also written and read as an OpenSfM reconstruction), and times every step (wall
// clock, one run each) with the step's peak resident memory (and how far above the memory at its
// start that peak is). When `colmap` is on the PATH, its own text reader runs on the same model in
// the same run (`colmap model_converter` text -> binary, and binary -> text for its writer) as the
// peer. The dataset stays in --out_dir for the bundle-adjustment benchmark:
//   cameras.csv points.csv marks.csv frames.csv     the block's tables (perturbed start, GNSS)
//   truth/frames.csv truth/points.csv truth/blunders.csv
//   colmap/{cameras,images,points3D}.txt             the same block as a COLMAP model
//   colmap_binary/{cameras,images,points3D}.bin      and as a binary one
//   opensfm/{reconstruction.json,tracks.csv}         and as an OpenSfM reconstruction
//
// Usage: photopose_block_io_benchmark --out_dir=DIR [--lines=25] [--images_per_line=40]
//            [--forward_spacing_m=13] [--side_spacing_m=30] [--tie_points=120000] [--seed=1]
//            [--no_peer]
#include <sys/resource.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/block.h"
#include "core/io/block_tables.h"
#include "core/io/colmap.h"
#include "core/io/opensfm.h"
#include "core/simulation/synthetic_block.h"
#include "core/io/tables.h"

namespace photopose {
namespace {

// A field of /proc/self/status in MB ("VmHWM", "VmRSS"), or the peak of getrusage where there is
// no /proc.
double StatusMb(const char* field) {
  if (std::FILE* status = std::fopen("/proc/self/status", "r")) {
    char line[256];
    const size_t length = std::strlen(field);
    double kib = -1.0;
    while (std::fgets(line, sizeof(line), status) != nullptr) {
      if (std::strncmp(line, field, length) == 0 && line[length] == ':')
        kib = std::atof(line + length + 1);
    }
    std::fclose(status);
    if (kib >= 0.0) return kib / 1024.0;
  }
  rusage usage;
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;  // ru_maxrss is in KiB on Linux
}

// Resets the peak resident memory (VmHWM) to the current one, so that each step reports its own
// peak (Linux >= 4.0; elsewhere the peak stays the process's).
void ResetPeakRss() {
#ifdef __GLIBC__
  malloc_trim(0);  // hand the memory freed by the steps before back, so that RSS is what is in use
#endif
  if (std::FILE* clear = std::fopen("/proc/self/clear_refs", "w")) {
    std::fputs("5", clear);
    std::fclose(clear);
  }
}

double FileMb(const std::string& path) {
  std::error_code error;
  const auto size = std::filesystem::file_size(path, error);
  return error ? 0.0 : static_cast<double>(size) / (1024.0 * 1024.0);
}

// Runs `step`, prints its wall time and the peak memory so far; false (and the reason) on failure.
bool Timed(const char* name, const std::function<Status()>& step, double* seconds) {
  ResetPeakRss();
  const double start_mb = StatusMb("VmRSS");
  const auto start = std::chrono::steady_clock::now();
  const Status status = step();
  *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!status.ok()) {
    std::fprintf(stderr, "%s failed: %s\n", name, status.message().c_str());
    return false;
  }
  const double peak_mb = StatusMb("VmHWM");
  std::printf("%-44s %8.3f s   peak RSS %7.1f MB (%+7.1f MB over its start)\n", name, *seconds,
              peak_mb, peak_mb - start_mb);
  std::fflush(stdout);
  return true;
}

bool TimedCommand(const char* name, const std::string& command, double* seconds) {
  return Timed(
      name,
      [&] {
        return std::system((command + " > /dev/null 2>&1").c_str()) == 0
                   ? Status::Ok()
                   : Status::Error("'" + command + "' failed");
      },
      seconds);
}

bool Flag(const std::string& arg, const char* name, std::string* value) {
  const std::string prefix = std::string("--") + name + "=";
  if (arg.compare(0, prefix.size(), prefix) != 0) return false;
  *value = arg.substr(prefix.size());
  return true;
}

// What the command line asks for.
struct Arguments {
  SyntheticBlockOptions block = BenchmarkBlockOptions();
  std::string out_dir;
  bool peer = true;  // time colmap's own reader and writer when it is on the PATH
};

// Parses the flags of the comment at the top; false (and the reason on stderr) on a bad one.
bool ParseArguments(int argc, char** argv, Arguments* arguments) {
  SyntheticBlockOptions& options = arguments->block;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    std::string v;
    if (Flag(arg, "out_dir", &v)) {
      arguments->out_dir = v;
    } else if (Flag(arg, "lines", &v)) {
      options.num_lines = std::stoi(v);
    } else if (Flag(arg, "images_per_line", &v)) {
      options.images_per_line = std::stoi(v);
    } else if (Flag(arg, "forward_spacing_m", &v)) {
      options.forward_spacing_m = std::stod(v);
    } else if (Flag(arg, "side_spacing_m", &v)) {
      options.side_spacing_m = std::stod(v);
    } else if (Flag(arg, "tie_points", &v)) {
      options.num_tie_points = std::stoll(v);
    } else if (Flag(arg, "seed", &v)) {
      options.seed = std::stoull(v);
    } else if (arg == "--no_peer") {
      arguments->peer = false;
    } else {
      std::fprintf(stderr, "unknown argument '%s' (see the comment at the top of %s)\n",
                   arg.c_str(), __FILE__);
      return false;
    }
  }
  if (arguments->out_dir.empty()) {
    std::fprintf(stderr, "--out_dir=DIR is required\n");
    return false;
  }
  return true;
}

// The dataset's files below --out_dir (the comment at the top).
struct DatasetPaths {
  explicit DatasetPaths(const std::string& out_dir)
      : out_dir(out_dir),
        tables{out_dir + "/cameras.csv", out_dir + "/points.csv", out_dir + "/marks.csv",
               out_dir + "/frames.csv"},
        colmap_text(out_dir + "/colmap"),
        colmap_binary(out_dir + "/colmap_binary"),
        opensfm(out_dir + "/opensfm") {}

  std::string out_dir;
  BlockTableFiles tables;
  std::string colmap_text;    // folder of the COLMAP text model
  std::string colmap_binary;  // folder of the COLMAP binary model
  std::string opensfm;        // folder of the OpenSfM reconstruction
};

// The times the peer comparison needs, in seconds.
struct ColmapTimes {
  double write_text = 0.0;
  double read_text = 0.0;
};

// Whether a block read back holds every mark written; prints "<verb> N <what>, wrote M" if not.
bool AllMarks(const Block& block, size_t num_marks, const char* verb, const char* what) {
  if (block.marks.size() == num_marks) return true;
  std::fprintf(stderr, "%s %zu %s, wrote %zu\n", verb, block.marks.size(), what, num_marks);
  return false;
}

// Step 1: generates the block and writes it as tables (with its truth) and as COLMAP text and
// binary models; the number of marks written.
bool WriteDataset(const SyntheticBlockOptions& options, const DatasetPaths& paths,
                  size_t* num_marks, ColmapTimes* colmap) {
  std::filesystem::create_directories(paths.out_dir + "/truth");
  Block block;
  SyntheticBlockTruth truth;
  double t = 0.0;
  if (!Timed("generate (MakeSyntheticBlock)", [&] { return MakeSyntheticBlock(options, &block, &truth); },
             &t))
    return false;
  std::printf("  %zu images, %zu points, %zu marks\n", block.images.size(), block.points.size(),
              block.marks.size());
  if (!Timed("write tables (WriteBlockTables)", [&] { return WriteBlockTables(block, paths.tables); },
             &t))
    return false;
  if (!Timed("write truth (WriteSyntheticBlockTruth)",
             [&] {
               return WriteSyntheticBlockTruth(
                   block, truth, options,
                   {paths.out_dir + "/truth/frames.csv", paths.out_dir + "/truth/points.csv",
                    paths.out_dir + "/truth/blunders.csv"});
             },
             &t))
    return false;
  if (!Timed("write COLMAP text (WriteColmapModel)",
             [&] { return WriteColmapModel(paths.colmap_text, block); }, &colmap->write_text))
    return false;
  std::printf("  sizes: marks.csv %.1f MB, images.txt %.1f MB, points3D.txt %.1f MB\n",
              FileMb(paths.tables.marks), FileMb(paths.colmap_text + "/images.txt"),
              FileMb(paths.colmap_text + "/points3D.txt"));
  ColmapWriteOptions binary;
  binary.format = ColmapFormat::kBinary;
  if (!Timed("write COLMAP binary (WriteColmapModel)",
             [&] { return WriteColmapModel(paths.colmap_binary, block, nullptr, binary); }, &t))
    return false;
  std::printf("  sizes: images.bin %.1f MB, points3D.bin %.1f MB\n",
              FileMb(paths.colmap_binary + "/images.bin"),
              FileMb(paths.colmap_binary + "/points3D.bin"));
  *num_marks = block.marks.size();
  return true;
}

// Step 2: reads the COLMAP text model, writes it as an OpenSfM reconstruction (its COLMAP pinhole
// camera) and reads that, then reads the COLMAP binary model.
bool ReadModels(const DatasetPaths& paths, size_t num_marks, ColmapTimes* colmap) {
  double t = 0.0;
  Block again;
  if (!Timed("read COLMAP text (ReadColmapModel)",
             [&] { return ReadColmapModel(paths.colmap_text, &again); }, &colmap->read_text) ||
      !AllMarks(again, num_marks, "read", "marks"))
    return false;
  std::filesystem::create_directories(paths.opensfm);
  if (!Timed("write OpenSfM (WriteOpenSfmReconstruction)",
             [&] { return WriteOpenSfmReconstruction(paths.opensfm, again); }, &t))
    return false;
  std::printf("  sizes: reconstruction.json %.1f MB, tracks.csv %.1f MB\n",
              FileMb(paths.opensfm + "/reconstruction.json"), FileMb(paths.opensfm + "/tracks.csv"));
  again = Block();
  if (!Timed("read OpenSfM (ReadOpenSfmReconstruction)",
             [&] { return ReadOpenSfmReconstruction(paths.opensfm, &again); }, &t) ||
      !AllMarks(again, num_marks, "read", "OpenSfM marks"))
    return false;
  again = Block();
  return Timed("read COLMAP binary (ReadColmapModel)",
               [&] { return ReadColmapModel(paths.colmap_binary, &again); }, &t) &&
         AllMarks(again, num_marks, "read", "marks from the binary model");
}

// Step 3: the tables as `photopose bundle --cameras --points --marks --frames` reads them
// (ReadBlock), step by step: each table, then the assembly of the block from them; then ReadBlock
// at once.
bool ReadTables(const BlockTableFiles& files, size_t num_marks) {
  double t = 0.0;
  {
    std::vector<ImageMark> marks;
    if (!Timed("read marks table (ReadImageMarks)",
               [&] { return ReadImageMarks(files.marks, &marks); }, &t))
      return false;
  }
  {
    BlockTables tables;
    tables.cameras_file = files.cameras;
    tables.points_file = files.points;
    tables.marks_file = files.marks;
    tables.frames_file = files.frames;
    FramesTableOptions frames_options;
    frames_options.cameras = &tables.cameras;
    Block assembled;
    if (!Timed("read camera table (ReadCameraTable)",
               [&] { return ReadCameraTable(files.cameras, &tables.cameras); }, &t) ||
        !Timed("read points table (ReadGroundPoints)",
               [&] { return ReadGroundPoints(files.points, &tables.points); }, &t) ||
        !Timed("read frames table (ReadFramesTable)",
               [&] { return ReadFramesTable(files.frames, frames_options, &tables.frames); }, &t) ||
        !Timed("read marks table again (ReadImageMarks)",
               [&] { return ReadImageMarks(files.marks, &tables.marks); }, &t) ||
        !Timed("assemble the block (AssembleBlock)",
               [&] { return AssembleBlock(tables, &assembled); }, &t) ||
        !AllMarks(assembled, num_marks, "assembled", "marks"))
      return false;
  }
  BlockFiles block_files;
  block_files.cameras = files.cameras;
  block_files.points = files.points;
  block_files.marks = files.marks;
  block_files.frames = files.frames;
  Block block;
  return Timed("read the block from tables (ReadBlock)",
               [&] { return ReadBlock(block_files, &block); }, &t);
}

// Step 4: colmap's own converter on the same model, when it is on the PATH.
bool RunPeer(const DatasetPaths& paths, const ColmapTimes& colmap) {
  if (std::system("command -v colmap > /dev/null 2>&1") != 0) {
    std::printf("  (colmap not on the PATH: no peer)\n");
    return true;
  }
  const std::string bin_dir = paths.out_dir + "/colmap_bin", txt_dir = paths.out_dir + "/colmap_txt";
  std::filesystem::create_directories(bin_dir);
  std::filesystem::create_directories(txt_dir);
  double peer_read = 0.0, peer_write = 0.0;
  if (!TimedCommand("peer: colmap model_converter TXT -> BIN",
                    "colmap model_converter --input_path " + paths.colmap_text +
                        " --output_path " + bin_dir + " --output_type BIN",
                    &peer_read) ||
      !TimedCommand("peer: colmap model_converter BIN -> TXT",
                    "colmap model_converter --input_path " + bin_dir + " --output_path " +
                        txt_dir + " --output_type TXT",
                    &peer_write))
    return false;
  std::printf("  photopose reads the text model in %.2fx, writes it in %.2fx the time COLMAP\n"
              "  takes to read it and write binary / read binary and write it (whole processes)\n",
              colmap.read_text / peer_read, colmap.write_text / peer_write);
  return true;
}

int Run(int argc, char** argv) {
  Arguments arguments;
  if (!ParseArguments(argc, argv, &arguments)) return 2;
  const DatasetPaths paths(arguments.out_dir);
  size_t num_marks = 0;
  ColmapTimes colmap;
  if (!WriteDataset(arguments.block, paths, &num_marks, &colmap) ||
      !ReadModels(paths, num_marks, &colmap) || !ReadTables(paths.tables, num_marks))
    return 1;
  if (!arguments.peer) {
    std::printf("  (colmap not on the PATH: no peer)\n");
    return 0;
  }
  return RunPeer(paths, colmap) ? 0 : 1;
}

}  // namespace
}  // namespace photopose

int main(int argc, char** argv) { return photopose::Run(argc, argv); }
