#include "io/input_crs.hpp"

#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <atomic>
#include <exception>
#include <mutex>

#include "io/errors.hpp"
#include "io/raster.hpp"

namespace lodforge {

std::string raster_crs_wkt(const std::string& path, const std::string& key) {
  const Dataset d = open_raster(path, key);
  std::string result;
  if (const OGRSpatialReference* srs = d->GetSpatialRef()) {
    char* wkt = nullptr;
    srs->exportToWkt(&wkt);
    result = wkt ? wkt : "";
    CPLFree(wkt);
  }
  return result;
}

std::string epsg_of(const std::string& wkt) {
  OGRSpatialReference srs;
  if (wkt.empty() || srs.importFromWkt(wkt.c_str()) != OGRERR_NONE) return {};
  srs.AutoIdentifyEPSG();
  const char* name = srs.GetAuthorityName(nullptr);
  const char* code = srs.GetAuthorityCode(nullptr);
  return name && code && std::string(name) == "EPSG" ? std::string("EPSG:") + code : std::string();
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
  // Read once, by the first caller, outside TBB (no task of the run may cancel or skip it);
  // a caller arriving meanwhile waits. A failure is kept and thrown to every caller.
  std::mutex mutex;
  std::atomic<bool> done{false};
  std::exception_ptr error;
  std::string wkt, epsg;

  void read() {
    std::string seg = raster_crs_wkt(segmentation_path, segmentation_key);
    for (const Companion& c : companions)
      if (strict && !same_crs(seg, raster_crs_wkt(c.path, c.key)))
        throw InputError(c.key + ": '" + c.path + "': is on another grid and CRS than the segmentation (inputs.on_grid_mismatch: error)");
    epsg = epsg_of(seg);
    wkt = std::move(seg);
  }
};

InputCrs::InputCrs(std::string wkt) : impl_(new Impl) {
  impl_->epsg = epsg_of(wkt);
  impl_->wkt = std::move(wkt);
  impl_->done = true;
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
  if (!impl_->done.load(std::memory_order_acquire)) {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    if (!impl_->done.load(std::memory_order_relaxed)) {
      try {
        impl_->read();
      } catch (...) {
        impl_->error = std::current_exception();
      }
      impl_->done.store(true, std::memory_order_release);
    }
  }
  if (impl_->error) std::rethrow_exception(impl_->error);
  return impl_->wkt;
}

const std::string& InputCrs::epsg() const {
  wkt();  // read (or its failure thrown) first
  return impl_->epsg;
}

}  // namespace lodforge
