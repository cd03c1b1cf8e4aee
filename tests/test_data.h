#pragma once
// Where tests find the shared real datasets and the photopose executable.
#include <string>

namespace photopose::testing {

inline std::string SharedDataPath(const std::string& relative) {
  return std::string(PHOTOPOSE_SHARED_DATA_DIR) + "/" + relative;
}
inline std::string SourcePath(const std::string& relative) {
  return std::string(PHOTOPOSE_SOURCE_DIR) + "/" + relative;
}
inline std::string CliPath() { return PHOTOPOSE_CLI_PATH; }

}  // namespace photopose::testing
