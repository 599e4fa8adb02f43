#include "pipeline/building.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "corners/corners.hpp"
#include "directions/lattice.hpp"
#include "directions/ransac.hpp"
#include "directions/refine.hpp"
#include "geometry/polygon.hpp"
#include "labeling/mrf.hpp"
#include "models/noise.hpp"
#include "models/rectangle.hpp"
#include "models/statistics.hpp"
#include "normals/smoothing.hpp"
#include "peers/cgal_contours.hpp"
#include "pipeline/deformed_route.hpp"
#include "pipeline/model_choice.hpp"
#include "pipeline/outlines.hpp"

namespace lodforge {

namespace {

using chain::BudgetExceeded;
using chain::StageError;

using Clock = std::chrono::steady_clock;

// Why the chain does not take these rings (fewer than 4 edges, more than budget.max_edges), or empty.
std::string contour_problem(const std::vector<Ring>& rings, const CoreOptions& o) {
  if (rings.empty() || rings[0].size() < 4) return "contour has fewer than 4 edges";
  std::size_t edges = 0;
  for (const Ring& r : rings) edges += r.size();
  if (edges > std::size_t(o.budget.max_edges))
    return "contour has " + std::to_string(edges) + " edges, more than budget.max_edges = " + std::to_string(o.budget.max_edges);
  return "";
}

// The share of the contour's length whose smoothed normal lies within max_deg of the lattice's
// four directions.
double lattice_share(const std::vector<std::vector<Vec2>>& normals, const std::vector<std::vector<double>>& lengths,
                     const Vec2& lattice, double max_deg) {
  const double min_cos = std::cos(max_deg * M_PI / 180.0);
  double on = 0, total = 0;
  for (std::size_t r = 0; r < normals.size(); ++r)
    for (std::size_t i = 0; i < normals[r].size(); ++i) {
      total += lengths[r][i];
      if (nearest_lattice_axis(normals[r][i], lattice).dot(normals[r][i]) >= min_cos) on += lengths[r][i];
    }
  return total > 0 ? on / total : 0.0;
}

// How many full turns the normals make along a ring, each turn counted whichever way it goes,
// sampled every `step` of contour (so that a staircase's pixel-scale zigzag does not count).
double total_turning(const Ring& ring, const std::vector<Vec2>& normals, double step) {
  std::vector<Vec2> samples;
  double along = step;
  for (std::size_t i = 0; i < normals.size(); ++i) {
    if (along >= step) { samples.push_back(normals[i]); along = 0; }
    along += edge_vector(ring, i).norm();
  }
  double turning = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const Vec2& a = samples[i];
    const Vec2& b = samples[(i + 1) % samples.size()];
    turning += std::abs(std::atan2(cross(a, b), a.dot(b)));
  }
  return turning / (2 * M_PI);
}

// The contour length labeled with each direction.
std::vector<double> labeled_support(const EdgeLabels& labels, const std::vector<std::vector<double>>& lengths,
                                    std::size_t directions) {
  std::vector<double> support(directions, 0.0);
  for (std::size_t r = 0; r < labels.size(); ++r)
    for (std::size_t i = 0; i < labels[r].size(); ++i) support[labels[r][i]] += lengths[r][i];
  return support;
}

// The building's lattice: the direction with the most labeled contour length.
Vec2 main_direction(const EdgeLabels& labels, const std::vector<std::vector<double>>& lengths, const std::vector<Vec2>& directions) {
  const std::vector<double> support = labeled_support(labels, lengths, directions.size());
  return directions[std::max_element(support.begin(), support.end()) - support.begin()];
}

// The lattice that holds the most labeled contour: the direction whose own labeled length and
// that of the directions within same_deg of it (lattice.max_gap_deg), up to quarter turns, sum to
// the most (ties: the one with the more of its own); none where that lies within min_turn_deg of
// `held`, the lattice the outline is held to (lattice.support_turn_deg; 0 = off). The main
// direction is the single direction with the most: where a street front of one direction outweighs
// each of the walls of two at right angles behind it, but not both, their lattice is the one the
// steps are squared on. (Nearer the held lattice it is that lattice, moved by its chords or its
// fit, which average a wobble out; farther, it may also be the labeled main direction, where the
// chords or the fit took the lattice off it.)
std::optional<Vec2> lattice_of_support(const EdgeLabels& labels, const LabelingInput& input, const Vec2& held, double same_deg,
                                       double min_turn_deg) {
  if (min_turn_deg <= 0 || held.squaredNorm() == 0) return std::nullopt;
  const std::vector<Vec2>& directions = input.directions;
  const std::vector<double> support = labeled_support(labels, input.lengths, directions.size());
  std::size_t best = 0;
  double most = -1;
  for (std::size_t i = 0; i < directions.size(); ++i) {
    double sum = 0;
    for (std::size_t j = 0; j < directions.size(); ++j)
      if (angle_between_lattices_deg(directions[i], directions[j]) <= same_deg) sum += support[j];
    if (sum > most || (sum == most && support[i] > support[best])) best = i, most = sum;
  }
  if (most <= 0 || angle_between_lattices_deg(directions[best], held) <= min_turn_deg) return std::nullopt;
  return directions[best];
}

// The contour's normals (the start's) and its edges' lengths, per ring, for the labeling.
LabelingInput labeling_input(const std::vector<Ring>& rings, std::vector<std::vector<Vec2>> normals) {
  LabelingInput input;
  input.normals = std::move(normals);
  for (const Ring& ring : rings) {
    input.lengths.emplace_back();
    for (std::size_t i = 0; i < ring.size(); ++i) input.lengths.back().push_back(edge_vector(ring, i).norm());
  }
  return input;
}

// The building's dominant directions (RANSAC over its edges' normals, by length) into input, its
// edges labeled with them, and the directions re-estimated from the labeled runs.
EdgeLabels label_directions(const std::vector<Ring>& rings, double pixel_size, const CoreOptions& o, LabelingInput& input) {
  std::vector<Vec2> all_normals;
  std::vector<double> all_lengths;
  for (std::size_t r = 0; r < rings.size(); ++r) {
    all_normals.insert(all_normals.end(), input.normals[r].begin(), input.normals[r].end());
    all_lengths.insert(all_lengths.end(), input.lengths[r].begin(), input.lengths[r].end());
  }
  for (const DominantDirection& d : detect_directions(all_normals, all_lengths, o.directions)) {
    input.directions.push_back(d.normal);
    input.support.push_back(d.support);
  }
  if (input.directions.size() < 2)
    throw StageError("directions", "found " + std::to_string(input.directions.size()) + " dominant direction(s), need 2");
  // Label, re-estimate the directions from the labeled runs (labeled again after).
  EdgeLabels labels = label_edges(input, o.labeling);
  refine_directions(rings, labels, input.directions, pixel_size, o.refinement);
  return labels;
}

// The building's lattice: the labeled main direction, unless the chords' lattice is followed
// (follow_chords) and the main direction is not within lattice.max_gap_deg of it.
Vec2 building_lattice(const EdgeLabels& labels, const LabelingInput& input, bool follow_chords, const ChordLattice& chord,
                      const LatticeOptions& o) {
  const Vec2 main = main_direction(labels, input.lengths, input.directions);
  return !follow_chords || angle_between_lattices_deg(main, chord.direction) <= o.max_gap_deg ? main : chord.direction;
}

// The building's boundary noise about the lines of its lattice, and about parabolas along them
// (*arc_noise), at least the noise pooled over its mask: walls shorter than a wobble's wavelength,
// or runs cut short by its flanks at fine pixels, measure too little of a segmentation's noise,
// which is its mask's. And at most noise.pooled_ceiling times the pooled noise: a contour that lies
// farther than that off the lines of its lattice is not noisier than its mask's other buildings, it
// has arcs or walls off the lattice (a round building's measures metres), which the noise must not
// hide. (About the chords' lattice, the start measured it for its sample, on the same normals.)
// *regularity: the same measure held to noise.regularity_ceiling instead, at least the noise: what
// the building's regularity (snaps, squarings, curves, the lattice outline's and the rectangle's
// tolerance) is judged by.
double building_noise(const std::vector<Ring>& rings, const std::vector<std::vector<Vec2>>& normals, const Vec2& lattice,
                      bool follow_chords, const BuildingStart& start, double pixel_size, double noise_floor_m, const CoreOptions& o,
                      double* arc_noise, double* regularity) {
  *arc_noise = start.chord_arc_noise_m;
  const double own = std::max(noise_floor_m, follow_chords && start.chord_noise_m >= 0
                                                 ? start.chord_noise_m
                                                 : lattice_noise(rings, normals, lattice, pixel_size, o.noise, arc_noise, nullptr,
                                                                 start.cut.empty() ? nullptr : &start.cut));
  const bool pooled = noise_floor_m > 0 && o.noise.pooled_floor > 0;
  // (The floor is pooled_floor times the pooled noise: a ceiling of c times the pooled noise is c / pooled_floor floors.)
  // (And a ceiling at least the floor and noise.ceiling_staircase_px's staircase added in quadrature.)
  const double staircase = std::hypot(noise_floor_m, o.noise.ceiling_staircase_px * pixel_size);
  const auto held = [&](double ceiling) {
    return pooled && ceiling > 0 ? std::min(own, std::max(std::max(1.0, ceiling / o.noise.pooled_floor) * noise_floor_m, staircase)) : own;
  };
  const double noise = held(o.noise.pooled_ceiling);
  *regularity = std::max(noise, held(o.noise.regularity_ceiling));
  *arc_noise = std::max(*arc_noise, noise_floor_m);
  return noise;
}

// Whether the contour's best rectangle along the lattice (rounded by `rounding` where above 0, as
// its mask rounds corners) explains it as well as its moments' ellipse does, and within twice its
// noise, noise_m, or pixel (refinement.round_fit_ratio, round_fit_noise): under a wobble of a metre
// a house's normals spread off its walls; a clean triangle's rectangle leaves a corner out by
// metres; under a rounding of 2 m a house of 5 m is a disc, which its rectangle rounded so draws.
// (A rounding that moves a corner less than a pixel, R (sqrt 2 - 1), is the staircase's: none.)
bool resolves_rounding(double rounding, double pixel_size) { return rounding * (std::sqrt(2.0) - 1) >= pixel_size; }
bool no_rounder_than_rectangle(const Ring& outer, const Vec2& lattice, double pixel_size, double noise_m, double rounding,
                               const RefineOptions& o) {
  if (o.round_fit_ratio <= 0) return false;
  const double rectangle_fit = best_rectangle_fit(outer, {lattice}, resolves_rounding(rounding, pixel_size) ? rounding : 0.0);
  const bool within_noise = o.round_fit_noise <= 0 || rectangle_fit <= o.round_fit_noise * std::max(noise_m, pixel_size);
  return std::isfinite(rectangle_fit) && within_noise && rectangle_fit <= o.round_fit_ratio * moment_ellipse_fit(outer);
}

// Whether the building's walls are held to its lattice: not a round or oblique shape (little of
// it along the lattice, its outline turning about once, as a convex one does, not back and forth as
// a wobble does). A building of a few dozen pixels, or of a few dozen times its mask's noise,
// shows no curvature: it is taken as on its lattice. So is one that its normals read as round or
// oblique but whose best rectangle explains its contour as well as its moments' ellipse does
// (no_rounder_than_rectangle; rounded by its mask's rounding, mask_rounding_m, where above 0).
// *undetermined: taken so because its shape does not tell (too small for its noise, under
// undetermined_noise noises, or no rounder than a rectangle), not by its walls: its neighbours'
// lattice is lent to it (outline_lattice). (Between undetermined_noise and min_round_noise noises
// it is held to a lattice, its own unless, as a larger building, its walls do not show and its
// rectangle explains it: a clean house of 5 x 4 m at 1 m pixels may stand askew to its street.)
// (Not held: read as round by its rectangle's test, or with that test off.)
bool holds_to_lattice(const std::vector<Ring>& rings, const LabelingInput& input, const Vec2& lattice, double pixel_size,
                      double noise_floor_m, double noise_m, double mask_rounding_m, const RefineOptions& o, double undetermined_noise,
                      bool* undetermined) {
  const double outline_m = perimeter(rings[0]);
  *undetermined = outline_m < undetermined_noise * noise_floor_m;
  const bool short_for_noise = outline_m < o.min_round_noise * noise_floor_m;
  // (Undetermined by its size, held only within min_round_noise: at 0 that rule is off.)
  if (too_short_in_pixels(outline_m, pixel_size, o) || (*undetermined && short_for_noise)) return true;
  if (lattice_share(input.normals, input.lengths, lattice, o.lattice_deg) >= o.min_lattice_share ||
      total_turning(rings[0], input.normals[0], std::max(1.0, 2 * pixel_size)) >= o.min_turning)
    return true;
  // (Between undetermined_noise and min_round_noise noises and its walls not showing: held, and its
  // lattice undetermined where no rounder than its rectangle, as a larger building's.)
  *undetermined = no_rounder_than_rectangle(rings[0], lattice, pixel_size, noise_m, mask_rounding_m, o);
  return *undetermined || short_for_noise;
}

// The lattice fitted to the contour's runs along it (lattice.fit_*), its direction's standard error
// and the runs' spread about it.
struct FittedLattice {
  std::optional<Vec2> direction;
  double uncertainty = 0, spread = 0;
};

// The lattice the outlines hold the walls to (zero: none, a round or oblique shape): the labeled
// one (main direction or chords'), or the fitted one unless the labeled one lies within its
// uncertainty (on a clean wall the labeled direction is exact). A building whose own lattice is
// undetermined takes its neighbours' (lattice.neighbour_*, result.lattice_lent): one too small to
// show its walls under its mask's noise (lattice.undetermined_noise) or no rounder than its best
// rectangle (refinement.round_fit_ratio), one whose fitted lattice
// lies within fit_keep_uncertainty standard errors of theirs, or, without a fit, one whose chords
// give it no lattice. (A fitted lattice is held only to its near neighbours', those whose centres
// are near: the lattice of the walls whose boxes alone come near is the street's, which a
// building with walls of its own need not follow.)
Vec2 outline_lattice(const Vec2& labeled, const FittedLattice& fitted, bool undetermined, const ChordLattice& chord,
                     const NeighbourLattice& neighbours, const LatticeOptions& o, BuildingResult& result) {
  Vec2 lattice = labeled;
  if (fitted.direction && angle_between_lattices_deg(*fitted.direction, lattice) * M_PI / 180.0 > o.fit_keep_uncertainty * fitted.uncertainty)
    lattice = *fitted.direction;
  const Vec2& lent = neighbours.direction;
  if (lent.squaredNorm() > 0) {
    const double gap = angle_between_lattices_deg(lent, lattice) * M_PI / 180.0;
    result.lattice_lent = undetermined || (fitted.direction ? !neighbours.from_boxes && gap <= o.fit_keep_uncertainty * fitted.uncertainty
                                                               : chord.share < o.min_share);
    if (result.lattice_lent) lattice = lent;
  }
  return lattice;
}

// A building whose outline is shorter than lattice.neighbour_noise times its mask's noise, held
// to a lattice of its own while its neighbours agree on one: a wobble as long as the building
// bends its whole blob and turns its walls together, and its lattice with them (a shed of 4 x 2.5 m
// under half a metre of wobble, up to 35 degrees off its street's), where its neighbours' is the
// likelier; but not always (a clean house of 5 x 4 m at 1 m pixels set askew to its street). Its
// outline drawn on its neighbours' lattice (lent) is taken over the one on its own (own) where
// every wall of it lies on that lattice (a wall the chain drew off it says the building is not on
// it) and it explains the contour no worse by the model choice's information criterion, its own
// lattice counted as one parameter more (fitted to the contour, where the lent one is given).
constexpr double kOnLatticeDeg = 0.01;  // a wall drawn on a lattice lies on it but for rounding
bool takes_neighbours_lattice(const std::vector<Ring>& rings, double pixel_size, const CoreOptions& o, double noise_m,
                              const PolygonWithHoles& own, const PolygonWithHoles& lent, const Vec2& lattice) {
  const auto on_lattice = [&lattice](const Ring& ring) {
    for (std::size_t i = 0; i < ring.size(); ++i) {
      const Vec2 e = edge_vector(ring, i);
      if (e.squaredNorm() > 0 && angle_between_lattices_deg(Vec2(-e.y(), e.x()).normalized(), lattice) > kOnLatticeDeg) return false;
    }
    return true;
  };
  if (!on_lattice(lent.outer) || !std::all_of(lent.holes.begin(), lent.holes.end(), on_lattice)) return false;
  return chain::outline_criterion(rings, pixel_size, o, noise_m, lent) <= chain::outline_criterion(rings, pixel_size, o, noise_m, own, 1.0);
}

// The building's outline drawn again on another lattice (own: its labeled building, drawn on its
// own lattice; input and trial as they were before that outline was chosen, trial receiving the
// new one): false where none could be drawn (its budget, or no outline on that lattice), when its
// own outline stands.
bool outline_on_lattice(const chain::LabeledBuilding& own, const Vec2& lattice, const CoreOptions& o,
                        const std::function<bool()>& over_budget, LabelingInput& input, BuildingResult& trial) {
  CornerContext context = own.context;
  context.lattice = lattice;
  try {
    chain::choose_outline({own.rings, own.fit_rings, own.origin, own.pixel_size, own.labels, input, context, own.on_lattice,
                           own.follow_chords, own.fit_spread},
                          o, over_budget, trial);
  } catch (const std::exception&) {
    return false;
  }
  return true;
}

// The building's outline drawn on the lattice with the most labeled contour (lattice_of_support,
// outline_on_lattice), taken over its own outline (result) where it has no more vertices and
// explains the contour better by the model choice's information criterion: both lattices are read
// off the same labels, neither is given.
void take_supported_lattice(const chain::LabeledBuilding& own, const Vec2& supported, const CoreOptions& o,
                            const std::function<bool()>& over_budget, LabelingInput& input, BuildingResult trial,
                            BuildingResult& result) {
  if (!outline_on_lattice(own, supported, o, over_budget, input, trial) ||
      vertex_count(trial.footprint) > vertex_count(result.footprint) ||
      chain::outline_criterion(own.rings, own.pixel_size, o, own.context.noise, trial.footprint) >=
          chain::outline_criterion(own.rings, own.pixel_size, o, own.context.noise, result.footprint))
    return;
  trial.chain_seconds = result.chain_seconds;
  trial.lattice_of_support = true;
  result = std::move(trial);
}

void run_chain(const std::vector<Ring>& rings, double pixel_size, const CoreOptions& o, double noise_floor_m,
               BuildingStart start, BuildingResult& result, const std::function<bool()>& over_budget) {
  if (const std::string problem = contour_problem(rings, o); !problem.empty()) throw StageError("input", problem);
  bool started = start.normals.size() == rings.size();
  for (std::size_t r = 0; started && r < rings.size(); ++r) started = start.normals[r].size() == rings[r].size();
  const NeighbourLattice neighbour_lattice = start.neighbour_lattice;  // (a start made here has none)
  const double mask_rounding = start.mask_rounding_m;                 // (nor this)
  // Each stage's time, charged as it ends, or as the chain leaves it (a stage that throws).
  struct Laps {
    double* stage;
    Clock::time_point lap = Clock::now();
    void next(double* following) {
      const auto now = Clock::now();
      *stage += std::chrono::duration<double>(now - lap).count();
      lap = now;
      stage = following;
    }
    ~Laps() { next(stage); }
  } laps{&result.chain_seconds.start};
  if (!started) start = start_building(rings, pixel_size, o, false, start.smoothing_noise_m, Ring(start.cut));
  laps.next(&result.chain_seconds.labeling);
  LabelingInput input = labeling_input(rings, std::move(start.normals));
  if (over_budget()) throw BudgetExceeded("smoothing", "time budget exceeded");
  EdgeLabels labels = label_directions(rings, pixel_size, o, input);
  // The building's lattice: the labeled main direction, unless the contour's chords gather along
  // a direction of their own (lattice.min_share) and few of them lie along the main one (less
  // than lattice.main_share_ratio of the peak's share): a wobble's flank took the main direction
  // off the walls, and the chords' direction is followed. After labeling again, the main
  // direction stays the lattice where it is near the chords'.
  const ChordLattice& chord = start.chord;
  const Vec2 first_main = main_direction(labels, input.lengths, input.directions);
  const bool follow_chords = chord.share >= o.lattice.min_share &&
                             angle_between_lattices_deg(first_main, chord.direction) > o.lattice.max_gap_deg &&
                             chord.share_at(first_main, o.lattice.window_deg) < o.lattice.main_share_ratio * chord.share;
  const Vec2 lattice = follow_chords ? chord.direction : first_main;
  double arc_noise = 0, regularity_noise = 0;
  const double noise =
      building_noise(rings, input.normals, lattice, follow_chords, start, pixel_size, noise_floor_m, o, &arc_noise, &regularity_noise);
  // The lattice fitted to the contour's runs along it, from the chords' direction where they give
  // one (under a wobble the labeled main direction follows a flank, degrees off the walls); and
  // the spread of those runs about it, which a wobble's flanks do not cut short (the model choice).
  FittedLattice fitted;
  if (o.lattice.fit_max_turn_deg > 0)
    fitted.direction = fit_lattice(rings, input.normals, chord.share >= o.lattice.min_share ? chord.direction : first_main, pixel_size,
                                   o.lattice, o.noise, o.corners.snap_correlation_m, &fitted.uncertainty, &fitted.spread, noise);
  bool undetermined = false;
  const bool on_lattice = holds_to_lattice(rings, input, lattice, pixel_size, noise_floor_m, noise, mask_rounding, o.refinement,
                                           o.lattice.undetermined_noise, &undetermined);
  // (Read as round by its rectangle before its mask's rounding is known: tested again under it,
  // held_under_rounding.)
  if (!on_lattice && o.refinement.round_fit_ratio > 0 && mask_rounding < 0) result.read_round = BuildingResult::ReadRound{lattice, noise};
  result.noise_m = noise;
  result.regularity_noise_m = regularity_noise;
  result.arc_noise_m = arc_noise;
  // Label again: without the directions off the lattice that have no wall of their own, long
  // against the noise about that lattice (a wobble's; their support unknown), then with the
  // labeled support, refined; long runs released to their own directions.
  const auto drop_and_label = [&] {
    if (!on_lattice || !drop_insignificant_directions(rings, labels, input.directions,
                                                      building_lattice(labels, input, follow_chords, chord, o.lattice), noise, o.refinement))
      return false;
    input.support.assign(input.directions.size(), 1.0);
    labels = label_edges(input, o.labeling);
    return true;
  };
  drop_and_label();
  input.support = labeled_support(labels, input.lengths, input.directions.size());
  labels = label_edges(input, o.labeling);
  refine_directions(rings, labels, input.directions, pixel_size, o.refinement);
  if (drop_and_label()) refine_directions(rings, labels, input.directions, pixel_size, o.refinement);  // once more, on the new runs
  release_runs(rings, labels, input.directions, pixel_size, noise, o.refinement);
  if (over_budget()) throw BudgetExceeded("labeling", "time budget exceeded");
  result.directions = input.directions;
  result.labels = labels;
  laps.next(&result.chain_seconds.outline);

  const Vec2 origin = rings[0][0];
  const std::vector<Ring> fit_rings = chain::route_rings(rings, origin, pixel_size, labels, input.directions, o, over_budget, result);
  CornerContext context;
  if (on_lattice)
    context.lattice = outline_lattice(building_lattice(labels, input, follow_chords, chord, o.lattice), fitted, undetermined, chord,
                                      neighbour_lattice, o.lattice, result);
  context.noise = noise;
  context.regularity_noise = regularity_noise;
  context.mask_noise = noise_floor_m;
  context.mask_rounding = mask_rounding;
  // (Its outline on its neighbours' lattice, where it may be on theirs: drawn from the same labels.)
  const bool trial = on_lattice && !result.lattice_lent && neighbour_lattice.direction.squaredNorm() > 0 &&
                     perimeter(rings[0]) < o.lattice.neighbour_noise * noise_floor_m;
  std::optional<LabelingInput> trial_input;
  std::optional<BuildingResult> lent;
  if (trial) trial_input = input, lent = result;
  // (And on the lattice with the most labeled contour, where that is not its own.)
  const std::optional<Vec2> supported =
      on_lattice && !result.lattice_lent
          ? lattice_of_support(labels, input, context.lattice, o.lattice.max_gap_deg, o.lattice.support_turn_deg)
          : std::nullopt;
  std::optional<LabelingInput> supported_input;
  std::optional<BuildingResult> on_supported;
  if (supported) supported_input = input, on_supported = result;
  const chain::LabeledBuilding labeled{rings, fit_rings, origin, pixel_size, labels, input, context, on_lattice, follow_chords, fitted.spread};
  chain::choose_outline(labeled, o, over_budget, result);
  if (supported) take_supported_lattice(labeled, *supported, o, over_budget, *supported_input, std::move(*on_supported), result);
  if (!trial) return;
  lent->lattice_lent = true;
  if (!outline_on_lattice(labeled, neighbour_lattice.direction, o, over_budget, *trial_input, *lent)) return;
  if (takes_neighbours_lattice(rings, pixel_size, o, noise, result.footprint, lent->footprint, neighbour_lattice.direction)) {
    lent->chain_seconds = result.chain_seconds;
    result = std::move(*lent);
  }
}

// The start's noise sample, from its normals and chords.
void measure_sample(const std::vector<Ring>& rings, double pixel_size, const CoreOptions& o, BuildingStart& start) {
  double arc_noise = 0, measured = 0;
  double noise = lattice_noise(rings, start.normals, start.chord.direction, pixel_size, o.noise, &arc_noise, &measured,
                               start.cut.empty() ? nullptr : &start.cut);
  start.chord_noise_m = noise, start.chord_arc_noise_m = arc_noise;
  if (o.models.arc_noise_ratio > 0) noise = std::min(noise, o.models.arc_noise_ratio * arc_noise);
  // Weighed by its perimeter; of a building the raster's edge cuts, by its perimeter inside the raster.
  double weight = perimeter(rings[0]);
  if (!start.cut.empty()) {
    weight = 0;
    for (std::size_t i = 0; i < rings[0].size(); ++i)
      if (point_in_ring(rings[0][i] + 0.5 * edge_vector(rings[0], i), start.cut)) weight += edge_vector(rings[0], i).norm();
  }
  start.sample = measured > 0 && weight > 0 ? NoiseSample{noise, weight} : NoiseSample{};  // (a clean contour may measure 0, and says so)
}

}  // namespace

