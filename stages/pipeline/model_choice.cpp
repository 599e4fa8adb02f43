#include "pipeline/model_choice.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <optional>
#include <string>
#include <utility>

#include "directions/refine.hpp"
#include "geometry/polygon.hpp"
#include "models/rectangle.hpp"
#include "models/statistics.hpp"
#include "models/steps.hpp"
#include "pipeline/outlines.hpp"

namespace lodforge::chain {

namespace {

// The boundary noise the model choice allows for (m): as measured, and at least a staircase's;
// at most models.arc_noise_ratio times the noise about parabolas along the same runs (a round
// building's contour lies metres off lattice lines, and that is no noise). regularity: the noise
// its regularity is judged by instead (noise.regularity_ceiling: the lattice outline's and the
// rectangle's tolerances).
double model_noise(const BuildingResult& result, double pixel_size, const ModelOptions& o, bool regularity = false) {
  double noise = regularity ? std::max(result.noise_m, result.regularity_noise_m) : result.noise_m;
  if (o.arc_noise_ratio > 0 && result.arc_noise_m >= 0) noise = std::min(noise, o.arc_noise_ratio * result.arc_noise_m);
  return std::max(noise, o.min_noise_px * pixel_size);
}

// How much worse a simpler outline may explain the contour (mean distance) and still be taken:
// models.lattice_tolerance standard errors of that mean, the noise over the square root of the
// number of independent stretches of contour (of the noise's correlation length) along the rings.
double fit_tolerance(const std::vector<Ring>& rings, double pixel_size, const BuildingResult& result, const CoreOptions& o) {
  const double perimeter_m = total_perimeter(rings);
  const double correlation = noise_correlation_m(o.corners, pixel_size);
  return o.models.lattice_tolerance * model_noise(result, pixel_size, o.models, true) * std::sqrt(correlation / std::max(perimeter_m, correlation));
}

// The staircase's own noise: the RMS distance of a wall's pixel edges from it, a rounding to the
// pixel (uniform over one: its width over the square root of 12).
double staircase_noise(double pixel_size) { return pixel_size / std::sqrt(12.0); }

// How closely an outline that follows the contour's noise lies to it (models.noise_fit): the
// noise's own mean distance (noise_fit noises, a Gaussian's) and the standard errors a simpler
// outline may add to it or to that outline's fit (fit_tolerance). None where noise_fit is off or
// the pixels do not resolve the noise (models.noise_fit_min_px): under a pixel a contour's
// deviations are its staircase and real jogs of a pixel or two, not the noise.
struct NoiseFit {
  double mean, tolerance;
  // The most a simpler outline's mean distance may be beside one that follows the contour at chosen_fit.
  double bound(double chosen_fit) const { return std::max(chosen_fit, mean) + tolerance; }
};
std::optional<NoiseFit> noise_fit(const std::vector<Ring>& rings, double pixel_size, const BuildingResult& result, const CoreOptions& o) {
  const double noise_m = model_noise(result, pixel_size, o.models);
  if (o.models.noise_fit <= 0 || noise_m < o.models.noise_fit_min_px * pixel_size) return std::nullopt;
  return NoiseFit{o.models.noise_fit * noise_m, fit_tolerance(rings, pixel_size, result, o)};
}

// The same at any noise: where the pixels do not resolve it (models.noise_fit_min_px), the noise's
// mean distance that of its part beyond the pixels' staircase (staircase_noise, off in quadrature;
// where they do, the staircase is at most a twelfth of its square, and left in).
std::optional<NoiseFit> noise_fit_beyond_staircase(const std::vector<Ring>& rings, double pixel_size, const BuildingResult& result,
                                                   const CoreOptions& o) {
  if (std::optional<NoiseFit> resolved = noise_fit(rings, pixel_size, result, o)) return resolved;
  if (o.models.noise_fit <= 0) return std::nullopt;
  const double noise_m = model_noise(result, pixel_size, o.models), staircase_m = staircase_noise(pixel_size);
  return NoiseFit{o.models.noise_fit * std::sqrt(std::max(0.0, noise_m * noise_m - staircase_m * staircase_m)),
                  fit_tolerance(rings, pixel_size, result, o)};
}

// Whether an outline leaves a stretch of the contour that a reference outline explains:
// leaves_a_stretch on each ring, the reference's distances computed once.
class StretchGuard {
 public:
  StretchGuard(const std::vector<Ring>& rings, const PolygonWithHoles& reference, double noise, double correlation, double k)
      : rings_(rings), noise_(noise), correlation_(correlation), k_(k) {
    for (const Ring& ring : rings) reference_.push_back(boundary_distances(ring, reference));
  }
  bool leaves_stretch(const PolygonWithHoles& outline) const {
    for (std::size_t r = 0; r < rings_.size(); ++r)
      if (leaves_a_stretch(boundary_distances(rings_[r], outline), reference_[r], noise_, correlation_, k_)) return true;
    return false;
  }

