#include "io/raster.hpp"

#include <filesystem>
#include <gdal_priv.h>
#include <memory>
#include <opencv2/core.hpp>

#include "io/errors.hpp"

namespace lodforge {

std::string BuildingSelector::describe() const {
  if (rgb) return "colour (" + std::to_string((*rgb)[0]) + ", " + std::to_string((*rgb)[1]) + ", " + std::to_string((*rgb)[2]) + ")";
  std::string s;
  for (int v : values) s += (s.empty() ? "" : ", ") + std::to_string(v);
  return "value " + s;
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

cv::Mat read_band(GDALDataset& d, int band, const std::string& path) {
  cv::Mat m(d.GetRasterYSize(), d.GetRasterXSize(), CV_32S);
  if (d.GetRasterBand(band)->RasterIO(GF_Read, 0, 0, m.cols, m.rows, m.data, m.cols, m.rows, GDT_Int32, 0, 0) != CE_None)
    throw InputError("'" + path + "': cannot read band " + std::to_string(band) + ": " + CPLGetLastErrorMsg());
  return m;
}

}  // namespace

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
  // The whole mask is read at once (4 bytes a pixel and more): a raster of a region is run in tiles.
  constexpr double kMaxPixels = 1e9;
  if (double(d->GetRasterXSize()) * double(d->GetRasterYSize()) > kMaxPixels)
    throw InputError("'" + path + "': " + std::to_string(d->GetRasterXSize()) + " x " + std::to_string(d->GetRasterYSize()) +
                     " pixels is more than this command reads at once (10^9); process it in tiles with `lodforge run JOB.yaml` " +
                     "(lodforge config --defaults prints a job)");
  if (selector.rgb) {
    if (d->GetRasterCount() < 3)
      throw InputError("'" + path + "': has " + std::to_string(d->GetRasterCount()) +
                       " band(s); a building colour needs an RGB raster with 3 bands");
    cv::Mat mask = cv::Mat::ones(d->GetRasterYSize(), d->GetRasterXSize(), CV_8U);
    for (int b = 0; b < 3; ++b) {
      cv::Mat match = read_band(*d, b + 1, path) == (*selector.rgb)[b];
      cv::bitwise_and(mask, match / 255, mask);
    }
    out.mask = mask;
  } else {
    const cv::Mat band = read_band(*d, 1, path);
    cv::Mat mask = cv::Mat::zeros(band.size(), CV_8U);
    for (int v : selector.values) {
      cv::Mat match = band == v;
      cv::bitwise_or(mask, match / 255, mask);
    }
    out.mask = mask;
  }
  if (cv::countNonZero(out.mask) == 0)
    throw InputError("'" + path + "': no building pixel (" + selector.describe() + ") in the raster");
  return out;
}

}  // namespace lodforge
