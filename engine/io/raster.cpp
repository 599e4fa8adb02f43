#include "io/raster.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <gdal_priv.h>
#include <memory>
#include <opencv2/core.hpp>

#include "io/errors.hpp"
#include "io/input_crs.hpp"

namespace lodforge {

namespace {

// A raster value for a message: an integer as one, anything else to six significant digits.
std::string value_text(double v) {
  char text[32];
  std::snprintf(text, sizeof text, v == std::floor(v) && std::abs(v) < 1e15 ? "%.0f" : "%.6g", v);
  return text;
}

// A threshold to suggest about `v`: two significant digits (0.499999 is 0.5), an integer for a
// band of whole numbers.
std::string threshold_text(double v, bool fractions) {
  if (!fractions) return value_text(std::ceil(v));
  char text[32];
  std::snprintf(text, sizeof text, "%.2g", v);
  return value_text(std::strtod(text, nullptr));
}

}  // namespace

std::string BuildingSelector::describe() const {
  if (rgb) return "colour (" + std::to_string((*rgb)[0]) + ", " + std::to_string((*rgb)[1]) + ", " + std::to_string((*rgb)[2]) + ")";
  if (min) return "value at least " + value_text(*min);
  std::string s;
  for (int v : values) s += (s.empty() ? "" : ", ") + std::to_string(v);
  return "value " + s;
}

std::string BuildingSelector::job_key() const {
  return std::string("inputs.segmentation.") + (rgb ? "building_rgb" : min ? "building_min" : "building_values");
}

bool floating_band(GDALDataset& d, int band) { return GDALDataTypeIsFloating(d.GetRasterBand(band)->GetRasterDataType()) != 0; }

std::optional<double> band_nodata(GDALDataset& d, int band) {
  GDALRasterBand* b = d.GetRasterBand(band);
  int has = 0;
  const double nodata = b->GetNoDataValue(&has);
  if (!has) return std::nullopt;
  // As the band holds it: a Float32 band's 0.1 is float(0.1), not the double 0.1.
  return b->GetRasterDataType() == GDT_Float32 || b->GetRasterDataType() == GDT_CFloat32 ? double(float(nodata)) : nodata;
}

void DatasetCloser::operator()(GDALDataset* d) const { GDALClose(d); }

Dataset open_raster(const std::string& path, const std::string& key) {
  const std::string name = (key.empty() ? "" : key + ": ") + "'" + path + "'";
  // (a path of a GDAL virtual file system, /vsizip/ or /vsicurl/, is for GDAL to judge)
  if (path.rfind("/vsi", 0) != 0 && !std::filesystem::exists(path)) throw InputError(name + ": file not found");
  GDALAllRegister();
  CPLPushErrorHandler(CPLQuietErrorHandler);
  Dataset d(static_cast<GDALDataset*>(GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr)));
  CPLPopErrorHandler();
  if (!d) throw InputError(name + ": not a raster GDAL can read");
  if (d->GetRasterCount() < 1) throw InputError(name + ": has no raster band");
  return d;
}

