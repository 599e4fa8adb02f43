#include "run/batch.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <limits>
#include <optional>
#include <numeric>

#include <tbb/parallel_for.h>

#include "directions/lattice.hpp"
#include "geometry/polygon.hpp"
#include "io/ogr_polygon.hpp"
#include "normals/smoothing.hpp"
#include "run/tiles.hpp"

namespace lodforge {

namespace {

using Clock = std::chrono::steady_clock;

// Into starts[i], for each i of `indices` in parallel, start(i); a start that throws is left
// empty, for the chain to start again (its normals smoothed for smoothing_noise_m) and say what
// failed. *seconds (when given): the time of each added.
template <class Start>
void start_each(const std::vector<std::size_t>& indices, double smoothing_noise_m, const Start& start,
                std::vector<BuildingStart>& starts, std::vector<double>* seconds) {
  if (seconds) seconds->resize(starts.size(), 0.0);
  tbb::parallel_for(std::size_t(0), indices.size(), [&](std::size_t k) {
    const std::size_t i = indices[k];
    const auto started = Clock::now();
    try {
      starts[i] = start(i);
    } catch (const std::exception&) {
      starts[i] = {};
      starts[i].smoothing_noise_m = smoothing_noise_m;
    }
    if (seconds) (*seconds)[i] += std::chrono::duration<double>(Clock::now() - started).count();
  });
}

// A start's noise sample as the pool takes it: none of a building the raster's edge cuts where the
// whole ones pool alone (whole_only).
NoiseSample pooled_sample(const BuildingStart& s, bool whole_only) { return whole_only && !s.cut.empty() ? NoiseSample{} : s.sample; }

std::vector<NoiseSample> samples_of(const std::vector<BuildingStart>& starts, bool whole_only = false) {
  std::vector<NoiseSample> samples;
  for (const BuildingStart& s : starts) samples.push_back(pooled_sample(s, whole_only));
  return samples;
}

// Whether the buildings the raster's edge cuts are left out of the mask's noise: where enough
// whole buildings measure it (noise.pooled_whole). cut: per sample, whether its building is cut.
bool whole_only(const std::vector<NoiseSample>& samples, const std::vector<bool>& cut, const CoreOptions& options) {
  if (options.noise.pooled_whole <= 0) return false;
  std::size_t whole = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) whole += !cut[i] && samples[i].weight_m > 0;
  return whole >= std::size_t(options.noise.pooled_whole);
}
std::vector<bool> cut_of(const std::vector<BuildingStart>& starts) {
  std::vector<bool> cut;
  for (const BuildingStart& s : starts) cut.push_back(!s.cut.empty());
  return cut;
}

std::size_t measured(const std::vector<NoiseSample>& samples) {
  return std::size_t(std::count_if(samples.begin(), samples.end(), [](const NoiseSample& s) { return s.weight_m > 0; }));
}

// The noise pooled over the samples at `indices`.
double pooled_at(const std::vector<NoiseSample>& samples, const std::vector<std::size_t>& indices, const CoreOptions& options) {
  std::vector<NoiseSample> some;
  for (std::size_t i : indices) some.push_back(samples[i]);
  return pooled_noise_floor(some, options);
}

// The mask's noise pooled in rounds, from `samples` (every building's, its normals smoothed for no
// noise): each next round smooths for the noise the round before pooled
// (smoothing.noise_neighbourhood), while the neighbourhood that asks for is more than 5 % wider
// than the last one's, in smoothing.noise_rounds at most. A wider round is kept only where it
// pools more noise, by more than smoothing.noise_gain: a contour smoothed too little measures too
// little noise where a fast wobble's flanks cut its runs short, but where the narrower smoothing
// measured the noise whole the wider one only averages short walls away. The rounds are judged
// on the buildings at `judged` (spread_indices, smoothing.noise_gain_buildings), each pooled both
// ways, and a kept round's noise, which the next round smooths for, is pooled over them: only the
// last round kept smooths the others (the first round's width is pooled over every building).
// judge(noise_m): the judged buildings' samples, in their order, smoothed for noise_m;
// keep_judged(), called right after judge when its round is kept; finish(noise_m), once at the end
// with the last kept round's noise when one was: every building's samples. `samples` ends as the
// kept round's.
template <class Judge, class KeepJudged, class Finish>
MaskNoise pool_in_rounds(std::vector<NoiseSample>& samples, const std::vector<std::size_t>& judged, double pixel_size,
                         const CoreOptions& options, const Judge& judge, const KeepJudged& keep_judged, const Finish& finish) {
  MaskNoise noise;
  noise.floor_m = pooled_noise_floor(samples, options);
  const auto neighbourhood = [&](double noise_m) { return smoothing_neighbourhood_m(pixel_size, options.smoothing, noise_m); };
  std::vector<std::size_t> order(judged.size());
  std::iota(order.begin(), order.end(), std::size_t(0));
  double next_m = noise.floor_m;  // the noise the next round smooths for
  for (int round = 1; round < options.smoothing.noise_rounds; ++round) {
    const double wider_m = next_m;
    if (neighbourhood(wider_m) <= 1.05 * neighbourhood(noise.smoothing_m)) break;
    const std::vector<NoiseSample> trial = judge(wider_m);
    if (pooled_at(trial, order, options) <= (1.0 + options.smoothing.noise_gain) * pooled_at(samples, judged, options)) break;
    keep_judged();
    for (std::size_t k = 0; k < judged.size(); ++k) samples[judged[k]] = trial[k];
    noise.smoothing_m = wider_m;
    next_m = pooled_at(samples, judged, options);
  }
  if (noise.smoothing_m > 0) {
    samples = finish(noise.smoothing_m);
    noise.floor_m = pooled_noise_floor(samples, options);
  }
  return noise;
}

// The buildings started, and their noise pooled in rounds (pool_in_rounds).
struct PooledStarts {
  std::vector<BuildingStart> starts;  // of the round kept
  std::size_t samples = 0;            // buildings measured in it
  MaskNoise noise;                    // the noise it pooled, and the noise it smoothed for
};
PooledStarts pool_starts(const std::vector<BuildingContour>& buildings, double pixel_size, const CoreOptions& options,
                         std::vector<double>* seconds) {
  PooledStarts pooled;
  pooled.starts.resize(buildings.size());
  std::vector<std::size_t> all(buildings.size());
  std::iota(all.begin(), all.end(), std::size_t(0));
  start_each(all, 0.0, [&](std::size_t i) { return start_building(buildings[i].rings, pixel_size, options, true, 0.0, buildings[i].cut); }, pooled.starts,
             seconds);
  const bool whole = whole_only(samples_of(pooled.starts), cut_of(pooled.starts), options);
  std::vector<NoiseSample> samples = samples_of(pooled.starts, whole);
  const std::vector<std::size_t> judged = spread_indices(buildings.size(), std::size_t(std::max(1, options.smoothing.noise_gain_buildings)));
  std::vector<std::size_t> rest;
  std::set_difference(all.begin(), all.end(), judged.begin(), judged.end(), std::back_inserter(rest));
  // The judged buildings' starts smoothed wider beside the kept ones (the round's time counts in
  // each judged building's, whether the round is kept or not).
  std::vector<BuildingStart> trial;
  const auto judge = [&](double wider_m) {
    trial.assign(buildings.size(), BuildingStart{});
    start_each(judged, wider_m, [&](std::size_t i) { return restart_building(buildings[i].rings, pixel_size, options, pooled.starts[i], wider_m); },
               trial, seconds);
    std::vector<NoiseSample> judged_samples;
    for (std::size_t i : judged) judged_samples.push_back(pooled_sample(trial[i], whole));
    return judged_samples;
  };
  const auto keep_judged = [&] {
    for (std::size_t i : judged) pooled.starts[i] = std::move(trial[i]);
  };
  const auto finish = [&](double wider_m) {
    start_each(rest, wider_m,
               [&](std::size_t i) { return restart_building(buildings[i].rings, pixel_size, options, std::move(pooled.starts[i]), wider_m); },
               pooled.starts, seconds);
    return samples_of(pooled.starts, whole);
  };
  pooled.noise = pool_in_rounds(samples, judged, pixel_size, options, judge, keep_judged, finish);
  pooled.samples = measured(samples);
  return pooled;
}

// Each building's neighbours' lattice (lattice.neighbour_radius_m) into its start; starts are made
// (empty, smoothed for smoothing_noise_m) where there are none. Lent by the batch's own buildings
// (their ids their indices, in the order of their first pixels as extract_contours sorts them, which
// the tiles' ids sum in; the chords' lattices of a start used, those of an empty one computed)
// or by those given.
void lend_neighbour_lattices(const std::vector<BuildingContour>& buildings, double pixel_size, const Lenders& lenders, const CoreOptions& options,
                             double smoothing_noise_m, std::vector<BuildingStart>& starts) {
  if (starts.empty()) {
    starts.resize(buildings.size());
    for (BuildingStart& s : starts) s.smoothing_noise_m = smoothing_noise_m;
  }
  const bool own = lenders.from == Lenders::From::batch;
  std::vector<LatticeLender> own_lenders(own ? buildings.size() : 0);
  std::vector<Vec2> centres(buildings.size());
  std::vector<std::int64_t> ids(buildings.size());
  tbb::parallel_for(std::size_t(0), buildings.size(), [&](std::size_t i) {
    const std::vector<Ring>& rings = buildings[i].rings;
    ids[i] = own ? std::int64_t(i) : contour_id(buildings[i]);
    if (!own) {
      centres[i] = lattice_lender(ids[i], rings, {}).centre;
      return;
    }
    const bool started = starts[i].normals.size() == rings.size();
    own_lenders[i] = started ? lattice_lender(ids[i], rings, starts[i].chord) : lattice_lender(ids[i], rings, chord_lattice(rings, options.lattice));
    centres[i] = own_lenders[i].centre;
  });
  const std::vector<NeighbourLattice> lattices = neighbour_lattices(centres, ids, own ? std::move(own_lenders) : lenders.given, pixel_size, options.lattice);
  for (std::size_t i = 0; i < buildings.size(); ++i) starts[i].neighbour_lattice = lattices[i];
}

}  // namespace

