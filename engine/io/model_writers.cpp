#include "io/model_writers.hpp"

#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <sstream>
#include <unordered_map>

#include "io/atomic_file.hpp"
#include "geometry/polygon.hpp"
#include "io/errors.hpp"
#include "io/footprint_writer.hpp"
#include "triangulation/triangulate.hpp"

namespace lodforge {

namespace fs = std::filesystem;

std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

const std::vector<std::string>& model_formats() {
  static const std::vector<std::string> formats{"citygml", "cityjson", "cityjsonseq", "obj", "gpkg", "geojson", "gltf"};
  return formats;
}

std::string extension_of(const std::string& format) {
  if (format == "citygml") return ".gml";
  if (format == "cityjson") return ".city.json";
  if (format == "cityjsonseq") return ".city.jsonl";
  if (format == "obj") return ".obj";
  if (format == "gpkg") return ".gpkg";
  if (format == "gltf") return ".glb";
  return ".geojson";
}

namespace {

// A coordinate with three decimals, exactly as a fixed precision 3 stream writes it (to_chars
// is specified as printf's "%.3f" in the C locale) without iostream's formatting machinery, which
// was the writers' largest cost.
struct Fixed3 {
  double value;
};
std::ostream& operator<<(std::ostream& out, Fixed3 f) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, f.value, std::chars_format::fixed, 3);
  return out.write(buffer, result.ptr - buffer);
}

// Every other number in the model files has three decimals too (heights, the origin).
std::ostream& three_decimals(std::ostream& out) {
  out.precision(3);
  return out << std::fixed;
}

}  // namespace

std::string cadastral_object_id(const std::string& cadastre_id) {
  std::string id = cadastre_id;
  for (char& c : id)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-' && c != '.') c = '_';
  if (id.empty() || (!std::isalpha(static_cast<unsigned char>(id[0])) && id[0] != '_')) id = "id_" + id;
  return id;
}

std::string object_id(const BuildingModel& m) {
  return m.cadastre_id.empty() ? "lodforge_b" + std::to_string(m.id) : cadastral_object_id(m.cadastre_id);
}

