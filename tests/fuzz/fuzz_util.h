#pragma once
// Shared checks of the libFuzzer harnesses: what every error message must satisfy.
#include <cstdlib>
#include <string>

#include "core/block.h"
#include "core/io/csv.h"
#include "core/io/tables.h"
#include "core/status.h"

namespace photopose::fuzz {

// An error message is one line of printable UTF-8: EscapeForMessage leaves it as it is.
inline void CheckMessage(const Status& status) {
  if (status.ok()) return;
  const std::string& message = status.message();
  if (message.empty() || EscapeForMessage(message) != message) std::abort();
}

// An error message repeats no more than a few dozen characters of any token of the input: it
// stays short however long the input (file names and fixed text fill the rest).
inline void CheckMessageLength(const Status& status) {
  constexpr size_t kMaxMessageBytes = 1000;
  if (!status.ok() && status.message().size() > kMaxMessageBytes) std::abort();
}

// A block a COLMAP reader accepted is inside the documented limits (core/io/colmap.h): focal
// lengths, finite poses, point coordinates.
inline void CheckColmapBlockLimits(const Block& block) {
  for (const BlockCamera& camera : block.cameras) {
    if (!(camera.params[0] >= kMinFocalLengthPx && camera.params[0] <= kMaxCoordinate))
      std::abort();
  }
  for (const BlockImage& image : block.images)
    if (!image.eo || !image.eo->parameters.allFinite()) std::abort();
  for (const BlockPoint& point : block.points)
    if (!(point.position_m->cwiseAbs().maxCoeff() <= kMaxCoordinate)) std::abort();
}

}  // namespace photopose::fuzz
