#include "run/run_report.hpp"

#include <algorithm>
#include <cmath>
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
#include "io/raster.hpp"

namespace lodforge {

namespace fs = std::filesystem;

namespace {

using Json = nlohmann::ordered_json;  // keys in the order they are written

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
      t.failed.emplace_back(tile_index, Totals::Failed{a, tile, b, c});
    } else if (kind == "cadastre") {
      std::size_t confirmed = 0, not_in_footprints = 0, not_in_mask = 0;
      fields >> confirmed >> not_in_footprints >> not_in_mask;
      t.confirmed += confirmed;
      t.not_in_footprints += not_in_footprints;
      t.not_in_mask += not_in_mask;
    } else if (kind == "model") {
      std::size_t count = 0;
      std::getline(fields, a, '\t');
      fields >> count;
      t.models[a] += count;
    } else if (kind == "too_large") {
      std::getline(fields, a);
      t.too_large.emplace_back(tile_index, a);
    }
  }
}

// A building's id in the report: a number (its first pixel, or a cadastral ID of digits without a
// leading zero), else text.
Json id_json(const std::string& id) {
  const bool number = !id.empty() && id.size() <= 18 && id.find_first_not_of("0123456789") == std::string::npos && (id[0] != '0' || id == "0");
  return number ? Json(std::stoll(id)) : Json(id);
}
std::string id_text(const Json& id) { return id.is_string() ? id.get<std::string>() : id.dump(); }

// Slowest first; equal times by id and tile (the report's order does not depend on the tiles' order).
bool slower(const Totals::Slow& a, const Totals::Slow& b) {
  return a.seconds != b.seconds ? a.seconds > b.seconds : a.id != b.id ? (a.id.size() != b.id.size() ? a.id.size() < b.id.size() : a.id < b.id) : a.tile < b.tile;
}

// Keeps the kSlowest slowest, sorted.
void keep_slowest(std::vector<Totals::Slow>& slow) {
  const std::size_t keep = std::min(slow.size(), Totals::kSlowest);
  std::partial_sort(slow.begin(), slow.begin() + long(keep), slow.end(), slower);
  slow.resize(keep);
}