namespace {

// Reads band `band` in strips of rows (a whole number of the band's blocks, at least 64 rows;
// 512 rows where a block is taller, as in a GeoTIFF of one strip, whose block GDAL's cache then
// keeps) as 32-bit integers (as_double: 64-bit floats) and hands each strip to
// `use(first_row, strip)`: a strip at a time, not the whole band at 4 or 8 bytes a pixel.
template <class Use>
void read_band_strips(GDALDataset& d, int band, const std::string& path, bool as_double, Use use) {
  GDALRasterBand* b = d.GetRasterBand(band);
  int block_x = 0, block_y = 0;
  b->GetBlockSize(&block_x, &block_y);
  const int rows = d.GetRasterYSize(), cols = d.GetRasterXSize();
  const int strip = block_y > 512 ? 512 : std::max(64, block_y > 0 ? (64 + block_y - 1) / block_y * block_y : 64);
  cv::Mat buffer(std::min(strip, rows), cols, as_double ? CV_64F : CV_32S);
  for (int y = 0; y < rows; y += strip) {
    cv::Mat part = buffer.rowRange(0, std::min(strip, rows - y));
    if (b->RasterIO(GF_Read, 0, y, cols, part.rows, part.data, cols, part.rows, as_double ? GDT_Float64 : GDT_Int32, 0, 0) != CE_None)
      throw InputError("'" + path + "': cannot read band " + std::to_string(band) + ": " + CPLGetLastErrorMsg());
    use(y, part);
  }
}

// What a raster holds where no building pixel was found, for the message: the values of its first
// band (is_rgb: the colours of its first three) and their shares, the eight most common (a band of
// more values, as a probability's: their range), and the option that selects the buildings.
std::string held_values(GDALDataset& d, const std::string& path, bool is_rgb) {
  // Per value (a colour: its three bands' values), the pixels holding it, counted on at most 4
  // million pixels of it (a raster of a region read with every n-th pixel, as GDAL decimates: from
  // its overviews where it has some, which hold other values where they were averaged). A band is
  // read as 64-bit floats, which hold its values whatever its type.
  std::map<std::array<double, 3>, std::size_t> counts;
  const int bands = is_rgb ? 3 : 1, cols = d.GetRasterXSize(), rows = d.GetRasterYSize();
  const double step = std::max(1.0, std::sqrt(double(cols) * double(rows) / 4e6));
  const int w = std::max(1, int(cols / step)), h = std::max(1, int(rows / step));
  std::vector<double> buffer(std::size_t(w) * std::size_t(h) * std::size_t(bands));
  GDALRasterIOExtraArg extra;
  INIT_RASTERIO_EXTRA_ARG(extra);
  extra.eResampleAlg = GRIORA_NearestNeighbour;
  if (d.RasterIO(GF_Read, 0, 0, cols, rows, buffer.data(), w, h, GDT_Float64, bands, nullptr, int(sizeof(double)) * bands,
                 int(sizeof(double)) * bands * w, int(sizeof(double)), &extra) != CE_None)
    throw InputError("'" + path + "': cannot read it: " + CPLGetLastErrorMsg());
  std::array<std::size_t, 256> bytes{};  // (the usual values, counted without the map)
  double low = HUGE_VAL, high = -HUGE_VAL;
  const std::optional<double> nodata = band_nodata(d, 1);  // (a band's nodata value is none of its values, nor is a NaN)
  bool fractions = false;                                  // a value that is not a whole number: a probability's
  for (std::size_t k = 0; k < std::size_t(w) * std::size_t(h); ++k) {
    const double* v = &buffer[k * std::size_t(bands)];
    if (std::isnan(v[0]) || (bands == 3 && (std::isnan(v[1]) || std::isnan(v[2])))) continue;
    if (bands == 1 && nodata && v[0] == *nodata) continue;
    if (bands == 1) low = std::min(low, v[0]), high = std::max(high, v[0]), fractions |= v[0] != std::floor(v[0]);
    if (bands == 1 && v[0] >= 0 && v[0] < 256 && v[0] == std::floor(v[0])) ++bytes[std::size_t(v[0])];
    else ++counts[{v[0], bands == 3 ? v[1] : 0, bands == 3 ? v[2] : 0}];
  }
  for (int v = 0; v < 256; ++v)
    if (bytes[std::size_t(v)]) counts[{double(v), 0, 0}] += bytes[std::size_t(v)];
  std::vector<std::pair<std::size_t, std::array<double, 3>>> common;
  std::size_t total = 0;
  for (const auto& [value, count] : counts) {
    common.push_back({count, value});
    total += count;
  }
  std::sort(common.begin(), common.end(), [](const auto& a, const auto& b) { return a.first != b.first ? a.first > b.first : a.second < b.second; });
  // A band of fractions (a network's probability or score): their range, and a threshold; of more
  // whole numbers than a class raster has (bytes of a probability, or a class raster of many),
  // the most common and a threshold besides their values.
  const bool one_band = !is_rgb && d.GetRasterCount() < 3;
  const std::string threshold = " (regularize --building-min V, e.g. " + threshold_text(low + 0.5 * (high - low), fractions) +
                                "; a job's inputs.segmentation.building_min)";
  std::string text = is_rgb ? "colours are " : "band 1 holds ";
  if (common.empty()) return text + "no value but its nodata" + (nodata ? " (" + value_text(*nodata) + ")" : std::string());
  if (one_band && fractions && common.size() > 8)
    return text + std::to_string(common.size()) + " different values, from " + value_text(low) + " to " + value_text(high) +
           " (a probability or a score?): select the buildings by a threshold" + threshold;
  for (std::size_t k = 0; k < common.size() && k < 8; ++k) {
    char share[32];
    std::snprintf(share, sizeof share, "%.1f", 100.0 * double(common[k].first) / double(std::max<std::size_t>(1, total)));
    const std::array<double, 3>& c = common[k].second;
    if (k) text += ", ";
    if (is_rgb) {
      text += '(';
      for (int b = 0; b < 3; ++b) text.append(b ? ", " : "").append(value_text(c[std::size_t(b)]));
      text += ')';
    } else {
      text += value_text(c[0]);
    }
    text += std::string(" (") + share + " %)";
  }
  if (common.size() > 8) text += " and " + std::to_string(common.size() - 8) + (is_rgb ? " more colours" : " more values");
  if (is_rgb)
    text += ": select the buildings by their colour (regularize --building-rgb R,G,B; a job's inputs.segmentation.building_rgb)";
  else if (d.GetRasterCount() >= 3)
    text += ", in " + std::to_string(d.GetRasterCount()) + " bands: a colour mask's buildings are selected by their colour "
            "(regularize --building-rgb 0,0,255, ISPRS's; a job's inputs.segmentation.building_rgb)";
  else if (fractions || common.size() > 32)
    text += ": select the buildings by their value (regularize --building-value V; a job's inputs.segmentation.building_values) "
            "or, a probability or a score, by a threshold" + threshold;
  else
    text += ": select the buildings by their value (regularize --building-value V; a job's inputs.segmentation.building_values)";
  return text;
}

}  // namespace

