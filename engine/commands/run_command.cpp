// lodforge run JOB.yaml: the tiled batch engine.
#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <gdal_priv.h>
#include <opencv2/imgproc.hpp>
#include <iostream>
#include <map>
#include <mutex>
#include <ogr_spatialref.h>
#include <spdlog/spdlog.h>
#include <sstream>
#include <sys/stat.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_pipeline.h>
#include <unistd.h>

#include "cli/args.hpp"
#include "commands/commands.hpp"
#include "common/option_visitors.hpp"
#include "geometry/polygon.hpp"
#include "io/errors.hpp"
#include "io/footprint_writer.hpp"
#include "io/height_reader.hpp"
#include "io/model_writers.hpp"
#include "io/quicklook.hpp"
#include "lod1/solid.hpp"
#include "io/raster.hpp"
#include "job/job.hpp"
#include "pipeline/building.hpp"
#include "run/checkpoint.hpp"
#include "run/progress.hpp"
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
  try {
    if (slash == std::string::npos) throw std::invalid_argument(text);
    s.index = std::stoi(text.substr(0, slash));
    s.count = std::stoi(text.substr(slash + 1));
  } catch (const std::exception&) {
    throw InputError("lodforge run: --shard '" + text + "': expected K/N, e.g. 0/4");
  }
  if (s.count < 1 || s.index < 0 || s.index >= s.count)
    throw InputError("lodforge run: --shard '" + text + "': needs 0 <= K < N");
  return s;
}

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
  std::string crs_wkt;
};

