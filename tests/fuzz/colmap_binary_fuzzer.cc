// libFuzzer harness: the COLMAP binary model reader (core/io/colmap.h) on arbitrary bytes, two
// ways per input:
//  1. as the three binary files: two little-endian uint32 lengths (cameras.bin, images.bin; cut
//     to what is there), then the files, points3D.bin the rest;
//  2. as a text model (cut at the first two NUL bytes, as colmap_fuzzer.cc does): a model the
//     text reader accepts is written as binary, which must read back as the same model, and then
//     read again cut short and with one byte changed (where and which from the input), so that
//     the text seeds of the documentation reach deep into the binary records.
// A message must be one clean line whose echoed tokens are cut; what the reader accepts must be
// inside the documented limits and written and read back with as many images, points and marks,
// in both formats.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "core/io/colmap.h"
#include "core/io/tables.h"
#include "tests/fuzz/fuzz_util.h"

namespace {

using photopose::Block;
using photopose::ColmapFormat;
using photopose::ColmapModelExtras;
using photopose::ColmapModelFiles;
using photopose::ColmapWriteOptions;

void Require(bool condition) {
  if (!condition) std::abort();
}

uint32_t U32(std::string_view bytes, size_t at) {
  uint32_t v = 0;
  for (size_t k = 0; k < 4 && at + k < bytes.size(); ++k)
    v |= static_cast<uint32_t>(static_cast<unsigned char>(bytes[at + k])) << (8 * k);
  return v;
}

std::string_view Take(std::string_view* rest, size_t size) {
  const std::string_view part = rest->substr(0, size);
  rest->remove_prefix(part.size());
  return part;
}

std::string_view NextPart(std::string_view* rest) {
  const size_t end = rest->find('\0');
  const std::string_view part = rest->substr(0, end);
  rest->remove_prefix(end == std::string_view::npos ? rest->size() : end + 1);
  return part;
}

bool SameCounts(const Block& a, const Block& b) {
  return a.images.size() == b.images.size() && a.points.size() == b.points.size() &&
         a.marks.size() == b.marks.size();
}

// Parses `files`; an accepted model must be within the limits and survive both writers.
void CheckModel(const ColmapModelFiles& files) {
  Block block;
  ColmapModelExtras extras;
  const photopose::Status status = photopose::ParseColmapModel(files, "model", &block, &extras);
  photopose::fuzz::CheckMessage(status);
  photopose::fuzz::CheckMessageLength(status);
  if (!status.ok()) return;
  photopose::fuzz::CheckColmapBlockLimits(block);
  for (const ColmapFormat format : {ColmapFormat::kBinary, ColmapFormat::kText}) {
    ColmapWriteOptions options;
    options.format = format;
    ColmapModelFiles written;
    if (!photopose::FormatColmapModel(block, &extras, options, &written).ok()) continue;
    Block again;
    Require(photopose::ParseColmapModel(written, "model", &again).ok());
    Require(SameCounts(again, block));
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view input(reinterpret_cast<const char*>(data), size);

  // 1. Three binary files.
  {
    std::string_view rest = input.substr(std::min<size_t>(8, input.size()));
    ColmapModelFiles files;
    files.format = ColmapFormat::kBinary;
    files.cameras = std::string(Take(&rest, U32(input, 0)));
    files.images = std::string(Take(&rest, U32(input, 4)));
    files.points3D = std::string(rest);
    CheckModel(files);
  }

  // 2. A text model, written as binary, then damaged.
  std::string_view rest = input;
  ColmapModelFiles text;
  text.cameras = std::string(NextPart(&rest));
  text.images = std::string(NextPart(&rest));
  text.points3D = std::string(rest);
  Block block;
  ColmapModelExtras extras;
  if (!photopose::ParseColmapModel(text, "model", &block, &extras).ok()) return 0;
  ColmapWriteOptions options;
  options.format = ColmapFormat::kBinary;
  ColmapModelFiles binary;
  if (!photopose::FormatColmapModel(block, &extras, options, &binary).ok()) return 0;
  Block again;
  Require(photopose::ParseColmapModel(binary, "model", &again).ok());
  Require(SameCounts(again, block));
  // Where to cut and what to change: from a hash of the input.
  uint64_t hash = 1469598103934665603ULL;
  for (const char c : input) hash = (hash ^ static_cast<unsigned char>(c)) * 1099511628211ULL;
  std::string* file[] = {&binary.cameras, &binary.images, &binary.points3D};
  std::string& damaged = *file[hash % 3];
  if (damaged.empty()) return 0;
  const size_t at = (hash >> 8) % damaged.size();
  const ColmapModelFiles kept = binary;
  damaged[at] = static_cast<char>(damaged[at] ^ static_cast<char>((hash >> 40) | 1));
  CheckModel(binary);
  binary = kept;
  file[hash % 3]->resize(at);
  CheckModel(binary);
  return 0;
}
