// Plain geometry types shared by all stages. Coordinates are map metres.
#pragma once
#include <Eigen/Core>
#include <cmath>
#include <vector>

namespace lodforge {

using Vec2 = Eigen::Vector2d;

// A closed ring: the closing edge from back() to front() is implied.
// Outer rings run counter-clockwise, holes clockwise, so the polygon's interior is always on
// the left of every edge and the outward normal of edge t is (t.y, -t.x).
using Ring = std::vector<Vec2>;

struct PolygonWithHoles {
  Ring outer;
  std::vector<Ring> holes;
};

// The index after i (< n) round a ring of n: (i + 1) % n without a division, which every stage
// would pay per edge.
inline std::size_t next_index(std::size_t i, std::size_t n) { return i + 1 < n ? i + 1 : 0; }

// Edge i of a ring goes from ring[i] to ring[(i+1) % size].
inline Vec2 edge_vector(const Ring& ring, std::size_t i) { return ring[next_index(i, ring.size())] - ring[i]; }

// Outward unit normal of a direction vector, for rings with the interior on the left.
inline Vec2 outward_normal(const Vec2& t) { return Vec2(t.y(), -t.x()).normalized(); }

// The tangent direction whose outward normal is n (inverse of outward_normal).
inline Vec2 tangent_of_normal(const Vec2& n) { return Vec2(-n.y(), n.x()); }

inline double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

// How far a polyline turns (degrees, 0-180) from edge `before` to edge `after`; 0 for a zero edge.
inline double turn_deg(const Vec2& before, const Vec2& after) {
  return std::abs(std::atan2(cross(before, after), before.dot(after))) * 180.0 / M_PI;
}

// Of the four unit normals of a building's lattice (lattice, and it turned by quarter turns), the
// one nearest to n.
inline Vec2 nearest_lattice_axis(const Vec2& n, const Vec2& lattice) {
  const Vec2 quarter(-lattice.y(), lattice.x());
  const double a = n.dot(lattice), b = n.dot(quarter);
  if (std::abs(a) >= std::abs(b)) return a >= 0 ? lattice : Vec2(-lattice);
  return b >= 0 ? quarter : Vec2(-quarter);
}

// The angle between two lattices (unit normals, each standing for itself and its quarter turns):
// 0 to 45 degrees.
inline double angle_between_lattices_deg(const Vec2& a, const Vec2& b) {
  const double diff = std::atan2(cross(a, b), a.dot(b)) * 180.0 / M_PI;
  return std::abs(diff - 90.0 * std::round(diff / 90.0));
}

}  // namespace lodforge
