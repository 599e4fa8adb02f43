// lodforge run JOB.yaml: the tiled batch engine.
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <tuple>
#include <fstream>
#include <gdal_priv.h>
#include <opencv2/imgproc.hpp>
#include <iostream>
#include <map>
#include <mutex>
#include <spdlog/spdlog.h>
#include <set>
#include <sstream>
#include <sys/stat.h>
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <unistd.h>

#include "cli/args.hpp"
#include "commands/commands.hpp"
#include "common/option_visitors.hpp"
#include "geometry/polygon.hpp"
#include "io/atomic_file.hpp"
#include "io/cadastre.hpp"
#include "io/errors.hpp"
#include "io/footprint_writer.hpp"
#include "io/height_reader.hpp"
#include "io/input_crs.hpp"
#include "io/model_writers.hpp"
#include "io/quicklook.hpp"
#include "lod1/solid.hpp"
#include "io/raster.hpp"
#include "job/job.hpp"
#include "pipeline/building.hpp"
#include "run/checkpoint.hpp"
#include "run/batch.hpp"
#include "run/progress.hpp"
#include "run/run_report.hpp"
#include "run/tile_worker.hpp"
#include "run/tiles.hpp"

namespace lodforge {

namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

struct Shard {
  int index = 0, count = 1;
};

Shard parse_shard(const std::string& text) {
  Shard s;
  const auto slash = text.find('/');
  const auto whole_number = [](const std::string& part, int& value) {
    if (part.empty() || part.size() > 9 || part.find_first_not_of("0123456789") != std::string::npos) return false;
    value = std::stoi(part);
    return true;
  };
  if (slash == std::string::npos || !whole_number(text.substr(0, slash), s.index) || !whole_number(text.substr(slash + 1), s.count))
    throw InputError("--shard '" + text + "': expected K/N with two whole numbers, e.g. 0/4");
  if (s.count < 1 || s.index >= s.count)
    throw InputError("--shard '" + text + "': needs 0 <= K < N");
  return s;
}

// What the options that a stage depends on look like, as stable text for checkpoint keys.
template <class S>
std::string options_text(S& options) {
  OptionPrinter printer;
  options.visit(printer);
  return printer.str();
}

struct RasterInfo {
  cv::Size size;
  GeoTransform transform;
  std::string crs_wkt;  // the segmentation's, read up front; a companion's only when the grids differ (InputCrs)
};

RasterInfo inspect_raster(const std::string& path, const std::string& key) {
  const Dataset d = open_raster(path, key);
  RasterInfo info;
  info.size = {d->GetRasterXSize(), d->GetRasterYSize()};
  const bool georeferenced = d->GetGeoTransform(info.transform.c.data()) == CE_None;
  if (!georeferenced) throw InputError(key + ": '" + path + "': has no georeference (no geotransform)");
  return info;
}

// Checks an optional raster on another grid than the segmentation: same CRS, overlapping.
void check_companion(const std::string& key, const std::string& path, const RasterInfo& r, const RasterInfo& seg, const Job& job) {
  const bool crs_equal = same_crs(seg.crs_wkt, r.crs_wkt);
  auto extent = [](const RasterInfo& i) {
    const Vec2 p0 = i.transform.to_map(0, 0), p1 = i.transform.to_map(i.size.width, i.size.height);
    return std::array<double, 4>{std::min(p0.x(), p1.x()), std::min(p0.y(), p1.y()), std::max(p0.x(), p1.x()), std::max(p0.y(), p1.y())};
  };
  const auto e0 = extent(seg), e1 = extent(r);
  if (crs_equal && (e1[0] >= e0[2] || e1[2] <= e0[0] || e1[1] >= e0[3] || e1[3] <= e0[1]))
    throw InputError(key + ": '" + path + "': does not overlap the segmentation raster");
  const bool same_grid = crs_equal && r.size == seg.size && r.transform.c == seg.transform.c;
  if (!same_grid && job.inputs.on_grid_mismatch == "error")
    throw InputError(key + ": '" + path + "': is on another grid" + std::string(crs_equal ? "" : " and CRS") +
                     " than the segmentation (inputs.on_grid_mismatch: error)");
}

std::string file_identity(const std::string& path) {
  struct stat st {};
  if (stat(path.c_str(), &st) != 0) return path;
  return path + "|" + std::to_string(st.st_size) + "|" + std::to_string(st.st_mtim.tv_sec) + "." + std::to_string(st.st_mtim.tv_nsec);
}

// The running program's own bytes, hashed, as a line for the checkpoint and run keys: a rerun with
// another build of lodforge, whose outlines may differ, computes every tile again rather than mix
// them with an earlier build's (and merge refuses shards of two builds, their run keys differing).
// Empty where /proc/self/exe cannot be read: the keys are then the inputs' and options' alone.
std::string program_identity() {
  std::ifstream in("/proc/self/exe", std::ios::binary);
  if (!in) return "";
  std::uint64_t h = fnv1a("lodforge");
  std::vector<char> buffer(std::size_t(1) << 16);
  while (in.read(buffer.data(), std::streamsize(buffer.size())) || in.gcount() > 0) h = fnv1a(buffer.data(), std::size_t(in.gcount()), h);
  return "\nprogram " + hex(h);
}

}  // namespace

