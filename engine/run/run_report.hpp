// The run's accounting: totals over tiles, the tile index and the report (JSON and a summary).
#pragma once
#include <array>
#include <cstddef>
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
  // Each entry with its tile: tiles are recorded in the order they are processed, the files list
  // them in tile order.
  std::vector<std::pair<int, std::string>> failed_json, too_large, tile_json;
  struct IndexFeature {
    std::string head;                            // the feature up to its geometry
    std::array<std::array<double, 2>, 4> ring;  // the tile's corners in map coordinates, counter-clockwise
  };
  std::vector<std::pair<int, IndexFeature>> index_features;
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

// Writes tile_index[.shard-K-of-N].geojson and report[...].json; logs the summary.
void write_index_and_report(const Totals& totals, const RunPlan& plan, const std::string& job_path, int shard_index,
                            int shard_count, std::size_t tiles, double elapsed);

}  // namespace lodforge