MaskNoise pooled_noise(const std::vector<BuildingContour>& buildings, double pixel_size, const CoreOptions& options, std::size_t* samples,
                       double* seconds) {
  std::vector<double> each;
  const PooledStarts pooled = pool_starts(buildings, pixel_size, options, seconds ? &each : nullptr);
  if (samples) *samples = pooled.samples;
  if (seconds) *seconds = std::accumulate(each.begin(), each.end(), 0.0);
  return pooled.noise;
}

bool tries_coarse_noise(double pixel_size, const CoreOptions& options) {
  return options.noise.pooled_floor > 0 && options.noise.coarse_resolved_px > 0 &&
         options.noise.coarse_resolved_px * pixel_size <= options.noise.coarse_max_m;
}

std::optional<MaskNoise> coarse_noise_taken(const MaskNoise& coarse, double pixel_size, const CoreOptions& options) {
  // (The pooled median itself against the pixels, whatever pooled_floor multiplies it by.)
  if (!(coarse.floor_m / options.noise.pooled_floor >= options.noise.coarse_resolved_px * pixel_size)) return std::nullopt;
  // The normals smoothed at the pixel at least as wide as the averaged mask's narrowest smoothing
  // (its min_neighbourhood_px of twice the pixel), which the noise was measured after.
  MaskNoise taken = coarse;
  if (options.smoothing.noise_neighbourhood > 0)
    taken.smoothing_m = std::max(taken.smoothing_m, options.smoothing.min_neighbourhood_px * 2 * pixel_size / options.smoothing.noise_neighbourhood);
  return taken;
}

