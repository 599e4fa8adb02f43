#include "io/ogr_polygon.hpp"

#include <algorithm>
#include <filesystem>
#include <gdal_priv.h>
#include <ogrsf_frmts.h>

#include "geometry/polygon.hpp"
#include "io/errors.hpp"

namespace lodforge {

OGRLinearRing to_ogr_ring(const Ring& ring) {
  OGRLinearRing out;
  for (const Vec2& p : ring) out.addPoint(p.x(), p.y());
  out.addPoint(ring.front().x(), ring.front().y());
  return out;
}

std::unique_ptr<OGRPolygon> to_ogr_polygon(const PolygonWithHoles& p) {
  auto polygon = std::make_unique<OGRPolygon>();
  OGRLinearRing outer = to_ogr_ring(p.outer);
  polygon->addRing(&outer);
  for (const Ring& h : p.holes) {
    OGRLinearRing hole = to_ogr_ring(h);
    polygon->addRing(&hole);
  }
  return polygon;
}

namespace {

Ring ring_of(const OGRLinearRing* r, bool outer) {
  Ring out;
  for (int i = 0; i + 1 < r->getNumPoints(); ++i) out.emplace_back(r->getX(i), r->getY(i));
  if (!out.empty() && (signed_area(out) > 0) != outer) std::reverse(out.begin(), out.end());
  return out;
}

}  // namespace

PolygonWithHoles from_ogr_polygon(const OGRPolygon& p) {
  PolygonWithHoles out;
  if (p.getExteriorRing()) out.outer = ring_of(p.getExteriorRing(), true);
  for (int k = 0; k < p.getNumInteriorRings(); ++k) out.holes.push_back(ring_of(p.getInteriorRing(k), false));
  return out;
}

std::optional<PolygonWithHoles> clip_polygon(const PolygonWithHoles& polygon, const Ring& region) {
  const std::unique_ptr<OGRPolygon> p = to_ogr_polygon(polygon), r = to_ogr_polygon({region, {}});
  std::unique_ptr<OGRGeometry> clipped(p->Intersection(r.get()));
  if (!clipped) {  // (an invalid polygon: made valid first)
    const std::unique_ptr<OGRGeometry> valid(p->MakeValid());
    if (valid) clipped.reset(valid->Intersection(r.get()));
  }
  if (!clipped) return std::nullopt;
  std::optional<PolygonWithHoles> best;
  double best_area = 0;
  const auto take = [&](const OGRGeometry* g) {
    if (wkbFlatten(g->getGeometryType()) != wkbPolygon) return;
    const OGRPolygon* part = g->toPolygon();
    if (part->get_Area() <= best_area) return;
    PolygonWithHoles out = from_ogr_polygon(*part);
    out.outer = remove_degenerate_vertices(out.outer, 1e-9);
    for (Ring& h : out.holes) h = remove_degenerate_vertices(h, 1e-9);
    if (out.outer.size() < 3 || !polygon_problem(out).empty()) return;
    best_area = part->get_Area();
    best = std::move(out);
  };
  if (const auto* collection = dynamic_cast<const OGRGeometryCollection*>(clipped.get()))
    for (const OGRGeometry* g : *collection) take(g);
  else take(clipped.get());
  return best;
}

std::vector<PolygonWithHoles> read_polygons(const std::string& path, const std::string& label, std::string* crs_wkt,
                                            std::vector<std::string>* names) {
  if (path.rfind("/vsi", 0) != 0 && !std::filesystem::exists(path)) throw InputError(label + " '" + path + "': file not found");
  GDALDataset* d = static_cast<GDALDataset*>(GDALOpenEx(path.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
  if (!d) throw InputError(label + " '" + path + "': not a vector file GDAL can read");
  std::vector<PolygonWithHoles> out;
  auto add = [&out, names](const OGRPolygon* p, const std::string& name) {
    if (!p->getExteriorRing() || p->getExteriorRing()->getNumPoints() < 4) return;
    out.push_back(from_ogr_polygon(*p));
    if (names) names->push_back(name);
  };
  // A lodforge GeoPackage holds its footprints in "footprints" beside the LOD1 blocks' faces
  // (layer "lod1"): the footprints only, then.
  std::vector<OGRLayer*> layers;
  if (OGRLayer* footprints = d->GetLayerByName("footprints")) layers.push_back(footprints);
  else for (OGRLayer* layer : d->GetLayers()) layers.push_back(layer);
  for (OGRLayer* layer : layers) {
    if (crs_wkt && crs_wkt->empty() && layer->GetSpatialRef()) {
      char* wkt = nullptr;
      layer->GetSpatialRef()->exportToWkt(&wkt);
      *crs_wkt = wkt ? wkt : "";
      CPLFree(wkt);
    }
    const int id_field = layer->GetLayerDefn()->GetFieldIndex("id");
    // (Of several layers, each numbers its own features: the layer's name goes first.)
    const std::string prefix = layers.size() > 1 ? std::string(layer->GetName()) + ":" : std::string();
    for (auto& f : *layer) {
      const OGRGeometry* g = f->GetGeometryRef();
      if (!g) continue;
      const std::string name =
          names ? prefix + (id_field >= 0 && f->IsFieldSetAndNotNull(id_field) ? std::string(f->GetFieldAsString(id_field))
                                                                               : std::to_string(f->GetFID()))
                : std::string();
      const auto type = wkbFlatten(g->getGeometryType());
      if (type == wkbPolygon) {
        add(g->toPolygon(), name);
      } else if (type == wkbMultiPolygon) {
        int part_number = 0;
        for (const OGRPolygon* part : *g->toMultiPolygon()) add(part, name + "." + std::to_string(++part_number));
      }
    }
  }
  GDALClose(d);
  if (out.empty()) throw InputError(label + " '" + path + "': holds no polygon");
  return out;
}

}  // namespace lodforge
