// A tile's work in the run's pipeline: the parallel part (window, contours, footprints, heights,
// picture, each from its checkpoint when there is one) and the in-order part (its files).
#pragma once
#include <cstdint>
#include <filesystem>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <set>
#include <string>
#include <vector>

#include "heights/heights.hpp"
#include "io/input_crs.hpp"
#include "io/raster.hpp"
#include "job/job.hpp"
#include "run/batch.hpp"
#include "run/checkpoint.hpp"
#include "run/tiles.hpp"

namespace lodforge {

class HeightWindowReader;
class Cadastre;

// Raster readers kept open per worker thread for the whole run: GDAL's block cache belongs to
// an open dataset, and tiles overlap by their halos, so readers closed after each tile decoded
// the shared blocks again (the DSM and DTM windows most of all). Not for concurrent use of one
// reader: each thread gets its own.
class ReaderPool {
 public:
  // cache_bytes: the budget of the decoded blocks the threads share (0: none, GDAL's per handle).
  explicit ReaderPool(std::size_t cache_bytes = 0);
  ~ReaderPool();
  const MaskWindowReader& mask(const std::string& path, const BuildingSelector& selector);
  const HeightWindowReader& heights(const std::string& path);

  // The tiles in the order they are read, with the pixels each reads (tile_read_area). As each
  // tile says it has finished reading, the shared blocks that none of the next `lookahead` tiles
  // still to read overlaps are freed (rather than held until the budget is full, so memory stays
  // that of a few tiles' windows whatever the area). A freed block read again is decoded again.
  void plan_reads(const std::vector<int>& tiles, const std::vector<cv::Rect>& areas, std::size_t lookahead);
  void finished_reading(int tile);
  std::size_t blocks_decoded() const;  // by the shared cache so far (0 without one)

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Everything a tile needs to know about the run, fixed before the first tile.
struct RunPlan {
  const Job& job;
  cv::Size size;  // of the segmentation raster
  GeoTransform transform;
  const InputCrs& crs;  // read on first use: the writers wait for it
  double pixel;
  TileGrid grid;
  int halo_px, max_window_px;
  BuildingSelector selector;
  std::string dsm_source, dtm_source, ortho_source;  // on the segmentation's grid; empty: not given
  const CheckpointStore& store;
  // What each stage's results depend on besides its input, as text for the checkpoint keys.
  std::string contour_options, core_options, heights_options, transform_text;
  std::uint64_t job_key;  // inputs' identity, every option and the tiling: a complete tile's key
  std::filesystem::path out_dir;
  ReaderPool* readers;  // per-thread open rasters, owned by the run
  // Files under out_dir that an earlier tile index lists: lodforge's own, which it may replace.
  const std::set<std::string>* indexed_outputs = nullptr;
  const Cadastre* cadastre = nullptr;  // inputs.footprints, when given
  MaskNoise noise;                     // the boundary noise every building allows for, and its normals are smoothed for (survey_noise)
};

// A building's LoD1.3 part: where its roof steps (stages.parts), with its own heights.
struct BuildingPart {
  PolygonWithHoles footprint;
  Heights heights;
};

struct TileResult {
  int tile = 0;
  std::string name;
  bool skipped = false;  // complete from an earlier run
  bool contours_reused = false, buildings_reused = false;  // stage checkpoints found
  std::vector<BuildingOutput> buildings;
  std::vector<Heights> heights;  // per building, when a DSM is given
  std::vector<std::vector<BuildingPart>> parts;  // ... and its LoD1.3 parts (none: one part, its LoD1.2 block)
  int dropped_small = 0;
  std::vector<std::string> too_large;
  std::string summary;  // kept in the done marker, replayed on resume
  cv::Mat quicklook_background;  // the tile's picture, when output.quicklook
  double seconds = 0;  // the tile's wall time
  // Time in the per-building stages on one core, reads excluded (the run report's stage_seconds;
  // the regularization is each building's own seconds): contour labeling and tracing, heights and the LOD1
  // check, writing every format.
  double contour_seconds = 0, heights_seconds = 0, write_seconds = 0;
};

std::shared_ptr<TileResult> process_tile(const RunPlan& plan, int tile);

// The files of a tile (relative to out_dir) that lodforge can show it wrote, and so may replace:
// those its done marker or write intent lists (store.own_files) and those an earlier tile index
// lists (indexed, may be null).
std::set<std::string> replaceable_files(const CheckpointStore& store, const std::set<std::string>* indexed, const std::string& tile);

// The pixels a tile reads as planned: its rectangle with the halo, and with the heights' margin
// when there is a DSM (a window grown for a large building reads more).
cv::Rect tile_read_area(const RunPlan& plan, int tile);

// Writes the tile's files (every format and the quick look) and marks it complete; returns the
// files it has, relative to out_dir.
TileOutputs write_tile_outputs(const RunPlan& plan, TileResult& result);

}  // namespace lodforge
