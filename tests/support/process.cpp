#include "support/process.hpp"

#include <array>
#include <cstdio>
#include <fstream>
#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <ogrsf_frmts.h>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

namespace lodforge::test {

CommandOutput shell(const std::string& command) {
  CommandOutput result{-1, {}};
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return result;
  std::array<char, 4096> buffer;
  while (std::size_t n = fread(buffer.data(), 1, buffer.size(), pipe)) result.output.append(buffer.data(), n);
  const int status = pclose(pipe);
  result.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

CommandOutput lodforge(const std::string& arguments) { return shell(std::string(LODFORGE_BINARY) + " " + arguments); }

std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::map<long, std::string> gpkg_footprints(const std::filesystem::path& file) {
  GDALAllRegister();
  std::map<long, std::string> out;
  GDALDataset* d = static_cast<GDALDataset*>(GDALOpenEx(file.c_str(), GDAL_OF_VECTOR, nullptr, nullptr, nullptr));
  EXPECT_NE(d, nullptr) << file;
  if (!d) return out;
  for (auto& f : *d->GetLayer(0)) {
    char* wkt = nullptr;
    f->GetGeometryRef()->exportToWkt(&wkt);
    out[long(f->GetFieldAsInteger64("id"))] = wkt;
    CPLFree(wkt);
  }
  GDALClose(d);
  return out;
}

namespace {

// Removes the directories fresh_test_directory made for a test when the test has passed; a failed
// test's stay, for a look, and their paths are printed.
class RemoveTestDirectories : public ::testing::EmptyTestEventListener {
 public:
  std::vector<std::filesystem::path> made;

  void OnTestEnd(const ::testing::TestInfo& info) override {
    for (const std::filesystem::path& dir : made) {
      if (info.result() && info.result()->Failed()) {
        if (std::filesystem::exists(dir)) std::fprintf(stderr, "kept for a look at the failed test: %s\n", dir.c_str());
        continue;
      }
      std::error_code ignored;
      std::filesystem::remove_all(dir, ignored);
    }
    made.clear();
  }
};

RemoveTestDirectories& test_directories() {
  // (Appended once, on the first test that asks for a directory; gtest owns it from then on.)
  static RemoveTestDirectories* listener = [] {
    auto* l = new RemoveTestDirectories;
    ::testing::UnitTest::GetInstance()->listeners().Append(l);
    return l;
  }();
  return *listener;
}

}  // namespace

std::filesystem::path fresh_test_directory(const std::string& prefix) {
  const auto dir = std::filesystem::temp_directory_path() /
                   (prefix + "_" + std::to_string(::getpid()) + "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  test_directories().made.push_back(dir);
  return dir;
}

}  // namespace lodforge::test
