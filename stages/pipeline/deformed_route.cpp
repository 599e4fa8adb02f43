#include "pipeline/deformed_route.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "deformation/deform.hpp"
#include "geometry/polygon.hpp"
#include "pipeline/outlines.hpp"
#include "triangulation/triangulate.hpp"

namespace lodforge::chain {

namespace {

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

}  // namespace

std::vector<Ring> route_rings(const std::vector<Ring>& rings, const Vec2& origin, double pixel_size, const EdgeLabels& labels,
                              const std::vector<Vec2>& directions, const CoreOptions& o, const std::function<bool()>& over_budget,
                              BuildingResult& result) {
  std::size_t edges = 0;
  for (const Ring& r : rings) edges += r.size();
  std::vector<Ring> fit_rings = translate(rings, origin, 1.0);
  result.route = "original";
  if (o.corners.route == "deformed" && edges > std::size_t(o.budget.max_deformation_edges)) {
    result.note = "contour of " + std::to_string(edges) + " edges, more than budget.max_deformation_edges = " +
                  std::to_string(o.budget.max_deformation_edges) + ": original route";
  } else if (o.corners.route == "deformed") {
    try {
      fit_rings = deform_rings(translate(rings, origin, pixel_size), labels, directions, o, over_budget, result);
      for (Ring& ring : fit_rings) for (Vec2& p : ring) p *= pixel_size;
      result.route = "deformed";
    } catch (const DeformationSkipped& e) {
      result.note = std::string(e.what()) + ": original route";
    }
  }
  return fit_rings;
}

}  // namespace lodforge::chain
