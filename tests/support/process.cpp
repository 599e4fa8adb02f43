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

std::filesystem::path fresh_test_directory(const std::string& prefix) {
  const auto dir = std::filesystem::temp_directory_path() /
                   (prefix + "_" + std::to_string(::getpid()) + "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace lodforge::test