namespace {

// The footprint at height z, as one face.
Face lifted(const PolygonWithHoles& footprint, double z) {
  Face face;
  auto lift = [z](const Ring& r) {
    Ring3 out;
    for (const Vec2& p : r) out.emplace_back(p.x(), p.y(), z);
    return out;
  };
  face.rings.push_back(lift(footprint.outer));
  for (const Ring& h : footprint.holes) face.rings.push_back(lift(h));
  return face;
}


// CityGML 2.0: bldg:Building with lod0FootPrint, lod1Solid and measuredHeight.
class CityGmlWriter : public ModelWriter {
 public:
  CityGmlWriter(const std::string& path, const WriterContext& c) : file_(path) {
    three_decimals(file_.out());
    srs_ = c.epsg.empty() ? "" : " srsName=\"urn:ogc:def:crs:EPSG::" + c.epsg.substr(5) + "\"";
    auto& o = file_.out();
    o << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      << "<core:CityModel xmlns:core=\"http://www.opengis.net/citygml/2.0\" xmlns:bldg=\"http://www.opengis.net/citygml/building/2.0\""
         " xmlns:gen=\"http://www.opengis.net/citygml/generics/2.0\" xmlns:gml=\"http://www.opengis.net/gml\""
         " xmlns:xlink=\"http://www.w3.org/1999/xlink\" xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\""
         " xsi:schemaLocation=\"http://www.opengis.net/citygml/building/2.0 http://schemas.opengis.net/citygml/building/2.0/building.xsd"
         " http://www.opengis.net/citygml/generics/2.0 http://schemas.opengis.net/citygml/generics/2.0/generics.xsd\">\n"
      << "  <gml:name>lodforge tile " << xml_escape(c.tile) << "</gml:name>\n"
      << "  <gml:boundedBy><gml:Envelope" << srs_ << " srsDimension=\"3\"><gml:lowerCorner>" << Fixed3{c.extent[0]} << ' '
      << Fixed3{c.extent[1]} << ' ' << Fixed3{c.extent[2]} << "</gml:lowerCorner><gml:upperCorner>" << Fixed3{c.extent[3]} << ' '
      << Fixed3{c.extent[4]} << ' ' << Fixed3{c.extent[5]} << "</gml:upperCorner></gml:Envelope></gml:boundedBy>\n";
  }
  void add(const BuildingModel& m) override {
    auto& o = file_.out();
    o << "  <core:cityObjectMember>\n    <bldg:Building gml:id=\"" << object_id(m) << "\">\n";
    attribute("status", m.status);
    if (!m.stage.empty()) attribute("failed_stage", m.stage);
    if (!m.reason.empty()) attribute("reason", m.reason);
    attribute("regularizer", m.regularizer);
    attribute("tile", m.tile);
    if (!m.cadastre.empty()) {
      if (!m.cadastre_id.empty()) attribute("cadastre_id", m.cadastre_id);
      attribute("cadastre", m.cadastre);
      if (m.coverage >= 0) o << "      <gen:doubleAttribute name=\"cadastre_coverage\"><gen:value>" << m.coverage << "</gen:value></gen:doubleAttribute>\n";
    }
    if (m.has_lod1) heights(m.ground, m.roof, m.height_statistics, 6);
    const double z = m.has_lod1 ? m.ground : 0.0;
    o << "      <bldg:lod0FootPrint>\n        <gml:MultiSurface" << srs_ << " srsDimension=\"3\">\n          <gml:surfaceMember>\n";
    polygon(lifted(m.footprint, z), 12);
    o << "          </gml:surfaceMember>\n        </gml:MultiSurface>\n      </bldg:lod0FootPrint>\n";
    if (m.has_lod1) solid(m.solid, 6);
    for (std::size_t k = 0; k < m.parts.size(); ++k) {
      const PartModel& p = m.parts[k];
      o << "      <bldg:consistsOfBuildingPart>\n        <bldg:BuildingPart gml:id=\"" << object_id(m) << '-' << k + 1 << "\">\n";
      heights(p.ground, p.roof, p.height_statistics, 10);
      solid(p.solid, 10);
      o << "        </bldg:BuildingPart>\n      </bldg:consistsOfBuildingPart>\n";
    }
    o << "    </bldg:Building>\n  </core:cityObjectMember>\n";
  }
  void finish() override {
    file_.out() << "</core:CityModel>\n";
    file_.commit();
  }

