#include "geometry/polygon.hpp"
#include "run/tile_worker.hpp"

#include <algorithm>
#include <map>
#include <set>
#include <mutex>

#include <tbb/enumerable_thread_specific.h>

#include <chrono>
#include <gdal_priv.h>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <sstream>
#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>
#include <tbb/task_arena.h>

#include "io/block_cache.hpp"
#include "io/cadastre.hpp"
#include "io/errors.hpp"
#include "io/height_reader.hpp"
#include "io/model_writers.hpp"
#include "io/quicklook.hpp"
#include "lod1/solid.hpp"
#include "partition/partition.hpp"
#include "parts/parts.hpp"
#include "pipeline/building.hpp"
#include "run/batch.hpp"

namespace lodforge {

namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Runs a tile's nested parallel work (labeling, its buildings, their heights, its formats) so that a
// thread waiting in it helps with it only, never starts another tile meanwhile: a stolen tile
// would hold this one (and the in-order bookkeeping, and memory) until it is done. In a context
// of its own: when another tile fails and the run is cancelled, the nested loops of a tile in
// flight would otherwise stop short and return as if done, and the tile would save checkpoints
// of part of its buildings and be marked done without its files. So a tile in flight finishes
// whole (or fails), and the run stops after it.
template <class F>
void within_tile(F&& f) {
  tbb::task_group_context whole(tbb::task_group_context::isolated);
  tbb::task_group group(whole);
  group.run_and_wait([&] { tbb::this_task_arena::isolate(f); });
}


std::vector<BuildingOutput> regularize_tile(const TileBuildings& tile, const Job& job, long raster_width, double pixel_size,
                                            const MaskNoise& noise, const Lenders& lenders) {
  std::vector<BuildingOutput> out(tile.buildings.size());
  RegularizedBatch batch;
  MaskNoise given = noise;
  if (!given.rounding_m) given.rounding_m = 0.0;  // (a tile never pools its own: the tiling would change it)
  within_tile([&] { batch = regularize_batch(job.regularizer, tile.buildings, pixel_size, job.stages.core, given, lenders); });
  for (std::size_t i = 0; i < tile.buildings.size(); ++i) {
    const BuildingContour& b = tile.buildings[i];
    BuildingResult& r = batch.results[i];
    BuildingOutput& o = out[i];
    o.id = std::int64_t(b.first_row) * raster_width + b.first_col;
    o.first_row = b.first_row;
    o.first_col = b.first_col;
    o.footprint = std::move(r.footprint);
    o.ok = r.ok;
    o.stage = r.failed_stage;
    o.reason = r.remark();
    o.model = r.ok ? r.model : "";
    o.seconds = r.seconds;
  }
  return out;
}

// With a cadastre: the tile's buildings (one per mask component, as regularized) become one per
// footprint the mask confirms (its share of its block's outlines), one per part of a block that no
// footprint's cell covers (not_in_footprints), and one per footprint the mask does not confirm
// (not_in_mask, the cadastre's polygon, no LOD1). In block order; within a block, the
// footprints in the cadastre's order, then the parts.
std::vector<BuildingOutput> split_among_footprints(const std::vector<TileGroup>& groups, const std::vector<BuildingOutput>& blobs,
                                                   const RunPlan& plan) {
  const PartitionOptions& options = plan.job.stages.footprints;
  const Cadastre& cadastre = *plan.cadastre;
  const std::int64_t raster_pixels = std::int64_t(plan.size.width) * plan.size.height;
  std::vector<std::vector<BuildingOutput>> per_group(groups.size());
  within_tile([&] { tbb::parallel_for(std::size_t(0), groups.size(), [&](std::size_t g) {
    const auto started = Clock::now();
    const TileGroup& t = groups[g];
    std::vector<BuildingOutput>& out = per_group[g];
    std::vector<PolygonWithHoles> outlines;
    BuildingOutput block;  // what the block's outlines share: status, time, and their model where they have one (none if one failed)
    block.id = t.id;
    block.first_row = int(t.id / plan.size.width);
    block.first_col = int(t.id % plan.size.width);
    for (int b : t.buildings) {
      const BuildingOutput& o = blobs[std::size_t(b)];
      block.model = outlines.empty() || o.model == block.model ? o.model : "";
      outlines.push_back(o.footprint);
      block.seconds += o.seconds;
      if (!o.ok && block.ok) { block.ok = false; block.stage = o.stage; block.reason = o.reason; }
      else if (o.ok && block.ok && !o.reason.empty() && block.reason.empty()) block.reason = o.reason;
    }
    std::vector<char> is_confirmed(t.footprints.size());
    std::vector<std::vector<PolygonWithHoles>> confirmed;
    for (std::size_t k = 0; k < t.footprints.size(); ++k) {
      is_confirmed[k] = t.coverage[k] >= options.min_coverage && !outlines.empty();
      if (is_confirmed[k]) confirmed.push_back(cadastre.footprints()[std::size_t(t.footprints[k])].parts);
    }
    if (confirmed.empty()) {
      for (int b : t.buildings) {
        out.push_back(blobs[std::size_t(b)]);
        out.back().cadastre = "not_in_footprints";
      }
    }
    Partition split;
    std::string split_failure;
    if (!confirmed.empty()) {
      try {
        split = partition_outlines(outlines, confirmed, options, plan.job.stages.contour.min_area_m2);
      } catch (const std::exception& e) {  // (a failure is the block's status, never the run's end)
        split_failure = e.what();
        split.shares.resize(confirmed.size());  // (split is as it was: empty)
      }
    }
    std::size_t next_share = 0;
    for (std::size_t k = 0; k < t.footprints.size(); ++k) {
      const CadastralFootprint& footprint = cadastre.footprints()[std::size_t(t.footprints[k])];
      BuildingOutput o;
      o.id = -1 - std::int64_t(t.footprints[k]);  // (internal: the files name it by its cadastre ID, o.cadastre_id)
      o.first_row = block.first_row;
      o.first_col = block.first_col;
      o.cadastre_id = footprint.id;
      o.coverage = t.coverage[k];
      if (is_confirmed[k]) {
        const FootprintShare& share = split.shares[next_share++];
        o.cadastre = "confirmed";
        o.ok = block.ok;
        o.stage = block.stage;
        o.reason = block.reason;
        o.model = options.lod0 != "cadastre" ? block.model : "";  // (with lod0: cadastre, the cadastre's polygon)
        o.footprint = share.polygon;
        if (!share.note.empty()) o.reason += (o.reason.empty() ? "" : "; ") + share.note;
        if (share.polygon.outer.empty()) {
          // Nothing of its own (under earlier footprints), or the split failed: the cadastre's polygon, as a fallback.
          o.footprint = footprint.parts.front();
          o.ok = false;
          o.model.clear();
          o.stage = "footprints";
          o.reason = split_failure.empty() ? "the footprint lies under earlier ones; its first part is its LOD0"
                                           : "splitting the block among its footprints failed (" + split_failure + "); the cadastre's polygon is its LOD0";
        }
        if (next_share == 1) o.seconds = block.seconds;  // (the block's regularization, counted once)
      } else {
        o.cadastre = "not_in_mask";
        o.footprint = footprint.parts.front();
      }
      out.push_back(std::move(o));
    }
    for (std::size_t k = 0; k < split.rest.size(); ++k) {
      BuildingOutput o = block;
      o.id = t.id + std::int64_t(k) * raster_pixels;  // (beyond the raster's pixels: a block's further parts)
      o.footprint = split.rest[k];
      o.cadastre = "not_in_footprints";
      o.seconds = 0;
      out.push_back(std::move(o));
    }
    if (!out.empty()) out.front().seconds += std::chrono::duration<double>(Clock::now() - started).count();
  }); });
  std::vector<BuildingOutput> out;
  for (auto& list : per_group)
    for (BuildingOutput& b : list) out.push_back(std::move(b));
  return out;
}

std::string make_summary(const TileResult& r, bool cadastre) {
  // (A footprint the mask does not confirm is no building: counted apart.)
  int buildings = 0, ok = 0, lod1 = 0, confirmed = 0, not_in_footprints = 0, not_in_mask = 0;
  for (const BuildingOutput& b : r.buildings) {
    not_in_mask += b.cadastre == "not_in_mask";
    confirmed += b.cadastre == "confirmed";
    not_in_footprints += b.cadastre == "not_in_footprints";
    if (b.cadastre == "not_in_mask") continue;
    ++buildings;
    ok += b.ok;
  }
  for (const Heights& h : r.heights) lod1 += h.ok;
  std::ostringstream s;
  s << buildings << ' ' << ok << ' ' << buildings - ok << ' ' << r.dropped_small << ' ' << lod1 << '\n';
  if (cadastre) s << "cadastre\t" << confirmed << '\t' << not_in_footprints << '\t' << not_in_mask << '\n';
  for (const BuildingOutput& b : r.buildings)
    if (!b.ok) s << "failed\t" << b.display_id() << '\t' << b.stage << '\t' << b.reason << '\n';
  for (std::size_t i = 0; i < r.heights.size(); ++i)
    if (!r.heights[i].ok && r.buildings[i].cadastre != "not_in_mask") s << "failed\t" << r.buildings[i].display_id() << "\theights\t" << r.heights[i].reason << " (LOD0 only)\n";
  for (const std::string& t : r.too_large) s << "too_large\t" << t << '\n';
  std::map<std::string, int> models;  // (of the buildings modeled: a footprint the mask does not confirm is none)
  for (const BuildingOutput& b : r.buildings)
    if (b.ok && !b.model.empty() && b.cadastre != "not_in_mask") ++models[b.model];
  for (const auto& [model, count] : models) s << "model\t" << model << '\t' << count << '\n';
  return s.str();
}

std::string serialize_heights(const std::vector<Heights>& heights) {
  std::ostringstream s;
  s.precision(17);
  for (const Heights& h : heights)
    s << h.ok << '\t' << h.roof << '\t' << h.ground << '\t' << h.roof_samples << '\t' << h.ground_samples << '\t' << h.roof_min << '\t'
      << h.roof_50p << '\t' << h.roof_70p << '\t' << h.roof_max << '\t' << h.dsm_coverage << '\t' << h.dsm_cells << '\t' << h.reason << '\n';
  return s.str();
}

// Each building's parts: a line "parts N", then per part its heights line and its rings, each a
// line "ring x y x y ..." (the outer first).
std::string serialize_parts(const std::vector<std::vector<BuildingPart>>& parts) {
  std::ostringstream s;
  s.precision(17);
  for (const std::vector<BuildingPart>& building : parts) {
    s << "parts " << building.size() << '\n';
    for (const BuildingPart& p : building) {
      s << serialize_heights({p.heights});
      for (const Ring* ring : rings_of(p.footprint)) {
        s << "ring";
        for (const Vec2& v : *ring) s << ' ' << v.x() << ' ' << v.y();
        s << '\n';
      }
      s << "end\n";
    }
  }
  return s.str();
}

std::optional<std::vector<Heights>> parse_heights(const std::string& text, std::size_t count) {
  std::vector<Heights> out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream f(line);
    Heights h;
    std::string ok;
    std::getline(f, ok, '\t');
    f >> h.roof >> h.ground >> h.roof_samples >> h.ground_samples >> h.roof_min >> h.roof_50p >> h.roof_70p >> h.roof_max >> h.dsm_coverage >> h.dsm_cells;
    if (!f) return std::nullopt;  // (written by another version: computed again)
    f.get();
    std::getline(f, h.reason);
    h.ok = ok == "1";
    out.push_back(h);
  }
  if (out.size() != count) return std::nullopt;
  return out;
}

