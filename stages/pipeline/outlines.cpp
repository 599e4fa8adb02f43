#include "pipeline/outlines.hpp"

#include <algorithm>

#include "geometry/polygon.hpp"
#include "models/rectangle.hpp"

namespace lodforge::chain {

namespace {

// rings: in a local frame (metres, less origin). Lengths of the options are in metres or pixels.
PolygonWithHoles corner_polygon(const std::vector<Ring>& rings, const EdgeLabels& labels,
                                const std::vector<Vec2>& directions, const CornerOptions& options, const Vec2& origin,
                                double pixel_size, const CornerContext& context, bool* curved) {
  PolygonWithHoles footprint;
  *curved = false;
  for (std::size_t r = 0; r < rings.size(); ++r) {
    std::string problem;
    bool ring_curved = false;
    Ring ring = extract_corners(rings[r], labels[r], directions, pixel_size, options, &problem, context, &ring_curved);
    *curved |= ring_curved;
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

}  // namespace

StageProblem outline(const std::vector<Ring>& rings, const EdgeLabels& labels, const std::vector<Vec2>& directions,
                     const CornerOptions& o, const Vec2& origin, double pixel_size, const CornerContext& context,
                     double min_run_px, PolygonWithHoles& footprint, bool* curved) {
  bool drawn_curved = false;
  CornerOptions corner_options = o;
  std::string problem;
  PolygonWithHoles first;  // the polygon drawn as first asked
  bool first_curved = false;
  try {
    for (const double split_px : {o.split_px, 0.0}) {
      corner_options.split_px = split_px;
      corner_options.min_run_px = min_run_px;
      for (int attempt = 0; attempt <= o.repair_attempts; ++attempt) {
        footprint = corner_polygon(rings, labels, directions, corner_options, origin, pixel_size, context, &drawn_curved);
        problem = polygon_problem(footprint);
        if (problem.empty()) {
          if (curved) *curved = drawn_curved;
          return {};
        }
        if (split_px == o.split_px && attempt == 0) first = footprint, first_curved = drawn_curved;
        corner_options.min_run_px = std::max(2.0, 2 * corner_options.min_run_px);
      }
    }
  } catch (const StageError& e) {
    return {e.stage, e.what()};
  }
  // Still invalid where only holes are (a courtyard drawn across a wall within the noise of it,
  // or a gap between houses a wobble closed into a hole): the polygon drawn as first asked keeps
  // its outer ring and the holes that fit, not the whole building lost to the fallback.
  if (!first.holes.empty() && polygon_problem({first.outer, {}}).empty()) {
    footprint = holes_that_fit(first);
    if (curved) *curved = first_curved;
    return {};
  }
  return {"validation", problem};
}

StageProblem lattice_outline_of(const std::vector<Ring>& fit_rings, const EdgeLabels& axis_labels, const std::vector<Vec2>& axes,
                                const CornerOptions& o, const Vec2& origin, double pixel_size, const CornerContext& context,
                                PolygonWithHoles& footprint) {
  CornerOptions straight = o;
  straight.curve_px = 0;
  return outline(fit_rings, axis_labels, axes, straight, origin, pixel_size, context, regular_min_run_px(o, context.noise, pixel_size),
                 footprint);
}

double contour_fit(const std::vector<Ring>& rings, const PolygonWithHoles& polygon) {
  std::vector<std::vector<std::pair<double, double>>> distances;
  for (const Ring& ring : rings) distances.push_back(boundary_distances(ring, polygon));
  return contour_fit(rings, distances);
}

double contour_fit(const std::vector<Ring>& rings, const std::vector<std::vector<std::pair<double, double>>>& distances) {
  double sum = 0, total = 0;
  for (std::size_t r = 0; r < rings.size(); ++r) {
    const double length = perimeter(rings[r]);
    sum += length * mean_distance(distances[r]);
    total += length;
  }
  return total > 0 ? sum / total : 0.0;
}

double total_perimeter(const std::vector<Ring>& rings) {
  double length = 0;
  for (const Ring& ring : rings) length += perimeter(ring);
  return length;
}

}  // namespace lodforge::chain
