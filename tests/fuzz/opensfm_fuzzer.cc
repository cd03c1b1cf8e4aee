// libFuzzer harness: the OpenSfM reader (core/io/opensfm.h) on arbitrary bytes, cut at the first
// two NUL bytes into reconstruction.json, tracks.csv and (when there is a second NUL)
// reference_lla.json. A message must be one clean line whose echoed tokens are cut; what the
// reader accepts must be inside the documented limits, and a reconstruction it accepts and the
// writer can hold must be read back with as many cameras, images, points and marks.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "core/io/opensfm.h"
#include "core/io/tables.h"
#include "tests/fuzz/fuzz_util.h"

namespace {

void Require(bool condition) {
  if (!condition) std::abort();
}

// The text up to the next NUL byte (all of it when there is none); *rest is what follows it and
// *found whether there was a NUL.
std::string_view NextPart(std::string_view* rest, bool* found) {
  const size_t end = rest->find('\0');
  *found = end != std::string_view::npos;
  const std::string_view part = rest->substr(0, end);
  rest->remove_prefix(*found ? end + 1 : rest->size());
  return part;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view rest(reinterpret_cast<const char*>(data), size);
  photopose::OpenSfmText text;
  bool found = false;
  text.reconstruction_json = std::string(NextPart(&rest, &found));
  text.tracks_csv = std::string(NextPart(&rest, &found));
  if (found) text.reference_lla_json = std::string(rest);
  photopose::Block block;
  photopose::OpenSfmExtras extras;
  const photopose::Status status =
      photopose::ParseOpenSfmReconstruction(text, "opensfm/reconstruction.json", &block, &extras);
  photopose::fuzz::CheckMessage(status);
  photopose::fuzz::CheckMessageLength(status);
  if (!status.ok()) return 0;
  for (const photopose::BlockCamera& camera : block.cameras)
    Require(camera.params[0] >= photopose::kMinFocalLengthPx &&
            camera.params[0] <= photopose::kMaxCoordinate && camera.table.n_columns >= 1 &&
            camera.table.n_rows >= 1);
  for (const photopose::BlockImage& image : block.images)
    Require(image.eo && image.eo->parameters.allFinite());
  for (const photopose::BlockPoint& point : block.points)
    Require(point.position_m->cwiseAbs().maxCoeff() <= photopose::kMaxCoordinate);
  for (const photopose::BlockMark& mark : block.marks)
    Require(mark.observation.cwiseAbs().maxCoeff() <= photopose::kMaxCoordinate);
  photopose::OpenSfmText written;
  const photopose::Status format = photopose::FormatOpenSfmReconstruction(block, &extras, &written);
  photopose::fuzz::CheckMessage(format);
  if (!format.ok()) return 0;
  photopose::Block again;
  Require(photopose::ParseOpenSfmReconstruction(written, "again/reconstruction.json", &again).ok());
  Require(again.cameras.size() == block.cameras.size() &&
          again.images.size() == block.images.size() &&
          again.points.size() == block.points.size() && again.marks.size() == block.marks.size());
  return 0;
}