// (Anything malformed: nullopt, and the parts are computed again.)
std::optional<std::vector<std::vector<BuildingPart>>> parse_parts(const std::string& text, std::size_t count) {
  std::vector<std::vector<BuildingPart>> out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream header(line);
    std::string word;
    std::size_t n = 0;
    if (!(header >> word >> n) || word != "parts" || !(header >> std::ws).eof() || n > 100000) return std::nullopt;
    std::vector<BuildingPart>& building = out.emplace_back();
    for (std::size_t k = 0; k < n; ++k) {
      BuildingPart p;
      if (!std::getline(in, line)) return std::nullopt;
      const auto heights = parse_heights(line + "\n", 1);
      if (!heights) return std::nullopt;
      p.heights = heights->front();
      bool ended = false;
      while (std::getline(in, line)) {
        if (line == "end") { ended = true; break; }
        if (line.rfind("ring ", 0) != 0) return std::nullopt;
        std::istringstream f(line.substr(5));
        std::vector<double> values;
        for (double v; f >> v;) values.push_back(v);
        if (!f.eof() || values.size() % 2 || values.size() < 6) return std::nullopt;
        Ring ring;
        for (std::size_t j = 0; j < values.size(); j += 2) ring.emplace_back(values[j], values[j + 1]);
        (p.footprint.outer.empty() ? p.footprint.outer : p.footprint.holes.emplace_back()) = std::move(ring);
      }
      if (!ended || p.footprint.outer.empty()) return std::nullopt;
      building.push_back(std::move(p));
    }
  }
  if (out.size() != count) return std::nullopt;
  return out;
}

