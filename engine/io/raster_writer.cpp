#include "io/raster_writer.hpp"

#include <filesystem>
#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include "io/errors.hpp"

namespace lodforge {

std::string epsg_wkt(int epsg) {
  OGRSpatialReference srs;
  if (srs.importFromEPSG(epsg) != OGRERR_NONE) throw InputError("EPSG:" + std::to_string(epsg) + " is not a known CRS");
  char* wkt = nullptr;
  srs.exportToWkt(&wkt);
  std::string out = wkt;
  CPLFree(wkt);
  return out;
}

void write_geotiff(const std::string& path, const std::vector<cv::Mat>& bands, const RasterMeta& meta) {
  GDALAllRegister();
  const std::string temp = path + ".partial";
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  const GDALDataType type = bands.front().depth() == CV_8U ? GDT_Byte : GDT_Float32;
  char** create_options = nullptr;
  create_options = CSLSetNameValue(create_options, "COMPRESS", "DEFLATE");
  create_options = CSLSetNameValue(create_options, "TILED", "YES");
  GDALDataset* ds = driver->Create(temp.c_str(), bands.front().cols, bands.front().rows, int(bands.size()), type, create_options);
  CSLDestroy(create_options);
  if (!ds) throw InputError("'" + path + "': cannot create: " + CPLGetLastErrorMsg());
  std::array<double, 6> gt = meta.transform.c;
  ds->SetGeoTransform(gt.data());
  if (!meta.crs_wkt.empty()) ds->SetProjection(meta.crs_wkt.c_str());
  bool ok = true;
  for (std::size_t b = 0; b < bands.size(); ++b) {
    GDALRasterBand* band = ds->GetRasterBand(int(b) + 1);
    if (meta.has_nodata) band->SetNoDataValue(meta.nodata);
    cv::Mat data = bands[b].isContinuous() ? bands[b] : bands[b].clone();
    ok &= band->RasterIO(GF_Write, 0, 0, data.cols, data.rows, data.data, data.cols, data.rows, type, 0, 0) == CE_None;
  }
  GDALClose(ds);
  if (!ok) {
    std::filesystem::remove(temp);
    throw InputError("'" + path + "': writing failed: " + CPLGetLastErrorMsg());
  }
  std::filesystem::rename(temp, path);
}

}  // namespace lodforge
