#include "io/input_crs.hpp"

#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
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

std::string declared_output_crs(const std::string& output_crs, const std::string& wkt) {
  if (output_crs.empty()) return {};
  OGRSpatialReference declared;
  const std::string code = output_crs.rfind("EPSG:", 0) == 0 ? output_crs.substr(5) : std::string();
  if (code.empty() || code.find_first_not_of("0123456789") != std::string::npos ||
      declared.importFromEPSG(std::stoi(code)) != OGRERR_NONE)
    throw InputError("output.crs: '" + output_crs + "' is not an EPSG code GDAL knows (write it as EPSG:7415, say)");
  OGRSpatialReference horizontal = declared;
  if (horizontal.IsCompound()) horizontal.StripVertical();
  if (horizontal.IsVertical() || !(horizontal.IsProjected() || horizontal.IsGeographic()))
    throw InputError("output.crs: '" + output_crs + "' (" + (declared.GetName() ? declared.GetName() : "?") +
                     ") has no horizontal CRS; give the inputs' CRS with a vertical one, a compound CRS");
  OGRSpatialReference inputs;
  if (!wkt.empty() && inputs.importFromWkt(wkt.c_str()) == OGRERR_NONE) {
    const std::string inputs_epsg = epsg_of(wkt);
    char* horizontal_wkt = nullptr;
    horizontal.exportToWkt(&horizontal_wkt);
    const std::string horizontal_epsg = epsg_of(horizontal_wkt ? horizontal_wkt : "");
    CPLFree(horizontal_wkt);
    const char* options[] = {"IGNORE_DATA_AXIS_TO_SRS_AXIS_MAPPING=YES", nullptr};
    const bool same = !inputs_epsg.empty() && !horizontal_epsg.empty() ? inputs_epsg == horizontal_epsg
                                                                        : horizontal.IsSame(&inputs, options) != 0;
    if (!same)
      throw InputError("output.crs: '" + output_crs + "' is horizontally " + (horizontal.GetName() ? horizontal.GetName() : "?") +
                       (horizontal_epsg.empty() ? "" : " (" + horizontal_epsg + ")") + ", but the inputs are in " +
                       (inputs.GetName() ? inputs.GetName() : "?") + (inputs_epsg.empty() ? "" : " (" + inputs_epsg + ")") +
                       "; lodforge does not reproject: give a CRS whose horizontal part is the inputs'");
  }
  return "EPSG:" + code;
}

std::vector<std::array<double, 2>> to_lon_lat(const std::string& wkt, const std::vector<std::array<double, 2>>& points) {
  OGRSpatialReference source, wgs84;
  if (wkt.empty() || source.importFromWkt(wkt.c_str()) != OGRERR_NONE || wgs84.importFromEPSG(4326) != OGRERR_NONE) return {};
  source.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);  // longitude first
  std::unique_ptr<OGRCoordinateTransformation> transform(OGRCreateCoordinateTransformation(&source, &wgs84));
  if (!transform) return {};
  std::vector<double> x, y;
  for (const auto& p : points) { x.push_back(p[0]); y.push_back(p[1]); }
  if (!points.empty() && !transform->Transform(int(points.size()), x.data(), y.data())) return {};
  std::vector<std::array<double, 2>> out;
  for (std::size_t i = 0; i < points.size(); ++i) out.push_back({x[i], y[i]});
  return out;
}

std::string crs_label(const std::string& wkt) {
  OGRSpatialReference srs;
  if (wkt.empty() || srs.importFromWkt(wkt.c_str()) != OGRERR_NONE) return "no CRS";
  const std::string epsg = epsg_of(wkt);
  return std::string(srs.GetName() ? srs.GetName() : "?") + (epsg.empty() ? "" : " (" + epsg + ")");
}

namespace {

// The horizontal part of a CRS (a compound one less its vertical CRS); false when wkt is empty or
// not a CRS.
bool horizontal_of(const std::string& wkt, OGRSpatialReference& srs) {
  if (wkt.empty() || srs.importFromWkt(wkt.c_str()) != OGRERR_NONE) return false;
  if (srs.IsCompound()) srs.StripVertical();
  return true;
}

std::string wkt_of(const OGRSpatialReference& srs) {
  char* text = nullptr;
  srs.exportToWkt(&text);
  std::string out = text ? text : "";
  CPLFree(text);
  return out;
}

// Whether (x, y) can be no longitude and latitude.
bool beyond_degrees(double x, double y) { return !(std::abs(x) <= 360 && std::abs(y) <= 90); }

}  // namespace

bool degrees_out_of_range(const std::string& wkt, double x, double y) {
  OGRSpatialReference srs;
  return horizontal_of(wkt, srs) && srs.IsGeographic() && beyond_degrees(x, y);
}