 private:
  void attribute(const char* name, const std::string& value) {
    file_.out() << "      <gen:stringAttribute name=\"" << name << "\"><gen:value>" << xml_escape(value) << "</gen:value></gen:stringAttribute>\n";
  }
  // Generic attributes ground_height, roof_height and the statistics, then bldg:measuredHeight.
  void heights(double ground, double roof, const std::vector<double>& statistics, int indent) {
    auto& o = file_.out();
    const std::string pad(indent, ' ');
    o << pad << "<gen:doubleAttribute name=\"ground_height\"><gen:value>" << ground << "</gen:value></gen:doubleAttribute>\n";
    o << pad << "<gen:doubleAttribute name=\"roof_height\"><gen:value>" << roof << "</gen:value></gen:doubleAttribute>\n";
    for (std::size_t i = 0; i < height_statistic_fields().size() && i < statistics.size(); ++i) {
      const HeightStatistic& h = height_statistic_fields()[i];
      const char* type = h.integer ? "intAttribute" : "doubleAttribute";
      o << pad << "<gen:" << type << " name=\"" << h.name << "\"><gen:value>";
      if (h.integer) o << std::llround(statistics[i]);
      else o << statistics[i];
      o << "</gen:value></gen:" << type << ">\n";
    }
    o << pad << "<bldg:measuredHeight uom=\"m\">" << (roof - ground) << "</bldg:measuredHeight>\n";
  }
  void solid(const Solid& s, int indent) {
    auto& o = file_.out();
    const std::string pad(indent, ' ');
    o << pad << "<bldg:lod1Solid>\n" << pad << "  <gml:Solid" << srs_ << " srsDimension=\"3\">\n" << pad << "    <gml:exterior>\n" << pad
      << "      <gml:CompositeSurface>\n";
    for (const Face& f : s.faces) {
      o << pad << "        <gml:surfaceMember>\n";
      polygon(f, indent + 10);
      o << pad << "        </gml:surfaceMember>\n";
    }
    o << pad << "      </gml:CompositeSurface>\n" << pad << "    </gml:exterior>\n" << pad << "  </gml:Solid>\n" << pad << "</bldg:lod1Solid>\n";
  }
  void polygon(const Face& f, int indent) {
    auto& o = file_.out();
    const std::string pad(indent, ' ');
    o << pad << "<gml:Polygon>\n";
    for (std::size_t r = 0; r < f.rings.size(); ++r) {
      o << pad << (r == 0 ? "  <gml:exterior>" : "  <gml:interior>") << "<gml:LinearRing><gml:posList>";
      for (const Vec3& p : f.rings[r]) o << Fixed3{p.x()} << ' ' << Fixed3{p.y()} << ' ' << Fixed3{p.z()} << ' ';
      const Vec3& first = f.rings[r].front();
      o << Fixed3{first.x()} << ' ' << Fixed3{first.y()} << ' ' << Fixed3{first.z()};
      o << "</gml:posList></gml:LinearRing>" << (r == 0 ? "</gml:exterior>\n" : "</gml:interior>\n");
    }
    o << pad << "</gml:Polygon>\n";
  }
  AtomicTextFile file_;
  std::string srs_;
};

// CityJSON 2.0: integer vertices with a transform (mm), Solid LOD1 and MultiSurface LOD0.
// A JSON string's contents (nlohmann-json): quotes, backslashes and control characters escaped,
// invalid UTF-8 replaced.
std::string json_text(const std::string& s) {
  const std::string quoted = nlohmann::json(s).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  return quoted.substr(1, quoted.size() - 2);
}

// CityJSON's vertices of one file or one feature: integer millimetres from the origin, each once.
class CityJsonVertices {
 public:
  explicit CityJsonVertices(Vec2 origin) : origin_(origin) {}
  std::size_t index(const Vec3& p) {
    const std::array<long long, 3> q{std::llround((p.x() - origin_.x()) * 1000), std::llround((p.y() - origin_.y()) * 1000), std::llround(p.z() * 1000)};
    auto [it, inserted] = lookup_.try_emplace(q, vertices_.size());
    if (inserted) vertices_.push_back(q);
    return it->second;
  }
  // The "vertices" array's members; `wrap`: a line break every four.
  void write(std::ostream& o, bool wrap) const {
    for (std::size_t i = 0; i < vertices_.size(); ++i) {
      const auto& v = vertices_[i];
      o << (i ? (wrap ? ", " : ",") : "") << (wrap && i % 4 == 0 ? "\n  " : "") << '[' << v[0] << ',' << (wrap ? " " : "") << v[1] << ','
        << (wrap ? " " : "") << v[2] << ']';
    }
  }

