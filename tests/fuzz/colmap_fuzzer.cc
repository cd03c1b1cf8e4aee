// libFuzzer harness: the COLMAP text model reader (core/io/colmap.h) on arbitrary bytes, cut at
// the first two NUL bytes into cameras.txt, images.txt and points3D.txt. A message must be one
// clean line whose echoed tokens are cut; what the reader accepts must be inside the documented
// limits, and a model it accepts must be written and read back with as many images, points and
// marks.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "core/io/colmap.h"
#include "core/io/tables.h"
#include "tests/fuzz/fuzz_util.h"

namespace {

void Require(bool condition) {
  if (!condition) std::abort();
}

// The text up to the next NUL byte (all of it when there is none); *rest is what follows it.
std::string_view NextPart(std::string_view* rest) {
  const size_t end = rest->find('\0');
  const std::string_view part = rest->substr(0, end);
  rest->remove_prefix(end == std::string_view::npos ? rest->size() : end + 1);
  return part;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view rest(reinterpret_cast<const char*>(data), size);
  photopose::ColmapModelFiles text;
  text.cameras = std::string(NextPart(&rest));
  text.images = std::string(NextPart(&rest));
  text.points3D = std::string(rest);
  photopose::Block block;
  photopose::ColmapModelExtras extras;
  const photopose::Status status = photopose::ParseColmapModel(text, "model", &block, &extras);
  photopose::fuzz::CheckMessage(status);
  photopose::fuzz::CheckMessageLength(status);
  if (!status.ok()) return 0;
  photopose::fuzz::CheckColmapBlockLimits(block);
  photopose::ColmapModelFiles written;
  if (!photopose::FormatColmapModel(block, &extras, photopose::ColmapWriteOptions(), &written).ok())
    return 0;
  photopose::Block again;
  Require(photopose::ParseColmapModel(written, "model", &again).ok());
  Require(again.images.size() == block.images.size() &&
          again.points.size() == block.points.size() &&
          again.marks.size() == block.marks.size());
  return 0;
}
