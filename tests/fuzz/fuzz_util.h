#pragma once
// Shared checks of the libFuzzer harnesses: what every error message must satisfy.
#include <cstdlib>
#include <string>

#include "core/io/csv.h"
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

}  // namespace photopose::fuzz