 private:
  Vec2 origin_;
  std::vector<std::array<long long, 3>> vertices_;
  std::map<std::array<long long, 3>, std::size_t> lookup_;
};

// The height attributes (after others): measuredHeight, ground_height, roof_height and the statistics.
void write_height_attributes(std::ostream& o, double ground, double roof, const std::vector<double>& statistics) {
  o << ", \"measuredHeight\": " << (roof - ground) << ", \"ground_height\": " << ground << ", \"roof_height\": " << roof;
  for (std::size_t i = 0; i < height_statistic_fields().size() && i < statistics.size(); ++i) {
    o << ", \"" << height_statistic_fields()[i].name << "\": ";
    if (height_statistic_fields()[i].integer) o << std::llround(statistics[i]);
    else o << statistics[i];
  }
}

// A solid's "boundaries" member, its vertices indexed in `v`.
void write_solid_boundaries(std::ostream& o, const Solid& s, CityJsonVertices& v) {
  o << "[[";
  for (std::size_t f = 0; f < s.faces.size(); ++f) {
    o << (f ? ", [" : "[");
    for (std::size_t r = 0; r < s.faces[f].rings.size(); ++r) {
      o << (r ? ", [" : "[");
      for (std::size_t i = 0; i < s.faces[f].rings[r].size(); ++i) o << (i ? ", " : "") << v.index(s.faces[f].rings[r][i]);
      o << ']';
    }
    o << "]";
  }
  o << "]]";
}

// The CityJSON objects of one building: "id": {"type": "Building", ...} and its LoD1.3 parts
// ("id-1": {"type": "BuildingPart", ...}), its vertices indexed in `v`.
void write_city_object(std::ostream& o, const BuildingModel& m, CityJsonVertices& v) {
  const std::string id = object_id(m);
  o << '"' << id << "\": ";
  const auto ring3 = [&](const Ring3& r) {
    o << '[';
    for (std::size_t i = 0; i < r.size(); ++i) o << (i ? ", " : "") << v.index(r[i]);
    o << ']';
  };
  const auto ring = [&](const Ring& r, double z) {
    Ring3 lifted;
    for (const Vec2& p : r) lifted.emplace_back(p.x(), p.y(), z);
    ring3(lifted);
  };
  // (status, regularizer and tile are lodforge's own words and names; stage and reason are free text)
  o << "{\"type\": \"Building\", \"attributes\": {\"status\": \"" << m.status << "\", \"regularizer\": \"" << m.regularizer
    << "\", \"tile\": \"" << m.tile << "\"";
  if (!m.stage.empty()) o << ", \"failed_stage\": \"" << json_text(m.stage) << "\"";
  if (!m.reason.empty()) o << ", \"reason\": \"" << json_text(m.reason) << "\"";
  if (!m.cadastre.empty()) {
    if (!m.cadastre_id.empty()) o << ", \"cadastre_id\": \"" << json_text(m.cadastre_id) << "\"";
    o << ", \"cadastre\": \"" << m.cadastre << "\"";
    if (m.coverage >= 0) o << ", \"cadastre_coverage\": " << m.coverage;
  }
  if (m.has_lod1) write_height_attributes(o, m.ground, m.roof, m.height_statistics);
  o << "}, \"geometry\": [";
  const double z = m.has_lod1 ? m.ground : 0.0;
  o << "{\"type\": \"MultiSurface\", \"lod\": \"0\", \"boundaries\": [[";
  ring(m.footprint.outer, z);
  for (const Ring& h : m.footprint.holes) { o << ", "; ring(h, z); }
  o << "]]}";
  if (m.has_lod1) {
    o << ", {\"type\": \"Solid\", \"lod\": \"1\", \"boundaries\": ";
    write_solid_boundaries(o, m.solid, v);
    o << "}";
  }
  o << "]";
  if (!m.parts.empty()) {
    o << ", \"children\": [";
    for (std::size_t k = 0; k < m.parts.size(); ++k) o << (k ? ", " : "") << '"' << id << '-' << k + 1 << '"';
    o << "]";
  }
  o << "}";
  for (std::size_t k = 0; k < m.parts.size(); ++k) {
    const PartModel& p = m.parts[k];
    o << ", \"" << id << '-' << k + 1 << "\": {\"type\": \"BuildingPart\", \"parents\": [\"" << id << "\"], \"attributes\": {\"tile\": \"" << m.tile << "\"";
    write_height_attributes(o, p.ground, p.roof, p.height_statistics);
    o << "}, \"geometry\": [{\"type\": \"Solid\", \"lod\": \"1.3\", \"boundaries\": ";
    write_solid_boundaries(o, p.solid, v);
    o << "}]}";
  }
}

// What a CityJSON file (or a CityJSONSeq's first line) starts with: type, version, transform,
// metadata (without the closing brace of the object).
void write_cityjson_header(std::ostream& o, const WriterContext& c, const char* separator) {
  o << "{\"type\": \"CityJSON\", \"version\": \"2.0\"," << separator << "\"transform\": {\"scale\": [0.001, 0.001, 0.001], \"translate\": ["
    << c.origin.x() << ", " << c.origin.y() << ", 0.0]}," << separator << "\"metadata\": {\"title\": \"lodforge tile " << c.tile << "\"";
  if (!c.epsg.empty()) o << ", \"referenceSystem\": \"https://www.opengis.net/def/crs/EPSG/0/" << c.epsg.substr(5) << "\"";
  o << ", \"geographicalExtent\": [";
  for (std::size_t k = 0; k < 6; ++k) o << (k ? ", " : "") << Fixed3{c.extent[k]};
  o << "]}";
}

class CityJsonWriter : public ModelWriter {
 public:
  CityJsonWriter(const std::string& path, const WriterContext& c) : file_(path), vertices_(c.origin) {
    three_decimals(file_.out());
    write_cityjson_header(file_.out(), c, "\n ");
    file_.out() << ",\n \"CityObjects\": {";
  }
  void add(const BuildingModel& m) override {
    auto& o = file_.out();
    o << (first_ ? "\n  " : ",\n  ");
    first_ = false;
    write_city_object(o, m, vertices_);
  }
  void finish() override {
    auto& o = file_.out();
    o << "\n },\n \"vertices\": [";
    vertices_.write(o, true);
    o << "\n ]\n}\n";
    file_.commit();
  }