RasterInfo inspect_raster(const std::string& path, const std::string& key) {
  GDALAllRegister();
  CPLPushErrorHandler(CPLQuietErrorHandler);
  GDALDataset* d = static_cast<GDALDataset*>(GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
  CPLPopErrorHandler();
  if (!d) throw InputError(key + ": '" + path + "': not a raster GDAL can read");
  RasterInfo info;
  info.size = {d->GetRasterXSize(), d->GetRasterYSize()};
  const bool georeferenced = d->GetGeoTransform(info.transform.c.data()) == CE_None;
  if (const OGRSpatialReference* srs = d->GetSpatialRef()) {
    char* wkt = nullptr;
    srs->exportToWkt(&wkt);
    info.crs_wkt = wkt ? wkt : "";
    CPLFree(wkt);
  }
  GDALClose(d);
  if (!georeferenced) throw InputError(key + ": '" + path + "': has no georeference (no geotransform)");
  return info;
}

// Checks the optional rasters against the segmentation: georeferenced, same CRS, overlapping.
void check_companion(const std::string& key, const std::string& path, const RasterInfo& seg, const Job& job) {
  if (path.empty()) return;
  const RasterInfo r = inspect_raster(path, key);
  OGRSpatialReference a, b;
  const bool same_crs = seg.crs_wkt.empty() || r.crs_wkt.empty() ||
                        (a.importFromWkt(seg.crs_wkt.c_str()) == OGRERR_NONE && b.importFromWkt(r.crs_wkt.c_str()) == OGRERR_NONE &&
                         a.IsSame(&b));
  auto extent = [](const RasterInfo& i) {
    const Vec2 p0 = i.transform.to_map(0, 0), p1 = i.transform.to_map(i.size.width, i.size.height);
    return std::array<double, 4>{std::min(p0.x(), p1.x()), std::min(p0.y(), p1.y()), std::max(p0.x(), p1.x()), std::max(p0.y(), p1.y())};
  };
  const auto e0 = extent(seg), e1 = extent(r);
  if (same_crs && (e1[0] >= e0[2] || e1[2] <= e0[0] || e1[1] >= e0[3] || e1[3] <= e0[1]))
    throw InputError(key + ": '" + path + "': does not overlap the segmentation raster");
  const bool same_grid = same_crs && r.size == seg.size && r.transform.c == seg.transform.c;
  if (!same_grid && job.inputs.on_grid_mismatch == "error")
    throw InputError(key + ": '" + path + "': is on another grid" + std::string(same_crs ? "" : " and CRS") +
                     " than the segmentation (inputs.on_grid_mismatch: error)");
}

std::string file_identity(const std::string& path) {
  struct stat st {};
  if (stat(path.c_str(), &st) != 0) return path;
  return path + "|" + std::to_string(st.st_size) + "|" + std::to_string(st.st_mtim.tv_sec) + "." + std::to_string(st.st_mtim.tv_nsec);
}

struct TileResult {
  int tile = 0;
  std::string name;
  bool skipped = false;  // complete from an earlier run
  bool contours_reused = false, buildings_reused = false;  // stage checkpoints found
  std::vector<BuildingOutput> buildings;
  std::vector<Heights> heights;  // per building, when a DSM is given
  int dropped_small = 0;
  std::vector<std::string> too_large;
  std::string summary;  // kept in the done marker, replayed on resume
  cv::Mat quicklook_background;  // the tile's picture, when output.quicklook
  double seconds = 0;
};

std::vector<BuildingOutput> regularize_tile(const TileBuildings& tile, const Job& job, long raster_width, double pixel_size) {
  std::vector<BuildingOutput> out(tile.buildings.size());
  tbb::parallel_for(std::size_t(0), tile.buildings.size(), [&](std::size_t i) {
    const BuildingContour& b = tile.buildings[i];
    BuildingOutput& o = out[i];
    o.id = std::int64_t(b.first_row) * raster_width + b.first_col;
    o.first_row = b.first_row;
    o.first_col = b.first_col;
    if (job.regularizer == "deformation") {
      BuildingResult r = regularize_building(b.rings, pixel_size, job.stages.core);
      o.footprint = std::move(r.footprint);
      o.ok = r.ok;
      o.stage = r.failed_stage;
      o.reason = r.reason;
    } else if (job.regularizer == "douglas_peucker") {
      o.footprint = fallback_footprint(b.rings, job.stages.core.fallback.tolerance_m);
    } else {
      o.footprint = fallback_footprint(b.rings, 0.0);
    }
  });
  return out;
}

std::string make_summary(const TileResult& r) {
  int ok = 0, lod1 = 0;
  for (const BuildingOutput& b : r.buildings) ok += b.ok;
  for (const Heights& h : r.heights) lod1 += h.ok;
  std::ostringstream s;
  s << r.buildings.size() << ' ' << ok << ' ' << r.buildings.size() - ok << ' ' << r.dropped_small << ' ' << lod1 << '\n';
  for (const BuildingOutput& b : r.buildings)
    if (!b.ok) s << "failed\t" << b.id << '\t' << b.stage << '\t' << b.reason << '\n';
  for (std::size_t i = 0; i < r.heights.size(); ++i)
    if (!r.heights[i].ok) s << "failed\t" << r.buildings[i].id << "\theights\t" << r.heights[i].reason << " (LOD0 only)\n";
  for (const std::string& t : r.too_large) s << "too_large\t" << t << '\n';
  return s.str();
}

std::string serialize_heights(const std::vector<Heights>& heights) {
  std::ostringstream s;
  s.precision(17);
  for (const Heights& h : heights) s << h.ok << '\t' << h.roof << '\t' << h.ground << '\t' << h.roof_samples << '\t' << h.ground_samples << '\t' << h.reason << '\n';
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
    f >> h.roof >> h.ground >> h.roof_samples >> h.ground_samples;
    f.get();
    std::getline(f, h.reason);
    h.ok = ok == "1";
    out.push_back(h);
  }
  if (out.size() != count) return std::nullopt;
  return out;
}