PolygonWithHoles fallback_footprint(const std::vector<Ring>& rings, double tolerance) {
  PolygonWithHoles simplified, raw;
  for (std::size_t r = 0; r < rings.size(); ++r) {
    Ring ring = remove_degenerate_vertices(douglas_peucker(rings[r], tolerance), 1e-9);
    Ring plain = remove_degenerate_vertices(rings[r], 1e-9);
    if (r == 0) { simplified.outer = std::move(ring); raw.outer = std::move(plain); }
    else { simplified.holes.push_back(std::move(ring)); raw.holes.push_back(std::move(plain)); }
  }
  if (polygon_problem(simplified).empty()) return simplified;
  return raw;
}

BuildingStart start_building(const std::vector<Ring>& rings, double pixel_size, const CoreOptions& o, bool measure_noise,
                             double smoothing_noise_m, const Ring& cut) {
  BuildingStart start;
  start.smoothing_noise_m = smoothing_noise_m;
  start.cut = cut;
  if (!contour_problem(rings, o).empty()) return start;  // (the chain says why)
  for (const Ring& ring : rings) start.normals.push_back(smooth_normals(ring, pixel_size, o.smoothing, smoothing_noise_m));
  start.chord = chord_lattice(rings, o.lattice);
  if (measure_noise) measure_sample(rings, pixel_size, o, start);
  return start;
}