 private:
  AtomicTextFile file_;
  bool first_ = true;
  CityJsonVertices vertices_;
};

// CityJSON Text Sequences (CityJSONSeq, .city.jsonl), the streaming form 3DBAG publishes: a
// first line with the shared transform and metadata, then one CityJSONFeature per building
// with its own vertices (indices from 0), on one line each.
class CityJsonSeqWriter : public ModelWriter {
 public:
  CityJsonSeqWriter(const std::string& path, const WriterContext& c) : file_(path), origin_(c.origin) {
    three_decimals(file_.out());
    write_cityjson_header(file_.out(), c, " ");
    file_.out() << ", \"CityObjects\": {}, \"vertices\": []}\n";
  }
  void add(const BuildingModel& m) override {
    auto& o = file_.out();
    CityJsonVertices vertices(origin_);
    const std::string id = object_id(m);
    o << "{\"type\": \"CityJSONFeature\", \"id\": \"" << id << "\", \"CityObjects\": {";
    write_city_object(o, m, vertices);
    o << "}, \"vertices\": [";
    vertices.write(o, false);
    o << "]}\n";
  }
  void finish() override { file_.commit(); }

 private:
  AtomicTextFile file_;
  Vec2 origin_;
};

// The faces of a solid as polygons a mesh format takes, outward as the solid's: walls (one ring of
// at most 4 vertices) as they are, and faces with holes or more vertices (tops and bottoms)
// triangulated in the plan; with every_face, horizontal faces of up to 4 vertices too (a quad
// footprint need not be convex). origin: subtracted for the triangulation's numerical range.
void for_each_mesh_polygon(const Solid& solid, const Vec2& origin, bool every_face,
                           const std::function<void(const std::vector<Vec3>&)>& polygon) {
  for (const Face& f : solid.faces) {
    bool horizontal = true;
    for (const Vec3& p : f.rings[0]) horizontal &= p.z() == f.rings[0].front().z();
    if (f.rings.size() == 1 && f.rings[0].size() <= 4 && !(every_face && horizontal)) {
      polygon(std::vector<Vec3>(f.rings[0].begin(), f.rings[0].end()));
      continue;
    }
    // Triangulated in the plan (outer ring counter-clockwise, holes clockwise), the triangles
    // turned over for a face that looks down (the bottom).
    std::vector<Ring> rings;
    bool downward = false;
    for (std::size_t k = 0; k < f.rings.size(); ++k) {
      Ring flat;
      for (const Vec3& p : f.rings[k]) flat.emplace_back(p.x() - origin.x(), p.y() - origin.y());
      if (k == 0) downward = signed_area(flat) < 0;
      if ((signed_area(flat) > 0) != (k == 0)) std::reverse(flat.begin(), flat.end());
      rings.push_back(flat);
    }
    TriangulationOptions plain;
    plain.max_vertices = 0;  // no refinement: the input vertices only
    const TriangleMesh mesh = triangulate(rings, 1e9, plain);
    const double z = f.rings[0].front().z();
    for (const auto& t : mesh.triangles) {
      std::vector<Vec3> triangle;
      for (int k : t) triangle.emplace_back(mesh.vertices[k].x() + origin.x(), mesh.vertices[k].y() + origin.y(), z);
      if (downward) std::reverse(triangle.begin(), triangle.end());
      polygon(triangle);
    }
  }
}

// Wavefront OBJ: one object per building, coordinates relative to the tile origin so that single
// precision holds; the origin is in the header. Faces with holes are triangulated.
class ObjWriter : public ModelWriter {
 public:
  ObjWriter(const std::string& path, const WriterContext& c) : file_(path), origin_(c.origin) {
    three_decimals(file_.out());
    file_.out() << "# lodforge OBJ, tile " << c.tile << ", CRS " << (c.epsg.empty() ? "unknown" : c.epsg) << "\n"
                << "# origin " << origin_.x() << " " << origin_.y() << " 0.000 (add to every vertex)\n";
  }
  void add(const BuildingModel& m) override {
    if (!m.has_lod1) return;  // OBJ carries the LOD1 blocks only
    auto& o = file_.out();
    o << "o " << object_id(m) << "\n";
    object_vertices_.clear();
    for_each_mesh_polygon(m.solid, origin_, false, [&](const std::vector<Vec3>& polygon) {
      std::vector<std::size_t> ids;
      for (const Vec3& p : polygon) ids.push_back(vertex(p));
      face(ids);
    });
  }
  void finish() override { file_.commit(); }