// The values of height_statistic_fields() for a footprint with these heights.
std::vector<double> height_statistics(const PolygonWithHoles& footprint, const Heights& h) {
  return {h.roof_min, h.roof_50p, h.roof_70p, h.roof_max, area(footprint) * (h.roof - h.ground), h.dsm_coverage, double(h.dsm_cells)};
}

BuildingModel model_of(const BuildingOutput& b, const Heights* h, const std::vector<BuildingPart>* parts, const std::string& tile, const Job& job) {
  BuildingModel m;
  m.id = b.id;
  m.tile = tile;
  m.footprint = b.footprint;
  m.regularizer = b.ok ? job.regularizer : "douglas_peucker";
  m.stage = b.stage;
  m.reason = b.reason;
  m.cadastre_id = b.cadastre_id;
  m.cadastre = b.cadastre;
  m.coverage = b.coverage;
  m.model = b.model;
  if (b.cadastre == "not_in_mask" || (b.cadastre == "confirmed" && job.stages.footprints.lod0 == "cadastre")) m.regularizer = "cadastre";
  if (b.cadastre == "not_in_mask") {
    m.status = "not_in_mask";
    return m;
  }
  if (h && h->ok) {
    m.solid = extrude(b.footprint, h->ground, h->roof);
    m.has_lod1 = true;
    m.ground = h->ground;
    m.roof = h->roof;
    m.height_statistics = height_statistics(b.footprint, *h);
    if (parts)
      for (const BuildingPart& p : *parts)
        m.parts.push_back({p.footprint, p.heights.ground, p.heights.roof, height_statistics(p.footprint, p.heights),
                           extrude(p.footprint, p.heights.ground, p.heights.roof)});
  } else if (h) {
    if (b.ok) m.stage = "heights";
    m.reason += (m.reason.empty() ? "" : "; ") + std::string("heights: ") + h->reason;
  }
  m.status = !b.ok ? "fallback" : (m.has_lod1 || !h ? "ok" : "lod0_only");
  return m;
}