std::string values_held(const std::string& path, const BuildingSelector& selector) {
  GDALAllRegister();
  Dataset d = open_raster(path);
  return held_values(*d, path, selector.rgb && d->GetRasterCount() >= 3);
}

cv::Mat average_blocks(const cv::Mat& mask, cv::Size blocks, int f) {
  cv::Mat sums = cv::Mat::zeros(blocks, CV_32S);
  const int width = std::min(mask.cols, blocks.width * f);
  for (int y = 0; y < std::min(mask.rows, blocks.height * f); ++y) {
    const uint8_t* m = mask.ptr<uint8_t>(y);
    int* row = sums.ptr<int>(y / f);
    for (int x = 0, block = 0; x < width; ++block)  // (block by block: no division a pixel)
      for (const int end = std::min(width, x + f); x < end; ++x) row[block] += m[x];
  }
  cv::Mat out(blocks, CV_8U);
  for (int y = 0; y < blocks.height; ++y)
    for (int x = 0; x < blocks.width; ++x) out.at<uint8_t>(y, x) = uint8_t(2 * sums.at<int>(y, x) >= f * f);
  return out;
}

cv::Size blocks_of(cv::Size pixels, int f) { return {(pixels.width + f - 1) / f, (pixels.height + f - 1) / f}; }

MaskRaster averaged(const MaskRaster& raster, int f) {
  return {average_blocks(raster.mask, blocks_of(raster.mask.size(), f), f), raster.transform.coarsened(f), raster.crs_wkt};
}

