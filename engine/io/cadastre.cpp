#include "io/cadastre.hpp"

#include <algorithm>
#include <filesystem>
#include <gdal_priv.h>
#include <map>
#include <memory>
#include <ogrsf_frmts.h>

#include "geometry/polygon.hpp"
#include "geometry/rasterize.hpp"
#include "io/errors.hpp"
#include "io/model_writers.hpp"
#include "io/ogr_polygon.hpp"
#include "run/tiles.hpp"

namespace lodforge {

namespace {

// The same CRS by authority code when both have one (a GeoJSON's urn and a GeoTIFF's WKT of
// EPSG:28992 differ as text), else as OGR compares them.
bool same_crs(const OGRSpatialReference& a, const OGRSpatialReference& b) {
  const char* ca = a.GetAuthorityCode(nullptr);
  const char* cb = b.GetAuthorityCode(nullptr);
  const char* na = a.GetAuthorityName(nullptr);
  const char* nb = b.GetAuthorityName(nullptr);
  if (ca && cb && na && nb) return std::string(na) == nb && std::string(ca) == cb;
  const char* options[] = {"IGNORE_DATA_AXIS_TO_SRS_AXIS_MAPPING=YES", nullptr};
  return a.IsSame(&b, options);
}

// The valid polygons of a geometry (repaired with GEOS when it is not valid): empty when none.
std::vector<PolygonWithHoles> valid_parts(const OGRGeometry& geometry) {
  std::vector<PolygonWithHoles> out;
  auto collect = [&out](const OGRGeometry* g, auto& self) -> bool {
    const auto type = wkbFlatten(g->getGeometryType());
    if (type == wkbPolygon) {
      PolygonWithHoles p = from_ogr_polygon(*g->toPolygon());
      p.outer = remove_degenerate_vertices(p.outer, 1e-9);
      for (Ring& h : p.holes) h = remove_degenerate_vertices(h, 1e-9);
      p.holes.erase(std::remove_if(p.holes.begin(), p.holes.end(), [](const Ring& h) { return h.size() < 3; }), p.holes.end());
      if (p.outer.size() < 3 || !polygon_problem(p).empty()) return false;
      out.push_back(std::move(p));
      return true;
    }
    if (type == wkbMultiPolygon || type == wkbGeometryCollection) {
      bool all = true;
      for (const OGRGeometry* part : *g->toGeometryCollection()) all = self(part, self) && all;
      return all;
    }
    return wkbFlatten(type) == wkbLineString || type == wkbPoint || type == wkbMultiLineString || type == wkbMultiPoint;  // (left by a repair)
  };
  std::unique_ptr<OGRGeometry> linear(geometry.hasCurveGeometry() ? geometry.getLinearGeometry() : geometry.clone());
  if (linear && collect(linear.get(), collect)) return out;
  out.clear();
  std::unique_ptr<OGRGeometry> repaired(linear ? linear->MakeValid() : nullptr);
  if (repaired) collect(repaired.get(), collect);
  return out;
}

}  // namespace

Cadastre::Cadastre(const std::string& path, const std::string& layer_name, const std::string& id_field, const std::string& raster_crs_wkt,
                   const GeoTransform& transform, cv::Size raster) {
  const std::string key = "inputs.footprints.path";
  if (path.rfind("/vsi", 0) != 0 && !std::filesystem::exists(path)) throw InputError(key + ": '" + path + "': file not found");
  std::unique_ptr<GDALDataset> d(static_cast<GDALDataset*>(GDALOpenEx(path.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, nullptr, nullptr, nullptr)));
  if (!d || d->GetLayerCount() == 0) throw InputError(key + ": '" + path + "': not a vector source GDAL can read (or it has no layer)");
  OGRLayer* layer = layer_name.empty() ? d->GetLayer(0) : d->GetLayerByName(layer_name.c_str());
  if (!layer) {
    std::string names;
    for (OGRLayer* l : d->GetLayers()) names += std::string(names.empty() ? "" : ", ") + l->GetName();
    throw InputError("inputs.footprints.layer: '" + layer_name + "' is not a layer of '" + path + "' (it has: " + names + ")");
  }
  const std::string where = "'" + path + "' layer '" + layer->GetName() + "'";
  int id_index = -1;
  if (!id_field.empty()) {
    id_index = layer->GetLayerDefn()->GetFieldIndex(id_field.c_str());
    if (id_index < 0) {
      std::string names;
      for (int k = 0; k < layer->GetLayerDefn()->GetFieldCount(); ++k)
        names += std::string(k ? ", " : "") + layer->GetLayerDefn()->GetFieldDefn(k)->GetNameRef();
      throw InputError("inputs.footprints.id_field: '" + id_field + "' is not a field of " + where + " (it has: " + names + ")");
    }
  }
  const OGRSpatialReference* source_crs = layer->GetSpatialRef();
  if (!source_crs) throw InputError(key + ": " + where + " has no CRS; give the footprints a CRS (e.g. ogr2ogr -a_srs)");
  OGRSpatialReference raster_crs;
  if (raster_crs.importFromWkt(raster_crs_wkt.c_str()) != OGRERR_NONE)
    throw InputError("inputs.segmentation.path: has no CRS to put the footprints in");
  std::unique_ptr<OGRCoordinateTransformation> to_raster;
  if (!same_crs(*source_crs, raster_crs)) {
    OGRSpatialReference from(*source_crs), to(raster_crs);
    from.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    to.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    to_raster.reset(OGRCreateCoordinateTransformation(&from, &to));
    if (!to_raster) throw InputError(key + ": " + where + ": cannot reproject its CRS to the segmentation's");
  }

  std::map<std::string, std::size_t> by_id;
  long not_polygons = 0, empty = 0, invalid = 0, outside = 0;
  std::vector<std::string> invalid_ids;
  const cv::Rect bounds(0, 0, raster.width, raster.height);
  for (auto& f : *layer) {
    std::string id = id_index < 0 ? std::to_string(f->GetFID()) : f->IsFieldSetAndNotNull(id_index) ? f->GetFieldAsString(id_index) : "";
    if (id.empty()) throw InputError("inputs.footprints.id_field: feature " + std::to_string(f->GetFID()) + " of " + where + " has no '" + id_field + "'");
    if (id.find_first_of("\t\r\n") != std::string::npos)
      throw InputError("inputs.footprints.id_field: the ID of feature " + std::to_string(f->GetFID()) + " of " + where + " holds a tab or line break");
    OGRGeometry* g = f->GetGeometryRef();
    if (!g || g->IsEmpty()) { ++empty; continue; }
    const auto type = wkbFlatten(g->getGeometryType());
    if (type != wkbPolygon && type != wkbMultiPolygon && type != wkbCurvePolygon && type != wkbMultiSurface) { ++not_polygons; continue; }
    if (to_raster && g->transform(to_raster.get()) != OGRERR_NONE)
      throw InputError(key + ": " + where + ": feature " + std::to_string(f->GetFID()) + " cannot be reprojected to the segmentation's CRS");
    std::vector<PolygonWithHoles> parts = valid_parts(*g);
    if (parts.empty()) { ++invalid; if (invalid_ids.size() < 5) invalid_ids.push_back(id); continue; }
    auto [it, added] = by_id.emplace(id, footprints_.size());
    if (added) footprints_.push_back({id, {}, {}});
    for (PolygonWithHoles& p : parts) footprints_[it->second].parts.push_back(std::move(p));
  }
  // Their pixels, and those wholly outside the raster left out.
  std::vector<CadastralFootprint> kept;
  for (CadastralFootprint& c : footprints_) {
    cv::Rect box = pixel_box(c.parts.front(), transform);
    for (const PolygonWithHoles& p : c.parts) box |= pixel_box(p, transform);
    c.pixels = box & bounds;
    if (c.pixels.empty()) { ++outside; continue; }
    kept.push_back(std::move(c));
  }
  footprints_ = std::move(kept);
  // Distinct IDs must stay distinct as object IDs in the files (an XML name: "a b" and "a_b" would not).
  std::map<std::string, const std::string*> objects;
  for (const CadastralFootprint& c : footprints_) {
    const auto [it, added] = objects.emplace(cadastral_object_id(c.id), &c.id);
    if (!added)
      throw InputError("inputs.footprints.id_field: the IDs '" + *it->second + "' and '" + c.id + "' of " + where +
                       " both become the object ID '" + it->first + "' in CityGML and CityJSON (other characters than letters, digits, _, - and . are written as _)");
  }
  auto note = [&](long count, const std::string& what) {
    if (count) notes_.push_back(std::to_string(count) + " feature(s) of " + where + " " + what);
  };
  note(not_polygons, "are not polygons: not used");
  note(empty, "have no geometry: not used");
  std::string examples;
  for (const std::string& id : invalid_ids) examples += (examples.empty() ? " (" : ", ") + id;
  note(invalid, "are invalid polygons that GEOS could not repair" + (examples.empty() ? "" : examples + (invalid > 5 ? ", ..." : "") + ")") + ": not used");
  note(outside, "lie wholly outside the segmentation raster: not used");
  if (footprints_.empty()) throw InputError(key + ": " + where + " holds no valid polygon on the segmentation raster");

  bucket_cols_ = (raster.width + bucket_px_ - 1) / bucket_px_;
  bucket_rows_ = (raster.height + bucket_px_ - 1) / bucket_px_;
  buckets_.resize(std::size_t(bucket_cols_) * bucket_rows_);
  std::uint64_t all = fnv1a(where);
  for (std::size_t i = 0; i < footprints_.size(); ++i) {
    const cv::Rect& r = footprints_[i].pixels;
    for (int by = r.y / bucket_px_; by <= (r.y + r.height - 1) / bucket_px_; ++by)
      for (int bx = r.x / bucket_px_; bx <= (r.x + r.width - 1) / bucket_px_; ++bx) buckets_[std::size_t(by) * bucket_cols_ + bx].push_back(int(i));
    std::uint64_t h = fnv1a(footprints_[i].id);
    for (const PolygonWithHoles& p : footprints_[i].parts) {
      h = fnv1a(p.outer.data(), p.outer.size() * sizeof(Vec2), h);
      for (const Ring& hole : p.holes) h = fnv1a(hole.data(), hole.size() * sizeof(Vec2), h);
    }
    footprints_[i].hash = h;
    all = fnv1a(&h, sizeof h, all);
  }
  hash_ = all;
}

std::vector<int> Cadastre::in_window(const cv::Rect& window) const {
  std::vector<int> out;
  if (window.empty() || buckets_.empty()) return out;
  const int bx0 = std::max(0, window.x / bucket_px_), by0 = std::max(0, window.y / bucket_px_);
  const int bx1 = std::min(bucket_cols_ - 1, (window.x + window.width - 1) / bucket_px_);
  const int by1 = std::min(bucket_rows_ - 1, (window.y + window.height - 1) / bucket_px_);
  for (int by = by0; by <= by1; ++by)
    for (int bx = bx0; bx <= bx1; ++bx)
      for (int i : buckets_[std::size_t(by) * bucket_cols_ + bx])
        if (!(footprints_[std::size_t(i)].pixels & window).empty()) out.push_back(i);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace lodforge