int run_job(int argc, char** argv) {
  Args args("run", "Processes a whole area as described by a YAML job: tiles, checkpoints, resumable.\n"
                   "usage: lodforge run JOB.yaml [options]   (lodforge config --defaults prints a full job)");
  args.positional("job", "JOB.yaml", "the job file")
      .value("threads", "N", "worker threads, overrides the job's threads (0 = all cores)", false, "j")
      .value("shard", "K/N", "process only the tiles of shard K of N (0 <= K < N); N shards give the single-run outputs")
      .value("set", "KEY=VALUE", "override any job option, e.g. stages.labeling.kappa2=5", true)
      .value("progress", "MODE", "auto (a bar on a terminal, else JSON lines on stderr), bar, json or none (-q: none)");
  args.parse(argc, argv, 2);
  if (args.has("help")) { std::cout << args.help(); return 0; }
  if (!args.has("job")) throw UsageError("give a job file: lodforge run JOB.yaml (lodforge config --defaults prints one)");
  const std::string job_path = *args.get("job");
  std::vector<std::string> overrides = args.all("set");
  if (auto t = args.get("threads")) overrides.push_back("threads=" + *t);
  const Job job = load_job(job_path, overrides);
  const std::string gpkg_time = set_gpkg_timestamp();  // the GeoPackages' last change (the same bytes for the same run)
  const Shard shard = args.get("shard") ? parse_shard(*args.get("shard")) : Shard{};
  const std::string progress_mode = args.has("quiet") ? "none" : args.get("progress").value_or("auto");
  if (progress_mode != "auto" && progress_mode != "bar" && progress_mode != "json" && progress_mode != "none")
    throw UsageError("--progress '" + progress_mode + "': must be one of auto, bar, json, none");

  // Validate the inputs and the output before any work. The segmentation's CRS is read now (its
  // unit must be the metre); rasters on its very grid (the usual case) have theirs read and
  // compared while the first tiles start (InputCrs); on other grids the CRS are needed now.
  RasterInfo seg = inspect_raster(job.inputs.segmentation.path, "inputs.segmentation.path");
  seg.crs_wkt = raster_crs_wkt(job.inputs.segmentation.path, "inputs.segmentation.path");
  {
    const Vec2 centre = seg.transform.to_map(0.5 * seg.size.width, 0.5 * seg.size.height);
    if (const std::string problem = metric_crs_problem(seg.crs_wkt, centre.x(), centre.y()); !problem.empty())
      throw InputError("inputs.segmentation.path: '" + job.inputs.segmentation.path + "': " + problem);
  }
  std::vector<InputCrs::Companion> companions;
  for (const auto& [key, path] : {std::pair{"inputs.dsm.path", job.inputs.dsm.path}, std::pair{"inputs.dtm.path", job.inputs.dtm.path},
                                  std::pair{"inputs.orthophoto.path", job.inputs.orthophoto.path}})
    if (!path.empty()) companions.push_back({key, path});
  std::vector<RasterInfo> companion_grids;
  bool all_on_grid = true;
  for (const auto& c : companions) {
    companion_grids.push_back(inspect_raster(c.path, c.key));
    all_on_grid = all_on_grid && companion_grids.back().size == seg.size && companion_grids.back().transform.c == seg.transform.c;
  }
  std::unique_ptr<InputCrs> input_crs;
  if (all_on_grid) {
    input_crs = std::make_unique<InputCrs>(seg.crs_wkt, companions, job.inputs.on_grid_mismatch == "error", job.output.crs);
  } else {
    for (std::size_t i = 0; i < companions.size(); ++i) {
      companion_grids[i].crs_wkt = raster_crs_wkt(companions[i].path, companions[i].key);
      check_companion(companions[i].key, companions[i].path, companion_grids[i], seg, job);
    }
    input_crs = std::make_unique<InputCrs>(seg.crs_wkt, job.output.crs);
  }
  BuildingSelector selector;
  selector.values = job.inputs.segmentation.building_values;
  if (job.inputs.segmentation.building_rgb.size() == 3)
    selector.rgb = std::array<int, 3>{job.inputs.segmentation.building_rgb[0], job.inputs.segmentation.building_rgb[1],
                                      job.inputs.segmentation.building_rgb[2]};
  if (job.inputs.segmentation.building_min.size() == 1) selector.min = job.inputs.segmentation.building_min[0];
  MaskWindowReader(job.inputs.segmentation.path, selector);  // fails early on a wrong band count
  const fs::path out_dir = job.output.dir;
  std::error_code ec;
  fs::create_directories(out_dir / "tiles", ec);
  if (ec || access(out_dir.c_str(), W_OK) != 0) throw InputError("output.dir '" + out_dir.string() + "': cannot create or write");
  const CheckpointStore store(job.work_dir);
  // One run (or one run per shard) at a time in a work directory.
  const WorkDirLock lock(job.work_dir, "lodforge" + shard_suffix(shard.index, shard.count) + ".lock");
  // Checkpoints half-written by killed runs (10 minutes old, their writer gone) are cleaned.
  if (const int stale = remove_stale_temporaries(job.work_dir, 600))
    spdlog::info("work_dir {}: removed {} temporary file(s) left by killed runs", job.work_dir, stale);
  // A killed run may have left temporary files (named .partial-PID); they never look complete,
  // but go once their writer is gone. Another shard's files in progress stay.
  remove_stale_temporaries(out_dir / "tiles", 0);

  const GridSpec grid_spec{seg.size, seg.transform, seg.crs_wkt};
  const std::string dsm_source = job.inputs.dsm.path.empty() ? "" : aligned_source(job.inputs.dsm.path, grid_spec, (fs::path(job.work_dir) / "dsm.aligned.vrt").string(), true);
  const std::string dtm_source = job.inputs.dtm.path.empty() ? "" : aligned_source(job.inputs.dtm.path, grid_spec, (fs::path(job.work_dir) / "dtm.aligned.vrt").string(), true);
  if (!dsm_source.empty() && dsm_source != job.inputs.dsm.path) spdlog::info("{}: resampled onto the segmentation's grid ({})", job.inputs.dsm.path, dsm_source);
  const std::string ortho_source = job.inputs.orthophoto.path.empty() ? "" : aligned_source(job.inputs.orthophoto.path, grid_spec, (fs::path(job.work_dir) / "orthophoto.aligned.vrt").string(), false);
  if (!dtm_source.empty() && dtm_source != job.inputs.dtm.path) spdlog::info("{}: resampled onto the segmentation's grid ({})", job.inputs.dtm.path, dtm_source);
  const double pixel = seg.transform.pixel_size();
  std::unique_ptr<Cadastre> cadastre;
  if (!job.inputs.footprints.path.empty()) {
    const auto reading = Clock::now();
    cadastre = std::make_unique<Cadastre>(job.inputs.footprints.path, job.inputs.footprints.layer, job.inputs.footprints.id_field,
                                          seg.crs_wkt, seg.transform, seg.size);
    for (const std::string& note : cadastre->notes()) spdlog::warn("inputs.footprints: {}", note);
    spdlog::info("{}: {} footprints on the segmentation raster, read in {:.2f} s", job.inputs.footprints.path, cadastre->footprints().size(),
                 seconds_since(reading));
  }
  // A tile of a few pixels makes a file per tile and format without end, and no building fits it.
  constexpr double kMinTilePixels = 16;
  if (job.tiling.tile_size_m < kMinTilePixels * pixel)
    throw InputError("tiling.tile_size_m: " + std::to_string(job.tiling.tile_size_m) + " m is less than " +
                     std::to_string(int(kMinTilePixels)) + " pixels of " + std::to_string(pixel) + " m of '" +
                     job.inputs.segmentation.path + "'; give at least " + std::to_string(kMinTilePixels * pixel) +
                     " m (tiles of 100-500 m are usual)");
  const TileGrid grid(seg.size, int(std::lround(job.tiling.tile_size_m / pixel)));
  const int halo_px = int(std::ceil(job.tiling.halo_m / pixel));
  const int max_window_px = int(std::ceil(job.tiling.max_window_m / pixel));
  // The window a tile reads its lattice lenders in: its buildings' centres with the lenders'
  // margin around them, within the largest window a tile may read (for a tile of ordinary
  // buildings).
  const LatticeOptions& lattice = job.stages.core.lattice;
  if (job.regularizer == "deformation" && lattice.neighbour_radius_m > 0) {
    if (lattice.neighbour_max_extent_m <= 0) {
      spdlog::warn("stages.lattice.neighbour_max_extent_m: 0 (no limit): a tiled run lends no building its neighbours' lattice "
                   "(`lodforge regularize` lends every building's); give a limit (default 100 m) for the run to lend what "
                   "regularize lends");
    } else {
      const LenderMargins m = lender_margins(seg.transform, lattice);
      const double side = double(grid.tile_px + 2 * halo_px) + 2 * std::max(m.window.x(), m.window.y());
      if (side > max_window_px)
        throw InputError("stages.lattice.neighbour_radius_m + neighbour_max_extent_m: " + std::to_string(lattice.neighbour_radius_m) +
                         " + " + std::to_string(lattice.neighbour_max_extent_m) + " m around a tile of " +
                         std::to_string(job.tiling.tile_size_m) + " m makes windows of " + std::to_string(side * pixel) +
                         " m, more than tiling.max_window_m = " + std::to_string(job.tiling.max_window_m) +
                         " m; give smaller tiles or a smaller neighbour_max_extent_m, or a larger max_window_m");
    }
  }
  std::vector<int> tiles;
  for (int t = 0; t < grid.count(); ++t) if (t % shard.count == shard.index) tiles.push_back(t);
  spdlog::info("{}: {} x {} pixels of {:.3g} m, {} tiles of {} m ({} in this shard {}/{}), {} threads",
               job.inputs.segmentation.path, seg.size.width, seg.size.height, pixel, grid.count(), job.tiling.tile_size_m,
               tiles.size(), shard.index, shard.count, job.threads ? job.threads : tbb::info::default_concurrency());

  std::unique_ptr<tbb::global_control> limit;
  if (job.threads > 0) limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, job.threads);
  // The block budget: three quarters for the decoded blocks the threads share, a quarter for
  // GDAL's own cache (strips read in parts, blocks over 4 MB read in squares; the blocks of a tiled
  // raster are read whole, past GDAL's cache, and never take room there). Set before the survey,
  // whose windows GDAL reads through its own cache.
  const std::size_t cache_bytes = std::size_t(job.tiling.gdal_cache_mb) * 1024 * 1024, shared_bytes = cache_bytes - cache_bytes / 4;
  GDALSetCacheMax64(std::int64_t(cache_bytes - shared_bytes));
  // The boundary noise every building allows for, pooled over a survey of the raster (not per
  // tile: the same for every tiling and shard).
  NoiseSurvey survey;
  const bool surveys_noise = pools_noise(job.regularizer, job.stages.core) && job.tiling.noise_survey_windows > 0;
  const bool surveys_rounding = pools_rounding(job.regularizer, job.stages.core) && job.tiling.noise_survey_windows > 0;
  if (surveys_noise || surveys_rounding) {
    const auto surveying = Clock::now();
    // (At most the raster's side, and the largest window a tile may read.)
    const double window_px = std::min({job.tiling.noise_survey_window_m / pixel, double(std::max(seg.size.width, seg.size.height)),
                                       job.tiling.max_window_m / pixel});
    const MaskWindowReader reader(job.inputs.segmentation.path, selector);
    const int survey_px = std::max(16, int(std::ceil(window_px)));
    if (surveys_noise) {
      // First at twice the pixel (stages.noise.coarse_resolved_px), as regularize measures it.
      bool resolved = false;
      if (tries_coarse_noise(pixel, job.stages.core)) {
        survey = survey_noise(reader, seg.size, seg.transform, job.stages.contour, job.stages.core, survey_px, job.tiling.noise_survey_windows, 2);
        const std::optional<MaskNoise> taken = survey.buildings > 0 ? coarse_noise_taken(survey.noise, pixel, job.stages.core) : std::nullopt;
        resolved = taken.has_value();
        if (resolved) survey.noise = *taken;
        spdlog::info("boundary noise pooled over {} buildings of the mask averaged to twice its pixel: {:.3f} m, {} {} pixels "
                     "(stages.noise.coarse_resolved_px): {}",
                     survey.buildings, survey.noise.floor_m, resolved ? "at least" : "less than", job.stages.core.noise.coarse_resolved_px,
                     resolved ? "the raster's noise" : "surveyed again at the pixel");
      }
      if (!resolved)
        survey = survey_noise(reader, seg.size, seg.transform, job.stages.contour, job.stages.core, survey_px, job.tiling.noise_survey_windows);
      if (survey.buildings == 0)
        spdlog::warn("tiling.noise_survey_windows: no building found whole in the survey's {} window(s) of {} m; each building "
                     "allows for its own boundary noise only (more or larger windows survey more)",
                     survey.windows, job.tiling.noise_survey_window_m);
      else
        spdlog::info("boundary noise pooled over {} buildings in {} window(s) of {} m: {:.3f} m, normals smoothed for {:.3f} m ({:.1f} s)",
                     survey.buildings, survey.windows, job.tiling.noise_survey_window_m, survey.noise.floor_m, survey.noise.smoothing_m,
                     seconds_since(surveying));
    }
    // The corner rounding a building measuring none of its own takes, from the same windows at the
    // raster's pixel, the buildings regularized with that noise (or each with its own, where the
    // noise is not pooled: as regularize does).
    if (surveys_rounding && (!surveys_noise || survey.buildings > 0)) {
      const auto rounding = Clock::now();
      const RoundingSurvey r = survey_rounding(reader, seg.size, seg.transform, job.stages.contour, job.stages.core, survey_px,
                                               job.tiling.noise_survey_windows, survey.noise);
      survey.noise.rounding_m = r.rounding_m;
      spdlog::info("corner rounding pooled over the {} surveyed buildings that measured theirs: {} rounded, {} "
                   "(stages.models.pooled_rounding_share {}) ({:.1f} s)",
                   r.measured, r.rounded,
                   r.rounding_m > 0 ? fmt::format("a radius of {:.2f} m taken by the buildings measuring none", r.rounding_m) : std::string("none taken"),
                   job.stages.core.models.pooled_rounding_share, seconds_since(rounding));
    }
  }

  // Keys: everything an output depends on.
  Job key_job = job;
  key_job.threads = 0;
  key_job.work_dir.clear();
  key_job.output.dir.clear();  // where the files go, not what they hold (a done tile's files are checked where they are)
  key_job.tiling.gdal_cache_mb = 0;  // memory, not results: resuming with another cache size reuses every tile
  // The footprints decide which tile owns a building and how buildings are split: each tile's
  // contour key has those in its window (find_tile_window), the run's key all of them.
  const std::string cadastre_text = cadastre ? "\nfootprints " + hex(cadastre->hash()) : "";
  const std::string program = program_identity();
  const std::string contour_options = options_text(key_job.stages.contour) + (cadastre ? "\nfootprints" : "") + program;
  const std::string heights_options = options_text(key_job.stages.heights) + file_identity(job.inputs.dsm.path) + file_identity(job.inputs.dtm.path) +
                                      (cadastre ? options_text(key_job.stages.footprints) : "") + options_text(key_job.stages.parts) + program;
  // Building ids are first-pixel indices, so the footprints also depend on the raster's width.
  char floor_text[120];
  std::snprintf(floor_text, sizeof floor_text, "\nnoise floor %.17g smoothed for %.17g rounding %.17g", survey.noise.floor_m,
                survey.noise.smoothing_m, survey.noise.rounding_m.value_or(0.0));  // (none surveyed: none, a tile pools none)
  const std::string core_options = job.regularizer + "\n" + options_text(key_job.stages.core) + "\nwidth " + std::to_string(seg.size.width) + floor_text + program;
  const std::uint64_t job_key = fnv1a(gpkg_time + "\n" + file_identity(job.inputs.segmentation.path) + "\n" + file_identity(job.inputs.dsm.path) + "\n" +
                                      file_identity(job.inputs.dtm.path) + "\n" + file_identity(job.inputs.orthophoto.path) + "\n" + options_text(key_job) + cadastre_text + "\n" +
                                      std::to_string(grid.tile_px) + "/" + std::to_string(halo_px) + "/" + std::to_string(max_window_px) + program);
  std::string transform_text;
  for (double c : seg.transform.c) transform_text += std::to_string(c) + ",";
  // The tile indexes an earlier run left list lodforge's own files (which this run may replace).
  // One made from other inputs or options describes a run that is no more: it goes, with its
  // report, so that `merge` cannot take a mix of old and new tiles from an interrupted rerun.
  const std::string run_key = hex(job_key);
  std::set<std::string> indexed_outputs;
  for (const std::string& suffix : std::set<std::string>{"", shard_suffix(shard.index, shard.count)}) {
    const fs::path index_path = out_dir / ("tile_index" + suffix + ".geojson");
    const std::optional<TileIndex> index = read_tile_index(index_path);
    if (!index) continue;
    for (const auto& output : index->outputs) indexed_outputs.insert(output.first);
    if (index->run_key == run_key) continue;
    fs::remove(out_dir / ("report" + suffix + ".json"), ec);  // the report first: once the index is gone, both are
    fs::remove(index_path, ec);
    spdlog::info("{}: from a run with other inputs, options or build of lodforge; removed with its report (this run writes new ones)", index_path.string());
  }
  // Nothing that is not lodforge's is replaced: a file at a tile's output name that no index or
  // done marker lists is the user's, and stops the run before any work.
  {
    std::vector<std::string> extensions;
    for (const std::string& format : job.output.formats) extensions.push_back(extension_of(format));
    extensions.push_back(".png");
    for (int t : tiles) {
      std::optional<std::set<std::string>> own;  // the tile's files lodforge wrote, read when needed
      for (const std::string& extension : extensions) {
        const std::string relative = "tiles/" + grid.name(t) + extension;
        const fs::path file = out_dir / relative;
        if (!fs::exists(fs::symlink_status(file, ec))) continue;
        if (!fs::is_regular_file(fs::symlink_status(file, ec)))
          throw InputError("output.dir: '" + file.string() + "' is in the way of a tile's output and is not a regular file; move it away");
        if (!own) own = replaceable_files(store, &indexed_outputs, grid.name(t));
        if (!own->count(relative))
          throw InputError("output.dir: '" + file.string() + "' exists and lodforge did not write it (no tile index or work_dir " +
                           "lists it); move it away or give another output.dir");
      }
    }
  }

  ReaderPool readers(shared_bytes);  // declared before the plan that points to it; closed after the pipeline
  // Tiles are processed in bands of columns, row by row within a band, so that a tile finds the
  // blocks it shares with its upper neighbour still in the block cache (in raster order they
  // were decoded a whole raster width earlier and are gone). A band's tile windows, a row of them,
  // take about 16 KB of decoded blocks per pixel column (three rasters, 250 m tiles at 0.25 m):
  // 3 tiles of 1,000 pixels at the default cache. The files list the tiles in tile order all the same.
  const int band_cols = std::max(1, int(shared_bytes / 16384) / grid.tile_px);
  std::stable_sort(tiles.begin(), tiles.end(), [&](int a, int b) {
    return std::make_tuple(a % grid.cols / band_cols, a / grid.cols, a % grid.cols) <
           std::make_tuple(b % grid.cols / band_cols, b / grid.cols, b % grid.cols);
  });
  const RunPlan plan{job, seg.size, seg.transform, *input_crs, pixel, grid, halo_px, max_window_px, selector,
                     dsm_source, dtm_source, ortho_source, store, contour_options, core_options, heights_options,
                     transform_text, job_key, out_dir, &readers, &indexed_outputs, cadastre.get(), survey.noise};

  // At most `tokens` tiles in flight: one per thread and one more, so that a thread finds the next
  // tile while the oldest waits to be recorded in order (each in flight holds its windows: more
  // only adds memory, measured in docs/performance.md).
  const std::size_t tokens = std::size_t(job.threads ? job.threads : tbb::info::default_concurrency()) + 1;
  // The blocks a tile shares with the tiles still to read (those in flight, and a band's row
  // beyond them) stay cached; the others are freed as each tile finishes its reads.
  std::vector<cv::Rect> read_areas;
  for (int t : tiles) read_areas.push_back(tile_read_area(plan, t));
  readers.plan_reads(tiles, read_areas, std::size_t(band_cols) + tokens);

  Totals totals;
  Progress progress(tiles.size(), progress_mode == "none" ? Progress::Mode::none
                                  : progress_mode == "bar" || (progress_mode == "auto" && isatty(STDERR_FILENO)) ? Progress::Mode::bar
                                                                                                                  : Progress::Mode::json);
  std::size_t next = 0, tiles_done = 0;
  bool crs_queued = false;  // the inputs' CRS are read as the pipeline's first item (-1), beside the first tile
  const auto start = Clock::now();
  // Serial source; parallel tiles, each writing its own files; serial in-order bookkeeping (the
  // index and report are sorted into tile order when written).
  using Done = std::pair<std::shared_ptr<TileResult>, TileOutputs>;  // the tile and its files
  tbb::parallel_pipeline(
      tokens,
      tbb::make_filter<void, int>(tbb::filter_mode::serial_in_order,
                                  [&](tbb::flow_control& fc) -> int {
                                    if (!crs_queued) { crs_queued = true; return -1; }
                                    if (next >= tiles.size()) { fc.stop(); return 0; }
                                    return tiles[next++];
                                  }) &
          tbb::make_filter<int, Done>(tbb::filter_mode::parallel,
                                      [&](int tile) {
                                        if (tile < 0) { plan.crs.wkt(); return Done{}; }
                                        std::shared_ptr<TileResult> r = process_tile(plan, tile);
                                        TileOutputs files = write_tile_outputs(plan, *r);
                                        r->quicklook_background.release();  // written; not kept while queued
                                        return Done{std::move(r), std::move(files)};
                                      }) &
          tbb::make_filter<Done, void>(tbb::filter_mode::serial_in_order, [&](const Done& done) {
            if (!done.first) return;
            record_tile(totals, plan, *done.first, done.second);
            progress.update(++tiles_done, totals.buildings);
          }));
  progress.finish();
  totals.blocks_decoded = readers.blocks_decoded();
  write_index_and_report(totals, plan, job_path, shard.index, shard.count, tiles.size(), seconds_since(start));
  return 0;
}

int run_config(int argc, char** argv) {
  Args args("config", "Prints the full default job with every option, its default and its meaning.");
  args.flag("defaults", "print the default job").flag("help", "show this help");
  args.parse(argc, argv, 2);
  if (args.has("help") || !args.has("defaults")) { std::cout << args.help(); return args.has("help") ? 0 : 2; }
  std::cout << default_job_yaml();
  return 0;
}

}  // namespace lodforge
