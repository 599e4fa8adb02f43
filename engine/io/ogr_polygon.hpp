// Conversions between the core's polygons and OGR geometries, and reading polygon files.
#pragma once
#include <memory>
#include <optional>
#include <ogr_geometry.h>
#include <string>
#include <vector>

#include "geometry/types.hpp"

namespace lodforge {

std::unique_ptr<OGRPolygon> to_ogr_polygon(const PolygonWithHoles& polygon);
OGRLinearRing to_ogr_ring(const Ring& ring);  // closed (first point repeated)

// Oriented as the core expects: outer counter-clockwise, holes clockwise.
PolygonWithHoles from_ogr_polygon(const OGRPolygon& polygon);

// The polygon clipped to a convex region (a ring): its largest valid polygon part (GEOS; an
// invalid polygon made valid first), with the vertices where an edge goes on straight removed;
// nothing where none is left.
std::optional<PolygonWithHoles> clip_polygon(const PolygonWithHoles& polygon, const Ring& region);

// Every polygon of every layer of a vector file (multipolygons split into their parts); of the
// layer "footprints" alone when there is one (lodforge's GeoPackages: not the LOD1 faces). Throws
// InputError naming `label` and the file when it is missing, unreadable or holds no polygon.
// crs_wkt, when given, receives the first layer's CRS (empty if it has none); names, when given,
// each polygon's feature: its "id" field where the layer has one, else its FID, and ".K" for the
// K-th part (from 1) of a multipolygon; "LAYER:" before it where several layers are read.
std::vector<PolygonWithHoles> read_polygons(const std::string& path, const std::string& label, std::string* crs_wkt = nullptr,
                                            std::vector<std::string>* names = nullptr);

}  // namespace lodforge
