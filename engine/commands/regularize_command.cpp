// lodforge regularize: the per-building core on one segmentation raster, LOD0 polygons out.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <atomic>
#include <chrono>
#include <optional>
#include <sstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>
#include <tbb/global_control.h>

#include "cli/args.hpp"
#include "commands/commands.hpp"
#include "commands/stage_options.hpp"
#include "io/atomic_file.hpp"
#include "io/errors.hpp"
#include "io/footprint_writer.hpp"
#include "io/raster.hpp"
#include "pipeline/building.hpp"
#include "run/batch.hpp"

namespace lodforge {

namespace {

BuildingSelector parse_selector(const Args& args) {
  BuildingSelector selector;
  if (int(args.has("building-rgb")) + int(args.has("building-value")) + int(args.has("building-min")) > 1)
    throw InputError("give one of --building-value, --building-rgb and --building-min, not several");
  auto numbers = [](const std::string& text, const std::string& flag) {
    std::vector<int> out;
    std::size_t start = 0;
    while (start <= text.size()) {
      const std::size_t comma = text.find(',', start);
      const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
      try {
        std::size_t used = 0;
        out.push_back(std::stoi(item, &used));
        if (used != item.size()) throw std::invalid_argument(item);
      } catch (const std::exception&) {
        throw InputError("" + flag + " '" + text + "': not a comma-separated list of integers");
      }
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
    return out;
  };
  if (auto rgb = args.get("building-rgb")) {
    const auto v = numbers(*rgb, "--building-rgb");
    if (v.size() != 3) throw InputError("--building-rgb '" + *rgb + "': needs three values R,G,B");
    selector.rgb = std::array<int, 3>{v[0], v[1], v[2]};
  } else if (auto values = args.get("building-value")) {
    selector.values = numbers(*values, "--building-value");
  } else if (auto min = args.get("building-min")) {
    try {
      std::size_t used = 0;
      selector.min = std::stod(*min, &used);
      if (used != min->size() || !std::isfinite(*selector.min)) throw std::invalid_argument(*min);
    } catch (const std::exception&) {
      throw InputError("--building-min '" + *min + "': not a number");
    }
  }
  return selector;
}

// "deformation, cgal, ..." for the help and the errors.
std::string regularizer_list() {
  std::string list;
  for (const std::string& n : regularizer_names()) list += (list.empty() ? "" : ", ") + n;
  return list;
}

}  // namespace

int run_regularize(int argc, char** argv) {
  Args args("regularize", "Extracts every building of a segmentation raster and writes its regularized LOD0 footprint\n"
                          "(with holes) and its status to a GeoPackage.");
  args.value("mask", "RASTER", "segmentation raster (any GDAL format), georeferenced")
      .value("building-value", "V[,V...]", "class value(s) of buildings in a one-band raster (default 6)")
      .value("building-rgb", "R,G,B", "building colour in an RGB raster, e.g. 0,0,255 (ISPRS)")
      .value("building-min", "V", "buildings are the pixels of a one-band raster whose value is at least V: a network's probability or score, e.g. 0.5 (never its nodata value)")
      .value("out", "FILE", "output footprints (.gpkg or .geojson): id, status, stage, reason, regularizer, model (the outline the paper's chain chose: docs/models.md), vertex_count, area_m2")
      .value("route", "NAME", "corner route: 'original' (lines fitted to the raw contour) or 'deformed' (the paper)")
      .value("regularizer", "NAME", "one of " + regularizer_list() + " (default: deformation, the paper's chain; see lodforge options)")
      .value("stats", "FILE", "also write a JSON summary: counts by status (for the paper's chain, also by the outline model chosen) and the regularization time per building (mean, median, p99; also by contour size), and for the paper's chain where it goes: each stage's mean a building (chain_seconds_mean: start, labeling, outline, other)")
      .value("threads", "N", "worker threads (default: all cores)", false, "j")
      .value("set", "KEY=VALUE", "set any stage option as in a job, e.g. stages.labeling.kappa2=5 (see lodforge options)", true);
  args.parse(argc, argv, 2);
  if (args.has("help")) { std::cout << args.help(); return 0; }
  set_gpkg_timestamp();  // (the same mask and options, the same bytes)
  const std::string mask_path = args.require("mask");
  const std::string out_path = args.require("out");
  StageOptions options;
  std::vector<std::string> assignments = args.all("set");
  if (auto route = args.get("route")) assignments.push_back("corners.route=" + *route);
  apply_overrides(options, assignments);
  int threads = 0;
  if (auto t = args.get("threads")) {
    try { threads = std::stoi(*t); } catch (...) { threads = -1; }
    if (threads < 0) throw InputError("--threads '" + *t + "': must be a number >= 0");
  }
  const std::string regularizer = args.get("regularizer").value_or("deformation");
  const auto& names = regularizer_names();
  if (std::find(names.begin(), names.end(), regularizer) == names.end())
    throw InputError("--regularizer '" + regularizer + "': must be one of: " + regularizer_list());
  const BuildingSelector selector = parse_selector(args);
  check_output_path(out_path);

  const MaskRaster raster = read_building_mask(mask_path, selector);
  const double pixel_size = raster.transform.pixel_size();
  spdlog::info("{}: {} x {} pixels of {:.3g} m, buildings = {}", mask_path, raster.mask.cols, raster.mask.rows, pixel_size,
               selector.describe());
  const ContourResult contours =
      extract_contours(raster.mask, raster.transform, options.contour, {}, cv::Rect(0, 0, raster.mask.cols, raster.mask.rows));
  const std::size_t count = contours.buildings.size();
  if (count == 0) {
    std::string held;  // (what the raster holds, which may tell a wrong selector: a probability read by a value)
    try {
      if (!selector.min) held = "; its " + values_held(mask_path, selector);
    } catch (const std::exception&) {
    }
    throw InputError(fmt::format("'{}': no building of at least {:g} m^2 and {} pixels ({} smaller components dropped){}", mask_path,
                                 options.contour.min_area_m2, options.contour.min_pixels, contours.dropped_small, held));
  }
  spdlog::info("{} buildings, {} components below {} m^2 or {} pixels dropped", count, contours.dropped_small, options.contour.min_area_m2,
               options.contour.min_pixels);

  std::atomic<std::size_t> done{0};
  std::unique_ptr<tbb::global_control> limit;
  if (threads > 0) limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
  // The mask's noise measured first at twice its pixel (noise.coarse_resolved_px): taken where it
  // is resolved there, its pooling's time shared by every building.
  std::optional<MaskNoise> coarse_noise;
  double coarse_seconds = 0;
  std::size_t coarse_samples = 0;
  if (pools_noise(regularizer, options.core) && tries_coarse_noise(pixel_size, options.core)) {
    // (Its time: each start and round, summed and shared by the buildings; the averaging and the
    // tracing, as the tracing at the pixel, are not a building's regularization.)
    const MaskRaster half = averaged(raster, 2);
    const ContourResult coarse =
        extract_contours(half.mask, half.transform, options.contour, {}, cv::Rect(0, 0, half.mask.cols, half.mask.rows));
    const MaskNoise noise = pooled_noise(coarse.buildings, half.transform.pixel_size(), options.core, &coarse_samples, &coarse_seconds);
    coarse_noise = coarse_noise_taken(noise, pixel_size, options.core);
    const bool resolved = coarse_noise.has_value();
    spdlog::info("boundary noise pooled over the {} buildings of the mask averaged to twice its pixel: {:.3f} m, {} {} pixels "
                 "(stages.noise.coarse_resolved_px): {}",
                 coarse.buildings.size(), noise.floor_m, resolved ? "at least" : "less than", options.core.noise.coarse_resolved_px,
                 resolved ? "the mask's noise" : "measured again at the pixel");
  }
  if (pools_noise(regularizer, options.core) && !coarse_noise)
    spdlog::info("measuring the boundary noise of {} buildings, to pool it (stages.noise.pooled_floor)", count);
  RegularizedBatch batch = regularize_batch(regularizer, contours.buildings, pixel_size, options.core, coarse_noise,
                                                  Lenders{Lenders::From::batch, {}}, [&] {
    const std::size_t n = ++done;
    if (count >= 20 && n % (count / 10) == 0) spdlog::info("{}/{} buildings", n, count);
  });
  if (batch.noise_samples > 0)
    spdlog::info("boundary noise pooled over {} buildings: {:.3f} m (stages.noise.pooled_floor = {}), normals smoothed for {:.3f} m",
                 batch.noise_samples, batch.noise_floor_m, options.core.noise.pooled_floor, batch.noise_smoothing_m);
  for (BuildingResult& r : batch.results) r.add_start_seconds(coarse_seconds / double(count));
  if (coarse_noise) batch.noise_samples = coarse_samples;
  const std::vector<BuildingResult>& results = batch.results;

  std::vector<FootprintRecord> records(count);
  std::map<std::string, int> failures, models;
  int failed = 0, rerouted = 0, lent = 0, supported = 0, took_rounding = 0, covering = 0;
  std::vector<double> roundings;  // of the buildings whose corners the segmentation rounded (BuildingResult::rounding_m)
  for (std::size_t i = 0; i < count; ++i) {
    const BuildingResult& r = results[i];
    FootprintRecord& rec = records[i];
    rec.id = long(i) + 1;
    rec.polygon = r.footprint;
    rec.status = r.status();
    rec.failed_stage = r.failed_stage;
    rec.reason = r.remark();
    rec.regularizer = !r.ok ? "douglas_peucker" : regularizer == "deformation" ? "deformation_" + r.route : regularizer;
    rec.model = r.model;
    ++models[r.ok ? r.model : "fallback"];
    if (r.ok && !r.note.empty()) ++rerouted;
    if (r.ok && r.holes_covered > 0) ++covering;  // (a fallback's reason says why it failed)
    if (r.ok && r.lattice_lent) ++lent;
    if (r.ok && r.lattice_of_support) ++supported;
    if (r.ok && r.rounding_m > 0) roundings.push_back(r.rounding_m);
    if (r.ok && r.rounding_pooled) ++took_rounding;
    if (!r.ok) {
      ++failed;
      ++failures[r.failed_stage];
      if (failed <= 20) spdlog::warn("building {} (first pixel row {}, col {}): {} failed: {}; Douglas-Peucker fallback written",
                                     rec.id, contours.buildings[i].first_row, contours.buildings[i].first_col, r.failed_stage, r.reason);
    }
  }
  FootprintLayer layer;
  layer.crs_wkt = raster.crs_wkt;
  layer.write_model = true;
  write_footprints(out_path, layer, records);
  std::string by_stage;
  for (const auto& [stage, n] : failures) by_stage += (by_stage.empty() ? " (" : ", ") + stage + ": " + std::to_string(n);
  if (!by_stage.empty()) by_stage += ")";
  spdlog::info("wrote {} footprints to {}: {} ok, {} fallback{}", count, out_path, count - failed, failed, by_stage);
  std::sort(roundings.begin(), roundings.end());
  const double rounding_median = roundings.empty() ? 0.0 : roundings[roundings.size() / 2];
  if (!roundings.empty())
    spdlog::info("{} building(s) with corners the segmentation rounded by more than their noise explains (median radius {:.2f} m): "
                 "their short oblique walls squared (stages.models.rounding_noise)",
                 roundings.size(), rounding_median);
  if (batch.rounding_m > 0)
    spdlog::info("{} building(s) measuring no rounding of their own took the mask's, a radius of {:.2f} m pooled over the {} that "
                 "measured theirs (stages.models.pooled_rounding_share)",
                 took_rounding, batch.rounding_m, batch.rounding_samples);
  if (rerouted > 0)
    spdlog::info("{} building(s) took the original corner route instead of the deformed one (over a budget; the reason is in their 'reason' field)", rerouted);
  if (covering > 0)
    spdlog::info("{} building(s) cover holes of the mask (a courtyard drawn filled, or a hole that crossed the outline; "
                 "their 'reason' field says how many and their area)", covering);
  if (auto stats = args.get("stats")) {
    // Times overall, then by contour size (edges of all rings), which the cost grows with.
    struct SizeClass { const char* name; std::size_t below; std::vector<const BuildingResult*> results; };
    std::vector<SizeClass> classes = {{"edges_below_250", 250, {}}, {"edges_250_to_1000", 1000, {}}, {"edges_1000_and_more", SIZE_MAX, {}}};
    std::vector<const BuildingResult*> all;
    for (std::size_t i = 0; i < count; ++i) {
      std::size_t edges = 0;
      for (const Ring& ring : contours.buildings[i].rings) edges += ring.size();
      std::find_if(classes.begin(), classes.end(), [&](const SizeClass& c) { return edges < c.below; })->results.push_back(&results[i]);
      all.push_back(&results[i]);
    }
    const auto times = [](const std::vector<const BuildingResult*>& of, nlohmann::ordered_json& into) {  // mean, median, p99
      std::vector<double> seconds;
      for (const BuildingResult* r : of) seconds.push_back(r->seconds);
      std::sort(seconds.begin(), seconds.end());
      double total = 0;
      for (double s : seconds) total += s;
      const auto at = [&](double q) { return seconds.empty() ? 0.0 : seconds[std::min(seconds.size() - 1, std::size_t(q * double(seconds.size())))]; };
      into["seconds_mean"] = seconds.empty() ? 0.0 : total / double(seconds.size());
      into["seconds_median"] = at(0.5);
      into["seconds_p99"] = at(0.99);
    };
    // Where the time goes (the paper's chain): each stage's mean a building (BuildingResult::chain_seconds).
    const auto stage_means = [&](const std::vector<const BuildingResult*>& of, nlohmann::ordered_json& into) {
      if (regularizer != "deformation" || of.empty()) return;
      double start = 0, labeling = 0, outline = 0, whole = 0;
      for (const BuildingResult* r : of) {
        start += r->chain_seconds.start;
        labeling += r->chain_seconds.labeling;
        outline += r->chain_seconds.outline;
        whole += r->seconds;
      }
      const double n = double(of.size());
      into["chain_seconds_mean"] = {{"start", start / n},
                                    {"labeling", labeling / n},
                                    {"outline", outline / n},
                                    {"other", std::max(0.0, whole - start - labeling - outline) / n}};
    };
    double total = 0;
    for (const BuildingResult* r : all) total += r->seconds;
    nlohmann::ordered_json out;
    out["regularizer"] = regularizer;
    out["route"] = options.core.corners.route;
    out["buildings"] = count;
    out["ok"] = count - failed;
    out["fallback"] = failed;
    out["original_route"] = rerouted;
    out["lattice_lent"] = lent;
    out["lattice_of_support"] = supported;
    out["corner_rounding"] = {{"buildings", roundings.size()},
                              {"radius_m_median", rounding_median},
                              {"measured", batch.rounding_samples},
                              {"pooled_m", batch.rounding_m},
                              {"took_pooled", took_rounding}};
    out["noise_floor_m"] = batch.noise_floor_m;
    out["noise_smoothing_m"] = batch.noise_smoothing_m;
    out["noise_samples"] = batch.noise_samples;
    if (pools_noise(regularizer, options.core)) out["noise_pixel_m"] = coarse_noise ? 2 * pixel_size : pixel_size;  // where it was measured
    if (regularizer == "deformation") out["models"] = models;
    out["seconds_total"] = total;
    times(all, out);
    stage_means(all, out);
    for (const SizeClass& c : classes) {
      nlohmann::ordered_json size_class;
      size_class["buildings"] = c.results.size();
      times(c.results, size_class);
      stage_means(c.results, size_class);
      out["by_size"][c.name] = size_class;
    }
    write_text_atomically(*stats, out.dump(1) + "\n");
  }
  return 0;
}

int run_options(int argc, char** argv) {
  Args args("options", "Prints every stage option with its default and meaning (set them with --set KEY=VALUE).");
  args.flag("help", "show this help");
  args.parse(argc, argv, 2);
  if (args.has("help")) { std::cout << args.help(); return 0; }
  std::cout << print_defaults();
  return 0;
}

}  // namespace lodforge
