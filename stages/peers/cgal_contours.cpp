#include "peers/cgal_contours.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Shape_regularization/regularize_contours.h>
#include <iterator>

#include "geometry/polygon.hpp"

namespace lodforge {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_2;

}  // namespace

PolygonWithHoles cgal_regularize_contours(const std::vector<Ring>& rings, const CgalContourOptions& o,
                                          std::string* problem) {
  PolygonWithHoles out;
  if (rings.empty()) { *problem = "no contour"; return out; }
  const Vec2 origin = rings[0][0];  // local frame for numerical range
  for (std::size_t r = 0; r < rings.size(); ++r) {
    const Ring simplified = remove_degenerate_vertices(douglas_peucker(rings[r], o.simplify_m), 1e-9);
    if (simplified.size() < 3) { *problem = "ring " + std::to_string(r) + " has fewer than 3 vertices after simplification"; return {}; }
    std::vector<Point> input;
    for (const Vec2& p : simplified) input.emplace_back(p.x() - origin.x(), p.y() - origin.y());
    std::vector<Point> result;
    try {
      CGAL::Shape_regularization::Contours::Multiple_directions_2<Kernel, std::vector<Point>> directions(
          input, true, CGAL::parameters::minimum_length(o.min_length_m).maximum_angle(o.max_angle_deg));
      CGAL::Shape_regularization::Contours::regularize_closed_contour(input, directions, std::back_inserter(result),
                                                                      CGAL::parameters::maximum_offset(o.max_offset_m));
    } catch (const std::exception& e) {
      *problem = std::string("CGAL: ") + e.what();
      return {};
    }
    Ring ring;
    for (const Point& p : result) ring.push_back(Vec2(p.x(), p.y()) + origin);
    ring = remove_degenerate_vertices(ring, 1e-9);
    if (ring.size() < 3) { *problem = "ring " + std::to_string(r) + ": CGAL returned fewer than 3 vertices"; return {}; }
    // Keep the input's orientation (outer counter-clockwise, holes clockwise).
    if ((signed_area(ring) > 0) != (r == 0)) std::reverse(ring.begin(), ring.end());
    if (r == 0) out.outer = std::move(ring);
    else out.holes.push_back(std::move(ring));
  }
  *problem = polygon_problem(out);
  if (!problem->empty()) return {};
  return out;
}

}  // namespace lodforge
