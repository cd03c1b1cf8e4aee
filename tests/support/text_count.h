#pragma once
// How often a string occurs in a text (overlapping occurrences counted), for tests of generated
// pages and reports.
#include <cstddef>
#include <string>

namespace photopose::testing {

inline size_t CountOccurrences(const std::string& text, const std::string& what) {
  size_t count = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++count;
  return count;
}

}  // namespace photopose::testing