BuildingStart restart_building(const std::vector<Ring>& rings, double pixel_size, const CoreOptions& o, BuildingStart start,
                               double smoothing_noise_m) {
  start.smoothing_noise_m = smoothing_noise_m;
  if (start.normals.size() != rings.size()) return start;
  for (std::size_t r = 0; r < rings.size(); ++r) start.normals[r] = smooth_normals(rings[r], pixel_size, o.smoothing, smoothing_noise_m);
  measure_sample(rings, pixel_size, o, start);
  return start;
}

double pooled_noise_floor(const std::vector<NoiseSample>& samples, const CoreOptions& o) {
  if (o.noise.pooled_floor <= 0) return 0.0;
  std::vector<std::pair<double, double>> weighted;
  for (const NoiseSample& s : samples)
    if (s.weight_m > 0) weighted.emplace_back(s.noise_m, s.weight_m);
  return o.noise.pooled_floor * weighted_quantile(std::move(weighted), 0.5);
}

bool measured_rounding(const BuildingResult& result) {
  return result.ok && result.rounding_corners >= 3;
}

double pooled_rounding(const std::vector<double>& measured_m, const CoreOptions& o) {
  if (o.models.pooled_rounding_share <= 0 || o.models.rounding_noise <= 0) return 0.0;
  std::vector<double> rounded;
  for (double r : measured_m)
    if (r > 0) rounded.push_back(r);
  if (rounded.size() < 3 || double(rounded.size()) < o.models.pooled_rounding_share * double(measured_m.size())) return 0.0;
  const auto middle = rounded.begin() + long(rounded.size() / 2);  // (the upper median of an even count)
  std::nth_element(rounded.begin(), middle, rounded.end());
  return *middle;
}