bool pools_noise(const std::string& regularizer, const CoreOptions& options) {
  return regularizer == "deformation" && options.noise.pooled_floor > 0;
}

bool pools_rounding(const std::string& regularizer, const CoreOptions& options) {
  return regularizer == "deformation" && options.models.pooled_rounding_share > 0 && options.models.rounding_noise > 0;
}

namespace {

RegularizedBatch regularize_traced(const std::string& regularizer, const std::vector<BuildingContour>& buildings,
                                   double pixel_size, const CoreOptions& options, std::optional<MaskNoise> noise,
                                   const Lenders& lenders, const std::function<void()>& on_done) {
  RegularizedBatch batch;
  batch.results.resize(buildings.size());
  std::vector<BuildingStart> starts;
  std::vector<double> start_seconds;  // each building's time counts its start's
  // (Where none were made: empty starts, each building's chain starting itself, smoothed for the mask's noise.)
  const auto ensure_starts = [&] {
    if (!starts.empty()) return;
    starts.resize(buildings.size());
    for (BuildingStart& s : starts) s.smoothing_noise_m = batch.noise_smoothing_m;
  };
  if (noise) {
    batch.noise_floor_m = noise->floor_m;
    batch.noise_smoothing_m = noise->smoothing_m;
  } else if (pools_noise(regularizer, options)) {
    PooledStarts pooled = pool_starts(buildings, pixel_size, options, &start_seconds);
    starts = std::move(pooled.starts);
    batch.noise_samples = pooled.samples;
    batch.noise_floor_m = pooled.noise.floor_m;
    batch.noise_smoothing_m = pooled.noise.smoothing_m;
  }
  // The neighbours' lattices.
  if (lenders.from != Lenders::From::none && regularizer == "deformation" && options.lattice.neighbour_radius_m > 0)
    lend_neighbour_lattices(buildings, pixel_size, lenders, options, batch.noise_smoothing_m, starts);
  // The mask's corner rounding: given, or pooled after the chains (which keep the outlines that
  // may take it unsquared: mask_rounding_m negative).
  const bool rounds = pools_rounding(regularizer, options);
  const bool pool_rounding = rounds && !(noise && noise->rounding_m);
  if (rounds && noise && noise->rounding_m) batch.rounding_m = std::max(0.0, *noise->rounding_m);
  if (pool_rounding || batch.rounding_m > 0) {
    ensure_starts();
    for (BuildingStart& s : starts) s.mask_rounding_m = pool_rounding ? -1.0 : batch.rounding_m;
  }
  // The paper's chain starts from its start (the buildings the raster's edge cuts measure their
  // noise inside it, BuildingStart::cut).
  if (regularizer == "deformation") {
    ensure_starts();
    for (std::size_t i = 0; i < buildings.size(); ++i) starts[i].cut = buildings[i].cut;
  }
  // (The lattices lent, for a chain run again under the mask's rounding.)
  std::vector<NeighbourLattice> lent;
  if (pool_rounding)
    for (const BuildingStart& s : starts) lent.push_back(s.neighbour_lattice);
  tbb::parallel_for(std::size_t(0), buildings.size(), [&](std::size_t i) {
    batch.results[i] = regularize_with(regularizer, buildings[i].rings, pixel_size, options, batch.noise_floor_m,
                                       starts.empty() ? BuildingStart{} : std::move(starts[i]));
    if (!start_seconds.empty()) batch.results[i].add_start_seconds(start_seconds[i]);
    if (on_done) on_done();
  });
  if (!pool_rounding) return batch;
  std::vector<double> measured_m;
  for (const BuildingResult& r : batch.results)
    if (measured_rounding(r)) measured_m.push_back(r.rounding_m);
  batch.rounding_samples = measured_m.size();
  batch.rounding_m = pooled_rounding(measured_m, options);
  // A building read as round that the rounding explains as its rectangle is drawn again with the
  // rounding known (its start made again: the same, smoothed for the mask's noise); the others
  // take the rounding where their chains kept an outline for it.
  tbb::parallel_for(std::size_t(0), buildings.size(), [&](std::size_t i) {
    BuildingResult& result = batch.results[i];
    if (held_under_rounding(buildings[i].rings, pixel_size, options, result, batch.rounding_m)) {
      BuildingStart start;
      start.smoothing_noise_m = batch.noise_smoothing_m;
      if (i < lent.size()) start.neighbour_lattice = lent[i];
      start.cut = buildings[i].cut;
      start.mask_rounding_m = batch.rounding_m;
      BuildingResult again = regularize_with(regularizer, buildings[i].rings, pixel_size, options, batch.noise_floor_m, std::move(start));
      again.add_seconds(result);
      result = std::move(again);
      return;
    }
    take_mask_rounding(buildings[i].rings, pixel_size, options, batch.rounding_m, result);
  });
  return batch;
}

}  // namespace

