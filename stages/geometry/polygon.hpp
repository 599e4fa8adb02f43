// Polygon measures, validity checks and Douglas–Peucker simplification.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <string>

#include "geometry/types.hpp"

namespace lodforge {

double signed_area(const Ring& ring);  // > 0 for counter-clockwise
double area(const PolygonWithHoles& polygon);
double perimeter(const Ring& ring);
std::size_t vertex_count(const PolygonWithHoles& polygon);  // of its outer ring and holes
std::vector<const Ring*> rings_of(const PolygonWithHoles& polygon);  // the outer ring, then the holes
Ring& ring_at(PolygonWithHoles& polygon, std::size_t r);  // ring r: 0 the outer ring, r the hole r - 1
bool point_in_ring(const Vec2& p, const Ring& ring);  // even-odd rule, boundary undefined
// Whether p lies inside a convex counter-clockwise ring, at least `margin` from each of its sides
// (margin 0: its boundary counts as inside).
bool inside_convex(const Vec2& p, const Ring& convex, double margin = 0);

// The squared distance from p to the segment [a, b], and the distance (its square root). Inline:
// the models measure every contour edge against an outline's walls several times a building.
inline double squared_distance_to_segment(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  const double len2 = ab.squaredNorm();
  if (len2 == 0) return (p - a).squaredNorm();
  const double t = std::clamp((p - a).dot(ab) / len2, 0.0, 1.0);
  return (p - (a + t * ab)).squaredNorm();
}
inline double distance_to_segment(const Vec2& p, const Vec2& a, const Vec2& b) { return std::sqrt(squared_distance_to_segment(p, a, b)); }

// True when segments [a,b] and [c,d] share any point.
bool segments_intersect(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d);

// Empty string when the ring is simple (no repeated vertex, no self-intersection, no zero-length
// edge, at least 3 vertices, non-zero area); otherwise the reason.
std::string ring_problem(const Ring& ring);

// Empty string when the polygon is valid in the OGC sense as we write it: simple rings, outer
// counter-clockwise, holes clockwise, inside the outer ring and pairwise disjoint.
std::string polygon_problem(const PolygonWithHoles& polygon);

// The polygon with only those of its holes that keep it valid (polygon_problem), each tried in
// turn beside the ones kept; its outer ring must be valid alone.
PolygonWithHoles holes_that_fit(const PolygonWithHoles& polygon);

// A point strictly inside a simple ring: on the horizontal line halfway between the two vertex
// heights nearest its box's middle, the middle of the widest stretch inside it.
Vec2 interior_point(const Ring& ring);

// Which of the contour's holes (rings[1..]) the polygon covers: a point inside the hole
// (interior_point) lies inside its outer ring and in none of its holes. Their indices in rings.
std::vector<std::size_t> covered_holes(const std::vector<Ring>& rings, const PolygonWithHoles& polygon);

// Cuts off the loops of a ring that crosses itself: at each crossing the ring splits in two and
// the piece of larger area, turning the ring's way, is kept. Each piece cut off must be thinner
// than max_width on average (its area over half its perimeter). True, with the ring changed, when
// that leaves a simple ring; false, with the ring as it was, otherwise.
bool untangle(Ring& ring, double max_width);

// Takes away the needles of a polygon: a vertex where a ring turns back on itself, its corner
// sharper than max_angle_deg. Where its shorter arm (at most half the other) is a short wall
// turning back at the end of a long one, the long one's line and the line of the edge beyond the
// short one meet at their intersection (when within twice the short arm of the tip); else, or
// where that is not taken, the tip alone is dropped. A change is taken only where the polygon
// stays valid and its area changes by no more than a square of side max_side. Again at the new
// corners, until no change is taken (a needle whose changes are refused stays). The number of
// changes.
std::size_t remove_spikes(PolygonWithHoles& polygon, double max_angle_deg, double max_side);

// The ring with its dips along the line through a and b flattened: between two of its vertices
// on the line (within 1e-9 of its length), where every vertex between lies within `depth` of it
// (on either side), those are dropped and the ring goes along the line. (A clip's cut: where an
// outline drawn past a raster's edge crossed it back and forth, the clip left notches.) Given
// `filled`, also where the dip's area is: where the path between and the line enclose an area
// outside the ring (turning against it) and filled(p) holds at 95 % or more of the points of a
// grid of sample_step inside it (coarser where that would take more than 400; at least one
// point): a dip deeper than `depth` that the mask fills, which the outline drew past the edge.
Ring flatten_along_line(const Ring& ring, const Vec2& a, const Vec2& b, double depth,
                        const std::function<bool(const Vec2&)>& filled = {}, double sample_step = 0);

// Removes consecutive duplicates (closer than eps) and vertices whose two edges are collinear
// (deviation below eps from the line through their neighbours).
Ring remove_degenerate_vertices(const Ring& ring, double eps);

// Douglas–Peucker on a closed ring; keeps the orientation. tolerance in map units.
Ring douglas_peucker(const Ring& ring, double tolerance);

// Douglas–Peucker on an open polyline: which points to keep (both ends always).
std::vector<char> douglas_peucker_open(const std::vector<Vec2>& points, double tolerance);

}  // namespace lodforge