bool held_under_rounding(const std::vector<Ring>& rings, double pixel_size, const CoreOptions& o, const BuildingResult& result,
                         double mask_rounding_m) {
  return result.ok && result.read_round && resolves_rounding(mask_rounding_m, pixel_size) && !rings.empty() &&
         no_rounder_than_rectangle(rings[0], result.read_round->lattice, pixel_size, result.read_round->noise_m, mask_rounding_m,
                                   o.refinement);
}

void take_mask_rounding(const std::vector<Ring>& rings, double pixel_size, const CoreOptions& o, double mask_rounding_m,
                        BuildingResult& result) {
  result.read_round.reset();  // (judged by held_under_rounding before this)
  // A step under the mask's rounding, its time added to the building's outline time; a failure
  // there leaves the building as its chain drew it.
  const auto under_rounding = [&](const auto& step) {
    const auto start = Clock::now();
    const BuildingResult drawn = result;
    try {
      step();
    } catch (const std::exception&) {
      result = drawn;
    }
    const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
    result.seconds += seconds;
    result.chain_seconds.outline += seconds;
  };
  if (result.before_ellipse) {
    BuildingResult::BeforeEllipse before = std::move(*result.before_ellipse);
    result.before_ellipse.reset();
    if (result.ok && mask_rounding_m > 0)
      under_rounding([&] { chain::ellipse_under_rounding(rings, pixel_size, o, mask_rounding_m, std::move(before), result); });
  }
  if (result.rounding_candidates) {
    BuildingResult::RoundingCandidates kept = std::move(*result.rounding_candidates);
    result.rounding_candidates.reset();
    if (result.ok && mask_rounding_m > 0)
      under_rounding([&] {
        chain::simplify_under_rounding(rings, pixel_size, kept.context, o, mask_rounding_m, std::move(kept.outlines), result);
      });
  }
  if (!result.unsquared) return;
  BuildingResult::Unsquared kept = std::move(*result.unsquared);
  result.unsquared.reset();
  if (!result.ok || mask_rounding_m <= 0) return;
  const auto start = Clock::now();
  kept.context.mask_rounding = mask_rounding_m;
  // (A failure there leaves the building as its chain drew it, without the mask's rounding.)
  PolygonWithHoles drawn = std::move(result.footprint);
  const double own_m = result.rounding_m;
  const int corners = result.rounding_corners;
  const std::string model = result.model;
  result.footprint = std::move(kept.outline);
  try {
    chain::square_and_clean(rings, pixel_size, true, kept.context, o, result);
  } catch (const std::exception&) {
    result.footprint = std::move(drawn);
    result.rounding_m = own_m, result.rounding_corners = corners, result.rounding_pooled = false, result.model = model;
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  result.seconds += seconds;
  result.chain_seconds.outline += seconds;
}

BuildingResult regularize_building(const std::vector<Ring>& rings, double pixel_size, const CoreOptions& o, double noise_floor_m,
                                   BuildingStart started) {
  BuildingResult result;
  const auto start = Clock::now();
  const auto over_budget = [&] {
    return std::chrono::duration<double>(Clock::now() - start).count() > o.budget.max_seconds;
  };
  bool rescue = true;  // a failed chain may still be a rectangle, unless it ran out of time
  try {
    run_chain(rings, pixel_size, o, noise_floor_m, std::move(started), result, over_budget);
  } catch (const BudgetExceeded& e) {
    result.ok = rescue = false;
    result.failed_stage = e.stage;
    result.reason = e.what();
  } catch (const StageError& e) {
    result.ok = false;
    result.failed_stage = e.stage;
    result.reason = e.what();
  } catch (const std::exception& e) {
    result.ok = false;
    result.failed_stage = "internal";
    result.reason = e.what();
  }
  if (!result.ok) {
    // A failed chain on a rectangle-like contour (a building of a few pixels, say): its moment
    // rectangle, when that lies as close to the contour as the Douglas-Peucker fallback does
    // (within fallback_fit_ratio times its mean distance, or fallback_fit_px).
    result.footprint = fallback_footprint(rings, o.fallback.tolerance_m);
    double fit = 0;
    Ring rectangle = rescue && rings.size() == 1 ? best_rectangle(rings[0], result.directions, &fit) : Ring{};
    const double fallback_fit = rectangle.empty() ? 0.0 : mean_distance_to_boundary(rings[0], result.footprint);
    if (!rectangle.empty() && fit <= std::max(o.models.fallback_fit_px * pixel_size, o.models.fallback_fit_ratio * fallback_fit) &&
        polygon_problem({rectangle, {}}).empty()) {
      result.footprint = {std::move(rectangle), {}};
      result.ok = true;
      result.model = "rectangle";
      result.failed_stage.clear();
      result.reason.clear();
    }
  }
  result.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return result;
}

void BuildingResult::count_covered_holes(const std::vector<Ring>& rings) {
  holes_covered = 0, holes_covered_m2 = 0;
  for (const std::size_t r : covered_holes(rings, footprint)) ++holes_covered, holes_covered_m2 += std::abs(signed_area(rings[r]));
}

std::string BuildingResult::remark() const {
  if (!ok) return reason;
  if (holes_covered == 0) return note;
  std::ostringstream text;
  text << (note.empty() ? "" : note + "; ") << "its outline covers " << holes_covered << " hole" << (holes_covered == 1 ? "" : "s")
       << " of the mask (" << std::fixed << std::setprecision(1) << holes_covered_m2 << " m^2)";
  return text.str();
}

const std::vector<std::string>& regularizer_names() {
  static const std::vector<std::string> names = {"deformation", "cgal", "douglas_peucker", "none"};
  return names;
}

BuildingResult regularize_with(const std::string& regularizer, const std::vector<Ring>& rings, double pixel_size,
                               const CoreOptions& options, double noise_floor_m, BuildingStart started) {
  if (regularizer == "deformation") return regularize_building(rings, pixel_size, options, noise_floor_m, std::move(started));
  const auto start = Clock::now();
  BuildingResult result;
  if (rings.empty()) {
    result.ok = false;
    result.failed_stage = "input";
    result.reason = "no contour";
    return result;
  }
  if (regularizer != "cgal" && regularizer != "douglas_peucker" && regularizer != "none")
    throw std::invalid_argument("unknown regularizer '" + regularizer + "'");
  try {
    if (regularizer == "cgal") {
      std::string problem;
      result.footprint = cgal_regularize_contours(rings, options.cgal, &problem);
      if (!problem.empty()) {
        result.ok = false;
        result.failed_stage = "cgal";
        result.reason = problem;
        result.footprint = fallback_footprint(rings, options.fallback.tolerance_m);
      }
    } else {
      result.footprint = fallback_footprint(rings, regularizer == "douglas_peucker" ? options.fallback.tolerance_m : 0.0);
    }
  } catch (const std::exception& e) {  // one building's failure is its own, never the run's
    result.ok = false;
    result.failed_stage = "internal";
    result.reason = e.what();
    result.footprint = fallback_footprint(rings, options.fallback.tolerance_m);
  }
  result.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return result;
}

}  // namespace lodforge
