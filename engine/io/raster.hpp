// Reading rasters through GDAL into the core's types.
#pragma once
#include <array>
#include <memory>
#include <optional>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "contour/contour.hpp"

class GDALDataset;

namespace lodforge {

struct DatasetCloser {
  void operator()(GDALDataset* d) const;
};
using Dataset = std::unique_ptr<GDALDataset, DatasetCloser>;

// Opens a raster read-only, or throws InputError "KEY: 'path': file not found" (not a raster GDAL
// can read, has no raster band); "KEY: " only when a key is given.
Dataset open_raster(const std::string& path, const std::string& key = "");

// Which pixels are buildings: class values of a one-band raster, an RGB colour, or the values of a
// one-band raster at or above a threshold (a network's probability or score; not its nodata value).
// A floating-point band's values are compared as they are (0.85 is not class 1).
struct BuildingSelector {
  std::vector<int> values{6};
  std::optional<std::array<int, 3>> rgb;
  std::optional<double> min;  // overrides values
  std::string describe() const;  // "value 6", "colour (0, 0, 255)", "value at least 0.5"
  std::string job_key() const;   // the job's key that selects so: "inputs.segmentation.building_values", ...
};

struct MaskRaster {
  cv::Mat mask;             // CV_8U, 1 = building
  GeoTransform transform;
  std::string crs_wkt;      // may be empty if the raster has none
};

// Whether a band holds floating-point values (Float32, Float64 and their complex kinds).
bool floating_band(GDALDataset& dataset, int band);

// A band's nodata value as its pixels hold it (a Float32 band's as a float), if it has one.
std::optional<double> band_nodata(GDALDataset& dataset, int band);

// A building mask (CV_8U, 1 = building) averaged over blocks of f x f pixels: a block is a building
// where at least half of its f^2 pixels are (pixels beyond the mask count as none). `mask`'s pixel
// (0, 0) is the first of block (0, 0); the result has `blocks` (columns and rows) blocks.
cv::Mat average_blocks(const cv::Mat& mask, cv::Size blocks, int f);

// The blocks of f x f that cover `pixels` (the last ones cut by its edges).
cv::Size blocks_of(cv::Size pixels, int f);

// The whole mask so averaged (from its first pixel), its geotransform's pixel f times as large.
MaskRaster averaged(const MaskRaster& raster, int f);

// Of one band's values (any depth), the buildings' pixels (0 / 255) by the selector's class
// values, or by its threshold (never at the band's nodata value; a NaN is below any): how
// read_building_mask and a run's windows (MaskWindowReader) select them alike. Not for a colour.
cv::Mat building_pixels(const cv::Mat& values, const BuildingSelector& selector, const std::optional<double>& nodata);

// Throws InputError naming the file: missing, not a raster, no georeference, wrong band
// count for the selector, or no building pixel at all.
MaskRaster read_building_mask(const std::string& path, const BuildingSelector& selector);

// "band 1 holds 0 (86.2 %), 255 (13.8 %): select the buildings by their value (...)": what
// a raster without a building pixel holds instead (the eight most common values, or colours
// for an RGB selector; counted on at most 4 million of its pixels), and the option that selects
// the buildings.
std::string values_held(const std::string& path, const BuildingSelector& selector);

}  // namespace lodforge
