#include "io/input_crs.hpp"

#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <tbb/collaborative_call_once.h>

#include "io/errors.hpp"

namespace lodforge {

std::string raster_crs_wkt(const std::string& path, const std::string& key) {
  CPLPushErrorHandler(CPLQuietErrorHandler);
  GDALDataset* d = static_cast<GDALDataset*>(GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
  CPLPopErrorHandler();
  if (!d) throw InputError(key + ": '" + path + "': not a raster GDAL can read");
  std::string result;
  if (const OGRSpatialReference* srs = d->GetSpatialRef()) {
    char* wkt = nullptr;
    srs->exportToWkt(&wkt);
    result = wkt ? wkt : "";
    CPLFree(wkt);
  }
  GDALClose(d);
  return result;
}

bool same_crs(const std::string& a, const std::string& b) {
  if (a.empty() || b.empty() || a == b) return true;  // the usual case, without PROJ
  OGRSpatialReference sa, sb;
  return sa.importFromWkt(a.c_str()) == OGRERR_NONE && sb.importFromWkt(b.c_str()) == OGRERR_NONE && sa.IsSame(&sb);
}

struct InputCrs::Impl {
  std::string segmentation_path, segmentation_key;
  std::vector<Companion> companions;
  bool strict = false;
  tbb::collaborative_once_flag once;
  std::string wkt;

  void read() {
    std::string seg = raster_crs_wkt(segmentation_path, segmentation_key);
    for (const Companion& c : companions)
      if (strict && !same_crs(seg, raster_crs_wkt(c.path, c.key)))
        throw InputError(c.key + ": '" + c.path + "': is on another grid and CRS than the segmentation (inputs.on_grid_mismatch: error)");
    wkt = std::move(seg);
  }
};

InputCrs::InputCrs(std::string wkt) : impl_(new Impl) {
  impl_->wkt = std::move(wkt);
  tbb::collaborative_call_once(impl_->once, [] {});
}

InputCrs::InputCrs(std::string segmentation_path, std::string segmentation_key, std::vector<Companion> companions, bool strict)
    : impl_(new Impl) {
  impl_->segmentation_path = std::move(segmentation_path);
  impl_->segmentation_key = std::move(segmentation_key);
  impl_->companions = std::move(companions);
  impl_->strict = strict;
}

InputCrs::~InputCrs() = default;

const std::string& InputCrs::wkt() const {
  tbb::collaborative_call_once(impl_->once, [this] { impl_->read(); });
  return impl_->wkt;
}

}  // namespace lodforge