 private:
  const std::vector<Ring>& rings_;
  double noise_, correlation_, k_;
  std::vector<std::vector<std::pair<double, double>>> reference_;
};

// Replaces the chain's outline by the building's moment rectangle when that explains the contour
// (a high percentile, models.rectangle_quantile, of the contour's distances to each) no worse than the outline plus the allowed noise,
// and leaves out no stretch of it that the outline explains (a wing, a notch, an arc's bow)
// unless the outline leaves one the rectangle explains:
// the simplest outline that explains the contour within its noise. (lattice: the rectangle is held
// to it, a building whose own lattice is undetermined; else the best fitting one.)
// rounding: the segmentation's corner rounding (m), when known: the rectangle and the outline are
// compared with the contour as the mask would draw them, their corners rounded so, and a building
// whose every corner the rounding took (a small house read as an octagon) becomes its rectangle
// as a sharp one does.
void choose_rectangle(const std::vector<Ring>& rings, double pixel_size, const CoreOptions& co, BuildingResult& result,
                      const Vec2* lattice = nullptr, double rounding = 0) {
  const ModelOptions& o = co.models;
  // (A triangle and a quadrilateral are tested too, unless the quadrilateral is a rectangle
  // already: a skewed one, or a triangle, a small building's blob read as two or three
  // directions, competes with the rectangle as any outline does.)
  const Ring& outer = result.footprint.outer;
  const auto square = [&outer] {
    for (std::size_t i = 0; i < outer.size(); ++i)
      if (std::abs(turn_deg(edge_vector(outer, (i + outer.size() - 1) % outer.size()), edge_vector(outer, i)) - 90.0) > 1.0) return false;
    return true;
  };
  if (o.rectangle_tolerance <= 0 || rings.size() != 1 || outer.size() < 3 || (outer.size() == 4 && square())) return;
  double mean_fit = 0;  // the best rectangle's mean distance, which chose it
  Ring rectangle = lattice ? moment_rectangle(rings[0], *lattice) : best_rectangle(rings[0], result.directions, &mean_fit);
  if (rectangle.empty()) return;
  // (Under a rounding, the sides moved out of the arcs where that draws the contour nearer.)
  if (rounding > 0) rectangle = rectangle_under_rounding(rings[0], rectangle, rounding);
  PolygonWithHoles candidate{std::move(rectangle), {}};
  const auto outline_distances = boundary_distances(rings[0], rounding > 0 ? rounded_polygon(result.footprint, rounding) : result.footprint);
  const auto rectangle_distances = boundary_distances(rings[0], rounding > 0 ? rounded_polygon(candidate, rounding) : candidate);
  const double outline_fit = weighted_quantile(outline_distances, o.rectangle_quantile);
  const double rectangle_fit = weighted_quantile(rectangle_distances, o.rectangle_quantile);
  const double noise = model_noise(result, pixel_size, o, true);
  if (rectangle_fit > outline_fit + o.rectangle_tolerance * noise) return;
  // (Unless the outline itself leaves a stretch the rectangle explains: then it is no better an
  // explanation, only a more intricate one, as where a chain's outline went astray.)
  const double correlation = noise_correlation_m(co.corners, pixel_size);
  if (o.rectangle_stretch_noise > 0 &&
      leaves_a_stretch(rectangle_distances, outline_distances, noise, correlation, o.rectangle_stretch_noise) &&
      !leaves_a_stretch(outline_distances, rectangle_distances, noise, correlation, o.rectangle_stretch_noise))
    return;
  if (!polygon_problem(candidate).empty()) return;
  result.footprint = std::move(candidate);
  result.model = "rectangle";
}

// n ln(d^2) + k ln(n), n samples of contour: d the mean distance (at least a tenth of a pixel) for
// the standard deviation, two parameters a vertex (an ellipse's five, kEllipseVertices).
double information_criterion(double fit, double vertices, double samples, double pixel_size) {
  fit = std::max(0.1 * pixel_size, fit);
  return samples * std::log(fit * fit) + 2.0 * std::log(samples) * vertices;
}
constexpr double kEllipseVertices = 2.5;

// The criterion's independent samples of the contour: its length over models.coarse_correlation_noise
// times the building's noise (at least a pixel), at least two.
double criterion_samples(const std::vector<Ring>& rings, double pixel_size, const ModelOptions& o, double noise_m) {
  return std::max(2.0, total_perimeter(rings) / std::max(pixel_size, o.coarse_correlation_noise * noise_m));
}

// Round, not a rectangle whose corners the segmentation rounded: the contour's best rectangle
// (the same five parameters as its ellipse; rounded by `rounding` where that is above 0, the
// mask's, as the mask draws it) leaves it ellipse_rectangle_ratio times as far as its ellipse
// (ellipse_fit, mean distances); under a noise taken as the mask's (within) each beyond the
// noise's own mean distance, in quadrature, the ellipse's at least fit_tolerance (at most its
// fit): under a noise that large a blob of a small house lies within the noise of its ellipse
// and of its rectangle alike, and under a rounding of 2 m a house of 5 m is a disc in its mask.
bool round_beyond_rectangle(const std::vector<Ring>& rings, double pixel_size, const CoreOptions& co, const std::optional<NoiseFit>& within,
                            double ellipse_fit, const std::vector<Vec2>& directions, double rounding) {
  const double rectangle_fit = best_rectangle_fit(rings[0], directions, rounding);
  const double noise_mean = within ? within->mean : 0.0;
  const auto beyond_noise = [noise_mean](double fit) { return std::sqrt(std::max(0.0, fit * fit - noise_mean * noise_mean)); };
  const double ellipse_excess = within ? std::min(ellipse_fit, std::max(beyond_noise(ellipse_fit), within->tolerance)) : ellipse_fit;
  return beyond_noise(rectangle_fit) >= co.models.ellipse_rectangle_ratio * ellipse_excess;
}

// A building becomes the ellipse of its contour's moments (models.ellipse_turn_deg) where that
// explains the contour better by an information criterion of the form the simpler outlines compete
// by (five parameters against two a vertex; one sample of contour per models.coarse_correlation_noise
// of the model choice's noise, which arc_noise_ratio bounds on a round building), lies
// ellipse_rectangle_ratio times as near it as its best rectangle, and leaves out no
// stretch of it that the outline explains, unless the outline leaves one the ellipse explains:
// a round or oval building's runs are chords of a few metres, which the curve test does not see
// bow at coarse pixels, and its outline a polygon of a few of them; an octagon's or a pentagon's
// corners lie farther from their ellipse than their polygon's fewer parameters pay for, a small
// house whose corners the segmentation rounded lies about as near its rectangle. mask_rounding:
// its mask's corner rounding where known (round_beyond_rectangle), else 0. Where it takes the
// ellipse, `replaced` (when given) receives the outline it replaced, its model and lattice_lent.
void choose_ellipse(const std::vector<Ring>& rings, double pixel_size, const CoreOptions& co, double mask_noise, double mask_rounding,
                    BuildingResult& result, BuildingResult::BeforeEllipse* replaced = nullptr) {
  const ModelOptions& o = co.models;
  if (o.ellipse_turn_deg <= 0 || rings.size() != 1 || !result.footprint.holes.empty()) return;
  // (The ellipse measured to first order, not drawn: a polygon of 80 vertices, measured as the
  // outlines are, cost a small building a tenth of its time.)
  const auto ellipse_distances = moment_ellipse_distances(rings[0]);
  if (ellipse_distances.empty()) return;
  const auto outline_distances = boundary_distances(rings[0], result.footprint);
  const double noise = model_noise(result, pixel_size, o);
  const double samples = std::max(2.0, total_perimeter(rings) / std::max(pixel_size, o.coarse_correlation_noise * noise));
  const double outline_fit = mean_distance(outline_distances), ellipse_fit = mean_distance(ellipse_distances);
  // Where the noise is its mask's (pooled: mask_noise known), the ellipse is taken too where it
  // explains the contour as the lattice outline must to stand in for an outline that follows the
  // noise (noise_fit, take_lattice_outline_within_noise): a wobble of a wavelength of a few metres
  // around a round building of 60 m has as many lobes as an octagon has sides, which an outline of
  // as many chords follows closer than the noise. (A building's own measure alone is no noise to
  // judge by: an octagon's, its four diagonals off its lattice, is metres.) Also where the pixels
  // do not resolve the noise, its mean distance then that of its part beyond the pixels' staircase
  // (noise_fit_beyond_staircase): under a pixel of noise such a wobble still draws lobes tens of
  // pixels long, which the chords follow, while a mask whose only noise is its staircase measures
  // about that alone and leaves the ellipse to explain the contour as well as the outline (a
  // D-shaped hall at 2 m, its straight wall a polygon's).
  const std::optional<NoiseFit> within = mask_noise > 0 ? noise_fit_beyond_staircase(rings, pixel_size, result, co) : std::nullopt;
  if (!(within && ellipse_fit <= within->bound(outline_fit)) &&
      !(information_criterion(ellipse_fit, kEllipseVertices, samples, pixel_size) <
        information_criterion(outline_fit, double(vertex_count(result.footprint)), samples, pixel_size)))
    return;
  if (!round_beyond_rectangle(rings, pixel_size, co, within, ellipse_fit, result.directions, mask_rounding)) return;
  const double correlation = noise_correlation_m(co.corners, pixel_size);
  if (o.rectangle_stretch_noise > 0 &&
      leaves_a_stretch(ellipse_distances, outline_distances, noise, correlation, o.rectangle_stretch_noise) &&
      !leaves_a_stretch(outline_distances, ellipse_distances, noise, correlation, o.rectangle_stretch_noise))
    return;
  PolygonWithHoles candidate{moment_ellipse(rings[0], o.ellipse_turn_deg), {}};
  if (candidate.outer.empty() || !polygon_problem(candidate).empty()) return;
  if (replaced) {
    replaced->outline = std::move(result.footprint);
    replaced->model = std::move(result.model);
    replaced->lattice_lent = result.lattice_lent;
  }
  result.footprint = std::move(candidate);
  result.model = "ellipse";
  result.lattice_lent = false;  // (no wall of it held to a lattice)
}

// A stretch of contour: edges [first, first + count) of a ring, cyclically.
struct Stretch {
  std::size_t ring;
  int first, count;
};

// The regular outline's walls off the lattice that the lattice outline explains as well: the
// stretches of contour (maximal runs of edges) whose nearest wall of the regular outline lies more
// than near_deg off the lattice, where the lattice outline explains the stretch no worse than the
// regular outline plus `tolerance` (mean distances of its edges) and the lattice labeling draws
// at most two walls along it (its runs within the stretch at least min_run long: an estimate of
// the walls the lattice outline draws there), or, drawing more, no worse than the regular outline.
std::vector<Stretch> lattice_stretches(const std::vector<Ring>& rings, const EdgeLabels& axis_labels, const Vec2& lattice,
                                       const PolygonWithHoles& regular, const PolygonWithHoles& lattice_outline,
                                       double min_run, double near_deg, double tolerance) {
  const double near_cos = std::cos(near_deg * M_PI / 180.0);
  std::vector<int> oblique_wall;  // per edge of the regular outline, numbered as boundary_distances does
  for (const Ring* ring : rings_of(regular))
    for (std::size_t k = 0; k < ring->size(); ++k) {
      const Vec2 e = edge_vector(*ring, k);
      const Vec2 n = e.norm() > 0 ? outward_normal(e) : lattice;
      oblique_wall.push_back(nearest_lattice_axis(n, lattice).dot(n) < near_cos);
    }
  std::vector<Stretch> stretches;
  for (std::size_t r = 0; r < rings.size(); ++r) {
    const Ring& ring = rings[r];
    const int n = int(ring.size());
    std::vector<std::size_t> nearest;
    const auto off_regular = boundary_distances(ring, regular, &nearest);
    if (int(nearest.size()) != n) continue;
    std::vector<int> oblique(n);
    for (int i = 0; i < n; ++i) oblique[i] = oblique_wall[nearest[i]];
    const auto runs = label_runs(oblique);
    if (runs.size() < 2) continue;  // the ring all on the lattice, or all off it: nothing to hold a stretch
    std::vector<std::pair<double, double>> off_lattice;  // computed when a stretch needs them
    for (const auto& [first, count] : runs) {
      if (!oblique[first]) continue;
      if (off_lattice.empty()) off_lattice = boundary_distances(ring, lattice_outline);
      double sum_regular = 0, sum_lattice = 0, length = 0, wall = 0;
      int walls = 0;
      for (int j = 0; j < count; ++j) {
        const int i = (first + j) % n;
        sum_regular += off_regular[i].second * off_regular[i].first;
        sum_lattice += off_lattice[i].second * off_lattice[i].first;
        length += off_regular[i].second;
        wall += off_regular[i].second;
        if (j + 1 == count || axis_labels[r][(i + 1) % n] != axis_labels[r][i]) {
          walls += wall >= min_run;
          wall = 0;
        }
      }
      if (length > 0 && sum_lattice <= sum_regular + (walls <= 2 ? tolerance : 0.0) * length)
        stretches.push_back({r, first, count});
    }
  }
  return stretches;
}

// The contour's rings as one polygon: the first ring outer, the others its holes.
PolygonWithHoles contour_polygon(const std::vector<Ring>& rings) { return {rings[0], {rings.begin() + 1, rings.end()}}; }

// How far the polygon's boundary reaches from the contour (its rings as one polygon): the largest
// distance to it of the points a quarter and three quarters along each of the polygon's edges
// (the midpoints of the edges halved). Not of its vertices: a square corner lies beyond a contour
// the segmentation rounded, and should.
double outline_reach(const PolygonWithHoles& polygon, const PolygonWithHoles& contour) {
  double reach = 0;
  for (const Ring* ring : rings_of(polygon)) {
    Ring halved;
    for (std::size_t i = 0; i < ring->size(); ++i) {
      halved.push_back((*ring)[i]);
      halved.push_back((*ring)[i] + 0.5 * edge_vector(*ring, i));
    }
    for (const auto& [d, length] : boundary_distances(halved, contour)) reach = std::max(reach, d);
  }
  return reach;
}

// True when a ring of the polygon turns by 0.5 to 20 degrees at three vertices in a row (vertices
// that turn less, collinear ones, are passed over): an arc drawn by its chords, whose vertices are
// samples of one curved wall, not corners a criterion should count.
bool has_arc(const PolygonWithHoles& polygon) {
  for (const Ring* r : rings_of(polygon)) {
    const Ring& ring = *r;
    const std::size_t n = ring.size();
    if (n < 3) continue;
    int run = 0;
    for (std::size_t i = 0; i < n + 2; ++i) {
      const Vec2 a = ring[(i + n - 1) % n], b = ring[i % n], c = ring[(i + 1) % n];
      const double turn = turn_deg(b - a, c - b);
      if (turn <= 0.5) continue;
      run = turn < 20.0 ? run + 1 : 0;
      if (run >= 3) return true;
    }
  }
  return false;
}

// The Bayesian information criterion simpler outlines compete by, against the chosen one, and
// the outlines it takes in turn, each the least so far.
class Criterion {
 public:
  // samples: the contour's length over the length of one independent sample of it.
  Criterion(const std::vector<Ring>& rings, double pixel_size, double samples, bool guarded, BuildingResult& result)
      : rings_(rings), pixel_size_(pixel_size), samples_(samples), guarded_(guarded), result_(result) {}
  double of(double fit, std::size_t vertices) const { return information_criterion(fit, double(vertices), samples_, pixel_size_); }
  double of(const PolygonWithHoles& p) const { return of(contour_fit(rings_, p), vertex_count(p)); }
  void start(double chosen) { best_ = chosen; }
  // Whether criterion c is below the least so far; then the outline is taken, with its model's name.
  bool offer(double c) const { return c < best_; }
  void take(PolygonWithHoles p, double c, const char* model) {
    best_ = c;
    if (guarded_) {
      if (!chosen_) chosen_.emplace(result_.footprint, result_.model);
      taken_.emplace_back(p, model);
    }
    result_.footprint = std::move(p);
    result_.model = model;
  }
  // A simpler outline that explains the contour as well on the whole may still leave a stretch
  // of it that the outline chosen before explains (a block's real setbacks drawn as one oblique
  // wall): the last one taken that leaves none stands, else the one chosen before
  // (models.criterion_stretch_noise, as leaves_a_stretch judges a rectangle).
  void settle(double noise, double correlation, double k) {
    if (!chosen_) return;
    const StretchGuard guard(rings_, chosen_->first, noise, correlation, k);
    while (!taken_.empty() && guard.leaves_stretch(taken_.back().first)) taken_.pop_back();
    auto& stands = taken_.empty() ? *chosen_ : taken_.back();
    result_.footprint = std::move(stands.first);
    result_.model = std::move(stands.second);
  }