RegularizedBatch regularize_batch(const std::string& regularizer, const std::vector<BuildingContour>& buildings,
                                  double pixel_size, const CoreOptions& options, std::optional<MaskNoise> noise,
                                  const Lenders& lenders, const std::function<void()>& on_done) {
  RegularizedBatch batch = regularize_traced(regularizer, buildings, pixel_size, options, std::move(noise), lenders, on_done);
  // The buildings the raster's edge cuts, traced swept out across it: clipped back to the raster,
  // and the notches flattened that an outline crossing the edge back and forth leaves along it:
  // within the mask's noise (at least two pixels), or deeper where the mask fills them.
  const double depth = std::max(2 * pixel_size, batch.noise_floor_m);
  tbb::parallel_for(std::size_t(0), buildings.size(), [&](std::size_t i) {
    const Ring& cut = buildings[i].cut;
    if (cut.empty()) return;
    BuildingResult& r = batch.results[i];
    std::optional<PolygonWithHoles> clipped = clip_polygon(r.footprint, cut);
    // (Its outline not clipped, its fallback then: the traced contour, swept, clipped.)
    if (!clipped && (clipped = clip_polygon(fallback_footprint(buildings[i].rings, options.fallback.tolerance_m), cut))) {
      r.model.clear();
      r.ok = false;
      r.failed_stage = "clip";
      r.reason = "the outline could not be clipped to the raster's edge (stages.contour.edge_sweep_m)";
    }
    if (!clipped) return;
    PolygonWithHoles flat = *clipped;
    // (A dip the mask fills, deeper than that: inside the raster the traced contour is the mask's.)
    const std::vector<Ring>& traced = buildings[i].rings;
    const auto in_mask = [&traced](const Vec2& p) {
      if (traced.empty() || !point_in_ring(p, traced[0])) return false;
      return std::none_of(traced.begin() + 1, traced.end(), [&p](const Ring& hole) { return point_in_ring(p, hole); });
    };
    for (std::size_t k = 0; k < cut.size(); ++k) {
      const Vec2 &a = cut[k], &b = cut[(k + 1) % cut.size()];
      flat.outer = flatten_along_line(flat.outer, a, b, depth, in_mask, pixel_size);
      for (Ring& h : flat.holes) h = flatten_along_line(h, a, b, depth);
    }
    flat.outer = remove_degenerate_vertices(flat.outer, 1e-9);
    for (Ring& h : flat.holes) h = remove_degenerate_vertices(h, 1e-9);
    r.footprint = polygon_problem(flat).empty() ? std::move(flat) : std::move(*clipped);
  });
  for (std::size_t i = 0; i < buildings.size(); ++i) batch.results[i].count_covered_holes(buildings[i].rings);
  return batch;
}

