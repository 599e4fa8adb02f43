#include "run/run_report.hpp"

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>
#include <sstream>

#include "io/atomic_file.hpp"
#include "io/errors.hpp"
#include "io/input_crs.hpp"
#include "io/model_writers.hpp"

namespace lodforge {

namespace fs = std::filesystem;

namespace {

std::string json_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '"' || c == '\\') { out += '\\'; out += c; }
    else if (c == '\n') out += "\\n";
    else if (static_cast<unsigned char>(c) < 0x20) out += ' ';
    else out += c;
  }
  return out;
}


void account(const std::string& summary, const std::string& tile, int tile_index, Totals& t, std::size_t& buildings_in_tile) {
  std::istringstream in(summary);
  std::size_t n = 0, ok = 0, fb = 0, dropped = 0, lod1 = 0;
  in >> n >> ok >> fb >> dropped >> lod1;
  t.lod1 += lod1;
  buildings_in_tile = n;
  t.buildings += n;
  t.ok += ok;
  t.fallback += fb;
  t.dropped_small += dropped;
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string kind, a, b, c;
    std::getline(fields, kind, '\t');
    if (kind == "failed") {
      std::getline(fields, a, '\t');
      std::getline(fields, b, '\t');
      std::getline(fields, c);
      t.failed_json.emplace_back(tile_index, "{\"id\": " + a + ", \"tile\": \"" + tile + "\", \"stage\": \"" + json_escape(b) +
                                                 "\", \"reason\": \"" + json_escape(c) + "\"}");
    } else if (kind == "too_large") {
      std::getline(fields, a);
      t.too_large.emplace_back(tile_index, a);
    }
  }
}


// The entries in the order of their tiles (stable: a tile's own entries keep their order).
template <class T>
std::vector<T> in_tile_order(std::vector<std::pair<int, T>> entries) {
  std::stable_sort(entries.begin(), entries.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<T> out;
  for (auto& e : entries) out.push_back(std::move(e.second));
  return out;
}

}  // namespace

void record_tile(Totals& totals, const RunPlan& plan, const TileResult& result, const TileOutputs& outputs) {
  const TileGrid& grid = plan.grid;
  const TileResult* r = &result;
  std::size_t count = 0;
  account(r->summary, r->name, r->tile, totals, count);
  (r->skipped ? totals.tiles_skipped : totals.tiles_processed)++;
  totals.contours_reused += r->contours_reused;
  if (!r->buildings_reused) for (const BuildingOutput& b : r->buildings) totals.core_seconds += b.seconds;
  totals.contour_seconds += r->contour_seconds;
  totals.heights_seconds += r->heights_seconds;
  totals.write_seconds += r->write_seconds;
  totals.buildings_reused += r->buildings_reused;
  if (count == 0) totals.tiles_empty++;
  const cv::Rect rect = grid.rect(r->tile);
  const Vec2 a = plan.transform.to_map(rect.x, rect.y), b = plan.transform.to_map(rect.x + rect.width, rect.y + rect.height);
  std::ostringstream feature;
  feature.precision(12);
  feature << "{\"type\": \"Feature\", \"properties\": {\"tile\": \"" << r->name << "\", \"col\": " << r->tile % grid.cols
          << ", \"row\": " << r->tile / grid.cols << ", \"status\": \"" << (count ? "done" : "empty")
          << "\", \"buildings\": " << count << ", \"origin\": [" << a.x() << ", " << b.y() << "], \"outputs\": [";
  for (std::size_t i = 0; i < outputs.size(); ++i) feature << (i ? ", " : "") << '"' << outputs[i].first << '"';
  feature << "], \"fingerprints\": [";
  for (std::size_t i = 0; i < outputs.size(); ++i) feature << (i ? ", " : "") << '"' << outputs[i].second << '"';
  // The tile's extent, counter-clockwise as RFC 7946 wants an exterior ring.
  std::array<Vec2, 4> corners{a, Vec2(b.x(), a.y()), b, Vec2(a.x(), b.y())};
  if ((b.x() - a.x()) * (b.y() - a.y()) < 0) std::swap(corners[1], corners[3]);  // (signed area of that order < 0)
  feature << "]}, \"geometry\": ";  // written with the index, in WGS 84
  Totals::IndexFeature entry{feature.str(), {}};
  for (int k = 0; k < 4; ++k) entry.ring[k] = {corners[k].x(), corners[k].y()};
  totals.index_features.emplace_back(r->tile, std::move(entry));
  std::ostringstream tile_json;
  tile_json << "{\"tile\": \"" << r->name << "\", \"buildings\": " << count << ", \"skipped\": " << (r->skipped ? "true" : "false")
            << ", \"seconds\": " << r->seconds << "}";
  totals.tile_json.emplace_back(r->tile, tile_json.str());
}

