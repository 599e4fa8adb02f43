#include "pipeline/building.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "corners/corners.hpp"
#include "deformation/deform.hpp"
#include "directions/lattice.hpp"
#include "directions/ransac.hpp"
#include "directions/refine.hpp"
#include "geometry/polygon.hpp"
#include "labeling/mrf.hpp"
#include "models/noise.hpp"
#include "models/rectangle.hpp"
#include "models/statistics.hpp"
#include "models/steps.hpp"
#include "normals/smoothing.hpp"
#include "peers/cgal_contours.hpp"
#include "triangulation/triangulate.hpp"

namespace lodforge {

namespace {

// A stage failure: which stage and why.
struct StageError : std::runtime_error {
  StageError(std::string stage_name, const std::string& why) : std::runtime_error(why), stage(std::move(stage_name)) {}
  std::string stage;
};

// A building over its time budget: it gets the fallback, not another model (the budget is a
// safety net for pathological contours).
struct BudgetExceeded : StageError {
  using StageError::StageError;
};

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

std::vector<Ring> translate(const std::vector<Ring>& rings, const Vec2& offset, double scale) {
  std::vector<Ring> out = rings;
  for (Ring& ring : out) for (Vec2& p : ring) p = (p - offset) / scale;
  return out;
}

// The rings with each labeled run simplified by Douglas–Peucker (run ends kept): which vertices
// stay, per ring. Everything is kept when the simplified rings would not be a valid polygon.
std::vector<std::vector<char>> coarse_vertices(const std::vector<Ring>& rings, const EdgeLabels& labels, double tolerance) {
  std::vector<std::vector<char>> kept(rings.size());
  for (std::size_t r = 0; r < rings.size(); ++r) kept[r].assign(rings[r].size(), 1);
  if (tolerance <= 0) return kept;
  PolygonWithHoles coarse;
  for (std::size_t r = 0; r < rings.size(); ++r) {
    const Ring& ring = rings[r];
    const auto runs = label_runs(labels[r]);
    if (runs.size() < 2) {  // kept whole, and checked with the others
      (r == 0 ? coarse.outer : coarse.holes.emplace_back()) = ring;
      continue;
    }
    kept[r].assign(ring.size(), 0);
    for (auto [first, count] : runs) {
      std::vector<Vec2> points;
      for (int k = 0; k <= count; ++k) points.push_back(ring[(first + k) % ring.size()]);
      const std::vector<char> keep = douglas_peucker_open(points, tolerance);
      for (int k = 0; k < count; ++k) if (keep[k]) kept[r][(first + k) % ring.size()] = 1;
    }
    Ring simplified;
    for (std::size_t i = 0; i < ring.size(); ++i) if (kept[r][i]) simplified.push_back(ring[i]);
    (r == 0 ? coarse.outer : coarse.holes.emplace_back()) = std::move(simplified);
  }
  if (!polygon_problem(coarse).empty())
    for (std::size_t r = 0; r < rings.size(); ++r) kept[r].assign(rings[r].size(), 1);
  return kept;
}

// A deformation that did not finish within its budget: the building takes the original route.
struct DeformationSkipped : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::size_t kept_count(const std::vector<std::vector<char>>& kept) {
  std::size_t n = 0;
  for (const auto& ring : kept) for (char k : ring) n += k;
  return n;
}

// The deformed positions of every ring vertex (pixel units in, pixel units out). The mesh is
// built on the rings simplified per labeled run (options.deformation.simplify_px); a removed
// vertex follows its simplified edge, at its arc-length position along the original run.
// The mesh is bounded (budget.max_mesh_vertices): runs are simplified further and triangles
// made larger until about that many vertices remain, so a fine raster (0.1 m) meshes a house
// as coarsely as a 0.5 m one; the Newton iterations are bounded by budget.max_deformation_work.
std::vector<Ring> deform_rings(const std::vector<Ring>& rings_px, const EdgeLabels& labels,
                               const std::vector<Vec2>& directions, const CoreOptions& o,
                               const std::function<bool()>& over_budget, BuildingResult& result) {
  const int max_vertices = o.budget.max_mesh_vertices;
  double tolerance = o.deformation.simplify_px;
  auto kept = coarse_vertices(rings_px, labels, tolerance);
  // Half of the mesh's vertices at most on its boundary; the tolerance doubles (at most to
  // 64 px, where every run is its two ends).
  while (max_vertices > 0 && kept_count(kept) > std::size_t(max_vertices / 2) && tolerance < 64) {
    tolerance = std::max(2 * tolerance, 1.0);
    kept = coarse_vertices(rings_px, labels, tolerance);
  }
  std::vector<Ring> coarse(rings_px.size());
  EdgeLabels coarse_labels(rings_px.size());
  for (std::size_t r = 0; r < rings_px.size(); ++r)
    for (std::size_t i = 0; i < rings_px[r].size(); ++i)
      if (kept[r][i]) {
        coarse[r].push_back(rings_px[r][i]);
        coarse_labels[r].push_back(labels[r][i]);  // the edge from a kept vertex lies in one run
      }
  // A refined mesh of longest edge h has about area / (kMeshDensity h^2) interior vertices.
  constexpr double kMeshDensity = 0.25;
  double size_bound = o.triangulation.size_bound_px;
  if (max_vertices > 0) {
    double area_px = signed_area(coarse[0]);
    for (std::size_t r = 1; r < coarse.size(); ++r) area_px += signed_area(coarse[r]);
    const double interior = std::max(double(max_vertices) - double(kept_count(kept)), max_vertices / 2.0);
    size_bound = std::max(size_bound, std::sqrt(std::abs(area_px) / (kMeshDensity * interior)));
  }
  TriangleMesh mesh;
  try {
    mesh = triangulate(coarse, size_bound, o.triangulation);
  } catch (const std::exception& e) {
    throw StageError("triangulation", e.what());
  }
  std::vector<Vec2> targets;
  for (const BoundaryEdge& b : mesh.boundary) targets.push_back(directions[coarse_labels[b.ring][b.edge]]);
  // The work budget counts Newton iterations (one stop check each) times the mesh's vertices.
  const double vertices = double(mesh.vertices.size());
  double work = 0;
  bool over_work = false;
  const auto stop = [&] {
    work += vertices;
    over_work = o.budget.max_deformation_work > 0 && work > o.budget.max_deformation_work;
    return over_work || over_budget();
  };
  const DeformationResult d = deform(mesh, targets, o.deformation, stop);
  result.mesh_vertices = int(mesh.vertices.size());
  if (d.stopped)
    throw DeformationSkipped(over_work ? "deformation stopped after budget.max_deformation_work = " + std::to_string(long(o.budget.max_deformation_work)) +
                                             " vertex-iterations (mesh of " + std::to_string(mesh.vertices.size()) + " vertices)"
                                       : "deformation stopped at the time budget of " + std::to_string(o.budget.max_seconds) + " s");
  result.alignment_rms_deg = d.rms_deg;
  result.alignment_max_deg = d.max_deg;
  result.deformation_iterations = d.iterations;
  std::vector<Ring> out = rings_px;
  for (std::size_t r = 0; r < out.size(); ++r) {
    const Ring& ring = rings_px[r];
    const std::size_t n = ring.size();
    std::vector<int> coarse_index(n, -1);
    for (std::size_t i = 0, c = 0; i < n; ++i) if (kept[r][i]) coarse_index[i] = int(c++);
    for (std::size_t i = 0; i < n; ++i) {
      if (!kept[r][i]) continue;
      std::size_t j = (i + 1) % n;  // the next kept vertex
      while (!kept[r][j]) j = (j + 1) % n;
      const Vec2 a = d.vertices[mesh.ring_vertex[r][coarse_index[i]]], b = d.vertices[mesh.ring_vertex[r][coarse_index[j]]];
      out[r][i] = a;
      double total = 0;
      for (std::size_t k = i; k != j; k = (k + 1) % n) total += edge_vector(ring, k).norm();
      double along = 0;
      for (std::size_t k = (i + 1) % n; k != j; k = (k + 1) % n) {
        along += edge_vector(ring, (k + n - 1) % n).norm();
        out[r][k] = a + (total > 0 ? along / total : 0.0) * (b - a);
      }
    }
  }
  return out;
}

// rings: in a local frame (metres, less origin). Lengths of the options are in metres or pixels.
PolygonWithHoles corner_polygon(const std::vector<Ring>& rings, const EdgeLabels& labels,
                                const std::vector<Vec2>& directions, const CornerOptions& options, const Vec2& origin,
                                double pixel_size, const CornerContext& context) {
  PolygonWithHoles footprint;
  for (std::size_t r = 0; r < rings.size(); ++r) {
    std::string problem;
    Ring ring = extract_corners(rings[r], labels[r], directions, pixel_size, options, &problem, context);
    if (ring.empty()) throw StageError("corners", (r == 0 ? "outer ring: " : "hole " + std::to_string(r - 1) + ": ") + problem);
    // Where two corner lines overshoot past each other, the ring crosses itself in a thin loop.
    if (options.untangle_noise > 0 && !ring_problem(ring).empty())
      untangle(ring, options.untangle_noise * std::max(pixel_size, context.noise));
    for (Vec2& p : ring) p += origin;
    if (r == 0) footprint.outer = std::move(ring);
    else footprint.holes.push_back(std::move(ring));
  }
  return footprint;
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

using StageProblem = std::pair<std::string, std::string>;  // stage, problem (empty: none)

// The corner polygon of the rings (metres from origin) at a context, validated: an invalid polygon
// is retried with coarser run absorption (short runs are where crossings come from), then again
// with runs left unsplit (steps are short too).
StageProblem outline(const std::vector<Ring>& rings, const EdgeLabels& labels, const std::vector<Vec2>& directions,
                     const CornerOptions& o, const Vec2& origin, double pixel_size, const CornerContext& context,
                     double min_run_px, PolygonWithHoles& footprint) {
  CornerOptions corner_options = o;
  std::string problem;
  try {
    for (const double split_px : {o.split_px, 0.0}) {
      corner_options.split_px = split_px;
      corner_options.min_run_px = min_run_px;
      for (int attempt = 0; attempt <= o.repair_attempts; ++attempt) {
        footprint = corner_polygon(rings, labels, directions, corner_options, origin, pixel_size, context);
        problem = polygon_problem(footprint);
        if (problem.empty()) return {};
        corner_options.min_run_px = std::max(2.0, 2 * corner_options.min_run_px);
      }
    }
  } catch (const StageError& e) {
    return {e.stage, e.what()};
  }
  return {"validation", problem};
}

// How well a polygon explains the contour: the length-weighted mean distance of every ring's
// edges to the polygon's boundary.
double contour_fit(const std::vector<Ring>& rings, const PolygonWithHoles& polygon) {
  double sum = 0, total = 0;
  for (const Ring& ring : rings) {
    const double length = perimeter(ring);
    sum += length * mean_distance_to_boundary(ring, polygon);
    total += length;
  }
  return total > 0 ? sum / total : 0.0;
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

// The boundary noise the model choice allows for (m): as measured, and at least a staircase's;
// at most models.arc_noise_ratio times the noise about parabolas along the same runs (a round
// building's contour lies metres off lattice lines, and that is no noise).
double model_noise(const BuildingResult& result, double pixel_size, const ModelOptions& o) {
  double noise = result.noise_m;
  if (o.arc_noise_ratio > 0 && result.arc_noise_m >= 0) noise = std::min(noise, o.arc_noise_ratio * result.arc_noise_m);
  return std::max(noise, o.min_noise_px * pixel_size);
}

// The length of all of a building's rings (m).
double total_perimeter(const std::vector<Ring>& rings) {
  double length = 0;
  for (const Ring& ring : rings) length += perimeter(ring);
  return length;
}

// How much worse a simpler outline may explain the contour (mean distance) and still be taken:
// models.lattice_tolerance standard errors of that mean, the noise over the square root of the
// number of independent stretches of contour (of the noise's correlation length) along the rings.
double fit_tolerance(const std::vector<Ring>& rings, double pixel_size, const BuildingResult& result, const CoreOptions& o) {
  const double perimeter_m = total_perimeter(rings);
  const double correlation = noise_correlation_m(o.corners, pixel_size);
  return o.models.lattice_tolerance * model_noise(result, pixel_size, o.models) * std::sqrt(correlation / std::max(perimeter_m, correlation));
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
void choose_rectangle(const std::vector<Ring>& rings, double pixel_size, const CoreOptions& co, BuildingResult& result,
                      const Vec2* lattice = nullptr) {
  const ModelOptions& o = co.models;
  if (o.rectangle_tolerance <= 0 || rings.size() != 1 || result.footprint.outer.size() <= 4) return;
  double mean_fit = 0;  // the best rectangle's mean distance, which chose it
  Ring rectangle = lattice ? moment_rectangle(rings[0], *lattice) : best_rectangle(rings[0], result.directions, &mean_fit);
  if (rectangle.empty()) return;
  PolygonWithHoles candidate{std::move(rectangle), {}};
  const auto outline_distances = boundary_distances(rings[0], result.footprint);
  const auto rectangle_distances = boundary_distances(rings[0], candidate);
  const double outline_fit = weighted_quantile(outline_distances, o.rectangle_quantile);
  const double rectangle_fit = weighted_quantile(rectangle_distances, o.rectangle_quantile);
  const double noise = model_noise(result, pixel_size, o);
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

// The lattice outline: the contour's edges labeled among the building's lattice directions alone,
// every wall straight (no curve), drawn for the noise in `context`.
StageProblem lattice_outline_of(const std::vector<Ring>& fit_rings, const EdgeLabels& axis_labels, const std::vector<Vec2>& axes,
                                const CornerOptions& o, const Vec2& origin, double pixel_size, const CornerContext& context,
                                PolygonWithHoles& footprint) {
  CornerOptions straight = o;
  straight.curve_px = 0;
  return outline(fit_rings, axis_labels, axes, straight, origin, pixel_size, context, regular_min_run_px(o, context.noise, pixel_size),
                 footprint);
}

void run_chain(const std::vector<Ring>& rings, double pixel_size, const CoreOptions& o, double noise_floor_m,
               BuildingStart start, BuildingResult& result, const std::function<bool()>& over_budget) {
  if (const std::string problem = contour_problem(rings, o); !problem.empty()) throw StageError("input", problem);
  std::size_t edges = 0;
  for (const Ring& r : rings) edges += r.size();
  bool started = start.normals.size() == rings.size();
  for (std::size_t r = 0; started && r < rings.size(); ++r) started = start.normals[r].size() == rings[r].size();
  const NeighbourLattice neighbour_lattice = start.neighbour_lattice;  // (a start made here has none)
  if (!started) start = start_building(rings, pixel_size, o, false, start.smoothing_noise_m);
  LabelingInput input;
  input.normals = std::move(start.normals);
  std::vector<Vec2> all_normals;
  std::vector<double> all_lengths;
  for (std::size_t r = 0; r < rings.size(); ++r) {
    input.lengths.emplace_back();
    for (std::size_t i = 0; i < rings[r].size(); ++i) input.lengths.back().push_back(edge_vector(rings[r], i).norm());
    all_normals.insert(all_normals.end(), input.normals[r].begin(), input.normals[r].end());
    all_lengths.insert(all_lengths.end(), input.lengths.back().begin(), input.lengths.back().end());
  }
  if (over_budget()) throw BudgetExceeded("smoothing", "time budget exceeded");
  for (const DominantDirection& d : detect_directions(all_normals, all_lengths, o.directions)) {
    input.directions.push_back(d.normal);
    input.support.push_back(d.support);
  }
  if (input.directions.size() < 2)
    throw StageError("directions", "found " + std::to_string(input.directions.size()) + " dominant direction(s), need 2");
  // Label, re-estimate the directions from the labeled runs, label again with them.
  EdgeLabels labels = label_edges(input, o.labeling);
  refine_directions(rings, labels, input.directions, pixel_size, o.refinement);
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
  // (About the chords' lattice, the start measured it for its sample, on the same normals.)
  double arc_noise = start.chord_arc_noise_m;
  double noise = follow_chords && start.chord_noise_m >= 0
                     ? start.chord_noise_m
                     : lattice_noise(rings, input.normals, follow_chords ? chord.direction : first_main, pixel_size, o.noise, &arc_noise);
  // At least the noise pooled over the buildings regularized with this one (a segmentation's
  // noise is its mask's): walls shorter than a wobble's wavelength, or runs cut short by its
  // flanks at fine pixels, measure too little of it.
  noise = std::max(noise, noise_floor_m);
  // And at most noise.pooled_ceiling times the pooled noise: a contour that lies farther than that
  // off the lines of its lattice is not noisier than its mask's other buildings, it has arcs or
  // walls off the lattice (a round building's measures metres), which the noise must not hide.
  if (noise_floor_m > 0 && o.noise.pooled_floor > 0 && o.noise.pooled_ceiling > 0)
    noise = std::min(noise, std::max(1.0, o.noise.pooled_ceiling / o.noise.pooled_floor) * noise_floor_m);
  arc_noise = std::max(arc_noise, noise_floor_m);
  // The lattice fitted to the contour's runs along it, from the chords' direction where they give
  // one (under a wobble the labeled main direction follows a flank, degrees off the walls); and
  // the spread of those runs about it, which a wobble's flanks do not cut short (below).
  double fit_uncertainty = 0, fit_spread = 0;
  const std::optional<Vec2> fitted_lattice =
      o.lattice.fit_max_turn_deg > 0
          ? fit_lattice(rings, input.normals, chord.share >= o.lattice.min_share ? chord.direction : first_main, pixel_size,
                        o.lattice, o.noise, o.corners.snap_correlation_m, &fit_uncertainty, &fit_spread, noise)
          : std::nullopt;
  const auto building_lattice = [&] {
    const Vec2 main = main_direction(labels, input.lengths, input.directions);
    return !follow_chords || angle_between_lattices_deg(main, chord.direction) <= o.lattice.max_gap_deg ? main : chord.direction;
  };
  // (The noise above: how noisy the contour is about lines along that lattice. Directions off the
  // lattice without a wall of their own, long against that noise, are a wobble's: label without them.)
  const Vec2 lattice = follow_chords ? chord.direction : first_main;
  // A round or oblique shape (little of it along the lattice, its outline turning about once, as
  // a convex one does, not back and forth as a wobble does) has no lattice to hold its walls to.
  // (A building of a few dozen pixels, or of a few dozen times its mask's noise, shows no curvature:
  // it is taken as on its lattice.)
  const double outline_m = perimeter(rings[0]);
  const bool small_for_noise = outline_m < o.refinement.min_round_noise * noise_floor_m;
  const bool on_lattice = small_for_noise || outline_m < std::max(o.refinement.min_round_px * pixel_size, o.refinement.min_round_m) ||
                          lattice_share(input.normals, input.lengths, lattice, o.refinement.lattice_deg) >= o.refinement.min_lattice_share ||
                          total_turning(rings[0], input.normals[0], std::max(1.0, 2 * pixel_size)) >= o.refinement.min_turning;
  result.noise_m = noise;
  result.arc_noise_m = arc_noise;
  // Drops the insignificant directions and labels again without them, their support unknown.
  const auto drop_and_label = [&] {
    if (!on_lattice || !drop_insignificant_directions(rings, labels, input.directions, building_lattice(), noise, o.refinement))
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

  // Corner lines are fitted in a local frame (metres from the first vertex) for numerical range.
  const Vec2 origin = rings[0][0];
  std::vector<Ring> fit_rings = translate(rings, origin, 1.0);
  result.route = "original";
  if (o.corners.route == "deformed" && edges > std::size_t(o.budget.max_deformation_edges)) {
    result.note = "contour of " + std::to_string(edges) + " edges, more than budget.max_deformation_edges = " +
                  std::to_string(o.budget.max_deformation_edges) + ": original route";
  } else if (o.corners.route == "deformed") {
    try {
      fit_rings = deform_rings(translate(rings, origin, pixel_size), labels, input.directions, o, over_budget, result);
      for (Ring& ring : fit_rings) for (Vec2& p : ring) p *= pixel_size;
      result.route = "deformed";
    } catch (const DeformationSkipped& e) {
      result.note = std::string(e.what()) + ": original route";
    }
  }
  // Two outlines from the same labels: the regular one (runs shorter than min_run_noise times
  // the noise absorbed, walls held to the lattice, steps, curves and cuts judged against the noise)
  // and the plain one (the paper's corners with pixel thresholds), and the regular one kept
  // unless it explains the contour worse than the plain one by more than the noise allows. (It is
  // also kept when it explains the contour within the noise itself: at a few centimetres a pixel,
  // the plain outline's thresholds of a few pixels let it follow a wobble of a metre.)
  CornerContext context;
  if (on_lattice) context.lattice = building_lattice();
  // The fitted lattice, unless the labeled one (main direction or chords') lies within its
  // uncertainty: on a clean wall the labeled direction is exact.
  if (on_lattice && fitted_lattice &&
      angle_between_lattices_deg(*fitted_lattice, context.lattice) * M_PI / 180.0 > o.lattice.fit_keep_uncertainty * fit_uncertainty)
    context.lattice = *fitted_lattice;
  // A building whose own lattice is undetermined takes its neighbours' (lattice.neighbour_*): one
  // too small to show its walls under its mask's noise (refinement.min_round_noise), one whose
  // fitted lattice lies within fit_keep_uncertainty standard errors of theirs, or, without a fit,
  // one whose chords give it no lattice. (A fitted lattice is held only to its near neighbours',
  // those whose centres are near: the lattice of the walls whose boxes alone come near is the
  // street's, which a building with walls of its own need not follow.)
  const Vec2& lent = neighbour_lattice.direction;
  if (on_lattice && lent.squaredNorm() > 0) {
    const double gap = angle_between_lattices_deg(lent, context.lattice) * M_PI / 180.0;
    result.lattice_lent =
        small_for_noise || (fitted_lattice ? !neighbour_lattice.from_boxes && gap <= o.lattice.fit_keep_uncertainty * fit_uncertainty
                                           : chord.share < o.lattice.min_share);
    if (result.lattice_lent) context.lattice = lent;
  }
  context.noise = noise;
  context.mask_noise = noise_floor_m;
  const double allowed = o.models.outline_tolerance * model_noise(result, pixel_size, o.models);
  PolygonWithHoles regular, plain;
  const double min_run_px = regular_min_run_px(o.corners, noise, pixel_size);
  const StageProblem regular_problem =
      outline(fit_rings, labels, input.directions, o.corners, origin, pixel_size, context, min_run_px, regular);
  // "Within the noise": the noise, or the spread of the runs along the fitted lattice where more
  // (the noise's runs, cut where a wobble's flank turns past 45 degrees, are shorter than the walls
  // at fine pixels, and their lines follow part of the wobble), bounded as the noise is by the
  // spread about parabolas (an arc's spread is no noise).
  const double within_noise =
      std::max(model_noise(result, pixel_size, o.models),
               o.models.arc_noise_ratio > 0 ? std::min(fit_spread, o.models.arc_noise_ratio * arc_noise) : fit_spread);
  // A regular outline that explains the contour within the noise is kept whatever the plain one
  // is: that one is drawn only where it may be chosen (it is a good part of the time).
  const double regular_fit = regular_problem.second.empty() ? contour_fit(rings, regular) : -1.0;
  const bool regular_within_noise = regular_fit >= 0 && regular_fit <= o.models.regular_fit_noise * within_noise;
  const StageProblem plain_problem =
      regular_within_noise
          ? StageProblem{}
          : outline(fit_rings, labels, input.directions, o.corners, origin, pixel_size, CornerContext{}, o.corners.min_run_px, plain);
  // The lattice outline: every wall on the building's lattice (its main direction and quarter
  // turns), labeled by the MRF among those four alone. The most regular outline the building can
  // have short of a rectangle; it replaces the chain's when it has no more vertices and explains
  // the contour about as well (fit_tolerance), and stands in for a chain that failed.
  PolygonWithHoles lattice_outline;
  bool lattice_ok = false;
  EdgeLabels axis_labels;
  if (on_lattice && o.models.lattice_tolerance > 0) {
    // (The labeling input's last use: its directions become the lattice's, its normals stay.)
    const Vec2 l = context.lattice;
    input.directions = {l, Vec2(-l.y(), l.x()), -l, Vec2(l.y(), -l.x())};
    input.support.assign(4, 1.0);
    axis_labels = label_edges(input, o.labeling);
    lattice_ok = lattice_outline_of(fit_rings, axis_labels, input.directions, o.corners, origin, pixel_size, context, lattice_outline)
                     .second.empty();
  }
  // (Each contour fit computed once, when it is needed: they are a good part of the time.)
  double chosen_fit = -1;  // the chosen outline's, unknown yet
  if (!regular_problem.second.empty() && !plain_problem.second.empty()) {
    // As a stand-in for a failed chain, the lattice outline must explain the contour within the
    // noise, or as well as the fallback does.
    const double lattice_fit = lattice_ok ? contour_fit(rings, lattice_outline) : 0.0;
    const bool rescues = lattice_ok && (lattice_fit <= o.models.rescue_fit_noise * model_noise(result, pixel_size, o.models) ||
                                        lattice_fit <= contour_fit(rings, fallback_footprint(rings, o.fallback.tolerance_m)) + allowed);
    if (!rescues) throw StageError(regular_problem.first, regular_problem.second);
    result.footprint = std::move(lattice_outline);
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
    if (lattice_ok && vertex_count(lattice_outline) <= vertex_count(result.footprint)) {
      if (chosen_fit < 0) chosen_fit = contour_fit(rings, result.footprint);
      const double lattice_fit = contour_fit(rings, lattice_outline);
      // (A building whose lattice came from its chords: its wobble, which the chosen outline may
      // follow, is what the lattice outline leaves within the noise; a wing it leaves out would
      // cost more than lattice_fit_gap_noise over the chosen outline.)
      const double model_noise_m = model_noise(result, pixel_size, o.models);
      const bool lattice_within_noise = follow_chords && vertex_count(lattice_outline) < vertex_count(result.footprint) &&
                                        lattice_fit <= o.models.lattice_fit_noise * model_noise_m &&
                                        lattice_fit <= chosen_fit + o.models.lattice_fit_gap_noise * model_noise_m;
      if (lattice_within_noise || lattice_fit <= chosen_fit + fit_tolerance(rings, pixel_size, result, o)) {
        result.footprint = std::move(lattice_outline);
        result.model = "lattice";
      }
    }
  }
  if (on_lattice) choose_rectangle(rings, pixel_size, o, result, result.lattice_lent ? &context.lattice : nullptr);  // a round shape is no rectangle
  // Per stretch of contour, the simpler model where it explains the stretch as well: the regular
  // outline's walls off the lattice redrawn with the lattice outline's walls where those explain
  // their contour within stretch_fit_noise noises (an oblique cut across a wobble or a notch).
  // (Skipped past the time budget: the regular outline stands.)
  if (result.model == "regular" && lattice_ok && o.models.stretch_fit_noise > 0 && !over_budget()) {
    const PolygonWithHoles& chosen = result.footprint;
    if (chosen_fit < 0) chosen_fit = contour_fit(rings, chosen);
    // The noise, as the regular outline leaves it where that is less: a shape off any lattice
    // (a hexagon, a disc) measures a large noise about lattice lines.
    const double noise_m = std::max(o.models.min_noise_px * pixel_size, std::min(model_noise(result, pixel_size, o.models), chosen_fit));
    const double tolerance = o.models.stretch_fit_noise * noise_m;
    const std::vector<Stretch> stretches = lattice_stretches(rings, axis_labels, context.lattice, chosen, lattice_outline,
                                                             min_run_px * pixel_size, o.corners.snap_max_deg, tolerance);
    if (!stretches.empty()) {
      // The chain's labels with the stretches' edges labeled as the lattice labeling has them
      // (the chain's directions, then the lattice's four).
      EdgeLabels mixed = labels;
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
      if (outline(fit_rings, mixed, mixed_directions, o.corners, origin, pixel_size, context, min_run_px, candidate)
              .second.empty() &&
          contour_fit(rings, candidate) <= chosen_fit + tolerance) {
        const PolygonWithHoles contour{rings[0], {rings.begin() + 1, rings.end()}};
        if (outline_reach(candidate, contour) <= outline_reach(chosen, contour) + noise_m) result.footprint = std::move(candidate);
      }
    }
  }
  // Simpler outlines against the chosen one, by a Bayesian information criterion: the lattice
  // outline drawn as if the noise were coarse_scale and its square times as large
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
  if ((o.models.coarse_scale > 1 || o.models.merge_patience > 0 || o.models.staircase_corners > 0) && lattice_ok &&
      vertex_count(result.footprint) > 4 && !has_arc(result.footprint) && !over_budget()) {
    const double correlation = std::max(pixel_size, o.models.coarse_correlation_noise * noise);
    const double samples = std::max(2.0, total_perimeter(rings) / correlation);
    // n ln(d^2) + k ln(n): d the mean distance (at least a tenth of a pixel) for the standard
    // deviation, two parameters a vertex.
    const auto criterion_of = [&](double fit, std::size_t vertices) {
      fit = std::max(0.1 * pixel_size, fit);
      return samples * std::log(fit * fit) + 2.0 * std::log(samples) * double(vertices);
    };
    const auto criterion = [&](const PolygonWithHoles& p) { return criterion_of(contour_fit(rings, p), vertex_count(p)); };
    // Each outline taken as the least so far, in turn, with its model's name (when guarded below).
    const bool guarded = o.models.criterion_stretch_noise > 0;
    std::optional<std::pair<PolygonWithHoles, std::string>> chosen;  // the outline chosen before these
    std::vector<std::pair<PolygonWithHoles, std::string>> taken;
    const auto take = [&](PolygonWithHoles p, const char* model) {
      if (guarded) {
        if (!chosen) chosen.emplace(result.footprint, result.model);
        taken.emplace_back(p, model);
      }
      result.footprint = std::move(p);
      result.model = model;
    };
    // (The merge path measures the chosen outline's fit, as contour_fit does, for the walk below:
    // made first, it gives the criterion's start, and is made again only if another outline wins.)
    std::optional<StepPath> path;
    if (o.models.merge_patience > 0) path.emplace(rings, result.footprint, o.models.merge_parallel_deg);
    double best = path ? criterion_of(path->fit(), vertex_count(result.footprint)) : criterion(result.footprint);
    bool replaced = false;
    double scale = 1;
    for (int k = 0; k < 2 && o.models.coarse_scale > 1; ++k) {
      scale *= o.models.coarse_scale;
      CornerContext coarse = context;
      coarse.noise = scale * noise;
      coarse.mask_noise = scale * context.mask_noise;
      PolygonWithHoles candidate;
      if (!lattice_outline_of(fit_rings, axis_labels, input.directions, o.corners, origin, pixel_size, coarse, candidate)
               .second.empty() ||
          vertex_count(candidate) >= vertex_count(result.footprint))
        continue;
      const double c = criterion(candidate);
      if (c < best) {
        best = c;
        take(std::move(candidate), "coarse_lattice");
        replaced = true;
      }
    }
    // A staircase drawn as the oblique wall it follows (a corner cut at an angle to the lattice,
    // which the lattice outlines draw in steps, and the merges below would make a square notch).
    if (o.models.staircase_corners > 0) {
      if (std::optional<PolygonWithHoles> lines =
              staircases_as_lines(result.footprint, o.models.staircase_corners, o.models.staircase_square_deg)) {
        const double c = criterion(*lines);
        if (c < best && polygon_problem(*lines).empty()) {
          best = c;
          take(std::move(*lines), "staircase_lines");
          replaced = true;
        }
      }
    }
    // The path of ever simpler outlines, the cheapest step merged at each: its criterion is not
    // monotone (a merge moves a wall to the mean of two), so the walk goes on until merge_patience
    // merges have passed without a new least, and keeps the least among its valid polygons.
    if (path) {
      if (replaced) path.emplace(rings, result.footprint, o.models.merge_parallel_deg);
      for (int since_best = 0; since_best < o.models.merge_patience && !over_budget() && path->merge_next();) {
        const double c = criterion_of(path->fit(), vertex_count(path->outline()));
        if (c < best && polygon_problem(path->outline()).empty()) {
          best = c;
          take(path->outline(), "merged_steps");
          since_best = 0;
        } else {
          ++since_best;
        }
      }
    }
    // A simpler outline that explains the contour as well on the whole may still leave a stretch
    // of it that the chosen one explains (a block's real setbacks drawn as one oblique wall): the
    // last one taken that leaves none stands, else the chosen one (models.criterion_stretch_noise,
    // as leaves_a_stretch judges a rectangle).
    if (chosen) {
      const StretchGuard guard(rings, chosen->first, model_noise(result, pixel_size, o.models), noise_correlation_m(o.corners, pixel_size),
                               o.models.criterion_stretch_noise);
      while (!taken.empty() && guard.leaves_stretch(taken.back().first)) taken.pop_back();
      auto& stands = taken.empty() ? *chosen : taken.back();
      result.footprint = std::move(stands.first);
      result.model = std::move(stands.second);
    }
  }
  // Last, the short oblique walls between two walls on the lattice that the noise does not tell
  // from it: square steps and corners (models.square_noise).
  if (on_lattice && o.models.square_noise > 0 && !has_arc(result.footprint))
    if (std::optional<PolygonWithHoles> squared =
            square_connectors(result.footprint, context.lattice, o.models.merge_parallel_deg, noise,
                              noise_correlation_m(o.corners, pixel_size), o.models.square_noise))
      result.footprint = std::move(*squared);
  // Last of all, the needles where two walls' lines met past the end of one (models.spike_deg).
  if (o.models.spike_deg > 0 &&
      remove_spikes(result.footprint, o.models.spike_deg, std::max(pixel_size, o.models.spike_noise * noise)) > 0) {
    result.footprint.outer = remove_degenerate_vertices(result.footprint.outer, 1e-3 * pixel_size);
    for (Ring& hole : result.footprint.holes) hole = remove_degenerate_vertices(hole, 1e-3 * pixel_size);
  }
}

// The start's noise sample, from its normals and chords.
void measure_sample(const std::vector<Ring>& rings, double pixel_size, const CoreOptions& o, BuildingStart& start) {
  double arc_noise = 0, measured = 0;
  double noise = lattice_noise(rings, start.normals, start.chord.direction, pixel_size, o.noise, &arc_noise, &measured);
  start.chord_noise_m = noise, start.chord_arc_noise_m = arc_noise;
  if (o.models.arc_noise_ratio > 0) noise = std::min(noise, o.models.arc_noise_ratio * arc_noise);
  start.sample = measured > 0 ? NoiseSample{noise, perimeter(rings[0])} : NoiseSample{};  // (a clean contour may measure 0, and says so)
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
                             double smoothing_noise_m) {
  BuildingStart start;
  start.smoothing_noise_m = smoothing_noise_m;
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