std::int64_t contour_id(const BuildingContour& building) {
  return (std::int64_t(building.first_row) << 32) + std::int64_t(building.first_col);
}

LenderMargins lender_margins(const GeoTransform& transform, const LatticeOptions& lattice) {
  // A map offset d moves the pixel column by r0 . d and the row by r1 . d (the inverse's rows):
  // by at most |r|_2 for a distance of one, and |r|_1 across a box of one a side.
  const auto& c = transform.c;
  const double det = c[1] * c[5] - c[2] * c[4];
  LenderMargins m;
  if (det == 0 || !std::isfinite(det)) return m;
  const Vec2 r0 = Vec2(c[5], -c[2]) / det, r1 = Vec2(-c[4], c[1]) / det;
  const double radius = std::max(0.0, lattice.neighbour_radius_m), extent = std::max(0.0, lattice.neighbour_max_extent_m);
  m.reach = Vec2(radius * r0.norm(), radius * r1.norm()) + Vec2::Constant(2);
  m.extent = Vec2(extent * r0.lpNorm<1>(), extent * r1.lpNorm<1>()) + Vec2::Constant(2);
  m.window = m.reach + m.extent;
  return m;
}

std::vector<LatticeLender> lattice_lenders(const MaskWindowReader& mask, cv::Size raster, const GeoTransform& transform,
                                           const ContourOptions& contour, const LatticeOptions& lattice,
                                           const std::vector<BuildingContour>& buildings) {
  std::vector<LatticeLender> lenders;
  const double pixel_size = transform.pixel_size();
  if (lattice.neighbour_radius_m <= 0 || lattice.neighbour_max_extent_m <= 0 || buildings.empty() || pixel_size <= 0) return lenders;
  // The buildings' centres' box in pixels, with the margin: a lender within the radius of a
  // centre, no wider than the extent, lies within both of it.
  double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
  std::vector<Vec2> centres;
  for (const BuildingContour& b : buildings) {
    const LatticeLender l = lattice_lender(0, b.rings, {});
    if (!l.centre.allFinite()) continue;
    centres.push_back(l.centre);
    const Vec2 p = transform.to_pixel(l.centre);
    x0 = std::min(x0, p.x()), x1 = std::max(x1, p.x()), y0 = std::min(y0, p.y()), y1 = std::max(y1, p.y());
  }
  if (!(x0 <= x1 && y0 <= y1)) return lenders;
  const LenderMargins m = lender_margins(transform, lattice);
  const cv::Rect full(0, 0, raster.width, raster.height);
  const cv::Rect window = cv::Rect(cv::Point(int(std::max(-1.0, std::floor(x0 - m.window.x()))), int(std::max(-1.0, std::floor(y0 - m.window.y())))),
                                   cv::Point(int(std::min(double(raster.width) + 1, std::ceil(x1 + m.window.x()))),
                                             int(std::min(double(raster.height) + 1, std::ceil(y1 + m.window.y()))))) & full;
  if (window.empty()) return lenders;
  // Traced: the components whole in it, no wider than the extent, whose box (which holds the
  // centre) comes within the radius of the centres' box.
  const cv::Rect zone = cv::Rect(cv::Point(int(std::floor(x0 - m.reach.x())) - window.x, int(std::floor(y0 - m.reach.y())) - window.y),
                                 cv::Point(int(std::ceil(x1 + m.reach.x())) - window.x, int(std::ceil(y1 + m.reach.y())) - window.y));
  ContourResult traced = extract_contours(
      mask.read(window), transform.window(window.x, window.y), contour,
      [&](const cv::Rect& box, const cv::Point&) {
        return !touches_inner_border(box, window, raster) && box.width <= m.extent.x() && box.height <= m.extent.y() && !(box & zone).empty();
      },
      cv::Rect(-window.tl(), raster));
  // Each one's chords' lattice (the costly part) where its centre lies within the radius of one
  // of the buildings', or within half of it and its box's diagonal (its box may come within half
  // the radius): the others lend to none of them.
  const PointsWithinRadius within(std::move(centres), std::max(lattice.neighbour_radius_m, lattice.neighbour_radius_m / 2 +
                                                                                            std::sqrt(2.0) * lattice.neighbour_max_extent_m));
  std::vector<std::optional<LatticeLender>> found(traced.buildings.size());
  tbb::parallel_for(std::size_t(0), traced.buildings.size(), [&](std::size_t i) {
    BuildingContour& b = traced.buildings[i];
    b.first_row += window.y;  // (in the raster, as the tiles' and the whole mask's)
    b.first_col += window.x;
    LatticeLender l = lattice_lender(contour_id(b), b.rings, {});
    if (!within.any_near(l.centre)) return;
    const ChordLattice chord = chord_lattice(b.rings, lattice);
    l.direction = chord.direction;
    l.share = chord.share;
    found[i] = l;
  });
  for (const std::optional<LatticeLender>& l : found)
    if (l) lenders.push_back(*l);
  return lenders;
}