// The entries in the order of their tiles (stable: a tile's own entries keep their order).
template <class T>
std::vector<T> in_tile_order(std::vector<std::pair<int, T>> entries) {
  std::stable_sort(entries.begin(), entries.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<T> out;
  for (auto& e : entries) out.push_back(std::move(e.second));
  return out;
}

// JSON text a person can read and a diff can compare: one member of the top object per line, an
// array of objects one object per line, everything else compact. Strings escaped by nlohmann-json
// (invalid UTF-8 replaced).
std::string readable(const Json& object) {
  const auto compact = [](const Json& j) { return j.dump(-1, ' ', false, Json::error_handler_t::replace); };
  std::string out = "{";
  bool first = true;
  for (const auto& [key, value] : object.items()) {
    out += (first ? "\n  " : ",\n  ") + compact(Json(key)) + ": ";
    first = false;
    if (value.is_array() && !value.empty() && value.front().is_object()) {
      out += "[";
      for (std::size_t i = 0; i < value.size(); ++i) out += (i ? ",\n    " : "\n    ") + compact(value[i]);
      out += "\n  ]";
    } else {
      out += compact(value);
    }
  }
  return out + "\n}\n";
}

// A coordinate rounded to `decimals` (written by nlohmann-json as the shortest text that reads back
// as that double: 7 decimals at most for 1e-7).
double rounded(double v, int decimals) {
  const double scale = std::pow(10.0, decimals);
  return std::round(v * scale) / scale;
}

// The tile index as RFC 7946 GeoJSON, one feature per line (merge reads it back as JSON).
std::string tile_index_text(const std::string& run_key, const Json& features) {
  std::string out = "{\"type\":\"FeatureCollection\",\"name\":\"tile_index\",\"run_key\":" + Json(run_key).dump() + ",\"features\":[";
  for (std::size_t i = 0; i < features.size(); ++i) out += (i ? ",\n" : "\n") + features[i].dump();
  return out + "\n]}\n";
}

Json read_json(const fs::path& path, const char* what) {
  std::ifstream in(path);
  if (!in) throw InputError("'" + path.string() + "': cannot read");
  try {
    return Json::parse(in);
  } catch (const std::exception& e) {
    throw InputError("'" + path.string() + "': not a " + std::string(what) + ": " + e.what());
  }
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
  for (const BuildingOutput& b : r->buildings) totals.slowest.push_back({b.seconds, b.display_id(), r->name});
  keep_slowest(totals.slowest);
  totals.contour_seconds += r->contour_seconds;
  totals.heights_seconds += r->heights_seconds;
  totals.write_seconds += r->write_seconds;
  totals.buildings_reused += r->buildings_reused;
  if (count == 0) totals.tiles_empty++;
  const cv::Rect rect = grid.rect(r->tile);
  const Vec2 a = plan.transform.to_map(rect.x, rect.y), b = plan.transform.to_map(rect.x + rect.width, rect.y + rect.height);
  // The tile's extent, counter-clockwise as RFC 7946 wants an exterior ring.
  std::array<Vec2, 4> corners{a, Vec2(b.x(), a.y()), b, Vec2(a.x(), b.y())};
  if ((b.x() - a.x()) * (b.y() - a.y()) < 0) std::swap(corners[1], corners[3]);  // (signed area of that order < 0)
  Totals::TileRecord entry{r->name, r->tile % grid.cols, r->tile / grid.cols, count, r->skipped, r->seconds, {a.x(), b.y()}, outputs, {}};
  for (int k = 0; k < 4; ++k) entry.ring[k] = {corners[k].x(), corners[k].y()};
  totals.tiles.emplace_back(r->tile, std::move(entry));
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
                            int shard_count, std::size_t tiles, double elapsed) {
  const Job& job = plan.job;
  const std::vector<Totals::TileRecord> tile_records = in_tile_order(totals.tiles);
  const fs::path& out_dir = plan.out_dir;
  // The tile index and the run report (one per shard when sharded).
  const std::string suffix = shard_suffix(shard_index, shard_count);
  // The tile index is RFC 7946 GeoJSON: WGS 84 longitude and latitude (7 decimals, about 1 cm),
  // no crs member. Only an input without a CRS leaves its tiles in map coordinates.
  std::vector<std::array<double, 2>> corners;
  for (const Totals::TileRecord& f : tile_records) corners.insert(corners.end(), f.ring.begin(), f.ring.end());
  std::vector<std::array<double, 2>> lon_lat = to_lon_lat(plan.crs.wkt(), corners);
  if (lon_lat.empty() && !corners.empty())
    spdlog::warn("the tile index is in map coordinates, not WGS 84 as RFC 7946 asks: the inputs' CRS is unknown or cannot be transformed");
  const int decimals = lon_lat.empty() ? 3 : 7;
  if (lon_lat.empty()) lon_lat = corners;
  Json features = Json::array();
  for (std::size_t i = 0; i < tile_records.size(); ++i) {
    const Totals::TileRecord& f = tile_records[i];
    Json files = Json::array(), fingerprints = Json::array(), ring = Json::array();
    for (const auto& [file, fingerprint] : f.outputs) {
      files.push_back(file);
      fingerprints.push_back(fingerprint);
    }
    for (int k = 0; k <= 4; ++k) ring.push_back({rounded(lon_lat[4 * i + k % 4][0], decimals), rounded(lon_lat[4 * i + k % 4][1], decimals)});
    features.push_back(Json{{"type", "Feature"},
                            {"properties", {{"tile", f.tile}, {"col", f.col}, {"row", f.row}, {"status", f.buildings ? "done" : "empty"},
                                            {"buildings", f.buildings}, {"origin", {rounded(f.origin[0], 3), rounded(f.origin[1], 3)}},
                                            {"outputs", files}, {"fingerprints", fingerprints}}},
                            {"geometry", {{"type", "Polygon"}, {"coordinates", Json::array({ring})}}}});
  }
  write_text_atomically(out_dir / ("tile_index" + suffix + ".geojson"), tile_index_text(hex(plan.job_key), features));
  Json failed = Json::array(), too_large = Json::array(), per_tile = Json::array(), slowest = Json::array();
  for (const Totals::Slow& b : totals.slowest) slowest.push_back({{"id", id_json(b.id)}, {"tile", b.tile}, {"seconds", b.seconds}});
  for (const Totals::Failed& f : in_tile_order(totals.failed))
    failed.push_back({{"id", id_json(f.id)}, {"tile", f.tile}, {"stage", f.stage}, {"reason", f.reason}});
  for (const std::string& t : in_tile_order(totals.too_large)) too_large.push_back(t);
  for (const Totals::TileRecord& t : tile_records)
    per_tile.push_back({{"tile", t.tile}, {"buildings", t.buildings}, {"skipped", t.skipped}, {"seconds", t.seconds}});
  Json report{{"job", fs::absolute(job_path).string()},
                    {"shard", std::to_string(shard_index) + "/" + std::to_string(shard_count)},
                    {"tiles", tiles},
                    {"tiles_processed", totals.tiles_processed},
                    {"tiles_resumed", totals.tiles_skipped},
                    {"tiles_empty", totals.tiles_empty},
                    {"checkpoints_reused", {{"contours", totals.contours_reused}, {"buildings", totals.buildings_reused}}},
                    {"buildings", totals.buildings},
                    {"ok", totals.ok},
                    {"fallback", totals.fallback},
                    {"lod1", totals.lod1},
                    {"models", totals.models},
                    {"dropped_small", totals.dropped_small},
                    {"too_large", totals.too_large.size()},
                    {"cadastre", {{"confirmed", totals.confirmed}, {"not_in_footprints", totals.not_in_footprints}, {"not_in_mask", totals.not_in_mask}}},
                    {"seconds", elapsed},
                    {"noise_floor_m", plan.noise.floor_m},
                    {"noise_smoothing_m", plan.noise.smoothing_m},
                    {"corner_rounding_m", plan.noise.rounding_m.value_or(0.0)},
                    {"core_seconds", totals.core_seconds},
                    {"stage_seconds", {{"contours", totals.contour_seconds}, {"regularization", totals.core_seconds},
                                       {"heights", totals.heights_seconds}, {"writing", totals.write_seconds}}},
                    {"blocks_decoded", totals.blocks_decoded},
                    {"failed_buildings", failed},
                    {"too_large_buildings", too_large},
                    {"slowest_buildings", slowest},
                    {"per_tile", per_tile}};
  if (!plan.cadastre) report.erase("cadastre");  // (no footprints given; a shard without tiles has the counts all the same)
  write_text_atomically(out_dir / ("report" + suffix + ".json"), readable(report));
  spdlog::info("{} tiles ({} computed, {} resumed from {}), {} buildings: {} ok, {} fallback, {} with LOD1; {} small components dropped{}; {:.1f} s",
               tiles, totals.tiles_processed, totals.tiles_skipped, job.work_dir, totals.buildings, totals.ok, totals.fallback, totals.lod1,
               totals.dropped_small, totals.too_large.empty() ? "" : "; " + std::to_string(totals.too_large.size()) + " too large (see report)",
               elapsed);
  if (plan.cadastre)
    spdlog::info("footprints: {} confirmed by the mask, {} not in the mask (listed in the GeoPackages); {} buildings not in the footprints",
                 totals.confirmed, totals.not_in_mask, totals.not_in_footprints);
  if (totals.tiles_processed > 0)
    spdlog::info("one-core time by stage: contours {:.1f} s, regularization {:.1f} s, heights {:.1f} s, writing {:.1f} s",
                 totals.contour_seconds, totals.core_seconds, totals.heights_seconds, totals.write_seconds);
  if (totals.buildings == 0 && totals.dropped_small == 0 && totals.too_large.empty()) {
    std::string held;  // (what the raster holds: read again, so for a whole raster only, not a shard)
    try {
      if (shard_count <= 1) held = " Its " + values_held(job.inputs.segmentation.path, plan.selector);
    } catch (const std::exception&) {
    }
    spdlog::warn("no building found in {}{}: is {} right for this raster?{}", job.inputs.segmentation.path,
                 shard_count > 1 ? " (in this shard)" : "", plan.selector.job_key(), held);
  }
  spdlog::info("outputs in {} (tile_index{}.geojson, report{}.json)", out_dir.string(), suffix, suffix);
}

namespace {

// Adds the numbers of `from` into `into`, member by member (integers stay integers), nested objects
// too; a member `into` lacks is taken as it is (a model only this shard kept); "seconds" (a run's
// wall time: shards run side by side) keeps the larger.
void add_numbers(Json& into, const Json& from) {
  for (const auto& [key, other] : from.items()) {
    if (!into.contains(key)) {
      into[key] = other;
      continue;
    }
    Json& value = into[key];
    if (value.is_object() && !other.is_object()) throw std::runtime_error("'" + key + "' is not an object");
    if (value.is_object()) add_numbers(value, other);
    else if (value.is_number() && !other.is_number()) throw std::runtime_error("'" + key + "' is not a number");
    else if (key == "seconds") value = std::max(value.get<double>(), other.get<double>());
    else if (value.is_number_integer() && other.is_number_integer()) value = value.get<long long>() + other.get<long long>();
    else if (value.is_number()) value = value.get<double>() + other.get<double>();
  }
}

}  // namespace

void merge_tile_indexes(const std::vector<fs::path>& parts, const fs::path& target) {
  std::vector<std::pair<std::string, Json>> features;  // (tile name, feature)
  std::string first_key;
  for (const fs::path& p : parts) {
    const Json index = read_json(p, "lodforge tile index");
    try {
      // Shards of one run: the same inputs, options and tiling (the run key), else not one result.
      const std::string run_key = index.at("run_key").get<std::string>();
      if (p == parts.front()) first_key = run_key;
      else if (run_key != first_key)
        throw InputError("'" + p.string() + "': from a run with other inputs, options or build of lodforge (run key " + run_key + ") than '" +
                         parts.front().string() + "' (" + first_key + "); rerun the shards with one job");
      for (const Json& f : index.at("features")) features.emplace_back(f.at("properties").at("tile").get<std::string>(), f);
    } catch (const Json::exception& e) {
      throw InputError("'" + p.string() + "': not a lodforge tile index: " + e.what());
    }
  }
  std::stable_sort(features.begin(), features.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  Json all = Json::array();
  for (auto& f : features) all.push_back(std::move(f.second));
  write_text_atomically(target, tile_index_text(first_key, all));
}

void merge_run_reports(const std::vector<fs::path>& parts, const fs::path& target) {
  Json merged;
  std::vector<std::pair<std::string, Json>> failed, per_tile;  // (tile name, entry)
  std::vector<std::pair<std::string, Json>> too_large;
  std::vector<Totals::Slow> slowest;
  for (const fs::path& p : parts) {
    const Json report = read_json(p, "lodforge run report");
    try {
      for (const char* list : {"failed_buildings", "too_large_buildings", "per_tile"})
        if (!report.at(list).is_array()) throw std::runtime_error(std::string("'") + list + "' is not a list");
      // (Every shard's the same, the survey of the whole raster: not a count.)
      for (const char* noise : {"noise_floor_m", "noise_smoothing_m", "corner_rounding_m"})
        if (!merged.is_null() && merged.value(noise, 0.0) != report.value(noise, 0.0))
          throw std::runtime_error(std::string("its ") + noise + " differs from the other shards': a run with other inputs or options");
      if (merged.is_null()) merged = report;
      else add_numbers(merged, report);
      for (const char* noise : {"noise_floor_m", "noise_smoothing_m", "corner_rounding_m"})
        if (report.contains(noise)) merged[noise] = report.at(noise);
      for (const Json& f : report.at("failed_buildings")) failed.emplace_back(f.at("tile").get<std::string>(), f);
      for (const Json& t : report.at("per_tile")) per_tile.emplace_back(t.at("tile").get<std::string>(), t);
      for (const Json& b : report.value("slowest_buildings", Json::array()))
        slowest.push_back({b.at("seconds").get<double>(), id_text(b.at("id")), b.at("tile").get<std::string>()});
      // "... around tile rRRRR_cCCCC ...": in tile order too.
      for (const Json& t : report.at("too_large_buildings")) {
        const std::string text = t.get<std::string>();
        const std::size_t at = text.find("tile r");
        too_large.emplace_back(at == std::string::npos ? text : text.substr(at, 16), t);
      }
    } catch (const std::exception& e) {
      throw InputError("'" + p.string() + "': not a lodforge run report: " + e.what());
    }
  }
  // In tile order, each tile's entries in their own order, as a single run lists them.
  const auto listed = [](std::vector<std::pair<std::string, Json>>& entries) {
    std::stable_sort(entries.begin(), entries.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    Json out = Json::array();
    for (auto& e : entries) out.push_back(std::move(e.second));
    return out;
  };
  merged["shard"] = "merged " + std::to_string(parts.size());
  merged["failed_buildings"] = listed(failed);
  merged["too_large_buildings"] = listed(too_large);
  merged["per_tile"] = listed(per_tile);
  keep_slowest(slowest);
  Json slow = Json::array();
  for (const Totals::Slow& b : slowest) slow.push_back({{"id", id_json(b.id)}, {"tile", b.tile}, {"seconds", b.seconds}});
  merged["slowest_buildings"] = slow;
  write_text_atomically(target, readable(merged));
}

}  // namespace lodforge