// The orthophoto's window on the segmentation's grid as a BGR picture (first three bands, or grey).
cv::Mat read_orthophoto(const std::string& path, const cv::Rect& w) {
  GDALDataset* d = static_cast<GDALDataset*>(GDALOpen(path.c_str(), GA_ReadOnly));
  if (!d) throw InputError("'" + path + "': not a raster GDAL can read");
  const int bands = std::min(3, d->GetRasterCount());
  std::vector<cv::Mat> channels;
  for (int b = bands; b >= 1; --b) {  // BGR
    cv::Mat m(w.height, w.width, CV_8U);
    if (d->GetRasterBand(b)->RasterIO(GF_Read, w.x, w.y, w.width, w.height, m.data, w.width, w.height, GDT_Byte, 0, 0) != CE_None) {
      GDALClose(d);
      throw InputError("'" + path + "': cannot read: " + CPLGetLastErrorMsg());
    }
    channels.push_back(m);
  }
  GDALClose(d);
  while (channels.size() < 3) channels.push_back(channels.front().clone());
  cv::Mat out;
  cv::merge(channels, out);
  return out;
}

}  // namespace

struct ReaderPool::Impl {
  struct PerThread {
    std::map<std::string, std::unique_ptr<MaskWindowReader>> masks;
    std::map<std::string, std::unique_ptr<HeightWindowReader>> heights;
  };
  tbb::enumerable_thread_specific<PerThread> threads;
  std::unique_ptr<BlockCache> cache;
  std::mutex schedule_mutex;  // the read schedule (plan_reads):
  std::size_t lookahead = 0;
  std::map<int, std::size_t> position;       // of each tile in the reading order
  std::map<std::size_t, cv::Rect> unread;    // the tiles still to read, by position: their areas
};

