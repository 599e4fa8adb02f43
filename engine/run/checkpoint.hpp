// Checkpoints: each tile's intermediate results per stage, in the work directory, named by a hash
// of everything they depend on (input window, options). Written atomically (temporary file, then
// rename); a file that is missing, truncated or of another version is recomputed, never trusted.
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "geometry/types.hpp"
#include "run/tiles.hpp"

namespace lodforge {

// The per-building result a tile keeps.
struct BuildingOutput {
  std::int64_t id = 0;  // first pixel: row * raster width + col
  int first_row = 0, first_col = 0;
  PolygonWithHoles footprint;
  bool ok = true;
  std::string stage, reason;
  double seconds = 0;  // regularization time (not checkpointed: 0 when restored)
};

class CheckpointStore {
 public:
  explicit CheckpointStore(std::string directory);  // creates it; throws InputError if it cannot
  void save_contours(const std::string& tile, std::uint64_t key, const TileBuildings& value) const;
  std::optional<TileBuildings> load_contours(const std::string& tile, std::uint64_t key) const;
  void save_buildings(const std::string& tile, std::uint64_t key, const std::vector<BuildingOutput>& value) const;
  std::optional<std::vector<BuildingOutput>> load_buildings(const std::string& tile, std::uint64_t key) const;
  // Any other stage's payload (serialized by the caller).
  void save_blob(const std::string& stage, const std::string& tile, std::uint64_t key, const std::string& payload) const;
  std::optional<std::string> load_blob(const std::string& stage, const std::string& tile, std::uint64_t key) const;
  // A tile whose outputs were written under this key is complete; its summary is kept with it.
  void mark_done(const std::string& tile, std::uint64_t key, const std::string& summary) const;
  std::optional<std::string> done_summary(const std::string& tile, std::uint64_t key) const;

 private:
  // One file per tile and stage; the key inside says which inputs it was made from.
  std::string path(const std::string& stage, const std::string& tile) const;
  std::string directory_;
};

std::string hex(std::uint64_t value);

}  // namespace lodforge