 private:
  // A building's faces share its vertices: each point (as written, to the millimetre) once per object.
  std::size_t vertex(const Vec3& p) {
    char line[128] = "v ";
    char* at = line + 2;
    for (const double c : {p.x() - origin_.x(), p.y() - origin_.y(), p.z()}) {
      at = std::to_chars(at, line + sizeof line - 2, c, std::chars_format::fixed, 3).ptr;
      *at++ = ' ';
    }
    at[-1] = '\n';
    const auto [it, added] = object_vertices_.try_emplace(std::string(line, at), count_ + 1);
    if (!added) return it->second;
    file_.out() << it->first;
    return ++count_;
  }
  void face(const std::vector<std::size_t>& ids) {
    file_.out() << 'f';
    for (std::size_t id : ids) file_.out() << ' ' << id;
    file_.out() << '\n';
  }
  AtomicTextFile file_;
  Vec2 origin_;
  std::size_t count_ = 0;
  std::unordered_map<std::string, std::size_t> object_vertices_;  // this object's: line -> index
};

// GeoPackage / GeoJSON footprints with attributes, for GIS users.
class FootprintModelWriter : public ModelWriter {
 public:
  FootprintModelWriter(const std::string& path, const WriterContext& c) : file_(path, layer_for(c)) {}
  void add(const BuildingModel& m) override {
    FootprintRecord r;
    r.id = long(m.id);
    r.polygon = m.footprint;
    r.status = m.status;
    r.failed_stage = m.stage;
    r.reason = m.reason;
    r.regularizer = m.regularizer;
    r.model = m.model;
    r.kind = m.tile;
    r.has_heights = m.has_lod1;
    r.roof_height = m.roof;
    r.ground_height = m.ground;
    r.height_statistics = m.height_statistics;
    if (m.has_lod1) r.lod1_faces = m.solid.faces;
    for (const PartModel& p : m.parts) r.parts.push_back({p.footprint, p.ground, p.roof, p.height_statistics});
    r.cadastre_id = m.cadastre_id;
    r.cadastre = m.cadastre;
    r.coverage = m.coverage;
    file_.add(r);
  }
  void finish() override { file_.finish(); }