std::vector<std::size_t> spread_indices(std::size_t n, std::size_t k) {
  k = std::min(k, n);
  std::vector<std::size_t> indices(k);
  for (std::size_t j = 0; j < k; ++j) indices[j] = j * n / k;
  return indices;
}

std::vector<cv::Rect> survey_cells(cv::Size raster, int window_px, int windows) {
  std::vector<cv::Rect> cells;
  if (windows <= 0 || raster.width <= 0 || raster.height <= 0) return cells;
  window_px = std::max(1, window_px);
  const long cols = (raster.width + window_px - 1) / window_px, rows = (raster.height + window_px - 1) / window_px;
  const auto cell = [&](long row, long col) {
    return cv::Rect(int(col * window_px), int(row * window_px), window_px, window_px) & cv::Rect(0, 0, raster.width, raster.height);
  };
  if (rows * cols <= windows) {
    for (long r = 0; r < rows; ++r)
      for (long c = 0; c < cols; ++c) cells.push_back(cell(r, c));
    return cells;
  }
  const long a = std::clamp(std::lround(std::sqrt(double(windows) * double(rows) / double(cols))), 1L, rows);
  const long b = std::clamp(windows / a, 1L, cols);
  for (long i = 0; i < a; ++i)
    for (long j = 0; j < b; ++j) cells.push_back(cell((2 * i + 1) * rows / (2 * a), (2 * j + 1) * cols / (2 * b)));
  return cells;
}

