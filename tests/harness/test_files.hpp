#pragma once
// The test data (tests/data, or PERISHELL_TEST_DATA_DIR where the binaries run away from the
// source tree) and whole files read as text.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace perishell_test {

// This header's directory is tests/harness, whatever the build directory.
inline const std::filesystem::path testsDirectory = std::filesystem::path(__FILE__).parent_path().parent_path();

inline const std::filesystem::path testDataDirectory = std::getenv("PERISHELL_TEST_DATA_DIR")
                                                           ? std::filesystem::path(std::getenv("PERISHELL_TEST_DATA_DIR"))
                                                           : testsDirectory / "data";

inline std::string readTextFile(const std::filesystem::path& path) {
  std::ifstream file(path);
  std::ostringstream text;
  text << file.rdbuf();
  return text.str();
}

}  // namespace perishell_test
