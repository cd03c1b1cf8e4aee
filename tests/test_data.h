#pragma once
// Where tests find the shared real datasets and the photopose executable.
#include <cstdlib>
#include <string>

namespace photopose::testing {

inline std::string SharedDataPath(const std::string& relative) {
  return std::string(PHOTOPOSE_SHARED_DATA_DIR) + "/" + relative;
}
inline std::string SourcePath(const std::string& relative) {
  return std::string(PHOTOPOSE_SOURCE_DIR) + "/" + relative;
}
// The photopose executable of this build; PHOTOPOSE_TEST_CLI runs the end-to-end tests against
// another one (e.g. an older build, to see which catalogue cases it fails).
inline std::string CliPath() {
  const char* other = std::getenv("PHOTOPOSE_TEST_CLI");
  return other != nullptr && other[0] != '\0' ? other : PHOTOPOSE_CLI_PATH;
}

}  // namespace photopose::testing