namespace {

// visit(first, buildings) for each survey cell's buildings, in the cells' order (first: how many
// came before): those whose first pixel lies in the cell, traced in its window (the cell with a
// margin of a quarter of window_px, cut by the raster) and whole in it. The count of them all.
using SurveyVisit = std::function<void(std::size_t first, std::vector<BuildingContour>& buildings)>;
std::size_t visit_survey_cells(const std::function<cv::Mat(const cv::Rect&)>& read, cv::Size raster, const GeoTransform& transform,
                               const ContourOptions& contour, const std::vector<cv::Rect>& cells, int window_px, const SurveyVisit& visit) {
  const int margin = std::max(1, window_px / 4);
  std::size_t first = 0;
  for (const cv::Rect& cell : cells) {
    const cv::Rect window = cv::Rect(cell.x - margin, cell.y - margin, cell.width + 2 * margin, cell.height + 2 * margin) &
                            cv::Rect(0, 0, raster.width, raster.height);
    ContourResult traced = extract_contours(
        read(window), transform.window(window.x, window.y), contour,
        [&](const cv::Rect& box, const cv::Point& at) { return cell.contains(at + window.tl()) && !touches_inner_border(box, window, raster); },
        cv::Rect(-window.tl(), raster));
    visit(first, traced.buildings);
    first += traced.buildings.size();
  }
  return first;
}

}  // namespace