 private:
  const std::vector<Ring>& rings_;
  double pixel_size_, samples_;
  bool guarded_;  // the outlines taken are held to the one chosen before them (settle)
  BuildingResult& result_;
  double best_ = 0;
  std::optional<std::pair<PolygonWithHoles, std::string>> chosen_;  // the outline chosen before these
  std::vector<std::pair<PolygonWithHoles, std::string>> taken_;
};

// The model choice's state: what the chain hands it (the building, labeled), and what its first
// step leaves the others.
struct ModelChoice : LabeledBuilding {
  const CoreOptions& o;
  const std::function<bool()>& over_budget;
  BuildingResult& result;

  ModelChoice(const LabeledBuilding& b, const CoreOptions& options, const std::function<bool()>& budget, BuildingResult& r)
      : LabeledBuilding(b), o(options), over_budget(budget), result(r) {}

  // The labels the chain's outlines are drawn from: the chain's, or those of relabel_with_missing_axis.
  EdgeLabels relabeled;  // (empty: none)
  const EdgeLabels& chain_labels() const { return relabeled.empty() ? labels : relabeled; }

  // Left by the first outline for the steps after it.
  double min_run_px = 0;  // of the regular outline's runs
  double chosen_fit = -1;  // the chosen outline's contour_fit, -1 while unknown
  double lattice_fit = -1;  // lattice_outline's contour_fit, -1 while unknown
  PolygonWithHoles lattice_outline;
  bool lattice_ok = false;  // lattice_outline was drawn
  EdgeLabels axis_labels;   // the contour labeled among the lattice's four directions (input.directions now)
  std::vector<PolygonWithHoles> coarse_outlines;  // coarse_lattice_outlines, once drawn
  bool coarse_drawn = false;