BuildingModel model_of(const BuildingOutput& b, const Heights* h, const std::string& tile, const Job& job) {
  BuildingModel m;
  m.id = b.id;
  m.tile = tile;
  m.footprint = b.footprint;
  m.regularizer = b.ok ? job.regularizer : "douglas_peucker";
  m.stage = b.stage;
  m.reason = b.reason;
  if (h && h->ok) {
    m.solid = extrude(b.footprint, h->ground, h->roof);
    if (const std::string problem = shell_problem(m.solid); problem.empty()) {
      m.has_lod1 = true;
      m.ground = h->ground;
      m.roof = h->roof;
    } else {
      m.reason += (m.reason.empty() ? "" : "; ") + std::string("lod1: invalid shell: ") + problem;
    }
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

struct Totals {
  std::size_t buildings = 0, ok = 0, fallback = 0, dropped_small = 0, tiles_processed = 0, tiles_skipped = 0, tiles_empty = 0;
  std::size_t contours_reused = 0, buildings_reused = 0, lod1 = 0;
  std::vector<std::string> failed_json, too_large, tile_json, index_features;
};

void account(const std::string& summary, const std::string& tile, Totals& t, std::size_t& buildings_in_tile) {
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
      t.failed_json.push_back("{\"id\": " + a + ", \"tile\": \"" + tile + "\", \"stage\": \"" + json_escape(b) +
                              "\", \"reason\": \"" + json_escape(c) + "\"}");
    } else if (kind == "too_large") {
      std::getline(fields, a);
      t.too_large.push_back(a);
    }
  }
}

void write_text_atomically(const fs::path& path, const std::string& text) {
  const fs::path temp = path.string() + ".partial";
  {
    std::ofstream out(temp, std::ios::trunc);
    out << text;
    if (!out.flush()) throw InputError("'" + path.string() + "': cannot write (disk full or not writable?)");
  }
  fs::rename(temp, path);
}

}  // namespace

