// Reads windows of a DSM or DTM on the segmentation's grid. A raster on another grid or CRS is
// resampled on the fly through a GDAL warped VRT (bilinear), made once per run.
#pragma once
#include <opencv2/core/mat.hpp>
#include <string>

#include "heights/heights.hpp"

namespace lodforge {

struct GridSpec {
  cv::Size size;
  GeoTransform transform;
  std::string crs_wkt;
};

// When the raster at path is not on grid, writes a warped VRT of it onto grid at vrt_path
// (atomically) and returns that path; else returns path unchanged. heights: resample to Float32
// with NaN where the source has no data (so uncovered pixels never count as height 0).
std::string aligned_source(const std::string& path, const GridSpec& grid, const std::string& vrt_path, bool heights);

// One per thread.
class BlockCache;

class HeightWindowReader {
 public:
  // cache: blocks shared with the other threads' readers (nullptr: GDAL's own, per handle).
  explicit HeightWindowReader(const std::string& path, BlockCache* cache = nullptr);
  ~HeightWindowReader();
  HeightWindowReader(const HeightWindowReader&) = delete;
  HeightWindowReader& operator=(const HeightWindowReader&) = delete;
  // The window in the source's pixels; nodata and non-finite values are marked invalid.
  HeightRaster read(const cv::Rect& window, const GeoTransform& grid_transform) const;

 private:
  struct Impl;
  Impl* impl_;
};

}  // namespace lodforge
