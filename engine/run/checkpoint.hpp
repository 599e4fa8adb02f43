// Checkpoints: each tile's intermediate results per stage, in the work directory, named by a hash
// of everything they depend on (input window, options). Written atomically (temporary file, then
// rename); a file that is missing, truncated or of another version is recomputed, never trusted.
#pragma once
#include <cstdint>
#include <optional>
#include <set>
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
  std::string model;    // the outline the chain chose (BuildingResult::model; docs/models.md); empty for a fallback and the cadastre's polygon
  double seconds = 0;  // regularization time (checkpointed: the report lists the slowest buildings of a resumed run too)
  // With inputs.footprints (set after the checkpoint, by the split among the footprints): as in BuildingModel.
  std::string cadastre_id, cadastre;
  double coverage = -1;
  // The building's name in logs and reports: the cadastral ID, else the first-pixel index.
  std::string display_id() const { return cadastre_id.empty() ? std::to_string(id) : cadastre_id; }
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
  // The tile's last done marker whatever its key (an earlier run's, other options): the files it lists
  // are lodforge's own. Empty when there is none or it does not check.
  std::optional<std::string> last_done_summary(const std::string& tile) const;
  // The files under output.dir that lodforge wrote or was about to write for the tile (its last
  // done marker's, and those recorded by record_intent before writing): its own, to replace.
  void record_intent(const std::string& tile, const std::vector<std::string>& relative_paths) const;
  std::set<std::string> own_files(const std::string& tile) const;

 private:
  // One file per tile and stage; the key inside says which inputs it was made from.
  std::string path(const std::string& stage, const std::string& tile) const;
  std::string directory_;
};

std::string hex(std::uint64_t value);

// "SIZE:HASH" of a regular file's bytes, recorded when lodforge writes an output and checked before
// the output is trusted again (resume, merge); empty when the file is missing or not regular.
std::string file_fingerprint(const std::string& path);

// The output files a tile summary lists ("output\tRELATIVE_PATH\tFINGERPRINT" lines): (path, fingerprint).
using TileOutputs = std::vector<std::pair<std::string, std::string>>;
TileOutputs summary_outputs(const std::string& summary);
std::string summary_output_line(const std::string& relative_path, const std::string& fingerprint);

// A run's hold on its work directory: an exclusive lock (flock) on DIR/NAME, which holds the
// holder's pid, for as long as the object lives. A second holder is refused with an InputError
// naming the first's pid. (Shards lock their own name: they share a work directory.)
class WorkDirLock {
 public:
  WorkDirLock(const std::string& directory, const std::string& name);
  ~WorkDirLock();
  WorkDirLock(const WorkDirLock&) = delete;
  WorkDirLock& operator=(const WorkDirLock&) = delete;

 private:
  int fd_ = -1;
};


}  // namespace lodforge