std::string metric_crs_problem(const std::string& wkt, double centre_x, double centre_y, bool vector, const std::string& target_epsg) {
  OGRSpatialReference srs;
  if (!horizontal_of(wkt, srs)) return {};
  std::string unit;
  if (srs.IsGeographic() && beyond_degrees(centre_x, centre_y)) {
    char at[96];
    std::snprintf(at, sizeof at, "(%.1f, %.1f)", centre_x, centre_y);
    return "says it is in " + crs_label(wkt) + ", in degrees, but its coordinates " + at + " are not: its CRS is missing or wrong; " +
           "give it the right one first, e.g. '" + (vector ? "ogr2ogr -a_srs EPSG:NNNN OUT IN'" : "gdal_edit.py -a_srs EPSG:NNNN IN'");
  }
  if (srs.IsGeographic()) {
    unit = "a geographic CRS, its coordinates in degrees";
  } else {
    const char* name = nullptr;
    const double metres = srs.GetLinearUnits(&name);
    if (std::abs(metres - 1.0) <= 1e-9) return {};
    unit = "a CRS in " + std::string(name && *name ? name : "an unknown unit") + " (" + std::to_string(metres) + " m)";
  }
  // The target: the one given, else the UTM zone of the centre (where UTM is defined).
  std::string target = target_epsg, why = target_epsg.empty() ? "" : "the CRS of the other inputs";
  if (target.empty()) {
    CPLPushErrorHandler(CPLQuietErrorHandler);  // (a local CRS has no longitude: no advice, no PROJ message)
    const std::vector<std::array<double, 2>> lon_lat = to_lon_lat(wkt_of(srs), {{centre_x, centre_y}});
    CPLPopErrorHandler();
    if (lon_lat.size() == 1 && std::isfinite(lon_lat[0][0]) && lon_lat[0][1] <= 84 && lon_lat[0][1] >= -80) {
      const double lon = lon_lat[0][0] - 360.0 * std::floor((lon_lat[0][0] + 180.0) / 360.0);  // in [-180, 180)
      const int zone = std::clamp(int(std::floor((lon + 180.0) / 6.0)) + 1, 1, 60);
      target = "EPSG:" + std::to_string((lon_lat[0][1] >= 0 ? 32600 : 32700) + zone);
      why = "the UTM zone of its centre, or take the national grid";
    }
  }
  const std::string to = target.empty() ? "<a projected CRS in metres>" : target;
  std::string note = why.empty() ? "" : target + ": " + why;
  if (!vector) note += std::string(note.empty() ? "" : "; ") + "-r near keeps a mask's classes";
  return "is in " + crs_label(wkt) + ", " + unit + "; lodforge measures in metres: reproject it first, e.g. '" +
         (vector ? "ogr2ogr -t_srs " + to + " OUT IN'" : "gdalwarp -t_srs " + to + " -r near IN OUT'") +
         (note.empty() ? "" : " (" + note + ")");
}

bool same_horizontal_crs(const std::string& a, const std::string& b) {
  if (a.empty() || b.empty() || a == b) return true;
  OGRSpatialReference sa, sb;
  if (!horizontal_of(a, sa) || !horizontal_of(b, sb)) return true;  // (not a CRS: unknown)
  const std::string ea = epsg_of(wkt_of(sa)), eb = epsg_of(wkt_of(sb));
  if (!ea.empty() && !eb.empty()) return ea == eb;
  const char* options[] = {"IGNORE_DATA_AXIS_TO_SRS_AXIS_MAPPING=YES", "CRITERION=EQUIVALENT_EXCEPT_AXIS_ORDER_GEOGCRS", nullptr};
  return sa.IsSame(&sb, options) != 0;
}

bool same_crs(const std::string& a, const std::string& b) {
  if (a.empty() || b.empty() || a == b) return true;  // the usual case, without PROJ
  OGRSpatialReference sa, sb;
  return sa.importFromWkt(a.c_str()) == OGRERR_NONE && sb.importFromWkt(b.c_str()) == OGRERR_NONE && sa.IsSame(&sb);
}

struct InputCrs::Impl {
  std::vector<Companion> companions;
  bool strict = false;
  // Read once, by the first caller, outside TBB (no task of the run may cancel or skip it);
  // a caller arriving meanwhile waits. A failure is kept and thrown to every caller.
  std::mutex mutex;
  std::atomic<bool> done{false};
  std::exception_ptr error;
  std::string wkt, epsg, output_crs;

  void read() {
    for (const Companion& c : companions)
      if (strict && !same_crs(wkt, raster_crs_wkt(c.path, c.key)))
        throw InputError(c.key + ": '" + c.path + "': is on another grid and CRS than the segmentation (inputs.on_grid_mismatch: error)");
    epsg = output_crs.empty() ? epsg_of(wkt) : declared_output_crs(output_crs, wkt);
  }
};

InputCrs::InputCrs(std::string wkt, std::string output_crs) : impl_(new Impl) {
  impl_->epsg = output_crs.empty() ? epsg_of(wkt) : declared_output_crs(output_crs, wkt);
  impl_->wkt = std::move(wkt);
  impl_->done = true;
}

InputCrs::InputCrs(std::string wkt, std::vector<Companion> companions, bool strict, std::string output_crs) : impl_(new Impl) {
  impl_->output_crs = std::move(output_crs);
  impl_->wkt = std::move(wkt);
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
