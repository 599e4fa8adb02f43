// lodforge merge OUT_DIR: combines a run's per-tile files into one file per format (and the
// shards' tile indexes into one), streaming, in tile order.
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <gdal_priv.h>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <ogrsf_frmts.h>
#include <nlohmann/json.hpp>
#include <libxml/xmlreader.h>
#include <libxml/xmlwriter.h>
#include <regex>
#include <set>
#include <spdlog/spdlog.h>
#include <sstream>
#include <tiny_gltf.h>
#include <unistd.h>

#include "cli/args.hpp"
#include "commands/commands.hpp"
#include "io/atomic_file.hpp"
#include "io/errors.hpp"
#include "io/footprint_writer.hpp"
#include "io/model_writers.hpp"
#include "run/checkpoint.hpp"
#include "run/overview.hpp"
#include "run/run_report.hpp"

namespace lodforge {

namespace fs = std::filesystem;

namespace {

std::string fixed3(double v) {
  char buffer[48];
  std::snprintf(buffer, sizeof buffer, "%.3f", v);
  return buffer;
}

// The union of the extents the tiles declare (6 numbers: min x, y, z, max x, y, z): the merged
// file's. A tile without one (written by an earlier lodforge) is named in a warning and left out.
class ExtentUnion {
 public:
  void add(const fs::path& file, const std::vector<double>& extent) {
    if (extent.size() != 6) {
      spdlog::warn("'{}': declares no extent (written by an earlier lodforge?); the merged extent leaves it out", file.string());
      return;
    }
    for (std::size_t i = 0; i < 3; ++i) {
      all_[i] = std::min(all_[i], extent[i]);
      all_[i + 3] = std::max(all_[i + 3], extent[i + 3]);
    }
  }
  // A CityJSON metadata's geographicalExtent, when it is 6 numbers.
  void add(const fs::path& file, const nlohmann::ordered_json& extent) {
    std::vector<double> values;
    if (extent.is_array())
      for (const auto& v : extent) if (v.is_number()) values.push_back(v.get<double>());
    add(file, extent.is_array() && values.size() == extent.size() ? values : std::vector<double>{});
  }
  Extent get() const { return all_[0] > all_[3] ? Extent{} : all_; }