int run_job(int argc, char** argv) {
  Args args("run", "Processes a whole area as described by a YAML job: tiles, checkpoints, resumable.\n"
                   "usage: lodforge run JOB.yaml [options]   (lodforge config --defaults prints a full job)");
  args.value("threads", "N", "worker threads, overrides the job's threads (0 = all cores)")
      .value("shard", "K/N", "process only the tiles of shard K of N (0 <= K < N); N shards give the single-run outputs")
      .value("set", "KEY=VALUE", "override any job option, e.g. stages.labeling.kappa2=5", true)
      .flag("help", "show this help");
  if (argc < 3 || std::string(argv[2]).rfind("--", 0) == 0) {
    if (argc >= 3 && std::string(argv[2]) == "--help") { std::cout << args.help(); return 0; }
    throw InputError("lodforge run: give a job file: lodforge run JOB.yaml (see lodforge config --defaults)");
  }
  const std::string job_path = argv[2];
  args.parse(argc, argv, 3);
  if (args.has("help")) { std::cout << args.help(); return 0; }
  std::vector<std::string> overrides = args.all("set");
  if (auto t = args.get("threads")) overrides.push_back("threads=" + *t);
  const Job job = load_job(job_path, overrides);
  const Shard shard = args.get("shard") ? parse_shard(*args.get("shard")) : Shard{};

  // Validate the inputs and the output before any work.
  const RasterInfo seg = inspect_raster(job.inputs.segmentation.path, "inputs.segmentation.path");
  check_companion("inputs.dsm.path", job.inputs.dsm.path, seg, job);
  check_companion("inputs.dtm.path", job.inputs.dtm.path, seg, job);
  check_companion("inputs.orthophoto.path", job.inputs.orthophoto.path, seg, job);
  BuildingSelector selector;
  selector.values = job.inputs.segmentation.building_values;
  if (job.inputs.segmentation.building_rgb.size() == 3)
    selector.rgb = std::array<int, 3>{job.inputs.segmentation.building_rgb[0], job.inputs.segmentation.building_rgb[1],
                                      job.inputs.segmentation.building_rgb[2]};
  MaskWindowReader(job.inputs.segmentation.path, selector);  // fails early on a wrong band count
  const fs::path out_dir = job.output.dir;
  std::error_code ec;
  fs::create_directories(out_dir / "tiles", ec);
  if (ec || access(out_dir.c_str(), W_OK) != 0) throw InputError("output.dir '" + out_dir.string() + "': cannot create or write");
  const CheckpointStore store(job.work_dir);
  // A killed run may have left temporary files; they never look complete, but go anyway.
  for (const auto& entry : fs::directory_iterator(out_dir / "tiles"))
    if (entry.path().filename().string().find(".partial") != std::string::npos) fs::remove(entry.path(), ec);

  const GridSpec grid_spec{seg.size, seg.transform, seg.crs_wkt};
  const std::string dsm_source = job.inputs.dsm.path.empty() ? "" : aligned_source(job.inputs.dsm.path, grid_spec, (fs::path(job.work_dir) / "dsm.aligned.vrt").string());
  const std::string dtm_source = job.inputs.dtm.path.empty() ? "" : aligned_source(job.inputs.dtm.path, grid_spec, (fs::path(job.work_dir) / "dtm.aligned.vrt").string());
  if (!dsm_source.empty() && dsm_source != job.inputs.dsm.path) spdlog::info("{}: resampled onto the segmentation's grid ({})", job.inputs.dsm.path, dsm_source);
  const std::string ortho_source = job.inputs.orthophoto.path.empty() ? "" : aligned_source(job.inputs.orthophoto.path, grid_spec, (fs::path(job.work_dir) / "orthophoto.aligned.vrt").string());
  if (!dtm_source.empty() && dtm_source != job.inputs.dtm.path) spdlog::info("{}: resampled onto the segmentation's grid ({})", job.inputs.dtm.path, dtm_source);
  const double pixel = seg.transform.pixel_size();
  const TileGrid grid(seg.size, int(std::lround(job.tiling.tile_size_m / pixel)));
  const int halo_px = int(std::ceil(job.tiling.halo_m / pixel));
  const int max_window_px = int(std::ceil(job.tiling.max_window_m / pixel));
  std::vector<int> tiles;
  for (int t = 0; t < grid.count(); ++t) if (t % shard.count == shard.index) tiles.push_back(t);
  spdlog::info("{}: {} x {} pixels of {:.3g} m, {} tiles of {} m ({} in this shard {}/{}), {} threads",
               job.inputs.segmentation.path, seg.size.width, seg.size.height, pixel, grid.count(), job.tiling.tile_size_m,
               tiles.size(), shard.index, shard.count, job.threads ? job.threads : int(std::thread::hardware_concurrency()));

  // Keys: everything an output depends on.
  Job key_job = job;
  key_job.threads = 0;
  key_job.work_dir.clear();
  const std::string contour_options = options_text(key_job.stages.contour);
  const std::string heights_options = options_text(key_job.stages.heights) + file_identity(job.inputs.dsm.path) + file_identity(job.inputs.dtm.path);
  const std::string core_options = job.regularizer + "\n" + options_text(key_job.stages.core);
  const std::uint64_t job_key = fnv1a(file_identity(job.inputs.segmentation.path) + "\n" + file_identity(job.inputs.dsm.path) + "\n" +
                                      file_identity(job.inputs.dtm.path) + "\n" + options_text(key_job) + "\n" +
                                      std::to_string(grid.tile_px) + "/" + std::to_string(halo_px) + "/" + std::to_string(max_window_px));
  std::string transform_text;
  for (double c : seg.transform.c) transform_text += std::to_string(c) + ",";

  CPLSetConfigOption("OGR_CURRENT_DATE", "2000-01-01T00:00:00.000Z");  // byte-identical GeoPackages
  GDALSetCacheMax64(std::int64_t(job.tiling.gdal_cache_mb) * 1024 * 1024);
  FootprintLayer layer;
  layer.crs_wkt = seg.crs_wkt;

  std::unique_ptr<tbb::global_control> limit;
  if (job.threads > 0) limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, job.threads);
  Totals totals;
  Progress progress(tiles.size(), isatty(STDERR_FILENO));
  std::size_t next = 0, tiles_done = 0;
  const auto start = Clock::now();
  const long width = seg.size.width;
  const std::size_t tokens = std::max<std::size_t>(2, 2 * std::size_t(job.threads ? job.threads : std::thread::hardware_concurrency()));
  tbb::parallel_pipeline(
      tokens,
      tbb::make_filter<void, int>(tbb::filter_mode::serial_in_order,
                                  [&](tbb::flow_control& fc) -> int {
                                    if (next >= tiles.size()) { fc.stop(); return 0; }
                                    return tiles[next++];
                                  }) &
          tbb::make_filter<int, std::shared_ptr<TileResult>>(
              tbb::filter_mode::parallel,
              [&](int tile) {
                auto r = std::make_shared<TileResult>();
                const auto t0 = Clock::now();
                r->tile = tile;
                r->name = grid.name(tile);
                const std::uint64_t done_key = fnv1a(r->name, job_key);
                if (auto summary = store.done_summary(r->name, done_key)) {
                  r->skipped = true;
                  r->summary = *summary;
                  return r;
                }
                const MaskWindowReader reader(job.inputs.segmentation.path, selector);
                const TileWindow window = find_tile_window(reader, grid, tile, halo_px, max_window_px, job.stages.contour.connectivity);
                const std::uint64_t contour_key = fnv1a(contour_options + transform_text + std::to_string(grid.tile_px), window.hash);
                std::optional<TileBuildings> contours = store.load_contours(r->name, contour_key);
                r->contours_reused = contours.has_value();
                if (!contours) {
                  contours = trace_tile(window, grid, tile, seg.transform, job.stages.contour);
                  store.save_contours(r->name, contour_key, *contours);
                }
                const std::uint64_t buildings_key = fnv1a(core_options, contour_key);
                std::optional<std::vector<BuildingOutput>> buildings = store.load_buildings(r->name, buildings_key);
                r->buildings_reused = buildings.has_value();
                if (!buildings) {
                  buildings = regularize_tile(*contours, job, width, pixel);
                  store.save_buildings(r->name, buildings_key, *buildings);
                }
                r->buildings = std::move(*buildings);
                if (!dsm_source.empty()) {
                  const std::uint64_t heights_key = fnv1a(heights_options, buildings_key);
                  std::optional<std::vector<Heights>> heights;
                  if (auto blob = store.load_blob("heights", r->name, heights_key)) heights = parse_heights(*blob, r->buildings.size());
                  if (!heights) {
                    const int margin = int(std::ceil((job.stages.heights.ring_outer_m + job.stages.core.corners.max_corner_shift_m) / pixel)) + 2;
                    const cv::Rect area = (contours->window + cv::Size(2 * margin, 2 * margin) - cv::Point(margin, margin)) &
                                          cv::Rect(0, 0, seg.size.width, seg.size.height);
                    const HeightRaster dsm = HeightWindowReader(dsm_source).read(area, seg.transform);
                    std::optional<HeightRaster> dtm;
                    if (!dtm_source.empty()) dtm = HeightWindowReader(dtm_source).read(area, seg.transform);
                    heights.emplace(r->buildings.size());
                    tbb::parallel_for(std::size_t(0), r->buildings.size(), [&](std::size_t i) {
                      (*heights)[i] = building_heights(r->buildings[i].footprint, dsm, dtm ? &*dtm : nullptr, job.stages.heights);
                    });
                    store.save_blob("heights", r->name, heights_key, serialize_heights(*heights));
                  }
                  r->heights = std::move(*heights);
                }
                if (job.output.quicklook && !r->buildings.empty()) {
                  const cv::Rect tile_rect = grid.rect(tile);
                  if (!job.inputs.orthophoto.path.empty()) {
                    r->quicklook_background = read_orthophoto(ortho_source, tile_rect);
                  } else if (!dsm_source.empty()) {
                    const HeightRaster dsm = HeightWindowReader(dsm_source).read(tile_rect, seg.transform);
                    r->quicklook_background = hillshade(dsm.values, dsm.valid, pixel);
                  } else {
                    cv::Mat grey = MaskWindowReader(job.inputs.segmentation.path, selector).read(tile_rect) * 120 + 40;
                    cv::cvtColor(grey, r->quicklook_background, cv::COLOR_GRAY2BGR);
                  }
                }
                r->dropped_small = contours->dropped_small;
                r->too_large = contours->too_large;
                r->summary = make_summary(*r);
                r->seconds = seconds_since(t0);
                return r;
              }) &
          tbb::make_filter<std::shared_ptr<TileResult>, void>(
              tbb::filter_mode::serial_in_order, [&](std::shared_ptr<TileResult> r) {
                std::vector<std::string> outputs;
                const cv::Rect tile_rect = grid.rect(r->tile);
                WriterContext context{seg.crs_wkt, r->name, seg.transform.to_map(tile_rect.x, tile_rect.y + tile_rect.height)};
                if (!r->buildings.empty() || r->skipped) {
                  for (const std::string& format : job.output.formats) {
                    const std::string relative = "tiles/" + r->name + extension_of(format);
                    if (!r->skipped) {
                      const auto writer = make_model_writer(format, (out_dir / relative).string(), context);
                      for (std::size_t i = 0; i < r->buildings.size(); ++i)
                        writer->add(model_of(r->buildings[i], r->heights.empty() ? nullptr : &r->heights[i], r->name, job));
                      writer->finish();
                    }
                    if (fs::exists(out_dir / relative)) outputs.push_back(relative);
                  }
                }
                if (!r->skipped && !r->quicklook_background.empty()) {
                  std::vector<QuicklookOutline> outlines;
                  for (const BuildingOutput& b : r->buildings) outlines.push_back({b.footprint, b.ok});
                  GeoTransform t = seg.transform;
                  t.c[0] = seg.transform.to_map(tile_rect.x, tile_rect.y).x();
                  t.c[3] = seg.transform.to_map(tile_rect.x, tile_rect.y).y();
                  write_quicklook((out_dir / ("tiles/" + r->name + ".png")).string(), r->quicklook_background, t, outlines);
                }
                if (fs::exists(out_dir / ("tiles/" + r->name + ".png"))) outputs.push_back("tiles/" + r->name + ".png");
                if (!r->skipped) store.mark_done(r->name, fnv1a(r->name, job_key), r->summary);
                std::size_t count = 0;
                account(r->summary, r->name, totals, count);
                (r->skipped ? totals.tiles_skipped : totals.tiles_processed)++;
                totals.contours_reused += r->contours_reused;
                totals.buildings_reused += r->buildings_reused;
                if (count == 0) totals.tiles_empty++;
                const cv::Rect rect = grid.rect(r->tile);
                const Vec2 a = seg.transform.to_map(rect.x, rect.y), b = seg.transform.to_map(rect.x + rect.width, rect.y + rect.height);
                std::ostringstream feature;
                feature.precision(12);
                feature << "{\"type\": \"Feature\", \"properties\": {\"tile\": \"" << r->name << "\", \"col\": " << r->tile % grid.cols
                        << ", \"row\": " << r->tile / grid.cols << ", \"status\": \"" << (count ? "done" : "empty")
                        << "\", \"buildings\": " << count << ", \"outputs\": [";
                for (std::size_t i = 0; i < outputs.size(); ++i) feature << (i ? ", " : "") << '"' << outputs[i] << '"';
                feature << "]}, \"geometry\": {\"type\": \"Polygon\", \"coordinates\": [[[" << a.x() << ", " << a.y() << "], [" << b.x()
                        << ", " << a.y() << "], [" << b.x() << ", " << b.y() << "], [" << a.x() << ", " << b.y() << "], [" << a.x()
                        << ", " << a.y() << "]]]}}";
                totals.index_features.push_back(feature.str());
                std::ostringstream tile_json;
                tile_json << "{\"tile\": \"" << r->name << "\", \"buildings\": " << count << ", \"skipped\": " << (r->skipped ? "true" : "false")
                          << ", \"seconds\": " << r->seconds << "}";
                totals.tile_json.push_back(tile_json.str());
                progress.update(++tiles_done, totals.buildings);
              }));
  progress.finish();

  // The tile index and the run report (one per shard when sharded).
  const std::string suffix = shard.count > 1 ? ".shard-" + std::to_string(shard.index) + "-of-" + std::to_string(shard.count) : "";
  std::ostringstream index;
  index << "{\"type\": \"FeatureCollection\", \"name\": \"tile_index\"";
  if (const std::string crs = epsg_of(seg.crs_wkt); !crs.empty())
    index << ", \"crs\": {\"type\": \"name\", \"properties\": {\"name\": \"urn:ogc:def:crs:" << crs.substr(0, crs.find(':')) << "::" << crs.substr(crs.find(':') + 1) << "\"}}";
  index << ", \"features\": [\n";
  for (std::size_t i = 0; i < totals.index_features.size(); ++i) index << totals.index_features[i] << (i + 1 < totals.index_features.size() ? ",\n" : "\n");
  index << "]}\n";
  write_text_atomically(out_dir / ("tile_index" + suffix + ".geojson"), index.str());
  const double elapsed = seconds_since(start);
  std::ostringstream report;
  report << "{\n  \"job\": \"" << json_escape(fs::absolute(job_path).string()) << "\",\n  \"shard\": \"" << shard.index << "/" << shard.count
         << "\",\n  \"tiles\": " << tiles.size() << ", \"tiles_processed\": " << totals.tiles_processed << ", \"tiles_resumed\": "
         << totals.tiles_skipped << ", \"tiles_empty\": " << totals.tiles_empty << ",\n  \"checkpoints_reused\": {\"contours\": " << totals.contours_reused << ", \"buildings\": " << totals.buildings_reused << "},\n  \"buildings\": " << totals.buildings
         << ", \"ok\": " << totals.ok << ", \"fallback\": " << totals.fallback << ", \"lod1\": " << totals.lod1 << ", \"dropped_small\": " << totals.dropped_small
         << ", \"too_large\": " << totals.too_large.size() << ",\n  \"seconds\": " << elapsed << ",\n  \"failed_buildings\": [";
  for (std::size_t i = 0; i < totals.failed_json.size(); ++i) report << (i ? ",\n    " : "\n    ") << totals.failed_json[i];
  report << "],\n  \"too_large_buildings\": [";
  for (std::size_t i = 0; i < totals.too_large.size(); ++i) report << (i ? ", " : "") << '"' << json_escape(totals.too_large[i]) << '"';
  report << "],\n  \"per_tile\": [";
  for (std::size_t i = 0; i < totals.tile_json.size(); ++i) report << (i ? ",\n    " : "\n    ") << totals.tile_json[i];
  report << "]\n}\n";
  write_text_atomically(out_dir / ("report" + suffix + ".json"), report.str());
  spdlog::info("{} tiles ({} computed, {} resumed from {}), {} buildings: {} ok, {} fallback, {} with LOD1; {} small components dropped{}; {:.1f} s",
               tiles.size(), totals.tiles_processed, totals.tiles_skipped, job.work_dir, totals.buildings, totals.ok, totals.fallback, totals.lod1,
               totals.dropped_small, totals.too_large.empty() ? "" : "; " + std::to_string(totals.too_large.size()) + " too large (see report)",
               elapsed);
  spdlog::info("outputs in {} (tile_index{}.geojson, report{}.json)", out_dir.string(), suffix, suffix);
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