ReaderPool::ReaderPool(std::size_t cache_bytes) : impl_(std::make_unique<Impl>()) {
  if (cache_bytes > 0) impl_->cache = std::make_unique<BlockCache>(cache_bytes);
}

ReaderPool::~ReaderPool() = default;

void ReaderPool::plan_reads(const std::vector<int>& tiles, const std::vector<cv::Rect>& areas, std::size_t lookahead) {
  std::lock_guard lock(impl_->schedule_mutex);
  impl_->lookahead = lookahead;
  impl_->position.clear();
  impl_->unread.clear();
  for (std::size_t k = 0; k < tiles.size(); ++k) {
    impl_->position[tiles[k]] = k;
    impl_->unread[k] = areas[k];
  }
}

std::size_t ReaderPool::blocks_decoded() const { return impl_->cache ? impl_->cache->decoded_blocks() : 0; }

void ReaderPool::finished_reading(int tile) {
  if (!impl_->cache) return;
  // Under the schedule's lock throughout, so that an older set never frees what a newer keeps.
  std::lock_guard lock(impl_->schedule_mutex);
  const auto p = impl_->position.find(tile);
  if (p == impl_->position.end() || !impl_->unread.erase(p->second)) return;
  std::vector<cv::Rect> needed;
  for (auto k = impl_->unread.begin(); k != impl_->unread.end() && needed.size() < impl_->lookahead; ++k)
    needed.push_back(k->second);
  impl_->cache->keep_only(needed);
}

namespace {

// Pixels around the footprints' window that the heights read (the ground ring, and corners that
// may lie past the contour).
int heights_margin_px(const RunPlan& plan) {
  const auto& stages = plan.job.stages;
  return int(std::ceil((stages.heights.ring_outer_m + stages.core.corners.max_corner_shift_m) / plan.pixel)) + 2;
}

}  // namespace

cv::Rect tile_read_area(const RunPlan& plan, int tile) {
  // The mask window first read, or the heights' margin around the tile's buildings if wider.
  // (Not the wider window the tile's lattice lenders are read in: keeping its blocks for the next
  // tiles cost more memory and time, 4x city 151 MB and 2.12 s against 135 MB and 2.05 s, than
  // decoding a few again.)
  const int m = std::max(first_window_margin(plan.halo_px, plan.grid.tile_px, plan.max_window_px),
                         plan.halo_px + (plan.dsm_source.empty() ? 0 : heights_margin_px(plan)));
  return (plan.grid.rect(tile) + cv::Size(2 * m, 2 * m) - cv::Point(m, m)) & cv::Rect(cv::Point(0, 0), plan.size);
}

const MaskWindowReader& ReaderPool::mask(const std::string& path, const BuildingSelector& selector) {
  auto& slot = impl_->threads.local().masks[path];
  if (!slot) slot = std::make_unique<MaskWindowReader>(path, selector, impl_->cache.get());
  return *slot;
}

const HeightWindowReader& ReaderPool::heights(const std::string& path) {
  auto& slot = impl_->threads.local().heights[path];
  if (!slot) slot = std::make_unique<HeightWindowReader>(path, impl_->cache.get());
  return *slot;
}

std::set<std::string> replaceable_files(const CheckpointStore& store, const std::set<std::string>* indexed, const std::string& tile) {
  std::set<std::string> files = store.own_files(tile);
  const std::string prefix = "tiles/" + tile + ".";
  if (indexed)
    for (auto it = indexed->lower_bound(prefix); it != indexed->end() && it->rfind(prefix, 0) == 0; ++it) files.insert(*it);
  return files;
}