 private:
  static constexpr double inf = std::numeric_limits<double>::infinity();
  Extent all_{inf, inf, inf, -inf, -inf, -inf};
};

// ---- CityGML, read with libxml2's streaming reader and written with its text writer ----

using Reader = std::unique_ptr<xmlTextReader, void (*)(xmlTextReaderPtr)>;
using Writer = std::unique_ptr<xmlTextWriter, void (*)(xmlTextWriterPtr)>;

constexpr const char* citygml_core = "http://www.opengis.net/citygml/2.0";
constexpr const char* gml_ns = "http://www.opengis.net/gml";

std::string text_of(const xmlChar* s) { return s ? reinterpret_cast<const char*>(s) : ""; }
const xmlChar* xml(const char* s) { return reinterpret_cast<const xmlChar*>(s); }

Reader open_xml(const fs::path& file) {
  Reader r(xmlReaderForFile(file.c_str(), nullptr, XML_PARSE_NONET), xmlFreeTextReader);
  if (!r) throw InputError("'" + file.string() + "': cannot read");
  return r;
}

// Advances to the next node; InputError naming the file and line when the XML is not well formed.
bool next_node(xmlTextReaderPtr r, const fs::path& file) {
  const int status = xmlTextReaderRead(r);
  if (status < 0) {
    const xmlError* e = xmlGetLastError();
    throw InputError("'" + file.string() + "': line " + std::to_string(e ? e->line : 0) + ": not well-formed XML" +
                     (e && e->message ? std::string(": ") + e->message : std::string()));
  }
  return status == 1;
}

bool is_element(xmlTextReaderPtr r, const char* ns, const char* local) {
  return xmlTextReaderNodeType(r) == XML_READER_TYPE_ELEMENT && text_of(xmlTextReaderConstLocalName(r)) == local &&
         text_of(xmlTextReaderConstNamespaceUri(r)) == ns;
}

// A lodforge CityGML tile's root (core:CityModel) and what its gml:boundedBy declares: the
// envelope's srsName and its corners. Leaves the reader on the root's first child.
struct CityGmlHead {
  std::vector<std::pair<std::string, std::string>> root_attributes;  // namespaces and schema locations
  std::string srs;
  std::vector<double> corners;  // 6 numbers, or none
};

CityGmlHead read_citygml_head(xmlTextReaderPtr r, const fs::path& file) {
  CityGmlHead head;
  while (next_node(r, file) && xmlTextReaderNodeType(r) != XML_READER_TYPE_ELEMENT) {}
  if (!is_element(r, citygml_core, "CityModel")) throw InputError("'" + file.string() + "': not a CityGML 2.0 file (its root is not core:CityModel)");
  while (xmlTextReaderMoveToNextAttribute(r) == 1)
    head.root_attributes.emplace_back(text_of(xmlTextReaderConstName(r)), text_of(xmlTextReaderConstValue(r)));
  xmlTextReaderMoveToElement(r);
  return head;
}

// Reads gml:boundedBy (the reader on it) into head; leaves the reader on its end.
void read_bounded_by(xmlTextReaderPtr r, const fs::path& file, CityGmlHead& head) {
  const int depth = xmlTextReaderDepth(r);
  std::string corner;
  while (next_node(r, file) && xmlTextReaderDepth(r) > depth) {
    if (is_element(r, gml_ns, "Envelope")) {
      xmlChar* srs = xmlTextReaderGetAttribute(r, xml("srsName"));
      head.srs = text_of(srs);
      xmlFree(srs);
    } else if (is_element(r, gml_ns, "lowerCorner") || is_element(r, gml_ns, "upperCorner")) {
      xmlChar* content = xmlTextReaderReadString(r);
      std::istringstream numbers(text_of(content));
      xmlFree(content);
      double v = 0;
      int count = 0;
      for (; count < 3 && numbers >> v; ++count) head.corners.push_back(v);
      if (count != 3) throw InputError("'" + file.string() + "': gml:boundedBy: a corner without 3 coordinates");
    }
  }
}

// Copies the element the reader is on, with everything inside it, to the writer; leaves the reader
// on its end.
void copy_element(xmlTextReaderPtr r, xmlTextWriterPtr w, const fs::path& file) {
  const int depth = xmlTextReaderDepth(r);
  do {
    switch (xmlTextReaderNodeType(r)) {
      case XML_READER_TYPE_ELEMENT: {
        const bool empty = xmlTextReaderIsEmptyElement(r);
        xmlTextWriterStartElement(w, xmlTextReaderConstName(r));
        while (xmlTextReaderMoveToNextAttribute(r) == 1) xmlTextWriterWriteAttribute(w, xmlTextReaderConstName(r), xmlTextReaderConstValue(r));
        xmlTextReaderMoveToElement(r);
        if (empty) {
          xmlTextWriterEndElement(w);
          if (xmlTextReaderDepth(r) == depth) return;
        }
        break;
      }
      case XML_READER_TYPE_END_ELEMENT:
        xmlTextWriterFullEndElement(w);
        if (xmlTextReaderDepth(r) == depth) return;
        break;
      case XML_READER_TYPE_TEXT:
      case XML_READER_TYPE_CDATA:
        xmlTextWriterWriteString(w, xmlTextReaderConstValue(r));
        break;
      case XML_READER_TYPE_WHITESPACE:
      case XML_READER_TYPE_SIGNIFICANT_WHITESPACE:
        xmlTextWriterWriteRaw(w, xmlTextReaderConstValue(r));  // the tiles' indentation, kept
        break;
      default:
        break;  // comments, processing instructions
    }
  } while (next_node(r, file));
  throw InputError("'" + file.string() + "': ends inside an element");
}

// Moves the reader from an element to its end.
void skip_element(xmlTextReaderPtr r, const fs::path& file) {
  if (xmlTextReaderIsEmptyElement(r)) return;
  const int depth = xmlTextReaderDepth(r);
  while (next_node(r, file))
    if (xmlTextReaderNodeType(r) == XML_READER_TYPE_END_ELEMENT && xmlTextReaderDepth(r) == depth) return;
  throw InputError("'" + file.string() + "': ends inside an element");
}

int to_stream(void* context, const char* buffer, int length) {
  static_cast<std::ostream*>(context)->write(buffer, length);
  return length;
}

// CityGML: the first tile's root (its namespaces), one name and envelope for the run (the union
// of the tiles' envelopes), then every tile's core:cityObjectMember elements, parsed and copied.
void merge_citygml(const std::vector<fs::path>& files, const fs::path& target) {
  ExtentUnion extents;
  CityGmlHead first;
  for (const fs::path& file : files) {  // the envelopes, each at the top of its file
    Reader r = open_xml(file);
    CityGmlHead head = read_citygml_head(r.get(), file);
    while (next_node(r.get(), file) && xmlTextReaderDepth(r.get()) > 0) {
      if (is_element(r.get(), gml_ns, "boundedBy")) { read_bounded_by(r.get(), file, head); break; }
      if (is_element(r.get(), citygml_core, "cityObjectMember")) break;
    }
    extents.add(file, head.corners);
    if (file == files.front()) first = std::move(head);
  }
  const Extent all = extents.get();
  AtomicTextFile o(target);
  xmlOutputBufferPtr buffer = xmlOutputBufferCreateIO(to_stream, nullptr, &o.out(), nullptr);
  Writer w(xmlNewTextWriter(buffer), xmlFreeTextWriter);
  if (!w) throw InputError("'" + target.string() + "': cannot write");
  xmlTextWriterStartDocument(w.get(), "1.0", "UTF-8", nullptr);
  xmlTextWriterStartElement(w.get(), xml("core:CityModel"));
  for (const auto& [name, value] : first.root_attributes) xmlTextWriterWriteAttribute(w.get(), xml(name.c_str()), xml(value.c_str()));
  xmlTextWriterWriteRaw(w.get(), xml("\n  "));
  xmlTextWriterWriteElement(w.get(), xml("gml:name"), xml(("lodforge, merged from " + std::to_string(files.size()) + " tiles").c_str()));
  xmlTextWriterWriteRaw(w.get(), xml("\n  "));
  xmlTextWriterStartElement(w.get(), xml("gml:boundedBy"));
  xmlTextWriterStartElement(w.get(), xml("gml:Envelope"));
  if (!first.srs.empty()) xmlTextWriterWriteAttribute(w.get(), xml("srsName"), xml(first.srs.c_str()));
  xmlTextWriterWriteAttribute(w.get(), xml("srsDimension"), xml("3"));
  const auto corner = [&](const char* name, std::size_t k) {
    xmlTextWriterWriteElement(w.get(), xml(name), xml((fixed3(all[k]) + ' ' + fixed3(all[k + 1]) + ' ' + fixed3(all[k + 2])).c_str()));
  };
  corner("gml:lowerCorner", 0);
  corner("gml:upperCorner", 3);
  xmlTextWriterEndElement(w.get());
  xmlTextWriterEndElement(w.get());
  for (const fs::path& file : files) {
    Reader r = open_xml(file);
    read_citygml_head(r.get(), file);
    while (next_node(r.get(), file) && xmlTextReaderDepth(r.get()) > 0) {
      if (xmlTextReaderNodeType(r.get()) != XML_READER_TYPE_ELEMENT) continue;
      if (is_element(r.get(), citygml_core, "cityObjectMember")) {
        xmlTextWriterWriteRaw(w.get(), xml("\n  "));
        copy_element(r.get(), w.get(), file);
      } else if (is_element(r.get(), gml_ns, "name") || is_element(r.get(), gml_ns, "boundedBy")) {
        skip_element(r.get(), file);  // the tile's own, replaced by the run's
      } else {
        throw InputError("'" + file.string() + "': line " + std::to_string(xmlTextReaderGetParserLineNumber(r.get())) + ": " +
                         text_of(xmlTextReaderConstName(r.get())) + " is not what a lodforge CityGML tile holds");
      }
    }
  }
  xmlTextWriterWriteRaw(w.get(), xml("\n"));
  xmlTextWriterEndElement(w.get());
  if (xmlTextWriterEndDocument(w.get()) < 0) throw InputError("'" + target.string() + "': writing the XML failed");
  w.reset();  // flushes into o
  o.commit();
}

// The union of the extents the CityJSONSeq tiles declare in their first lines (metadata's
// geographicalExtent): the merged file's.
Extent merged_extent(const std::vector<fs::path>& files) {
  ExtentUnion extents;
  for (const fs::path& file : files) {
    std::ifstream in(file);
    std::string line;
    std::getline(in, line);
    const nlohmann::ordered_json header = nlohmann::ordered_json::parse(line, nullptr, false);
    const bool has = header.is_object() && header.contains("metadata") && header["metadata"].contains("geographicalExtent");
    extents.add(file, has ? header["metadata"]["geographicalExtent"] : nlohmann::ordered_json());
  }
  return extents.get();
}

long long millimetres(double metres) { return std::llround(metres * 1000.0); }

// Millimetres as metres with three decimals, exactly (no floating point on the way).
std::string metres(long long mm) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%s%lld.%03lld", mm < 0 ? "-" : "", std::llabs(mm) / 1000, std::llabs(mm) % 1000);
  return buffer;
}

// A number of an OBJ line in millimetres; InputError naming the file and line when it is not one.
long long obj_millimetres(const std::string& text, const fs::path& file, std::size_t line) {
  double v = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (error != std::errc() || end != text.data() + text.size() || !std::isfinite(v))
    throw InputError("'" + file.string() + "': line " + std::to_string(line) + ": '" + text + "' is not a number");
  return millimetres(v);
}

// OBJ: each tile read line by line (its header, v, f and o lines; anything else refused), the
// vertices moved to the first tile's origin, the face indices offset and checked.
void merge_obj(const std::vector<fs::path>& files, const fs::path& target) {
  AtomicTextFile o(target);
  long long ox = 0, oy = 0;
  std::size_t offset = 0;
  for (std::size_t k = 0; k < files.size(); ++k) {
    std::ifstream in(files[k]);
    if (!in) throw InputError("'" + files[k].string() + "': cannot read");
    std::string line, crs;
    std::getline(in, line);
    const std::string head = "# lodforge OBJ, tile ";
    if (line.rfind(head, 0) != 0 || line.find(", CRS ") == std::string::npos)
      throw InputError("'" + files[k].string() + "': line 1: not a lodforge OBJ tile (no '" + head + "..., CRS ...')");
    crs = line.substr(line.find(", CRS ") + 6);
    std::getline(in, line);
    std::istringstream origin(line);
    std::string hash, word, x, y;
    if (!(origin >> hash >> word >> x >> y) || hash != "#" || word != "origin")
      throw InputError("'" + files[k].string() + "': line 2: not a lodforge OBJ tile (no '# origin X Y Z')");
    const long long tx = obj_millimetres(x, files[k], 2), ty = obj_millimetres(y, files[k], 2);
    if (k == 0) {
      ox = tx;
      oy = ty;
      o.out() << "# lodforge OBJ, merged from " << files.size() << " tiles, CRS " << crs << "\n" << line << '\n';
    }
    std::size_t count = 0;
    for (std::size_t number = 3; std::getline(in, line); ++number) {
      std::istringstream fields(line);
      std::string kind;
      fields >> kind;
      if (kind == "v") {
        std::string vx, vy, vz;
        if (!(fields >> vx >> vy >> vz)) throw InputError("'" + files[k].string() + "': line " + std::to_string(number) + ": a vertex without 3 coordinates");
        o.out() << "v " << metres(obj_millimetres(vx, files[k], number) + tx - ox) << ' ' << metres(obj_millimetres(vy, files[k], number) + ty - oy)
                << ' ' << metres(obj_millimetres(vz, files[k], number)) << '\n';
        ++count;
      } else if (kind == "f") {
        o.out() << 'f';
        std::size_t corners = 0;
        for (std::string id; fields >> id; ++corners) {
          std::size_t v = 0;
          const auto [end, error] = std::from_chars(id.data(), id.data() + id.size(), v);
          if (error != std::errc() || end != id.data() + id.size() || v == 0 || v > count)
            throw InputError("'" + files[k].string() + "': line " + std::to_string(number) + ": '" + id + "' is not one of the " +
                             std::to_string(count) + " vertices before it");
          o.out() << ' ' << v + offset;
        }
        if (corners < 3) throw InputError("'" + files[k].string() + "': line " + std::to_string(number) + ": a face with fewer than 3 corners");
        o.out() << '\n';
      } else if (kind == "o") {
        o.out() << line << '\n';
      } else if (!kind.empty() && kind[0] != '#') {
        throw InputError("'" + files[k].string() + "': line " + std::to_string(number) + ": '" + kind + "' is not what a lodforge OBJ tile holds");
      }
    }
    offset += count;
  }
  o.commit();
}

// The vertex indices of a CityJSON boundary (nested lists), renumbered by remap.
void renumber(nlohmann::ordered_json& boundary, const std::vector<std::size_t>& remap) {
  if (boundary.is_array()) {
    for (auto& b : boundary) renumber(b, remap);
  } else {
    const std::size_t i = boundary.get<std::size_t>();
    if (i >= remap.size()) throw std::runtime_error("vertex " + std::to_string(i) + " of " + std::to_string(remap.size()));
    boundary = remap[i];
  }
}

// A CityJSON tile's members but its CityObjects and vertices (parsed, not kept).
nlohmann::ordered_json cityjson_head(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError("'" + file.string() + "': cannot read");
  using Json = nlohmann::ordered_json;
  return Json::parse(in, [](int depth, Json::parse_event_t event, Json& parsed) {
    return !(depth == 1 && event == Json::parse_event_t::key && (parsed == "CityObjects" || parsed == "vertices"));
  });
}

// CityJSON: each tile parsed (nlohmann-json), first for its header and extent, then whole; its
// CityObjects written one per line, their vertices moved onto the first tile's transform (exact:
// integer millimetres) and shared across tiles.
void merge_cityjson(const std::vector<fs::path>& files, const fs::path& target) {
  AtomicTextFile o(target);
  std::map<std::array<long long, 3>, std::size_t> index;
  std::vector<std::array<long long, 3>> vertices;
  std::array<long long, 2> first_translate{};
  std::set<std::string> ids;
  ExtentUnion extents;
  nlohmann::ordered_json header;
  const auto fail = [](const fs::path& file, const std::exception& e) {
    return InputError("'" + file.string() + "': not a lodforge CityJSON tile: " + e.what());
  };
  for (const fs::path& file : files) {
    try {
      nlohmann::ordered_json head = cityjson_head(file);
      if (head.at("type") != "CityJSON") throw std::runtime_error("its type is not CityJSON");
      if (head.at("transform").at("scale") != nlohmann::json::array({0.001, 0.001, 0.001})) throw std::runtime_error("its scale is not 1 mm");
      extents.add(file, head["metadata"]["geographicalExtent"]);
      if (file == files.front()) header = std::move(head);
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      throw fail(file, e);
    }
  }
  header["metadata"]["title"] = "lodforge, merged from " + std::to_string(files.size()) + " tiles";
  header["metadata"]["geographicalExtent"] = extents.get();
  o.out() << '{';
  for (const auto& [key, value] : header.items())
    o.out() << (key == header.begin().key() ? "" : ",\n ") << nlohmann::json(key).dump() << ": "
            << value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  o.out() << ",\n \"CityObjects\": {";
  for (const fs::path& file : files) {
    std::ifstream in(file);
    try {
      nlohmann::ordered_json tile = nlohmann::ordered_json::parse(in);
      const auto& translate = tile.at("transform").at("translate");
      const std::array<long long, 2> here{millimetres(translate.at(0).get<double>()), millimetres(translate.at(1).get<double>())};
      if (file == files.front()) first_translate = here;
      std::vector<std::size_t> remap;
      for (const auto& v : tile.at("vertices")) {
        const std::array<long long, 3> p{v.at(0).get<long long>() + here[0] - first_translate[0],
                                         v.at(1).get<long long>() + here[1] - first_translate[1], v.at(2).get<long long>()};
        auto [it, inserted] = index.try_emplace(p, vertices.size());
        if (inserted) vertices.push_back(p);
        remap.push_back(it->second);
      }
      for (auto& [id, object] : tile.at("CityObjects").items()) {
        if (!ids.insert(id).second) throw std::runtime_error("the CityObject '" + id + "' is in an earlier tile too");
        if (object.contains("geometry"))
          for (auto& g : object["geometry"]) renumber(g.at("boundaries"), remap);
        o.out() << (ids.size() == 1 ? "\n  " : ",\n  ") << nlohmann::json(id).dump() << ": "
                << object.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
      }
    } catch (const std::exception& e) {
      throw fail(file, e);
    }
  }
  o.out() << "\n },\n \"vertices\": [";
  for (std::size_t i = 0; i < vertices.size(); ++i)
    o.out() << (i ? ", " : "") << (i % 4 == 0 ? "\n  " : "") << '[' << vertices[i][0] << ", " << vertices[i][1] << ", " << vertices[i][2] << ']';
  o.out() << "\n ]\n}\n";
  o.commit();
}

// glTF: one scene with a node per tile, placed by its origin's offset from the first tile's (exact:
// node translations are doubles), holding the tile's block nodes; the tiles' buffers become one.
void merge_gltf(const std::vector<fs::path>& files, const fs::path& target) {
  tinygltf::TinyGLTF io;
  tinygltf::Model merged;
  merged.buffers.emplace_back();
  merged.scenes.emplace_back();
  merged.scenes[0].name = "lodforge, merged from " + std::to_string(files.size()) + " tiles";
  merged.defaultScene = 0;
  std::array<double, 2> first_origin{};
  for (std::size_t k = 0; k < files.size(); ++k) {
    tinygltf::Model tile;
    std::string error, warning;
    if (!io.LoadBinaryFromFile(&tile, &error, &warning, files[k].string()) || tile.buffers.size() > 1)
      throw InputError("'" + files[k].string() + "': not a lodforge glTF tile: " + (error.empty() ? "more than one buffer" : error));
    const tinygltf::Value& origin = tile.asset.extras.Get("origin");
    if (!origin.IsArray() || origin.ArrayLen() < 2) throw InputError("'" + files[k].string() + "': no origin in the asset's extras");
    const std::array<double, 2> here{origin.Get(0).GetNumberAsDouble(), origin.Get(1).GetNumberAsDouble()};
    if (k == 0) {
      first_origin = here;
      merged.asset = tile.asset;
      tinygltf::Value::Object extras = tile.asset.extras.Get<tinygltf::Value::Object>();
      extras.erase("tile");
      extras["tiles"] = tinygltf::Value(int(files.size()));
      merged.asset.extras = tinygltf::Value(extras);
    }
    const int views = int(merged.bufferViews.size()), accessors = int(merged.accessors.size()), meshes = int(merged.meshes.size());
    std::vector<unsigned char>& bytes = merged.buffers[0].data;
    const std::size_t base = bytes.size();
    if (!tile.buffers.empty()) bytes.insert(bytes.end(), tile.buffers[0].data.begin(), tile.buffers[0].data.end());
    for (tinygltf::BufferView v : tile.bufferViews) { v.buffer = 0; v.byteOffset += base; merged.bufferViews.push_back(std::move(v)); }
    for (tinygltf::Accessor a : tile.accessors) { a.bufferView += views; merged.accessors.push_back(std::move(a)); }
    for (tinygltf::Mesh m : tile.meshes) {
      for (auto& p : m.primitives) {
        for (auto& [name, accessor] : p.attributes) accessor += accessors;
        p.indices += accessors;
      }
      merged.meshes.push_back(std::move(m));
    }
    tinygltf::Node group;
    group.name = tile.asset.extras.Get("tile").IsString() ? tile.asset.extras.Get("tile").Get<std::string>() : files[k].stem().string();
    group.translation = {here[0] - first_origin[0], 0.0, -(here[1] - first_origin[1])};  // glTF: +Z is south
    for (tinygltf::Node n : tile.nodes) {
      n.mesh += meshes;
      group.children.push_back(int(merged.nodes.size()));
      merged.nodes.push_back(std::move(n));
    }
    merged.scenes[0].nodes.push_back(int(merged.nodes.size()));
    merged.nodes.push_back(std::move(group));
  }
  AtomicTextFile o(target);
  if (!io.WriteGltfSceneToStream(&merged, o.out(), false, true)) throw InputError("'" + target.string() + "': glTF could not be written");
  o.commit();
}

// CityJSONSeq: the first tile's first line (transform, metadata), then every tile's features,
// each read as JSON and its vertices moved onto the first tile's transform (exact integers).
void merge_cityjsonseq(const std::vector<fs::path>& files, const fs::path& target) {
  AtomicTextFile o(target);
  const Extent extent = merged_extent(files);
  std::array<long long, 2> first_translate{};
  for (std::size_t k = 0; k < files.size(); ++k) {
    std::ifstream in(files[k]);
    std::string line;
    nlohmann::json header;
    std::array<long long, 2> here{};
    try {
      if (!std::getline(in, line)) throw std::runtime_error("empty");
      header = nlohmann::json::parse(line);
      if (header.at("type") != "CityJSON" || header.at("transform").at("scale") != nlohmann::json::array({0.001, 0.001, 0.001}))
        throw std::runtime_error("not a lodforge CityJSONSeq header");
      const auto& translate = header.at("transform").at("translate");
      here = {std::llround(translate.at(0).get<double>() * 1000), std::llround(translate.at(1).get<double>() * 1000)};
    } catch (const std::exception& e) {
      throw InputError("'" + files[k].string() + "': line 1: not a lodforge CityJSONSeq tile (" + e.what() + ")");
    }
    if (k == 0) {
      first_translate = here;
      header["metadata"]["title"] = "lodforge, merged from " + std::to_string(files.size()) + " tiles";
      header["metadata"]["geographicalExtent"] = extent;
      o.out() << header.dump() << '\n';
    }
    const long long dx = here[0] - first_translate[0], dy = here[1] - first_translate[1];
    for (std::size_t number = 2; std::getline(in, line); ++number) {
      if (line.empty()) continue;
      nlohmann::json feature;
      try {
        feature = nlohmann::json::parse(line);
        if (feature.at("type") != "CityJSONFeature") throw std::runtime_error("not a CityJSONFeature");
        for (auto& v : feature.at("vertices")) {
          v.at(0) = v.at(0).get<long long>() + dx;
          v.at(1) = v.at(1).get<long long>() + dy;
        }
      } catch (const std::exception& e) {
        throw InputError("'" + files[k].string() + "': line " + std::to_string(number) + ": " + e.what());
      }
      o.out() << feature.dump() << '\n';
    }
  }
  o.commit();
}

void merge_ogr_into(const std::vector<fs::path>& files, const fs::path& target, const fs::path& temp, const std::string& driver_name);

// GeoPackage / GeoJSON through OGR: the first tile's layer definition, every feature appended.
void merge_ogr(const std::vector<fs::path>& files, const fs::path& target, const std::string& driver_name) {
  GDALAllRegister();
  set_gpkg_timestamp();  // byte-identical GeoPackages
  // No SpatiaLite set-up for each GeoPackage opened (~1 ms a file; no SQL is run here).
  CPLSetConfigOption("SPATIALITE_LOAD", "NO");
  const fs::path temp = target.parent_path() / (target.stem().string() + ".partial-" + std::to_string(getpid()) + target.extension().string());
  fs::remove(temp);
  try {
    merge_ogr_into(files, target, temp, driver_name);
  } catch (...) {
    std::error_code ec;
    fs::remove(temp, ec);
    throw;
  }
}

void merge_ogr_into(const std::vector<fs::path>& files, const fs::path& target, const fs::path& temp, const std::string& driver_name) {
  // Every layer of the tiles (footprints, and lod1 in a GeoPackage), by name, in the first tile's
  // order; each tile's features appended to its layer. (The caller removes temp on any error.)
  using Dataset = std::unique_ptr<GDALDataset, void (*)(GDALDataset*)>;
  const auto close = [](GDALDataset* d) { if (d) GDALClose(d); };
  Dataset out(GetGDALDriverManager()->GetDriverByName(driver_name.c_str())->Create(temp.c_str(), 0, 0, 0, GDT_Unknown, nullptr), close);
  if (!out) throw InputError("'" + target.string() + "': cannot create");
  std::map<std::string, OGRLayer*> layers;
  for (const fs::path& f : files) {
    Dataset in(static_cast<GDALDataset*>(GDALOpenEx(f.c_str(), GDAL_OF_VECTOR, nullptr, nullptr, nullptr)), close);
    if (!in) throw InputError("'" + f.string() + "': cannot read");
    const bool transaction = out->StartTransaction() == OGRERR_NONE;
    for (int l = 0; l < in->GetLayerCount(); ++l) {
      OGRLayer* source = in->GetLayer(l);
      OGRLayer*& layer = layers[source->GetName()];
      if (!layer) {
        // GeoJSON as RFC 7946 (its tiles are WGS 84 already: nothing moves, the precision stays).
        layer = out->CreateLayer(source->GetName(), source->GetSpatialRef(), source->GetGeomType(),
                                 driver_name == "GeoJSON" ? rfc7946_layer_options() : nullptr);
        if (!layer) throw InputError("'" + target.string() + "': cannot create the layer " + source->GetName());
        for (int i = 0; i < source->GetLayerDefn()->GetFieldCount(); ++i)
          if (layer->CreateField(source->GetLayerDefn()->GetFieldDefn(i)) != OGRERR_NONE)
            throw InputError("'" + target.string() + "': cannot create a field");
      }
      for (auto& feature : *source) {
        OGRFeature copy(layer->GetLayerDefn());
        copy.SetFrom(feature.get());
        copy.SetFID(OGRNullFID);
        if (layer->CreateFeature(&copy) != OGRERR_NONE)
          throw InputError("'" + target.string() + "': cannot write a feature: " + CPLGetLastErrorMsg());
      }
    }
    if (transaction && out->CommitTransaction() != OGRERR_NONE) throw InputError("'" + target.string() + "': cannot commit");
  }
  CPLErrorReset();
  out->FlushCache(true);
  out.reset();
  if (CPLGetLastErrorType() == CE_Failure) throw InputError("'" + target.string() + "': writing failed: " + CPLGetLastErrorMsg());
  fs::rename(temp, target);
}

// The shards' files NAME.shard-K-of-N.EXT in dir, in shard order; empty when there are none.
// Every shard K = 0..N-1 of one N must be there; `what` names them in the errors.
std::vector<fs::path> shard_parts(const fs::path& dir, const std::string& name, const std::string& extension, const std::string& what) {
  std::map<int, std::map<int, fs::path>> by_count;  // N -> K -> file
  const std::regex part(std::regex_replace(name, std::regex(R"(\.)"), R"(\.)") + R"re(\.shard-(\d+)-of-(\d+)\.)re" + extension);
  for (const auto& e : fs::directory_iterator(dir)) {
    std::smatch m;
    const std::string file = e.path().filename().string();
    if (std::regex_match(file, m, part)) by_count[std::stoi(m[2])][std::stoi(m[1])] = e.path();
  }
  if (by_count.empty()) return {};
  if (by_count.size() > 1)
    throw InputError("'" + dir.string() + "': holds " + what + " of runs with different shard counts; remove the stale ones");
  const auto& [count, found] = *by_count.begin();
  std::vector<fs::path> parts;
  for (int k = 0; k < count; ++k)
    if (found.count(k)) parts.push_back(found.at(k));
  if (int(parts.size()) != count)
    throw InputError("'" + dir.string() + "': " + std::to_string(parts.size()) + " of " + std::to_string(count) + " shards' " + what +
                     " are there; run the missing shards first");
  return parts;
}

// The shards' tile indexes and run reports, as one each. Every shard of one N must be there.
void merge_shards(const fs::path& dir) {
  const std::vector<fs::path> indexes = shard_parts(dir, "tile_index", "geojson", "tile indexes");
  if (!indexes.empty()) merge_tile_indexes(indexes, dir / "tile_index.geojson");
  const std::vector<fs::path> reports = shard_parts(dir, "report", "json", "run reports");
  if (!reports.empty()) merge_run_reports(reports, dir / "report.json");
}

// The files the tile index lists (the run's own, not whatever else is in tiles/), in tile order,
// with the fingerprint each had when the run wrote it.
std::vector<std::pair<fs::path, std::string>> indexed_outputs(const fs::path& dir) {
  const std::optional<TileIndex> index = read_tile_index(dir / "tile_index.geojson");
  if (!index) throw InputError("'" + dir.string() + "': no tile_index.geojson; is it a lodforge run's output.dir (a finished one)?");
  std::vector<std::pair<fs::path, std::string>> out;
  for (const auto& [file, fingerprint] : index->outputs) out.emplace_back(dir / file, fingerprint);
  return out;
}

// Every listed file as the run wrote it, before anything is merged; else one error naming them.
void verify_outputs(const fs::path& dir, const std::vector<std::pair<fs::path, std::string>>& outputs) {
  std::vector<std::string> bad;
  for (const auto& [file, fingerprint] : outputs) {
    const std::string now = file_fingerprint(file.string());
    if (now.empty()) bad.push_back("'" + file.string() + "' is missing");
    else if (fingerprint.empty()) bad.push_back("'" + file.string() + "' has no fingerprint in the tile index (an index of an older lodforge)");
    else if (now != fingerprint) bad.push_back("'" + file.string() + "' changed since the run wrote it");
  }
  if (bad.empty()) return;
  std::string text = "'" + (dir / "tile_index.geojson").string() + "': " + std::to_string(bad.size()) + " of its " +
                     std::to_string(outputs.size()) + " files are not as the run wrote them; rerun `lodforge run` with the job " +
                     "(it writes them again), then merge:";
  for (std::size_t i = 0; i < bad.size() && i < 5; ++i) text += "\n  " + bad[i];
  if (bad.size() > 5) text += "\n  ...";
  throw InputError(text);
}

}  // namespace