NoiseSurvey survey_noise(const MaskWindowReader& mask, cv::Size fine_raster, const GeoTransform& fine_transform, const ContourOptions& contour,
                         const CoreOptions& options, int fine_window_px, int windows, int factor) {
  NoiseSurvey survey;
  if (options.noise.pooled_floor <= 0) return survey;
  // On the mask averaged over blocks of factor x factor pixels (average_blocks, as `averaged`
  // makes a whole mask): the survey's grid, cells and windows in blocks.
  const int f = std::max(1, factor);
  const cv::Size raster = blocks_of(fine_raster, f);
  const GeoTransform transform = fine_transform.coarsened(f);
  const int window_px = std::max(1, (fine_window_px + f - 1) / f);  // (rounded up: a window over the whole raster stays one)
  const auto read = [&](const cv::Rect& window) {
    if (f == 1) return mask.read(window);
    const cv::Rect fine = cv::Rect(window.x * f, window.y * f, window.width * f, window.height * f) & cv::Rect(cv::Point(0, 0), fine_raster);
    return average_blocks(mask.read(fine), window.size(), f);
  };
  const std::vector<cv::Rect> cells = survey_cells(raster, window_px, windows);
  survey.windows = int(cells.size());
  const double pixel_size = transform.pixel_size();
  // The rounds of pool_starts, with the same samples, over the windows read again for each pass:
  // a survey holds one window's contours at a time (and the rings of the buildings a round is
  // judged on), not every surveyed building's.
  const auto each_window = [&](const SurveyVisit& visit) { return visit_survey_cells(read, raster, transform, contour, cells, window_px, visit); };
  // Every building's sample, its normals smoothed for smoothing_noise_m.
  // (Whether the buildings the raster's edge cuts pool, as pool_starts decides: on the first round.)
  std::optional<bool> whole;
  const auto measure_all = [&](double smoothing_noise_m) {
    std::vector<NoiseSample> samples;
    std::vector<bool> cut;
    each_window([&](std::size_t, std::vector<BuildingContour>& buildings) {
      std::vector<BuildingStart> starts(buildings.size());
      std::vector<std::size_t> all(buildings.size());
      std::iota(all.begin(), all.end(), std::size_t(0));
      start_each(all, smoothing_noise_m,
                 [&](std::size_t i) { return start_building(buildings[i].rings, pixel_size, options, true, smoothing_noise_m, buildings[i].cut); }, starts,
                 nullptr);
      for (const BuildingStart& start : starts) samples.push_back(start.sample), cut.push_back(!start.cut.empty());  // (the samples only)
    });
    if (!whole) whole = whole_only(samples, cut, options);
    for (std::size_t i = 0; i < samples.size(); ++i)
      if (*whole && cut[i]) samples[i] = NoiseSample{};  // (as pooled_sample)
    return samples;
  };
  std::vector<NoiseSample> samples = measure_all(0.0);
  const std::vector<std::size_t> judged = spread_indices(samples.size(), std::size_t(std::max(1, options.smoothing.noise_gain_buildings)));
  std::vector<BuildingContour> judged_contours;  // read when a round is first judged
  const auto judge = [&](double wider_m) {
    if (judged_contours.empty() && !judged.empty()) {
      judged_contours.resize(judged.size());
      each_window([&](std::size_t first, std::vector<BuildingContour>& buildings) {
        for (std::size_t k = std::lower_bound(judged.begin(), judged.end(), first) - judged.begin();
             k < judged.size() && judged[k] < first + buildings.size(); ++k)
          judged_contours[k] = std::move(buildings[judged[k] - first]);
      });
    }
    std::vector<BuildingStart> trial(judged.size());
    std::vector<std::size_t> order(judged.size());
    std::iota(order.begin(), order.end(), std::size_t(0));
    start_each(order, wider_m, [&](std::size_t k) {
      return start_building(judged_contours[k].rings, pixel_size, options, true, wider_m, judged_contours[k].cut);
    }, trial,
               nullptr);
    return samples_of(trial, *whole);
  };
  survey.noise = pool_in_rounds(samples, judged, pixel_size, options, judge, [] {}, measure_all);
  survey.buildings = measured(samples);
  return survey;
}

RoundingSurvey survey_rounding(const MaskWindowReader& mask, cv::Size raster, const GeoTransform& transform, const ContourOptions& contour,
                               const CoreOptions& options, int window_px, int windows, const MaskNoise& noise) {
  RoundingSurvey survey;
  if (!pools_rounding("deformation", options)) return survey;
  window_px = std::max(1, window_px);
  MaskNoise given = noise;
  given.rounding_m = 0.0;  // (each measures its own)
  std::vector<double> measured_m;
  visit_survey_cells([&](const cv::Rect& window) { return mask.read(window); }, raster, transform, contour,
                     survey_cells(raster, window_px, windows), window_px, [&](std::size_t, std::vector<BuildingContour>& buildings) {
                       const RegularizedBatch batch = regularize_batch("deformation", buildings, transform.pixel_size(), options, given,
                                                                       Lenders{Lenders::From::batch, {}});
                       for (const BuildingResult& r : batch.results)
                         if (measured_rounding(r)) measured_m.push_back(r.rounding_m);
                     });
  survey.measured = measured_m.size();
  survey.rounded = std::size_t(std::count_if(measured_m.begin(), measured_m.end(), [](double r) { return r > 0; }));
  survey.rounding_m = pooled_rounding(measured_m, options);
  return survey;
}

}  // namespace lodforge