std::shared_ptr<TileResult> process_tile(const RunPlan& plan, int tile) {
  const Job& job = plan.job;
  const TileGrid& grid = plan.grid;
  const CheckpointStore& store = plan.store;
  const double pixel = plan.pixel;
  const long width = plan.size.width;
  auto r = std::make_shared<TileResult>();
  const auto t0 = Clock::now();
  r->tile = tile;
  r->name = grid.name(tile);
  const std::uint64_t done_key = fnv1a(r->name, plan.job_key);
  if (auto summary = store.done_summary(r->name, done_key)) {
    // Complete, if its files are still those it wrote; else made again (from its checkpoints).
    const TileOutputs outputs = summary_outputs(*summary);
    const auto changed = std::find_if(outputs.begin(), outputs.end(), [&](const auto& output) {
      return file_fingerprint((plan.out_dir / output.first).string()) != output.second;
    });
    if (changed == outputs.end()) {
      r->skipped = true;
      r->summary = *summary;
      plan.readers->finished_reading(tile);
      return r;
    }
    spdlog::warn("tile {}: {} is missing or changed since it was written; the tile is written again", r->name, changed->first);
  }
  std::uint64_t contour_key = 0;
  std::optional<TileBuildings> contours;
  std::vector<TileGroup> groups;  // with a cadastre
  {  // the window (mask and its labels) is freed once traced: tiles in flight hold only what they need
    const MaskWindowReader& reader = plan.readers->mask(job.inputs.segmentation.path, plan.selector);
    TileWindow window;  // (OpenCV labels the components with nested parallel work: isolated too)
    within_tile([&] { window = find_tile_window(reader, grid, tile, plan.halo_px, plan.max_window_px, job.stages.contour.connectivity,
                                                plan.cadastre, &plan.transform); });
    contour_key = fnv1a(plan.contour_options + plan.transform_text + std::to_string(grid.tile_px), window.hash);
    contours = store.load_contours(r->name, contour_key);
    r->contours_reused = contours.has_value();
    if (!contours) {
      const auto traced = Clock::now();
      contours = trace_tile(window, grid, tile, plan.transform, job.stages.contour);
      // The labeling, done in the window search, is the contour stage's first step.
      r->contour_seconds = window.label_seconds + seconds_since(traced);
      store.save_contours(r->name, contour_key, *contours);
    }
    if (plan.cadastre) groups = tile_groups(window, grid, tile, *contours, *plan.cadastre, plan.transform);
  }
  // The buildings that may lend the tile's their lattice, from a window around them (the same
  // lattices whatever the tiling): part of what the regularized buildings depend on.
  Lenders lenders;
  std::uint64_t lenders_key = contour_key;
  if (job.regularizer == "deformation" && job.stages.core.lattice.neighbour_radius_m > 0) {
    const auto traced = Clock::now();
    const MaskWindowReader& reader = plan.readers->mask(job.inputs.segmentation.path, plan.selector);
    within_tile([&] { lenders.given = lattice_lenders(reader, plan.size, plan.transform, job.stages.contour, job.stages.core.lattice,
                                                      contours->buildings); });
    lenders.from = Lenders::From::given;
    r->contour_seconds += seconds_since(traced);
    for (const LatticeLender& l : lenders.given) {
      const double fields[] = {l.centre.x(), l.centre.y(), l.direction.x(), l.direction.y(), l.share, l.perimeter, l.extent};
      lenders_key = fnv1a(&l.id, sizeof l.id, lenders_key);
      lenders_key = fnv1a(fields, sizeof fields, lenders_key);
    }
  }
  const std::uint64_t buildings_key = fnv1a(plan.core_options, lenders_key);
  std::optional<std::vector<BuildingOutput>> buildings = store.load_buildings(r->name, buildings_key);
  r->buildings_reused = buildings.has_value();
  if (!buildings) {
    buildings = regularize_tile(*contours, job, width, pixel, plan.noise, lenders);
    store.save_buildings(r->name, buildings_key, *buildings);
  }
  r->buildings = std::move(*buildings);
  if (plan.cadastre) r->buildings = split_among_footprints(groups, r->buildings, plan);
  if (!plan.dsm_source.empty()) {
    const std::uint64_t heights_key = fnv1a(plan.heights_options, buildings_key);
    std::optional<std::vector<Heights>> heights;
    std::optional<std::vector<std::vector<BuildingPart>>> parts;
    if (auto blob = store.load_blob("heights", r->name, heights_key)) heights = parse_heights(*blob, r->buildings.size());
    if (auto blob = store.load_blob("parts", r->name, heights_key)) parts = parse_parts(*blob, r->buildings.size());
    if (!heights || !parts) {
      parts.emplace(r->buildings.size());
      // Each building reads just the DSM and DTM pixels its heights need (heights_box), from the
      // shared blocks: a tile holds no window of the whole tile, and blocks no building touches
      // are never decoded. (Each thread reads through its own dataset handles.)
      heights.emplace(r->buildings.size());
      std::vector<double> seconds(r->buildings.size());
      within_tile([&] { tbb::parallel_for(std::size_t(0), r->buildings.size(), [&](std::size_t i) {
        if (r->buildings[i].cadastre == "not_in_mask") {  // (no model: the cadastre's polygon only)
          (*heights)[i].reason = "not in the mask";
          return;
        }
        const PolygonWithHoles& footprint = r->buildings[i].footprint;
        const cv::Rect box = heights_box(footprint, plan.transform, plan.size, job.stages.heights);
        HeightRaster dsm;
        std::optional<HeightRaster> dtm;
        if (!box.empty()) {
          dsm = plan.readers->heights(plan.dsm_source).read(box, plan.transform);
          if (!plan.dtm_source.empty()) dtm = plan.readers->heights(plan.dtm_source).read(box, plan.transform);
        } else {
          dsm.transform = plan.transform;  // (nothing of the footprint on the raster: reported as such)
        }
        const auto started = Clock::now();  // (reads excluded, as for every stage)
        Heights& h = (*heights)[i];
        h = building_heights(footprint, dsm, dtm ? &*dtm : nullptr, job.stages.heights);
        // The block must be a valid shell to count as LOD1; decided here so that the report,
        // the summary and every file agree.
        if (h.ok) {
          if (const std::string problem = shell_problem(extrude(footprint, h.ground, h.roof)); !problem.empty()) {
            h.ok = false;
            h.reason = "lod1: invalid shell: " + problem;
          }
        }
        // LoD1.3: the parts where the roof steps, each with its heights and a valid block (else none).
        if (h.ok) {
          std::vector<BuildingPart>& building_parts = (*parts)[i];
          std::vector<PolygonWithHoles> split;
          try {
            split = split_by_roof_steps(footprint, dsm, pixel, job.regularizer, job.stages.core, job.stages.parts);
          } catch (const std::exception&) {  // (no parts: the LoD1.2 block stands for the building)
            split.clear();
          }
          for (PolygonWithHoles& p : split) {
            BuildingPart part{std::move(p), {}};
            part.heights = building_heights(part.footprint, dsm, dtm ? &*dtm : nullptr, job.stages.heights);
            if (!part.heights.ok || !shell_problem(extrude(part.footprint, part.heights.ground, part.heights.roof)).empty()) {
              building_parts.clear();
              break;
            }
            building_parts.push_back(std::move(part));
          }
        }
        seconds[i] = seconds_since(started);
      }); });
      for (double s : seconds) r->heights_seconds += s;
      store.save_blob("heights", r->name, heights_key, serialize_heights(*heights));
      store.save_blob("parts", r->name, heights_key, serialize_parts(*parts));
    }
    r->heights = std::move(*heights);
    r->parts = std::move(*parts);
  }
  plan.readers->finished_reading(tile);  // (a quick look may read again: decoded again if freed)
  if (job.output.quicklook && !r->buildings.empty()) {
    const cv::Rect tile_rect = grid.rect(tile);
    if (!job.inputs.orthophoto.path.empty()) {
      r->quicklook_background = read_orthophoto(plan.ortho_source, tile_rect);
    } else if (!plan.dsm_source.empty()) {
      const HeightRaster dsm = plan.readers->heights(plan.dsm_source).read(tile_rect, plan.transform);
      r->quicklook_background = hillshade(dsm.values, dsm.valid, pixel);
    } else {
      cv::Mat grey = plan.readers->mask(job.inputs.segmentation.path, plan.selector).read(tile_rect) * 120 + 40;
      cv::cvtColor(grey, r->quicklook_background, cv::COLOR_GRAY2BGR);
    }
  }
  r->dropped_small = contours->dropped_small;
  r->too_large = contours->too_large;
  r->summary = make_summary(*r, plan.cadastre != nullptr);
  r->seconds = seconds_since(t0);
  return r;
}

