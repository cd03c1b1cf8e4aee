// libFuzzer harness: the BAL problem reader (core/io/bal.h) on arbitrary bytes. A message must be
// one clean line whose echoed tokens are cut; what the reader accepts must be inside the
// documented limits (docs/formats.md, "Limits and refusals").
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "core/io/bal.h"
#include "core/io/tables.h"
#include "tests/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  photopose::Block block;
  const photopose::Status status = photopose::ParseBalProblem(text, "problem.txt", &block);
  photopose::fuzz::CheckMessage(status);
  photopose::fuzz::CheckMessageLength(status);
  if (!status.ok()) return 0;
  for (const photopose::BlockCamera& camera : block.cameras) {
    const double f = std::abs(camera.params[0]);
    if (!(f >= photopose::kMinFocalLengthPx && f <= photopose::kMaxCoordinate)) std::abort();
  }
  for (const photopose::BlockImage& image : block.images)
    if (!image.eo || !image.eo->parameters.allFinite()) std::abort();
  for (const photopose::BlockPoint& point : block.points)
    if (!(point.position_m->cwiseAbs().maxCoeff() <= photopose::kMaxCoordinate)) std::abort();
  for (const photopose::BlockMark& mark : block.marks)
    if (!(mark.measured.cwiseAbs().maxCoeff() <= photopose::kMaxCoordinate)) std::abort();
  return 0;
}
