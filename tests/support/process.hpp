// Test helpers for running the lodforge binary and other commands, and reading files back.
#pragma once
#include <filesystem>
#include <map>
#include <string>

namespace lodforge::test {

struct CommandOutput {
  int code;            // exit code, -1 if killed
  std::string output;  // standard output and error together
};

CommandOutput shell(const std::string& command);
CommandOutput lodforge(const std::string& arguments);  // the built binary with these arguments
std::string slurp(const std::filesystem::path& path);
// id -> footprint WKT of the features of a vector file's first layer (a failure to open it fails
// the test and gives none).
std::map<long, std::string> gpkg_footprints(const std::filesystem::path& file);

// A fresh directory per test, named after it, removed when the test passes (kept when it fails).
std::filesystem::path fresh_test_directory(const std::string& prefix);

}  // namespace lodforge::test