 private:
  static FootprintLayer layer_for(const WriterContext& c) {
    FootprintLayer layer;
    layer.crs_wkt = c.crs_wkt;
    layer.write_heights = true;
    layer.write_model = true;
    layer.kind_field = "tile";
    layer.write_lod1 = true;  // (GeoPackage only)
    layer.rfc7946 = true;     // (GeoJSON only)
    layer.write_cadastre = c.cadastre;
    return layer;
  }
  FootprintFileWriter file_;
};

// glTF 2.0, binary (.glb): one mesh and node per LOD1 block (named by its gml:id), triangles with
// the block's points shared, positions in metres from the tile's origin in glTF's frame (+X
// east, +Y up, +Z south); the origin and CRS in the asset's extras. No normals: viewers shade
// the flat faces themselves.
class GltfWriter : public ModelWriter {
 public:
  GltfWriter(const std::string& path, const WriterContext& c) : file_(path), origin_(c.origin), epsg_(c.epsg), tile_(c.tile) {}
  void add(const BuildingModel& m) override {
    if (!m.has_lod1) return;  // glTF carries the LOD1 blocks only
    Block block{object_id(m), {}, {}};
    std::map<std::array<long long, 3>, std::uint32_t> index;  // this block's points, to the millimetre
    for_each_mesh_polygon(m.solid, origin_, true, [&](const std::vector<Vec3>& polygon) {
      std::vector<std::uint32_t> ids;
      for (const Vec3& p : polygon) {
        const double x = p.x() - origin_.x(), y = p.y() - origin_.y(), z = p.z();
        const std::array<long long, 3> key{std::llround(x * 1000), std::llround(y * 1000), std::llround(z * 1000)};
        const auto [it, added] = index.try_emplace(key, std::uint32_t(block.positions.size() / 3));
        if (added) block.positions.insert(block.positions.end(), {float(key[0] / 1000.0), float(key[2] / 1000.0), float(-key[1] / 1000.0)});
        ids.push_back(it->second);
      }
      for (std::size_t k = 1; k + 1 < ids.size(); ++k) block.indices.insert(block.indices.end(), {ids[0], ids[k], ids[k + 1]});
    });
    blocks_.push_back(std::move(block));
  }
  void finish() override {
    tinygltf::Model model;
    model.asset.version = "2.0";
    model.asset.generator = "lodforge";
    tinygltf::Value::Object extras;
    extras["tile"] = tinygltf::Value(tile_);
    extras["crs"] = tinygltf::Value(epsg_.empty() ? std::string("unknown") : epsg_);
    extras["origin"] = tinygltf::Value(tinygltf::Value::Array{tinygltf::Value(origin_.x()), tinygltf::Value(origin_.y()), tinygltf::Value(0.0)});
    extras["axes"] = tinygltf::Value(std::string("glTF +X = map x (east), +Y = height, +Z = -map y (south), metres from origin"));
    model.asset.extras = tinygltf::Value(extras);
    // One buffer: every block's positions, then every block's indices.
    std::vector<unsigned char> bytes;
    const auto append = [&](const void* data, std::size_t size) {
      const auto* b = static_cast<const unsigned char*>(data);
      bytes.insert(bytes.end(), b, b + size);
    };
    std::size_t positions_size = 0;
    for (const Block& b : blocks_) positions_size += b.positions.size() * sizeof(float);
    for (const Block& b : blocks_) append(b.positions.data(), b.positions.size() * sizeof(float));
    for (const Block& b : blocks_) append(b.indices.data(), b.indices.size() * sizeof(std::uint32_t));
    tinygltf::Scene scene;
    scene.name = tile_;  // (a scene without nodes and name would be written as null, which no reader takes)
    if (!blocks_.empty()) {
      tinygltf::Buffer buffer;
      buffer.data = bytes;
      model.buffers.push_back(std::move(buffer));
      tinygltf::BufferView positions, indices;
      positions.buffer = indices.buffer = 0;
      positions.byteLength = positions_size;
      positions.byteStride = 3 * sizeof(float);
      positions.target = TINYGLTF_TARGET_ARRAY_BUFFER;
      indices.byteOffset = positions_size;
      indices.byteLength = bytes.size() - positions_size;
      indices.target = TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER;
      model.bufferViews = {positions, indices};
      std::size_t position_offset = 0, index_offset = 0;
      for (const Block& b : blocks_) {
        tinygltf::Accessor p, i;
        p.bufferView = 0;
        p.byteOffset = position_offset;
        p.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
        p.type = TINYGLTF_TYPE_VEC3;
        p.count = b.positions.size() / 3;
        p.minValues = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
        p.maxValues = {-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
        for (std::size_t k = 0; k < b.positions.size(); ++k) {
          p.minValues[k % 3] = std::min(p.minValues[k % 3], double(b.positions[k]));
          p.maxValues[k % 3] = std::max(p.maxValues[k % 3], double(b.positions[k]));
        }
        i.bufferView = 1;
        i.byteOffset = index_offset;
        i.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
        i.type = TINYGLTF_TYPE_SCALAR;
        i.count = b.indices.size();
        position_offset += b.positions.size() * sizeof(float);
        index_offset += b.indices.size() * sizeof(std::uint32_t);
        tinygltf::Primitive primitive;
        primitive.attributes["POSITION"] = int(model.accessors.size());
        model.accessors.push_back(std::move(p));
        primitive.indices = int(model.accessors.size());
        model.accessors.push_back(std::move(i));
        primitive.mode = TINYGLTF_MODE_TRIANGLES;
        tinygltf::Mesh mesh;
        mesh.name = b.id;
        mesh.primitives.push_back(std::move(primitive));
        tinygltf::Node node;
        node.name = b.id;
        node.mesh = int(model.meshes.size());
        model.meshes.push_back(std::move(mesh));
        scene.nodes.push_back(int(model.nodes.size()));
        model.nodes.push_back(std::move(node));
      }
    }
    model.scenes.push_back(std::move(scene));
    model.defaultScene = 0;
    tinygltf::TinyGLTF writer;
    if (!writer.WriteGltfSceneToStream(&model, file_.out(), false, true)) throw InputError("glTF: the model could not be written");
    file_.commit();
  }

 private:
  struct Block {
    std::string id;
    std::vector<float> positions;        // x, y, z per point, glTF frame
    std::vector<std::uint32_t> indices;  // triangles
  };
  AtomicTextFile file_;
  Vec2 origin_;
  std::string epsg_, tile_;
  std::vector<Block> blocks_;
};

}  // namespace

Extent extent_of(const std::vector<BuildingModel>& models) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  Extent e{inf, inf, inf, -inf, -inf, -inf};
  const auto add = [&](const Vec2& p, double z_low, double z_high) {
    e[0] = std::min(e[0], p.x()); e[1] = std::min(e[1], p.y()); e[2] = std::min(e[2], z_low);
    e[3] = std::max(e[3], p.x()); e[4] = std::max(e[4], p.y()); e[5] = std::max(e[5], z_high);
  };
  for (const BuildingModel& m : models) {
    for (const Vec2& p : m.footprint.outer) add(p, m.has_lod1 ? std::min(m.ground, m.roof) : 0.0, m.has_lod1 ? std::max(m.ground, m.roof) : 0.0);
    for (const PartModel& part : m.parts)  // (each on its own ground, to its own roof)
      for (const Vec2& p : part.footprint.outer) add(p, std::min(part.ground, part.roof), std::max(part.ground, part.roof));
  }
  if (models.empty()) e = Extent{};
  return e;
}

std::unique_ptr<ModelWriter> make_model_writer(const std::string& format, const std::string& path, const WriterContext& context) {
  if (format == "citygml") return std::make_unique<CityGmlWriter>(path, context);
  if (format == "cityjson") return std::make_unique<CityJsonWriter>(path, context);
  if (format == "cityjsonseq") return std::make_unique<CityJsonSeqWriter>(path, context);
  if (format == "obj") return std::make_unique<ObjWriter>(path, context);
  if (format == "gltf") return std::make_unique<GltfWriter>(path, context);
  return std::make_unique<FootprintModelWriter>(path, context);
}

}  // namespace lodforge