  void first_outline();
  void relabel_with_missing_axis(const StageProblem& regular_problem, PolygonWithHoles& regular);
  std::vector<std::pair<PolygonWithHoles, std::string>> rounding_candidates();
  const std::vector<PolygonWithHoles>& coarse_lattice_outlines();
  void draw_lattice_outline();
  void take_lattice_outline_if_as_good();
  void take_lattice_outline_within_noise();
  void redraw_stretches();
  void simplify_by_criterion();
  bool offer_lattice_outlines(Criterion& criterion);
  bool offer_staircase_lines(Criterion& criterion);
  void walk_merged_steps(StepPath& path, bool outline_replaced, Criterion& criterion);
};

// Two outlines from the same labels: the regular one (runs shorter than min_run_noise times the
// noise absorbed, walls held to the lattice, steps, curves and cuts judged against the noise) and
// the plain one (the paper's corners with pixel thresholds), and the regular one kept unless it
// explains the contour worse than the plain one by more than the noise allows. (It is also kept
// when it explains the contour within the noise itself: at a few centimetres a pixel, the plain
// outline's thresholds of a few pixels let it follow a wobble of a metre.) Then the lattice
// outline, where it explains the contour about as well with no more vertices, or stands in for a
// chain whose outlines failed.
void ModelChoice::first_outline() {
  const double allowed = o.models.outline_tolerance * model_noise(result, pixel_size, o.models);
  PolygonWithHoles regular, plain;
  min_run_px = regular_min_run_px(o.corners, context.noise, pixel_size);
  bool curved = false;
  const StageProblem regular_problem =
      outline(fit_rings, chain_labels(), input.directions, o.corners, origin, pixel_size, context, min_run_px, regular, &curved);
  if (curved) relabel_with_missing_axis(regular_problem, regular);
  // "Within the noise": the noise, or the spread of the runs along the fitted lattice where more
  // (the noise's runs, cut where a wobble's flank turns past 45 degrees, are shorter than the walls
  // at fine pixels, and their lines follow part of the wobble), bounded as the noise is by the
  // spread about parabolas (an arc's spread is no noise).
  const double within_noise =
      std::max(model_noise(result, pixel_size, o.models),
               o.models.arc_noise_ratio > 0 ? std::min(fit_spread, o.models.arc_noise_ratio * result.arc_noise_m) : fit_spread);
  // A regular outline that explains the contour within the noise is kept whatever the plain one
  // is: that one is drawn only where it may be chosen (it is a good part of the time).
  const double regular_fit = regular_problem.second.empty() ? contour_fit(rings, regular) : -1.0;
  const bool regular_within_noise = regular_fit >= 0 && regular_fit <= o.models.regular_fit_noise * within_noise;
  const StageProblem plain_problem =
      regular_within_noise
          ? StageProblem{}
          : outline(fit_rings, chain_labels(), input.directions, o.corners, origin, pixel_size, CornerContext{}, o.corners.min_run_px, plain);
  draw_lattice_outline();
  // (Each contour fit computed once, when it is needed: they are a good part of the time.)
  if (!regular_problem.second.empty() && !plain_problem.second.empty()) {
    // As a stand-in for a failed chain, the lattice outline must explain the contour within the
    // noise, or as well as the fallback does.
    const double lattice_fit = lattice_ok ? contour_fit(rings, lattice_outline) : 0.0;
    const bool rescues = lattice_ok && (lattice_fit <= o.models.rescue_fit_noise * model_noise(result, pixel_size, o.models) ||
                                        lattice_fit <= contour_fit(rings, fallback_footprint(rings, o.fallback.tolerance_m)) + allowed);
    if (!rescues) throw StageError(regular_problem.first, regular_problem.second);
    result.footprint = std::move(lattice_outline);
    lattice_outline = {};  // (taken: no candidate of its own after this, rounding_candidates)
    result.model = "lattice";
  } else {
    bool regular_wins = regular_within_noise || !plain_problem.second.empty();
    if (regular_wins) {
      chosen_fit = regular_fit;  // (measured above: the regular outline was drawn, the case of both failing is the one before)
    } else if (regular_problem.second.empty()) {
      const double plain_fit = contour_fit(rings, plain);
      regular_wins = regular_fit <= plain_fit + allowed;
      chosen_fit = regular_wins ? regular_fit : plain_fit;
    }
    result.footprint = std::move(regular_wins ? regular : plain);
    result.model = regular_wins ? "regular" : "lines";
    take_lattice_outline_if_as_good();
  }
}

// A building on a lattice whose directions lie along one of its axes alone (refinement.missing_axis_deg),
// whose regular outline keeps a curve drawn without an arc (has_arc: no three vertices in a row
// turning by under 20 degrees, as a round wall's chords do): its ends' runs joined to its long
// walls' (a long thin building whose ends a wobble's flanks hid from the directions), bowing round
// the ends and drawn along the wobble, turning by tens of degrees one way and the other. The other
// axis's two directions are added, the contour labeled again, and the regular outline drawn from
// those labels replaces the curved one where it is valid and has fewer vertices; the outline's
// other steps, and result.directions and labels, then take those labels. (Where it has more, the
// curve was a wall off the lattice, now drawn in steps: it stays.) The whole contour is labeled
// again, from the same support for every direction (the chain's labels came from the labeled
// support and had runs released to their own directions): the outline is judged by its vertices
// alone, not by its fit, which a curve drawn along a wobble always wins; a round end of a few
// metres' radius whose chords turn by more than 20 degrees (no has_arc) would be squared too.
// (Past the time budget, not tried.)
void ModelChoice::relabel_with_missing_axis(const StageProblem& regular_problem, PolygonWithHoles& regular) {
  std::vector<Vec2> directions = input.directions;
  if (!on_lattice || !regular_problem.second.empty() || has_arc(regular) || over_budget() ||
      !add_missing_axis(directions, context.lattice, o.refinement))
    return;
  LabelingInput with_axis = input;
  with_axis.directions = std::move(directions);
  with_axis.support.assign(with_axis.directions.size(), 1.0);
  EdgeLabels labels_with_axis = label_edges(with_axis, o.labeling);
  PolygonWithHoles drawn;
  if (!outline(fit_rings, labels_with_axis, with_axis.directions, o.corners, origin, pixel_size, context, min_run_px, drawn).second.empty() ||
      vertex_count(drawn) >= vertex_count(regular))
    return;
  regular = std::move(drawn);
  input = std::move(with_axis);
  relabeled = std::move(labels_with_axis);
  result.directions = input.directions;
  result.labels = relabeled;
}

// The lattice outline: every wall on the building's lattice (its main direction and quarter
// turns), labeled by the MRF among those four alone. The most regular outline the building can
// have short of a rectangle; it replaces the chain's when it has no more vertices and explains
// the contour about as well (fit_tolerance), and stands in for a chain that failed.
void ModelChoice::draw_lattice_outline() {
  if (!on_lattice || o.models.lattice_tolerance <= 0) return;
  // (The labeling input's last use: its directions become the lattice's, its normals stay.)
  const Vec2 l = context.lattice;
  input.directions = {l, Vec2(-l.y(), l.x()), -l, Vec2(l.y(), -l.x())};
  input.support.assign(4, 1.0);
  axis_labels = label_edges(input, o.labeling);
  lattice_ok = lattice_outline_of(fit_rings, axis_labels, input.directions, o.corners, origin, pixel_size, context, lattice_outline)
                   .second.empty();
}

// The lattice outline in place of the chosen one where it has no more vertices and explains the
// contour about as well (fit_tolerance), or, its lattice from the chords, within the noise.
void ModelChoice::take_lattice_outline_if_as_good() {
  if (!lattice_ok || vertex_count(lattice_outline) > vertex_count(result.footprint)) return;
  if (chosen_fit < 0) chosen_fit = contour_fit(rings, result.footprint);
  lattice_fit = contour_fit(rings, lattice_outline);
  // (A building whose lattice came from its chords: its wobble, which the chosen outline may
  // follow, is what the lattice outline leaves within the noise; a wing it leaves out would
  // cost more than lattice_fit_gap_noise over the chosen outline.)
  const double model_noise_m = model_noise(result, pixel_size, o.models, true);
  const bool lattice_within_noise = follow_chords && vertex_count(lattice_outline) < vertex_count(result.footprint) &&
                                    lattice_fit <= o.models.lattice_fit_noise * model_noise_m &&
                                    lattice_fit <= chosen_fit + o.models.lattice_fit_gap_noise * model_noise_m;
  if (lattice_within_noise || lattice_fit <= chosen_fit + fit_tolerance(rings, pixel_size, result, o)) {
    result.footprint = std::move(lattice_outline);
    lattice_outline = {};  // (taken: no candidate of its own after this, rounding_candidates)
    result.model = "lattice";
  }
}

// The lattice outline in place of a chosen outline with more vertices (neither a rectangle nor
// the lattice outline) that follows the contour closer than the noise would leave it
// (models.noise_fit noises, a Gaussian's mean distance): such an outline follows the noise, and
// the lattice outline explains the contour as well where it lies within the larger of the two
// plus fit_tolerance. Unless it leaves a stretch of contour that the chosen outline explains
// (a wing or a real setback: models.criterion_stretch_noise) or reaches farther from the contour
// than it by models.noise_fit_reach_noise noises (lattice walls meeting beyond an oblique cut). Only
// where the pixels resolve the noise (models.noise_fit_min_px): under a pixel an outline drawn
// closer than the noise follows the staircase and real jogs of a pixel or two, not the noise.
// The noise is the one its steps are judged by (model_noise), the standard errors fit_tolerance's
// (its regularity noise), as lattice_tolerance's are: where the chosen outline lies within 0.8
// noises of the contour, the test before (take_lattice_outline_if_as_good) asked the lattice
// outline for the chosen outline's fit plus those, this one for the noise's own mean distance plus
// them. (A building whose lattice came from its chords has its own test there. An outline that
// draws an arc is not kept from this one, as it is from the information criterion's outlines: the
// stretch guard keeps a real arc; kept from it, 9 sweep rows changed, right angles -0.06 and max
// tangent +1.0 degree summed.)
void ModelChoice::take_lattice_outline_within_noise() {
  // (A lattice outline taken before is cleared: lattice_outline empty.)
  if (!lattice_ok || lattice_outline.outer.empty() || follow_chords || result.model == "rectangle" ||
      vertex_count(lattice_outline) >= vertex_count(result.footprint) || over_budget())
    return;
  const std::optional<NoiseFit> within = noise_fit(rings, pixel_size, result, o);
  if (!within) return;
  const double noise_m = model_noise(result, pixel_size, o.models);
  // (The chosen outline is still the first one, regular or plain: its fit is known, as the
  // lattice outline's is from the test before.)
  if (chosen_fit < 0) chosen_fit = contour_fit(rings, result.footprint);
  if (lattice_fit < 0) lattice_fit = contour_fit(rings, lattice_outline);
  if (lattice_fit > within->bound(chosen_fit)) return;
  if (o.models.criterion_stretch_noise > 0 &&
      StretchGuard(rings, result.footprint, noise_m, noise_correlation_m(o.corners, pixel_size), o.models.criterion_stretch_noise)
          .leaves_stretch(lattice_outline))
    return;
  const PolygonWithHoles contour = contour_polygon(rings);
  if (outline_reach(lattice_outline, contour) > outline_reach(result.footprint, contour) + o.models.noise_fit_reach_noise * noise_m) return;
  result.footprint = std::move(lattice_outline);
  lattice_outline = {};  // (taken: no candidate of its own after this, rounding_candidates)
  result.model = "lattice";
}

// Per stretch of contour, the simpler model where it explains the stretch as well: the regular
// outline's walls off the lattice redrawn with the lattice outline's walls where those explain
// their contour within stretch_fit_noise noises (an oblique cut across a wobble or a notch).
// (Skipped past the time budget: the regular outline stands.)
void ModelChoice::redraw_stretches() {
  if (result.model != "regular" || !lattice_ok || o.models.stretch_fit_noise <= 0 || over_budget()) return;
  const PolygonWithHoles& chosen = result.footprint;
  if (chosen_fit < 0) chosen_fit = contour_fit(rings, chosen);
  // The noise, as the regular outline leaves it where that is less: a shape off any lattice
  // (a hexagon, a disc) measures a large noise about lattice lines.
  const double noise_m = std::max(o.models.min_noise_px * pixel_size, std::min(model_noise(result, pixel_size, o.models), chosen_fit));
  const double tolerance = o.models.stretch_fit_noise * noise_m;
  const std::vector<Stretch> stretches = lattice_stretches(rings, axis_labels, context.lattice, chosen, lattice_outline,
                                                           min_run_px * pixel_size, o.corners.snap_max_deg, tolerance);
  if (stretches.empty()) return;
  // The chain's labels with the stretches' edges labeled as the lattice labeling has them
  // (the chain's directions, then the lattice's four).
  EdgeLabels mixed = chain_labels();
  for (const Stretch& s : stretches)
    for (int j = 0; j < s.count; ++j) {
      const std::size_t i = (s.first + j) % rings[s.ring].size();
      mixed[s.ring][i] = int(result.directions.size()) + axis_labels[s.ring][i];
    }
  std::vector<Vec2> mixed_directions = result.directions;
  mixed_directions.insert(mixed_directions.end(), input.directions.begin(), input.directions.end());
  // Taken when it is a valid polygon that explains the contour within the tolerance of the
  // regular outline and reaches no farther from it than that plus the noise (lines of the
  // lattice meeting beyond the contour). It keeps the name "regular".
  PolygonWithHoles candidate;
  if (!outline(fit_rings, mixed, mixed_directions, o.corners, origin, pixel_size, context, min_run_px, candidate).second.empty() ||
      contour_fit(rings, candidate) > chosen_fit + tolerance)
    return;
  const PolygonWithHoles contour = contour_polygon(rings);
  if (outline_reach(candidate, contour) <= outline_reach(chosen, contour) + noise_m) result.footprint = std::move(candidate);
}

// Other outlines against the chosen one, by a Bayesian information criterion: the lattice
// outline, as drawn and as if the noise were coarse_scale and its square times as large
// (models.coarse_scale), the outline with its staircases drawn as oblique walls
// (models.staircase_corners), and the path of its steps merged one at a time
// (models.merge_patience). A wobble whose wavelength is a few times its amplitude cuts the
// contour into a run at each flank, the noise measured about those runs is too low, and the
// outline keeps the wobble's crests as notches; the criterion weighs the fit against the
// vertices rather than against that noise (which only sets how long a sample of contour is), and
// finds that the coarser square outline, or the outline with its smaller steps merged, explains
// the contour about as well. The chain's own outline drawn coarser does not compete (it also
// dropped real steps of a metre between row houses under a noise that large), nor does anything
// against an arc. (Skipped past the time budget, as the stretches above.)
void ModelChoice::simplify_by_criterion() {
  if (!(o.models.coarse_scale > 1 || o.models.merge_patience > 0 || o.models.staircase_corners > 0) || !lattice_ok ||
      vertex_count(result.footprint) <= 4 || has_arc(result.footprint) || over_budget())
    return;
  Criterion criterion(rings, pixel_size, criterion_samples(rings, pixel_size, o.models, context.noise), o.models.criterion_stretch_noise > 0,
                      result);
  // (The merge path measures the chosen outline's fit, as contour_fit does, for the walk below:
  // made first, it gives the criterion's start, and is made again only if another outline wins.)
  std::optional<StepPath> path;
  if (o.models.merge_patience > 0) path.emplace(rings, result.footprint, o.models.merge_parallel_deg);
  criterion.start(path ? criterion.of(path->fit(), vertex_count(result.footprint)) : criterion.of(result.footprint));
  const bool coarse = offer_lattice_outlines(criterion);
  const bool lines = offer_staircase_lines(criterion);
  if (path) walk_merged_steps(*path, coarse || lines, criterion);
  criterion.settle(model_noise(result, pixel_size, o.models), noise_correlation_m(o.corners, pixel_size), o.models.criterion_stretch_noise);
}

// The lattice outline, and the lattice outline drawn as if the noise were coarse_scale and its
// square times as large, offered to the criterion whatever their vertices (lattice_more_vertices):
// a more regular outline with more of them is taken where it explains the contour enough better
// (a block's rear annexes, steps of a metre or two, drawn as square steps where the chain's
// outline cut a diagonal across them, or drew them as the plain lines at coarse pixels). Whether
// one was taken.
bool ModelChoice::offer_lattice_outlines(Criterion& criterion) {
  if (o.models.coarse_scale <= 1) return false;
  bool taken = false;
  const auto offer = [&](const PolygonWithHoles& drawn, const char* model) {
    if (!o.models.lattice_more_vertices && vertex_count(drawn) >= vertex_count(result.footprint)) return;
    const double c = criterion.of(drawn);
    if (criterion.offer(c)) {
      criterion.take(drawn, c, model);
      taken = true;
    }
  };
  // (A lattice outline taken before is cleared: lattice_outline empty. With lattice_more_vertices
  // off, the coarse ones alone compete, those with fewer vertices.)
  if (!lattice_outline.outer.empty() && o.models.lattice_more_vertices) offer(lattice_outline, "lattice");
  for (const PolygonWithHoles& drawn : coarse_lattice_outlines()) offer(drawn, "coarse_lattice");
  return taken;
}

// The lattice outline drawn as if the noise were coarse_scale and its square times as large (those
// drawn), drawn once.
const std::vector<PolygonWithHoles>& ModelChoice::coarse_lattice_outlines() {
  if (coarse_drawn) return coarse_outlines;
  coarse_drawn = true;
  double scale = 1;
  for (int k = 0; k < 2 && o.models.coarse_scale > 1; ++k) {
    scale *= o.models.coarse_scale;
    CornerContext coarse = context;
    coarse.noise = scale * context.noise;
    coarse.regularity_noise = scale * context.regularity_noise;
    coarse.mask_noise = scale * context.mask_noise;
    PolygonWithHoles candidate;
    if (lattice_outline_of(fit_rings, axis_labels, input.directions, o.corners, origin, pixel_size, coarse, candidate).second.empty())
      coarse_outlines.push_back(std::move(candidate));
  }
  return coarse_outlines;
}

// A staircase drawn as the oblique wall it follows (a corner cut at an angle to the lattice,
// which the lattice outlines draw in steps, and the merges below would make a square notch).
// Whether it was taken.
bool ModelChoice::offer_staircase_lines(Criterion& criterion) {
  if (o.models.staircase_corners <= 0) return false;
  std::optional<PolygonWithHoles> lines = staircases_as_lines(result.footprint, o.models.staircase_corners, o.models.staircase_square_deg);
  if (!lines) return false;
  const double c = criterion.of(*lines);
  if (!criterion.offer(c) || !polygon_problem(*lines).empty()) return false;
  criterion.take(std::move(*lines), c, "staircase_lines");
  return true;
}

// The path of ever simpler outlines, the cheapest step merged at each (made again from the outline
// taken, where one was): its criterion is not monotone (a merge moves a wall to the mean of two),
// so the walk goes on until merge_patience merges have passed without a new least, and keeps the
// least among its valid polygons.
void ModelChoice::walk_merged_steps(StepPath& path, bool outline_replaced, Criterion& criterion) {
  if (outline_replaced) path = StepPath(rings, result.footprint, o.models.merge_parallel_deg);
  for (int since_best = 0; since_best < o.models.merge_patience && !over_budget() && path.merge_next();) {
    const double c = criterion.of(path.fit(), vertex_count(path.outline()));
    if (criterion.offer(c) && polygon_problem(path.outline()).empty()) {
      criterion.take(path.outline(), c, "merged_steps");
      since_best = 0;
    } else {
      ++since_best;
    }
  }
}

// The outlines that compete with the chosen one under its mask's rounding (simplify_under_rounding):
// the lattice outline, unless it was taken (cleared then), and those drawn as if the noise were
// coarse_scale and its square times as large.
std::vector<std::pair<PolygonWithHoles, std::string>> ModelChoice::rounding_candidates() {
  std::vector<std::pair<PolygonWithHoles, std::string>> candidates;
  if (!lattice_ok) return candidates;
  if (!lattice_outline.outer.empty()) candidates.emplace_back(lattice_outline, "lattice");
  for (const PolygonWithHoles& drawn : coarse_lattice_outlines()) candidates.emplace_back(drawn, "coarse_lattice");
  return candidates;
}

// The outline's chains of walls off its lattice up to max_chain long squared, whatever the noise
// (square_connectors, between walls on the lattice at least two pixels and the noise's correlation
// length long): the squaring under a rounding of max_chain / 2; none where nothing is squared.
std::optional<PolygonWithHoles> square_rounded_chains(const PolygonWithHoles& outline, double pixel_size, const CornerContext& context,
                                                      const CoreOptions& o, double max_chain) {
  const double correlation = noise_correlation_m(o.corners, pixel_size);
  return square_connectors(outline, context.lattice, o.models.merge_parallel_deg, context.noise, correlation, 0.0, max_chain,
                           std::max(2 * pixel_size, correlation));
}

}  // namespace

void simplify_under_rounding(const std::vector<Ring>& rings, double pixel_size, const CornerContext& context, const CoreOptions& o,
                             double rounding, std::vector<std::pair<PolygonWithHoles, std::string>> candidates, BuildingResult& result) {
  if (!(rounding > 0) || !(o.models.rounded_criterion > 0) || candidates.empty()) return;
  CornerContext rounded_context = context;
  rounded_context.mask_rounding = rounding;
  // And the chosen outline with its chains off the lattice squared as if the rounding were
  // rounded_chain_scale times as large (square_and_clean's squaring, with chains that long).
  if (o.models.rounded_chain_scale > 1 && context.lattice.squaredNorm() > 0)
    if (std::optional<PolygonWithHoles> squared =
            square_rounded_chains(result.footprint, pixel_size, context, o, 2 * o.models.rounded_chain_scale * rounding))
      candidates.emplace_back(std::move(*squared), result.model);
  const double correlation =
      std::max({pixel_size, o.models.coarse_correlation_noise * context.noise, o.models.rounded_criterion * rounding});
  const double samples = std::max(2.0, total_perimeter(rings) / correlation);
  // Each contour ring's distances to an outline rounded so (boundary_distances; the guard below
  // reads them too), the criterion from their mean (contour_fit).
  using Distances = std::vector<std::vector<std::pair<double, double>>>;
  const auto distances = [&](const PolygonWithHoles& p) {
    const PolygonWithHoles rounded = rounded_polygon(p, rounding);
    Distances d;
    for (const Ring& ring : rings) d.push_back(boundary_distances(ring, rounded));
    return d;
  };
  const auto criterion = [&](const Distances& d, std::size_t vertices) {
    return information_criterion(contour_fit(rings, d), double(vertices), samples, pixel_size);
  };
  const Distances chosen = distances(result.footprint);
  double best = criterion(chosen, vertex_count(result.footprint));
  std::optional<BuildingResult> taken;
  Distances taken_distances;
  // (One drawn the same as one before it passed over: the coarser lattice outlines often are.)
  const auto same = [](const PolygonWithHoles& a, const PolygonWithHoles& b) { return a.outer == b.outer && a.holes == b.holes; };
  for (std::size_t k = candidates.size(); k-- > 1;)
    if (std::any_of(candidates.begin(), candidates.begin() + long(k), [&](const auto& c) { return same(c.first, candidates[k].first); }))
      candidates.erase(candidates.begin() + long(k));
  for (auto& [outline, model] : candidates) {
    // (Each squared and cleaned as the chosen one was, under the same rounding.)
    BuildingResult cleaned = result;
    cleaned.footprint = std::move(outline);
    cleaned.model = model;
    square_and_clean(rings, pixel_size, true, rounded_context, o, cleaned);
    if (cleaned.footprint.outer.empty()) continue;
    Distances d = distances(cleaned.footprint);
    const double c = criterion(d, vertex_count(cleaned.footprint));
    if (c < best && polygon_problem(cleaned.footprint).empty()) {
      best = c;
      taken = std::move(cleaned);
      taken_distances = std::move(d);
    }
  }
  if (!taken) return;
  // None that leaves a stretch of contour the chosen outline explains (models.rounded_stretch_noise).
  if (o.models.rounded_stretch_noise > 0) {
    const double noise = model_noise(result, pixel_size, o.models);
    for (std::size_t r = 0; r < rings.size(); ++r)
      if (leaves_a_stretch(taken_distances[r], chosen[r], noise, correlation, o.models.rounded_stretch_noise)) return;
  }
  result.footprint = std::move(taken->footprint);
  result.model = std::move(taken->model);
  result.rounding_m = taken->rounding_m, result.rounding_corners = taken->rounding_corners, result.rounding_pooled = taken->rounding_pooled;
}

void ellipse_under_rounding(const std::vector<Ring>& rings, double pixel_size, const CoreOptions& o, double rounding,
                            BuildingResult::BeforeEllipse before, BuildingResult& result) {
  if (result.model != "ellipse" || !(rounding > 0) || rings.size() != 1) return;
  const std::optional<NoiseFit> within =
      before.context.mask_noise > 0 ? noise_fit_beyond_staircase(rings, pixel_size, result, o) : std::nullopt;
  if (round_beyond_rectangle(rings, pixel_size, o, within, mean_distance(moment_ellipse_distances(rings[0])), result.directions, rounding))
    return;
  result.footprint = std::move(before.outline);
  result.model = std::move(before.model);
  result.lattice_lent = before.lattice_lent;
  before.context.mask_rounding = rounding;
  square_and_clean(rings, pixel_size, before.on_lattice, before.context, o, result);
}

void choose_outline(const LabeledBuilding& b, const CoreOptions& o, const std::function<bool()>& over_budget,
                    BuildingResult& result) {
  ModelChoice choice(b, o, over_budget, result);
  choice.first_outline();
  if (b.on_lattice)  // (a round shape is no rectangle)
    choose_rectangle(b.rings, b.pixel_size, o, result, result.lattice_lent ? &b.context.lattice : nullptr);
  choice.take_lattice_outline_within_noise();
  choice.redraw_stretches();
  choice.simplify_by_criterion();
  // (Also on a lattice: a wobble's flanks turn a round building's normals back and forth, and
  // it reads as on a lattice; not one too short to show its shape.)
  // (Past the time budget, not tried.)
  if ((!b.on_lattice || !too_short_to_show_round(perimeter(b.rings[0]), b.pixel_size, b.context.mask_noise, o.refinement)) &&
      !over_budget()) {
    // (Its mask's rounding not known yet: the outline the ellipse replaces kept for
    // take_mask_rounding, which compares the ellipse with the rectangle rounded so.)
    BuildingResult::BeforeEllipse replaced;
    choose_ellipse(b.rings, b.pixel_size, o, b.context.mask_noise, std::max(0.0, b.context.mask_rounding), result, &replaced);
    if (b.context.mask_rounding < 0 && result.model == "ellipse") {
      replaced.context = b.context;
      replaced.on_lattice = b.on_lattice;
      result.before_ellipse = std::move(replaced);
    }
  }
  const bool on_lattice = b.on_lattice && result.model != "ellipse";
  // (Its mask's rounding not known yet: the outline kept for take_mask_rounding, where it measures
  // none of its own and could take one.)
  std::optional<PolygonWithHoles> chosen;
  if (b.context.mask_rounding < 0 && on_lattice) chosen = result.footprint;
  square_and_clean(b.rings, b.pixel_size, on_lattice, b.context, o, result);
  if (chosen && result.rounding_corners >= 0 && result.rounding_m == 0)
    result.unsquared = BuildingResult::Unsquared{std::move(*chosen), b.context};
  // Where it measures a rounding of its own, the lattice outlines against the chosen one under
  // its mask's rounding: now where that is known, else kept for take_mask_rounding.
  if (on_lattice && o.models.rounded_criterion > 0 && result.rounding_m > 0 && !result.rounding_pooled && b.context.mask_rounding != 0 &&
      !over_budget()) {
    std::vector<std::pair<PolygonWithHoles, std::string>> candidates = choice.rounding_candidates();
    if (b.context.mask_rounding > 0) {
      // (A failure there leaves the outline as chosen, as take_mask_rounding's does.)
      const BuildingResult chosen_result = result;
      try {
        simplify_under_rounding(b.rings, b.pixel_size, b.context, o, b.context.mask_rounding, std::move(candidates), result);
      } catch (const std::exception&) {
        result = chosen_result;
      }
    } else if (!candidates.empty()) {
      result.rounding_candidates = BuildingResult::RoundingCandidates{std::move(candidates), b.context};
    }
  }
}

void square_and_clean(const std::vector<Ring>& rings, double pixel_size, bool on_lattice, const CornerContext& context,
                      const CoreOptions& o, BuildingResult& result) {
  // How far the segmentation rounded the building's corners, where more than its noise explains
  // (models.rounding_noise): its square corners lie R (sqrt 2 - 1) off the contour. (Corners of
  // walls at least two pixels and the noise's correlation length long, whose directions the
  // noise leaves defined.) Measured on the outline as chosen, also where it draws an arc: the
  // squarings below are local (a chain between two walls on the lattice, at most twice the
  // rounding long, or one wall the noise does not tell from the lattice), and a network's blur
  // draws a large building's roundings and steps as runs of small turns that read as an arc.
  const double correlation = noise_correlation_m(o.corners, pixel_size);
  const double min_wall = std::max(2 * pixel_size, correlation);
  double rounding_radius = 0;
  if (on_lattice && o.models.rounding_noise > 0) {
    std::size_t corners = 0;
    rounding_radius = corner_rounding_gap(result.footprint, rings, min_wall, o.corners.max_cut_m, o.corners.parallel_angle_deg,
                                          o.models.rounding_noise * context.noise, &corners) /
                      (std::sqrt(2.0) - 1);
    result.rounding_corners = int(corners);
  }
  result.rounding_m = rounding_radius;
  // None of its own (too few square corners, or sharp within its noise): its mask's, where the
  // mask's buildings measured one (models.pooled_rounding_share; a network rounds them alike).
  if (on_lattice && rounding_radius == 0 && context.mask_rounding > 0 && o.models.rounding_noise > 0) {
    rounding_radius = context.mask_rounding;
    result.rounding_pooled = true;
  }
  // The short oblique walls between two walls on the lattice that the noise does not tell from it:
  // square steps and corners (models.square_noise).
  if (on_lattice && o.models.square_noise > 0)
    if (std::optional<PolygonWithHoles> squared =
            square_connectors(result.footprint, context.lattice, o.models.merge_parallel_deg, context.regularity(), correlation,
                              o.models.square_noise, 0.0, min_wall))
      result.footprint = std::move(*squared);
  // The corners the segmentation rounded made sharp, where most of the building's are
  // (models.rounded_share; under a measured rounding, roundings up to 2.5 radii long too); on an
  // outline that draws an arc (a building rounded by design) only under a known rounding, the
  // building's or its mask's: its roundings of square corners are then the mask's (a blur draws
  // them as staircases of steps a few pixels high), and its arcs' chords meet at no square corner.
  if (rounding_radius > 0 || !has_arc(result.footprint))
    if (std::optional<PolygonWithHoles> sharp =
            sharpen_rounded_corners(result.footprint, o.corners.max_cut_m, o.corners.parallel_angle_deg, o.models.rounded_share,
                                    rounding_radius))
      result.footprint = std::move(*sharp);
  // Then, under a rounding (only an outline on the lattice has one), the chains of walls off the
  // lattice up to twice its radius long, whatever the noise: the rounded steps and the corners the
  // rules before left; and the building's rectangle compared with the contour rounded as the mask
  // rounds it: a small house whose every corner the rounding took, read as an octagon.
  if (rounding_radius > 0) {
    // (First the treads of its steps, turned onto the lattice: their risers are such chains then.)
    if (o.models.tread_rounding > 0)
      if (std::optional<PolygonWithHoles> leveled = level_rounded_treads(result.footprint, context.lattice, o.models.merge_parallel_deg,
                                                                          rounding_radius, o.models.tread_rounding))
        result.footprint = std::move(*leveled);
    if (std::optional<PolygonWithHoles> squared = square_rounded_chains(result.footprint, pixel_size, context, o, 2 * rounding_radius))
      result.footprint = std::move(*squared);
    choose_rectangle(rings, pixel_size, o, result, &context.lattice, rounding_radius);
  }
  // Last of all, the needles where two walls' lines met past the end of one (models.spike_deg).
  // (remove_spikes keeps the outline valid; the collinear vertices it may leave are dropped where
  // that keeps it valid too.)
  if (o.models.spike_deg > 0 &&
      remove_spikes(result.footprint, o.models.spike_deg, std::max(pixel_size, o.models.spike_noise * context.noise)) > 0) {
    PolygonWithHoles cleaned = result.footprint;
    cleaned.outer = remove_degenerate_vertices(cleaned.outer, 1e-3 * pixel_size);
    for (Ring& hole : cleaned.holes) hole = remove_degenerate_vertices(hole, 1e-3 * pixel_size);
    if (polygon_problem(cleaned).empty()) result.footprint = std::move(cleaned);
  }
}


double outline_criterion(const std::vector<Ring>& rings, double pixel_size, const CoreOptions& o, double noise_m,
                         const PolygonWithHoles& outline, double parameters) {
  // (Two parameters a vertex.)
  return information_criterion(contour_fit(rings, outline), double(vertex_count(outline)) + 0.5 * parameters,
                               criterion_samples(rings, pixel_size, o.models, noise_m), pixel_size);
}

}  // namespace lodforge::chain
