// Reading rasters through GDAL into the core's types.
#pragma once
#include <array>
#include <optional>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "contour/contour.hpp"

namespace lodforge {

// Which pixels are buildings: class values of a one-band raster, or an RGB colour.
struct BuildingSelector {
  std::vector<int> values{6};
  std::optional<std::array<int, 3>> rgb;
  std::string describe() const;
};

struct MaskRaster {
  cv::Mat mask;             // CV_8U, 1 = building
  GeoTransform transform;
  std::string crs_wkt;      // may be empty if the raster has none
};

// Throws InputError naming the file: missing, not a raster, no georeference, wrong band
// count for the selector, or no building pixel at all.
MaskRaster read_building_mask(const std::string& path, const BuildingSelector& selector);

}  // namespace lodforge
