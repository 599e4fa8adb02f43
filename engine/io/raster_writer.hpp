// Writes georeferenced rasters (GeoTIFF, DEFLATE, tiled) atomically: temporary name, then rename.
#pragma once
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "contour/contour.hpp"

namespace lodforge {

struct RasterMeta {
  GeoTransform transform;
  std::string crs_wkt;
  double nodata = 0;
  bool has_nodata = false;
};

// bands: one or more CV_8U or CV_32F images of equal size (one type for all).
void write_geotiff(const std::string& path, const std::vector<cv::Mat>& bands, const RasterMeta& meta);

// WKT of an EPSG code (throws InputError if unknown).
std::string epsg_wkt(int epsg);

}  // namespace lodforge