TileOutputs write_tile_outputs(const RunPlan& plan, TileResult& result) {
  const Job& job = plan.job;
  const TileGrid& grid = plan.grid;
  const CheckpointStore& store = plan.store;
  const fs::path& out_dir = plan.out_dir;
  TileResult* r = &result;

  // The inputs' CRS, checked (first use) before this tile touches any output.
  const std::string& crs_wkt = plan.crs.wkt();
  if (r->skipped) return summary_outputs(r->summary);
  const cv::Rect tile_rect = grid.rect(r->tile);
  // Files of this tile from an earlier run with other options (another format, no buildings any
  // more) must not outlive it: those lodforge can show it wrote, and only those (whatever else
  // is in tiles/ is not lodforge's).
  for (const std::string& relative : replaceable_files(store, plan.indexed_outputs, r->name)) {
    std::error_code ec;
    if (fs::is_regular_file(out_dir / relative, ec)) fs::remove(out_dir / relative, ec);
  }
  // The files about to be written (relative to out_dir), recorded first: a run killed before this
  // tile is marked done leaves files that are provably lodforge's (the next run replaces them).
  const std::vector<std::string>& formats = job.output.formats;
  std::vector<std::string> planned;
  if (!r->buildings.empty())
    for (const std::string& format : formats) planned.push_back("tiles/" + r->name + extension_of(format));
  if (!r->quicklook_background.empty()) planned.push_back("tiles/" + r->name + ".png");
  store.record_intent(r->name, planned);
  if (!r->buildings.empty()) {
    // The formats are written side by side (each its own file); a thread with no tile left to
    // take helps the last ones. An error in any is rethrown here, after all have stopped.
    // The models (LOD1 solids included) are made once for all the formats.
    const auto modeling = Clock::now();
    std::vector<BuildingModel> models;
    models.reserve(r->buildings.size());
    for (std::size_t i = 0; i < r->buildings.size(); ++i)
      models.push_back(model_of(r->buildings[i], r->heights.empty() ? nullptr : &r->heights[i], r->parts.empty() ? nullptr : &r->parts[i], r->name, job));
    r->write_seconds += seconds_since(modeling);
    const WriterContext context{crs_wkt, plan.crs.epsg(), r->name, plan.transform.to_map(tile_rect.x, tile_rect.y + tile_rect.height),
                                extent_of(models), plan.cadastre != nullptr};
    std::vector<double> seconds(formats.size());
    within_tile([&] { tbb::parallel_for(std::size_t(0), formats.size(), [&](std::size_t f) {
      const auto started = Clock::now();
      const auto writer = make_model_writer(formats[f], (out_dir / planned[f]).string(), context);
      // A footprint the mask does not confirm is listed with the footprints only, not modeled in 3D.
      const bool footprints_only = formats[f] == "gpkg" || formats[f] == "geojson";
      for (const BuildingModel& m : models)
        if (footprints_only || m.status != "not_in_mask") writer->add(m);
      writer->finish();
      seconds[f] = seconds_since(started);
    }); });
    for (double s : seconds) r->write_seconds += s;
  }
  if (!r->quicklook_background.empty()) {
    std::vector<QuicklookOutline> outlines;
    for (const BuildingOutput& b : r->buildings) outlines.push_back({b.footprint, b.ok});
    write_quicklook((out_dir / planned.back()).string(), r->quicklook_background, plan.transform.window(tile_rect.x, tile_rect.y), outlines);
  }
  // Each file with its fingerprint, in the done marker and (by the caller) in the tile index:
  // a later run or merge trusts it only while it is unchanged.
  TileOutputs outputs;
  for (const std::string& relative : planned) {
    std::string fingerprint = file_fingerprint((out_dir / relative).string());
    if (fingerprint.empty()) throw InputError("'" + (out_dir / relative).string() + "': written, but gone or not a file");
    r->summary += summary_output_line(relative, fingerprint);
    outputs.emplace_back(relative, std::move(fingerprint));
  }
  store.mark_done(r->name, fnv1a(r->name, plan.job_key), r->summary);
  return outputs;
}

}  // namespace lodforge