cv::Mat building_pixels(const cv::Mat& values, const BuildingSelector& selector, const std::optional<double>& nodata) {
  cv::Mat mask;
  if (selector.min) {
    cv::compare(values, cv::Scalar(*selector.min), mask, cv::CMP_GE);  // (a NaN compares false)
    if (nodata) {
      cv::Mat valid;
      cv::compare(values, cv::Scalar(*nodata), valid, cv::CMP_NE);
      cv::bitwise_and(mask, valid, mask);
    }
    return mask;
  }
  mask = cv::Mat::zeros(values.size(), CV_8U);
  for (int v : selector.values) {
    cv::Mat match;
    cv::compare(values, cv::Scalar(v), match, cv::CMP_EQ);
    cv::bitwise_or(mask, match, mask);
  }
  return mask;
}

MaskRaster read_building_mask(const std::string& path, const BuildingSelector& selector) {
  GDALAllRegister();
  Dataset d = open_raster(path);
  MaskRaster out;
  if (d->GetGeoTransform(out.transform.c.data()) != CE_None)
    throw InputError("'" + path + "': has no georeference (no geotransform); lodforge needs map coordinates");
  if (const OGRSpatialReference* srs = d->GetSpatialRef()) {
    char* wkt = nullptr;
    srs->exportToWkt(&wkt);
    out.crs_wkt = wkt ? wkt : "";
    CPLFree(wkt);
  }
  const Vec2 centre = out.transform.to_map(0.5 * d->GetRasterXSize(), 0.5 * d->GetRasterYSize());
  if (const std::string problem = metric_crs_problem(out.crs_wkt, centre.x(), centre.y()); !problem.empty())
    throw InputError("'" + path + "': " + problem);
  // The whole mask is held at once (a byte a pixel, and the labeling and tracing on it): a raster of a
  // region is run in tiles.
  constexpr double kMaxPixels = 1e9;
  if (double(d->GetRasterXSize()) * double(d->GetRasterYSize()) > kMaxPixels)
    throw InputError("'" + path + "': " + std::to_string(d->GetRasterXSize()) + " x " + std::to_string(d->GetRasterYSize()) +
                     " pixels is more than this command reads at once (10^9); process it in tiles with `lodforge run JOB.yaml` " +
                     "(lodforge config --defaults prints a job)");
  if (selector.rgb && d->GetRasterCount() < 3)
    throw InputError("'" + path + "': has " + std::to_string(d->GetRasterCount()) +
                     " band(s); a building colour needs an RGB raster with 3 bands");
  // 1 where the pixel is a building: every band at its colour's value, the band at any of the class
  // values, or at or above the threshold.
  out.mask = selector.rgb ? cv::Mat::ones(d->GetRasterYSize(), d->GetRasterXSize(), CV_8U)
                          : cv::Mat::zeros(d->GetRasterYSize(), d->GetRasterXSize(), CV_8U);
  if (selector.rgb) {
    for (int b = 0; b < 3; ++b)
      read_band_strips(*d, b + 1, path, false, [&](int first_row, const cv::Mat& strip) {
        const int value = (*selector.rgb)[std::size_t(b)];
        for (int r = 0; r < strip.rows; ++r) {
          const int* in = strip.ptr<int>(r);
          uint8_t* m = out.mask.ptr<uint8_t>(first_row + r);
          for (int x = 0; x < strip.cols; ++x) m[x] &= uint8_t(in[x] == value);
        }
      });
  } else {
    // A threshold, or the class values of a floating-point band, as 64-bit floats (GDAL's integers
    // would round 0.85 to 1).
    const std::optional<double> nodata = band_nodata(*d, 1);
    read_band_strips(*d, 1, path, selector.min || floating_band(*d, 1), [&](int first_row, const cv::Mat& strip) {
      cv::Mat rows = out.mask.rowRange(first_row, first_row + strip.rows);
      cv::bitwise_and(building_pixels(strip, selector, nodata), cv::Scalar(1), rows);
    });
  }
  if (cv::countNonZero(out.mask) == 0) {
    std::string held;  // (what it holds instead, unless that cannot be read)
    try {
      held = "; its " + held_values(*d, path, bool(selector.rgb));
    } catch (const std::exception&) {
    }
    throw InputError("'" + path + "': no building pixel (" + selector.describe() + ") in the raster" + held);
  }
  return out;
}

}  // namespace lodforge
