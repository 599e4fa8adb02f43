#include "io/height_reader.hpp"

#include "io/block_cache.hpp"

#include <cmath>
#include <limits>
#include <cstdio>
#include <filesystem>
#include <unistd.h>
#include <gdal_priv.h>
#include <opencv2/core.hpp>
#include <gdal_utils.h>
#include <ogr_spatialref.h>

#include "io/errors.hpp"

namespace lodforge {

namespace {
std::string exact(double v) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.17g", v);
  return buffer;
}
}  // namespace

std::string aligned_source(const std::string& path, const GridSpec& grid, const std::string& vrt_path, bool heights) {
  GDALAllRegister();
  GDALDatasetH source = GDALOpen(path.c_str(), GA_ReadOnly);
  if (!source) throw InputError("'" + path + "': not a raster GDAL can read");
  std::array<double, 6> gt{};
  GDALGetGeoTransform(source, gt.data());
  const bool same_grid = GDALGetRasterXSize(source) == grid.size.width && GDALGetRasterYSize(source) == grid.size.height &&
                         gt == grid.transform.c;
  if (same_grid) {
    GDALClose(source);
    return path;
  }
  const Vec2 a = grid.transform.to_map(0, 0), b = grid.transform.to_map(grid.size.width, grid.size.height);
  std::vector<std::string> words = {"-of", "VRT", "-r", "bilinear", "-te", exact(std::min(a.x(), b.x())),
                                    exact(std::min(a.y(), b.y())), exact(std::max(a.x(), b.x())),
                                    exact(std::max(a.y(), b.y())), "-ts", std::to_string(grid.size.width),
                                    std::to_string(grid.size.height)};
  if (heights) for (const char* w : {"-ot", "Float32", "-dstnodata", "nan"}) words.push_back(w);
  if (!grid.crs_wkt.empty()) { words.push_back("-t_srs"); words.push_back(grid.crs_wkt); }
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  GDALWarpAppOptions* options = GDALWarpAppOptionsNew(argv.data(), nullptr);
  int error = 0;
  // Written under a temporary name and renamed: concurrent shards may read the same file.
  const std::string temp = vrt_path + ".tmp-" + std::to_string(getpid());
  GDALDatasetH warped = GDALWarp(temp.c_str(), nullptr, 1, &source, options, &error);
  GDALWarpAppOptionsFree(options);
  GDALClose(source);
  if (!warped || error) throw InputError("'" + path + "': cannot resample onto the segmentation's grid: " + CPLGetLastErrorMsg());
  GDALClose(warped);
  std::filesystem::rename(temp, vrt_path);
  return vrt_path;
}

struct HeightWindowReader::Impl {
  GDALDataset* dataset = nullptr;
  std::string path;
  BlockCache* cache = nullptr;
};

HeightWindowReader::HeightWindowReader(const std::string& path, BlockCache* cache) : impl_(new Impl) {
  impl_->path = path;
  impl_->cache = cache;
  impl_->dataset = static_cast<GDALDataset*>(GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
  if (!impl_->dataset) {
    delete impl_;
    throw InputError("'" + path + "': not a raster GDAL can read");
  }
}

HeightWindowReader::~HeightWindowReader() {
  GDALClose(impl_->dataset);
  delete impl_;
}

HeightRaster HeightWindowReader::read(const cv::Rect& w, const GeoTransform& grid) const {
  HeightRaster r;
  r.values.create(w.height, w.width, CV_32F);
  GDALRasterBand* band = impl_->dataset->GetRasterBand(1);
  read_window(impl_->cache, *impl_->dataset, impl_->path, 1, GDT_Float32, w, r.values.data);
  int has_nodata = 0;
  const double nodata = band->GetNoDataValue(&has_nodata);
  // Valid: finite (|v| <= FLT_MAX is false for NaN and infinities) and not nodata; 1 or 0. One
  // pass, vectorised by the compiler (a NaN nodata is not finite already, so it never matches).
  r.valid.create(w.height, w.width, CV_8U);
  const float* v = r.values.ptr<float>();
  uint8_t* valid = r.valid.ptr<uint8_t>();
  const float no = has_nodata && std::isfinite(nodata) ? float(nodata) : std::numeric_limits<float>::quiet_NaN();
  const std::size_t n = r.values.total();
  for (std::size_t i = 0; i < n; ++i)
    valid[i] = uint8_t((std::abs(v[i]) <= std::numeric_limits<float>::max()) & (v[i] != no));
  r.transform = grid.window(w.x, w.y);
  return r;
}

}  // namespace lodforge
