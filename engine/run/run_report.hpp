// The run's accounting: totals over tiles, the tile index and the report (JSON and a summary).
#pragma once
#include <array>
#include <map>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "run/tile_worker.hpp"

namespace lodforge {

struct Totals {
  std::size_t buildings = 0, ok = 0, fallback = 0, dropped_small = 0, tiles_processed = 0, tiles_skipped = 0, tiles_empty = 0;
  std::size_t contours_reused = 0, buildings_reused = 0, lod1 = 0;
  double core_seconds = 0;  // summed regularization time of the buildings computed (not resumed)
  // Summed one-core time of the other per-building stages (TileResult), reads excluded.
  double contour_seconds = 0, heights_seconds = 0, write_seconds = 0;
  std::size_t blocks_decoded = 0;  // raster blocks decoded by the shared cache (a block freed and read again counts again)
  // With inputs.footprints: footprints the mask confirms, the mask's buildings outside them, footprints it does not confirm.
  std::size_t confirmed = 0, not_in_footprints = 0, not_in_mask = 0;
  std::map<std::string, std::size_t> models;  // the buildings modeled (ok) by the outline the chain chose (docs/models.md)
  // Each entry with its tile: tiles are recorded in the order they are processed, the files list
  // them in tile order.
  struct Failed {
    std::string id, tile, stage, reason;
  };
  struct TileRecord {  // a tile, for the tile index and the report's per_tile list
    std::string tile;
    int col = 0, row = 0;
    std::size_t buildings = 0;
    bool skipped = false;
    double seconds = 0;
    std::array<double, 2> origin{};              // the tile's upper-left corner in map coordinates
    TileOutputs outputs;                         // its files with their fingerprints
    std::array<std::array<double, 2>, 4> ring;  // the tile's corners in map coordinates, counter-clockwise
  };
  struct Slow {
    double seconds = 0;
    std::string id;  // BuildingOutput::display_id
    std::string tile;
  };
  std::vector<Slow> slowest;  // the slowest buildings' regularizations, slowest first (at most kSlowest)
  static constexpr std::size_t kSlowest = 20;
  std::vector<std::pair<int, Failed>> failed;
  std::vector<std::pair<int, std::string>> too_large;
  std::vector<std::pair<int, TileRecord>> tiles;
};

// Adds a finished (or resumed) tile to the totals and the index.
void record_tile(Totals& totals, const RunPlan& plan, const TileResult& result, const TileOutputs& outputs);

// ".shard-K-of-N" for shard K of a run in N shards, empty for a whole run: the suffix of its tile
// index, run report and work_dir lock.
std::string shard_suffix(int shard_index, int shard_count);

// What a tile index says: the run key, and every output file (relative to the output directory)
// with its fingerprint (empty in an index of an older lodforge), in tile order.
struct TileIndex {
  std::string run_key;
  TileOutputs outputs;
};
// Reads a tile index as JSON; nullopt when there is no such file; InputError when it is not one.
std::optional<TileIndex> read_tile_index(const std::filesystem::path& path);

// Writes tile_index[.shard-K-of-N].geojson and report[...].json (through nlohmann-json); logs the summary.
void write_index_and_report(const Totals& totals, const RunPlan& plan, const std::string& job_path, int shard_index,
                            int shard_count, std::size_t tiles, double elapsed);

// The shards' tile indexes (read as JSON) as one, written to target: every feature, in tile order.
// InputError naming the file when one is not a tile index or comes from another run (run key).
void merge_tile_indexes(const std::vector<std::filesystem::path>& parts, const std::filesystem::path& target);

// The shards' run reports (read as JSON) as one report.json: every count, core and stage seconds
// summed, the seconds the slowest shard's, the failed and too-large buildings and the per-tile
// entries in tile order. InputError naming the file when one is not a run report.
void merge_run_reports(const std::vector<std::filesystem::path>& parts, const std::filesystem::path& target);

}  // namespace lodforge