std::string shard_suffix(int shard_index, int shard_count) {
  return shard_count > 1 ? ".shard-" + std::to_string(shard_index) + "-of-" + std::to_string(shard_count) : "";
}

std::optional<TileIndex> read_tile_index(const fs::path& path) {
  std::ifstream in(path);
  if (!in) return std::nullopt;
  TileIndex index;
  try {
    const nlohmann::json json = nlohmann::json::parse(in);
    index.run_key = json.value("run_key", "");
    for (const auto& feature : json.at("features")) {
      const auto& properties = feature.at("properties");
      const auto& files = properties.at("outputs");
      const nlohmann::json fingerprints = properties.value("fingerprints", nlohmann::json::array());
      for (std::size_t i = 0; i < files.size(); ++i)
        index.outputs.emplace_back(files[i].get<std::string>(), i < fingerprints.size() ? fingerprints[i].get<std::string>() : "");
    }
  } catch (const std::exception& e) {
    throw InputError("'" + path.string() + "': not a lodforge tile index: " + e.what());
  }
  return index;
}

void write_index_and_report(const Totals& totals, const RunPlan& plan, const std::string& job_path, int shard_index,
                            int shard_count, std::size_t tiles_count, double elapsed) {
  const Job& job = plan.job;
  const std::vector<Totals::IndexFeature> index_features = in_tile_order(totals.index_features);
  const std::vector<std::string> tile_json = in_tile_order(totals.tile_json),
                                 failed_json = in_tile_order(totals.failed_json), too_large = in_tile_order(totals.too_large);
  const fs::path& out_dir = plan.out_dir;
  struct { int index, count; } shard{shard_index, shard_count};
  struct { std::size_t n; std::size_t size() const { return n; } } tiles{tiles_count};
  // The tile index and the run report (one per shard when sharded).
  const std::string suffix = shard_suffix(shard.index, shard.count);
  // The tile index is RFC 7946 GeoJSON: WGS 84 longitude and latitude (7 decimals, about 1 cm),
  // no crs member. Only an input without a CRS leaves its tiles in map coordinates.
  std::vector<std::array<double, 2>> corners;
  for (const Totals::IndexFeature& f : index_features) corners.insert(corners.end(), f.ring.begin(), f.ring.end());
  std::vector<std::array<double, 2>> lon_lat = to_lon_lat(plan.crs.wkt(), corners);
  if (lon_lat.empty() && !corners.empty())
    spdlog::warn("the tile index is in map coordinates, not WGS 84 as RFC 7946 asks: the inputs' CRS is unknown or cannot be transformed");
  const bool geographic = !lon_lat.empty();
  if (!geographic) lon_lat = corners;
  std::ostringstream index;
  index.precision(geographic ? 7 : 3);
  index << std::fixed;
  index << "{\"type\": \"FeatureCollection\", \"name\": \"tile_index\", \"run_key\": \"" << hex(plan.job_key) << "\"";
  index << ", \"features\": [\n";
  for (std::size_t i = 0; i < index_features.size(); ++i) {
    index << index_features[i].head << "{\"type\": \"Polygon\", \"coordinates\": [[";
    for (int k = 0; k <= 4; ++k) index << (k ? ", [" : "[") << lon_lat[4 * i + k % 4][0] << ", " << lon_lat[4 * i + k % 4][1] << "]";
    index << "]]}}" << (i + 1 < index_features.size() ? ",\n" : "\n");
  }
  index << "]}\n";
  write_text_atomically(out_dir / ("tile_index" + suffix + ".geojson"), index.str());
  std::ostringstream report;
  report << "{\n  \"job\": \"" << json_escape(fs::absolute(job_path).string()) << "\",\n  \"shard\": \"" << shard.index << "/" << shard.count
         << "\",\n  \"tiles\": " << tiles.size() << ", \"tiles_processed\": " << totals.tiles_processed << ", \"tiles_resumed\": "
         << totals.tiles_skipped << ", \"tiles_empty\": " << totals.tiles_empty << ",\n  \"checkpoints_reused\": {\"contours\": " << totals.contours_reused << ", \"buildings\": " << totals.buildings_reused << "},\n  \"buildings\": " << totals.buildings
         << ", \"ok\": " << totals.ok << ", \"fallback\": " << totals.fallback << ", \"lod1\": " << totals.lod1 << ", \"dropped_small\": " << totals.dropped_small
         << ", \"too_large\": " << totals.too_large.size() << ",\n  \"seconds\": " << elapsed << ", \"core_seconds\": " << totals.core_seconds << ",\n  \"stage_seconds\": {\"contours\": "
         << totals.contour_seconds << ", \"regularization\": " << totals.core_seconds << ", \"heights\": " << totals.heights_seconds
         << ", \"writing\": " << totals.write_seconds << "},\n  \"blocks_decoded\": " << totals.blocks_decoded << ",\n  \"failed_buildings\": [";
  for (std::size_t i = 0; i < failed_json.size(); ++i) report << (i ? ",\n    " : "\n    ") << failed_json[i];
  report << "],\n  \"too_large_buildings\": [";
  for (std::size_t i = 0; i < too_large.size(); ++i) report << (i ? ", " : "") << '"' << json_escape(too_large[i]) << '"';
  report << "],\n  \"per_tile\": [";
  for (std::size_t i = 0; i < tile_json.size(); ++i) report << (i ? ",\n    " : "\n    ") << tile_json[i];
  report << "]\n}\n";
  write_text_atomically(out_dir / ("report" + suffix + ".json"), report.str());
  spdlog::info("{} tiles ({} computed, {} resumed from {}), {} buildings: {} ok, {} fallback, {} with LOD1; {} small components dropped{}; {:.1f} s",
               tiles.size(), totals.tiles_processed, totals.tiles_skipped, job.work_dir, totals.buildings, totals.ok, totals.fallback, totals.lod1,
               totals.dropped_small, totals.too_large.empty() ? "" : "; " + std::to_string(totals.too_large.size()) + " too large (see report)",
               elapsed);
  if (totals.tiles_processed > 0)
    spdlog::info("one-core time by stage: contours {:.1f} s, regularization {:.1f} s, heights {:.1f} s, writing {:.1f} s",
                 totals.contour_seconds, totals.core_seconds, totals.heights_seconds, totals.write_seconds);
  if (totals.buildings == 0 && totals.dropped_small == 0 && totals.too_large.empty())
    spdlog::warn("no building found in {}{}: is inputs.segmentation.{} right for this raster?", job.inputs.segmentation.path,
                 shard.count > 1 ? " (in this shard)" : "", job.inputs.segmentation.building_rgb.empty() ? "building_values" : "building_rgb");
  spdlog::info("outputs in {} (tile_index{}.geojson, report{}.json)", out_dir.string(), suffix, suffix);
}

}  // namespace lodforge
