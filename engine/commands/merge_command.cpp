// lodforge merge OUT_DIR: combines a run's per-tile files into one file per format (and the
// shards' tile indexes into one), streaming, in tile order.
#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <gdal_priv.h>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <ogrsf_frmts.h>
#include <nlohmann/json.hpp>
#include <regex>
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
#include "run/run_report.hpp"

namespace lodforge {

namespace fs = std::filesystem;

namespace {

std::string fixed3(double v) {
  char buffer[48];
  std::snprintf(buffer, sizeof buffer, "%.3f", v);
  return buffer;
}

// The union of the extents the files declare in their first lines (CityGML's gml:boundedBy,
// CityJSON's geographicalExtent): the merged file's. A file without one (written by an earlier
// version) is named in a warning and left out.
Extent merged_extent(const std::vector<fs::path>& files) {
  static const std::regex gml(R"(<gml:lowerCorner>(\S+) (\S+) (\S+)</gml:lowerCorner><gml:upperCorner>(\S+) (\S+) (\S+)</gml:upperCorner>)");
  static const std::regex json(R"re("geographicalExtent": ?\[([^\]]*)\])re");
  constexpr double inf = std::numeric_limits<double>::infinity();
  Extent all{inf, inf, inf, -inf, -inf, -inf};
  for (const fs::path& file : files) {
    std::ifstream in(file);
    std::string line;
    std::vector<double> values;
    for (int k = 0; k < 8 && values.empty() && std::getline(in, line); ++k) {
      std::smatch m;
      if (std::regex_search(line, m, gml)) {
        for (std::size_t i = 1; i <= 6; ++i) values.push_back(std::stod(m[i]));
      } else if (std::regex_search(line, m, json)) {
        std::istringstream list(m[1].str());
        for (std::string item; std::getline(list, item, ',');) values.push_back(std::stod(item));
      }
    }
    if (values.size() != 6) {
      spdlog::warn("'{}': declares no extent (written by an earlier lodforge?); the merged extent leaves it out", file.string());
      continue;
    }
    for (std::size_t i = 0; i < 3; ++i) {
      all[i] = std::min(all[i], values[i]);
      all[i + 3] = std::max(all[i + 3], values[i + 3]);
    }
  }
  if (all[0] > all[3]) all = Extent{};
  return all;
}

// CityGML: one header, every tile's cityObjectMember blocks, one footer.
void merge_citygml(const std::vector<fs::path>& files, const fs::path& target) {
  AtomicTextFile o(target);
  const Extent extent = merged_extent(files);
  for (std::size_t k = 0; k < files.size(); ++k) {
    std::ifstream in(files[k]);
    std::string line;
    bool body = false;
    while (std::getline(in, line)) {
      if (line == "</core:CityModel>") break;
      if (line.rfind("  <core:cityObjectMember>", 0) == 0) body = true;
      if (!body && k == 0 && line.rfind("  <gml:name>lodforge tile ", 0) == 0)  // the merged file is the run's, not a tile's
        line = "  <gml:name>lodforge, merged from " + std::to_string(files.size()) + " tiles</gml:name>";
      if (!body && k == 0 && line.rfind("  <gml:boundedBy>", 0) == 0)
        line = std::regex_replace(line, std::regex("<gml:lowerCorner>.*</gml:upperCorner>"),
                                  "<gml:lowerCorner>" + fixed3(extent[0]) + ' ' + fixed3(extent[1]) + ' ' + fixed3(extent[2]) +
                                      "</gml:lowerCorner><gml:upperCorner>" + fixed3(extent[3]) + ' ' + fixed3(extent[4]) + ' ' +
                                      fixed3(extent[5]) + "</gml:upperCorner>");
      if (body || k == 0) o.out() << line << '\n';
    }
  }
  o.out() << "</core:CityModel>\n";
  o.commit();
}

long long millimetres(const std::string& text) { return std::llround(std::stod(text) * 1000.0); }

// Millimetres as metres with three decimals, exactly (no floating point on the way).
std::string metres(long long mm) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%s%lld.%03lld", mm < 0 ? "-" : "", std::llabs(mm) / 1000, std::llabs(mm) % 1000);
  return buffer;
}

// OBJ: vertices moved to the first tile's origin, face indices offset.
void merge_obj(const std::vector<fs::path>& files, const fs::path& target) {
  AtomicTextFile o(target);
  long long ox = 0, oy = 0;
  std::size_t offset = 0;
  const std::regex origin(R"(# origin (\S+) (\S+) )");
  std::string crs = "unknown";  // the first tile's, from its first line
  for (std::size_t k = 0; k < files.size(); ++k) {
    std::ifstream in(files[k]);
    std::string line;
    long long tx = 0, ty = 0;
    std::size_t count = 0;
    while (std::getline(in, line)) {
      std::smatch m;
      if (k == 0 && line.rfind("# lodforge OBJ, tile ", 0) == 0 && line.find(", CRS ") != std::string::npos) {
        crs = line.substr(line.find(", CRS ") + 6);
      } else if (std::regex_search(line, m, origin)) {
        tx = millimetres(m[1]);
        ty = millimetres(m[2]);
        if (k == 0) {
          ox = tx;
          oy = ty;
          o.out() << "# lodforge OBJ, merged from " << files.size() << " tiles, CRS " << crs << "\n" << line << '\n';
        }
      } else if (line.rfind("v ", 0) == 0) {
        std::istringstream v(line.substr(2));
        std::string x, y, z;
        v >> x >> y >> z;
        o.out() << "v " << metres(millimetres(x) + tx - ox) << ' ' << metres(millimetres(y) + ty - oy) << ' ' << z << '\n';
        ++count;
      } else if (line.rfind("f ", 0) == 0) {
        std::istringstream f(line.substr(2));
        o.out() << 'f';
        for (std::size_t id; f >> id;) o.out() << ' ' << id + offset;
        o.out() << '\n';
      } else if (line.rfind("o ", 0) == 0) {
        o.out() << line << '\n';
      }
    }
    offset += count;
  }
  o.commit();
}

// CityJSON: CityObjects concatenated, vertices re-indexed onto one transform.
void merge_cityjson(const std::vector<fs::path>& files, const fs::path& target) {
  AtomicTextFile o(target);
  const Extent extent = merged_extent(files);
  std::map<std::array<long long, 3>, std::size_t> index;
  std::vector<std::array<long long, 3>> vertices;
  long long ox = 0, oy = 0;
  bool first_object = true;
  const std::regex translate(R"("translate": \[(\S+), (\S+), )");
  for (std::size_t k = 0; k < files.size(); ++k) {
    std::ifstream in(files[k]);
    std::stringstream whole;
    whole << in.rdbuf();
    const std::string text = whole.str();
    std::smatch m;
    if (!std::regex_search(text, m, translate)) throw InputError("'" + files[k].string() + "': not a lodforge CityJSON tile");
    const long long tx = millimetres(m[1]), ty = millimetres(m[2]);
    if (k == 0) {
      ox = tx;
      oy = ty;
      const std::size_t objects = text.find("\"CityObjects\": {");
      const std::string merged_title = "\"title\": \"lodforge, merged from " + std::to_string(files.size()) + " tiles\"";
      std::string merged_extent_text = "\"geographicalExtent\": [";
      for (std::size_t i = 0; i < 6; ++i) merged_extent_text += (i ? ", " : "") + fixed3(extent[i]);
      merged_extent_text += "]";
      const std::string header = std::regex_replace(text.substr(0, objects), std::regex(R"re("title": "lodforge tile [^"]*")re"), merged_title);
      o.out() << std::regex_replace(header, std::regex(R"re("geographicalExtent": \[[^\]]*\])re"), merged_extent_text)
              << "\"CityObjects\": {";
    }
    // This tile's vertices, moved onto the first tile's translate.
    std::vector<std::size_t> remap;
    const std::size_t at = text.find("\"vertices\": [");
    std::istringstream numbers(text.substr(at + 13));
    std::string token;
    std::vector<long long> values;
    for (char c; numbers.get(c);) {
      if (std::isdigit(static_cast<unsigned char>(c)) || c == '-') token += c;
      else if (!token.empty()) { values.push_back(std::stoll(token)); token.clear(); }
    }
    for (std::size_t i = 0; i + 2 < values.size(); i += 3) {
      const std::array<long long, 3> v{values[i] + tx - ox, values[i + 1] + ty - oy, values[i + 2]};
      auto [it, inserted] = index.try_emplace(v, vertices.size());
      if (inserted) vertices.push_back(v);
      remap.push_back(it->second);
    }
    // Every CityObject line, its boundary indices renumbered.
    std::istringstream lines(text);
    std::string line;
    const std::regex number(R"(\d+)");
    while (std::getline(lines, line)) {
      if (line.rfind("  \"lodforge_b", 0) != 0) continue;
      if (!line.empty() && line.back() == ',') line.pop_back();
      std::string rewritten;
      std::size_t pos = 0;
      for (std::size_t b = line.find("\"boundaries\": "); b != std::string::npos; b = line.find("\"boundaries\": ", pos)) {
        const std::size_t start = b + 14;
        std::size_t end = start;
        for (int depth = 0; end < line.size(); ++end) {
          if (line[end] == '[') ++depth;
          if (line[end] == ']' && --depth == 0) break;
        }
        rewritten += line.substr(pos, start - pos);
        const std::string inner = line.substr(start, end + 1 - start);
        std::string renumbered;
        std::size_t last = 0;
        for (std::sregex_iterator it(inner.begin(), inner.end(), number), stop; it != stop; ++it) {
          renumbered += inner.substr(last, std::size_t(it->position()) - last) + std::to_string(remap.at(std::stoul(it->str())));
          last = std::size_t(it->position() + it->length());
        }
        rewritten += renumbered + inner.substr(last);
        pos = end + 1;
      }
      rewritten += line.substr(pos);
      o.out() << (first_object ? "\n" : ",\n") << rewritten;
      first_object = false;
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
    try {
      if (!std::getline(in, line)) throw std::runtime_error("empty");
      header = nlohmann::json::parse(line);
      if (header.at("type") != "CityJSON" || header.at("transform").at("scale") != nlohmann::json::array({0.001, 0.001, 0.001}))
        throw std::runtime_error("not a lodforge CityJSONSeq header");
    } catch (const std::exception& e) {
      throw InputError("'" + files[k].string() + "': line 1: not a lodforge CityJSONSeq tile (" + e.what() + ")");
    }
    const auto& translate = header["transform"]["translate"];
    const std::array<long long, 2> here{std::llround(translate.at(0).get<double>() * 1000), std::llround(translate.at(1).get<double>() * 1000)};
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
  CPLSetConfigOption("OGR_CURRENT_DATE", "2000-01-01T00:00:00.000Z");
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
                     "and the shards' tile indexes and run reports into OUT_DIR/tile_index.geojson and OUT_DIR/report.json.\nusage: lodforge merge OUT_DIR [options]");
  args.positional("dir", "OUT_DIR", "the run's output directory")
      .value("formats", "F[,F...]", "formats to merge (default: every format found)");
  args.parse(argc, argv, 2);
  if (args.has("help")) { std::cout << args.help(); return 0; }
  if (!args.has("dir")) throw UsageError("give the run's output directory: lodforge merge OUT_DIR");
  const fs::path dir = *args.get("dir");
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
  for (const std::string& format : formats) {
    const std::string extension = extension_of(format);
    std::vector<fs::path> files;
    for (const auto& output : outputs) {
      const std::string name = output.first.filename().string();
      if (name.size() > extension.size() && name.compare(name.size() - extension.size(), extension.size(), extension) == 0)
        files.push_back(output.first);
    }
    if (files.empty()) continue;
    const fs::path target = dir / "merged" / ("lodforge" + extension);
    if (format == "citygml") merge_citygml(files, target);
    else if (format == "cityjson") merge_cityjson(files, target);
    else if (format == "cityjsonseq") merge_cityjsonseq(files, target);
    else if (format == "obj") merge_obj(files, target);
    else if (format == "gpkg") merge_ogr(files, target, "GPKG");
    else if (format == "geojson") merge_ogr(files, target, "GeoJSON");
    else if (format == "gltf") merge_gltf(files, target);
    else throw InputError("--formats: unknown format '" + format + "'");
    spdlog::info("{}: {} tiles", target.string(), files.size());
  }
  return 0;
}

}  // namespace lodforge
