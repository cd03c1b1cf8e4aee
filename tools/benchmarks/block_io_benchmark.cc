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

int Run(int argc, char** argv) {
  SyntheticBlockOptions options = BenchmarkBlockOptions();
  std::string out_dir;
  bool peer = true;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    std::string v;
    if (Flag(arg, "out_dir", &v)) {
      out_dir = v;
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
      peer = false;
    } else {
      std::fprintf(stderr, "unknown argument '%s' (see the comment at the top of %s)\n",
                   arg.c_str(), __FILE__);
      return 2;
    }
  }
  if (out_dir.empty()) {
    std::fprintf(stderr, "--out_dir=DIR is required\n");
    return 2;
  }
  std::filesystem::create_directories(out_dir + "/truth");
  const std::string colmap_dir = out_dir + "/colmap";
  const BlockTableFiles files{out_dir + "/cameras.csv", out_dir + "/points.csv",
                              out_dir + "/marks.csv", out_dir + "/frames.csv"};

  Block block;
  SyntheticBlockTruth truth;
  double t = 0.0, colmap_read = 0.0, colmap_write = 0.0;
  if (!Timed("generate (MakeSyntheticBlock)", [&] { return MakeSyntheticBlock(options, &block, &truth); },
             &t))
    return 1;
  std::printf("  %zu images, %zu points, %zu marks\n", block.images.size(), block.points.size(),
              block.marks.size());
  if (!Timed("write tables (WriteBlockTables)", [&] { return WriteBlockTables(block, files); }, &t))
    return 1;
  if (!Timed("write truth (WriteSyntheticBlockTruth)",
             [&] {
               return WriteSyntheticBlockTruth(
                   block, truth, options,
                   {out_dir + "/truth/frames.csv", out_dir + "/truth/points.csv",
                    out_dir + "/truth/blunders.csv"});
             },
             &t))
    return 1;
  if (!Timed("write COLMAP text (WriteColmapModel)",
             [&] { return WriteColmapModel(colmap_dir, block); }, &colmap_write))
    return 1;
  std::printf("  sizes: marks.csv %.1f MB, images.txt %.1f MB, points3D.txt %.1f MB\n",
              FileMb(files.marks), FileMb(colmap_dir + "/images.txt"),
              FileMb(colmap_dir + "/points3D.txt"));
  const std::string binary_dir = out_dir + "/colmap_binary";
  ColmapWriteOptions binary;
  binary.format = ColmapFormat::kBinary;
  if (!Timed("write COLMAP binary (WriteColmapModel)",
             [&] { return WriteColmapModel(binary_dir, block, nullptr, binary); }, &t))
    return 1;
  std::printf("  sizes: images.bin %.1f MB, points3D.bin %.1f MB\n",
              FileMb(binary_dir + "/images.bin"), FileMb(binary_dir + "/points3D.bin"));
  const size_t num_marks = block.marks.size();
  block = Block();
  truth = SyntheticBlockTruth();

  Block again;
  if (!Timed("read COLMAP text (ReadColmapModel)", [&] { return ReadColmapModel(colmap_dir, &again); },
             &colmap_read))
    return 1;
  if (again.marks.size() != num_marks) {
    std::fprintf(stderr, "read %zu marks, wrote %zu\n", again.marks.size(), num_marks);
    return 1;
  }
  // The same block (its COLMAP pinhole camera) as an OpenSfM reconstruction.
  const std::string opensfm_dir = out_dir + "/opensfm";
  std::filesystem::create_directories(opensfm_dir);
  if (!Timed("write OpenSfM (WriteOpenSfmReconstruction)",
             [&] { return WriteOpenSfmReconstruction(opensfm_dir, again); }, &t))
    return 1;
  std::printf("  sizes: reconstruction.json %.1f MB, tracks.csv %.1f MB\n",
              FileMb(opensfm_dir + "/reconstruction.json"), FileMb(opensfm_dir + "/tracks.csv"));
  again = Block();
  if (!Timed("read OpenSfM (ReadOpenSfmReconstruction)",
             [&] { return ReadOpenSfmReconstruction(opensfm_dir, &again); }, &t))
    return 1;
  if (again.marks.size() != num_marks) {
    std::fprintf(stderr, "read %zu OpenSfM marks, wrote %zu\n", again.marks.size(), num_marks);
    return 1;
  }
  again = Block();
  if (!Timed("read COLMAP binary (ReadColmapModel)",
             [&] { return ReadColmapModel(binary_dir, &again); }, &t))
    return 1;
  if (again.marks.size() != num_marks) {
    std::fprintf(stderr, "read %zu marks from the binary model, wrote %zu\n", again.marks.size(),
                 num_marks);
    return 1;
  }
  again = Block();
  std::vector<ImageMark> marks;
  if (!Timed("read marks table (ReadImageMarks)", [&] { return ReadImageMarks(files.marks, &marks); },
             &t))
    return 1;
  marks.clear();
  marks.shrink_to_fit();
  // The tables as `photopose bundle --cameras --points --marks --frames` reads them (ReadBlock),
  // step by step: each table, then the assembly of the block from them.
  BlockTables tables;
  tables.cameras_file = files.cameras;
  tables.points_file = files.points;
  tables.marks_file = files.marks;
  tables.frames_file = files.frames;
  if (!Timed("read camera table (ReadCameraTable)",
             [&] { return ReadCameraTable(files.cameras, &tables.cameras); }, &t))
    return 1;
  if (!Timed("read points table (ReadGroundPoints)",
             [&] { return ReadGroundPoints(files.points, &tables.points); }, &t))
    return 1;
  FramesTableOptions frames_options;
  frames_options.cameras = &tables.cameras;
  if (!Timed("read frames table (ReadFramesTable)",
             [&] { return ReadFramesTable(files.frames, frames_options, &tables.frames); }, &t))
    return 1;
  if (!Timed("read marks table again (ReadImageMarks)",
             [&] { return ReadImageMarks(files.marks, &tables.marks); }, &t))
    return 1;
  if (!Timed("assemble the block (AssembleBlock)", [&] { return AssembleBlock(tables, &again); },
             &t))
    return 1;
  if (again.marks.size() != num_marks) {
    std::fprintf(stderr, "assembled %zu marks, wrote %zu\n", again.marks.size(), num_marks);
    return 1;
  }
  tables = BlockTables();
  again = Block();
  BlockFiles block_files;
  block_files.cameras = files.cameras;
  block_files.points = files.points;
  block_files.marks = files.marks;
  block_files.frames = files.frames;
  if (!Timed("read the block from tables (ReadBlock)",
             [&] { return ReadBlock(block_files, &again); }, &t))
    return 1;
  again = Block();

  if (peer && std::system("command -v colmap > /dev/null 2>&1") == 0) {
    const std::string bin_dir = out_dir + "/colmap_bin", txt_dir = out_dir + "/colmap_txt";
    std::filesystem::create_directories(bin_dir);
    std::filesystem::create_directories(txt_dir);
    double peer_read = 0.0, peer_write = 0.0;
    if (!TimedCommand("peer: colmap model_converter TXT -> BIN",
                      "colmap model_converter --input_path " + colmap_dir + " --output_path " +
                          bin_dir + " --output_type BIN",
                      &peer_read))
      return 1;
    if (!TimedCommand("peer: colmap model_converter BIN -> TXT",
                      "colmap model_converter --input_path " + bin_dir + " --output_path " +
                          txt_dir + " --output_type TXT",
                      &peer_write))
      return 1;
    std::printf("  photopose reads the text model in %.2fx, writes it in %.2fx the time COLMAP\n"
                "  takes to read it and write binary / read binary and write it (whole processes)\n",
                colmap_read / peer_read, colmap_write / peer_write);
  } else {
    std::printf("  (colmap not on the PATH: no peer)\n");
  }
  return 0;
}

}  // namespace
}  // namespace photopose

int main(int argc, char** argv) { return photopose::Run(argc, argv); }