int run_merge(int argc, char** argv) {
  Args args("merge", "Combines the per-tile files of a run (all shards) into one file per format in OUT_DIR/merged/,\n"
                     "and the shards' tile indexes and run reports into OUT_DIR/tile_index.geojson and OUT_DIR/report.json;\n"
                     "writes merged/overview.tif (the whole area: a DSM hillshade with every building's outline coloured by\n"
                     "status, a Cloud-Optimized GeoTIFF) and merged/report.html (the run's numbers, failed and slowest buildings).\n"
                     "usage: lodforge merge OUT_DIR [options]");
  args.positional("dir", "OUT_DIR", "the run's output directory")
      .value("formats", "F[,F...]", "formats to merge (default: every format found)")
      .value("overview-px", "N", "the longest side of merged/overview.tif in pixels (default 4096); 0: no overview.tif and report.html");
  args.parse(argc, argv, 2);
  if (args.has("help")) { std::cout << args.help(); return 0; }
  if (!args.has("dir")) throw UsageError("give the run's output directory: lodforge merge OUT_DIR");
  const fs::path dir = *args.get("dir");
  int overview_px = 4096;
  if (auto n = args.get("overview-px")) {
    if (n->empty() || n->size() > 6 || n->find_first_not_of("0123456789") != std::string::npos || std::stoi(*n) > 32768)
      throw UsageError("--overview-px '" + *n + "': expected a whole number of pixels up to 32768, e.g. 4096 (0: no overview)");
    overview_px = std::stoi(*n);
  }
  if (!fs::is_directory(dir / "tiles")) throw InputError("'" + dir.string() + "': no tiles/ directory; is it a lodforge run's output.dir?");
  std::vector<std::string> formats = model_formats();
  if (auto f = args.get("formats")) {
    formats.clear();
    std::stringstream s(*f);
    for (std::string x; std::getline(s, x, ',');) formats.push_back(x);
  }
  for (const std::string& format : formats)
    if (std::find(model_formats().begin(), model_formats().end(), format) == model_formats().end())
      throw InputError("--formats: unknown format '" + format + "'");
  merge_shards(dir);
  const auto outputs = indexed_outputs(dir);
  verify_outputs(dir, outputs);
  fs::create_directories(dir / "merged");
  remove_stale_temporaries(dir / "merged", 0);  // of merges that were killed
  // Every format is merged into a staging directory first and moved into merged/ only when all
  // succeeded: a failed merge leaves nothing behind (and the files of an earlier merge as they were).
  const fs::path staging = dir / "merged" / ("lodforge.partial-" + std::to_string(getpid()));
  fs::create_directories(staging);
  std::vector<std::string> written;
  try {
    for (const std::string& format : formats) {
      const std::string extension = extension_of(format);
      std::vector<fs::path> files;
      for (const auto& output : outputs) {
        const std::string name = output.first.filename().string();
        if (name.size() > extension.size() && name.compare(name.size() - extension.size(), extension.size(), extension) == 0)
          files.push_back(output.first);
      }
      if (files.empty()) continue;
      const fs::path target = staging / ("lodforge" + extension);
      if (format == "citygml") merge_citygml(files, target);
      else if (format == "cityjson") merge_cityjson(files, target);
      else if (format == "cityjsonseq") merge_cityjsonseq(files, target);
      else if (format == "obj") merge_obj(files, target);
      else if (format == "gpkg") merge_ogr(files, target, "GPKG");
      else if (format == "geojson") merge_ogr(files, target, "GeoJSON");
      else if (format == "gltf") merge_gltf(files, target);
      else throw InputError("--formats: unknown format '" + format + "'");
      written.push_back(target.filename().string());
      spdlog::info("{}: {} tiles", (dir / "merged" / written.back()).string(), files.size());
    }
    if (overview_px > 0) {
      std::vector<fs::path> gpkg_tiles;
      for (const auto& output : outputs)
        if (output.first.extension() == ".gpkg") gpkg_tiles.push_back(output.first);
      if (gpkg_tiles.empty()) spdlog::warn("the run wrote no GeoPackage tiles (output.formats): the overview shows no outlines");
      const fs::path report = dir / "report.json";
      std::string job;
      if (std::ifstream in(report); in)
        if (const nlohmann::json r = nlohmann::json::parse(in, nullptr, false); r.is_object() && r.contains("job") && r["job"].is_string())
          job = r["job"].get<std::string>();
      const Overview overview = write_overview(job, gpkg_tiles, staging / "overview.tif", overview_px);
      written.push_back("overview.tif");
      if (fs::exists(report)) {
        write_report_html(report, overview, staging / "report.html");
        written.push_back("report.html");
      } else {
        spdlog::warn("'{}': missing, so no report.html", report.string());
      }
      spdlog::info("{}: {} x {} pixels of {:.3g} m, {} outlines; {}", (dir / "merged" / "overview.tif").string(), overview.width,
                   overview.height, overview.pixel_size, overview.ok + overview.fallback + overview.lod0_only + overview.not_in_mask,
                   (dir / "merged" / "report.html").string());
    }
    for (const std::string& name : written) fs::rename(staging / name, dir / "merged" / name);
    std::error_code ec;
    fs::remove_all(staging, ec);  // (anything a driver left beside its file)
  } catch (...) {
    std::error_code ec;
    fs::remove_all(staging, ec);
    throw;
  }
  return 0;
}

}  // namespace lodforge
