#include "lod1/solid.hpp"

#include <Eigen/Geometry>
#include <map>
#include <tuple>

namespace lodforge {

namespace {

Ring3 lift(const Ring& ring, double z, bool reversed) {
  Ring3 out;
  for (const Vec2& p : ring) out.emplace_back(p.x(), p.y(), z);
  if (reversed) std::reverse(out.begin(), out.end());
  return out;
}

// Newell's area vector: its direction is the face normal, its length the area.
Vec3 area_vector(const Ring3& ring) {
  Vec3 n = Vec3::Zero();
  for (std::size_t i = 0; i < ring.size(); ++i) n += ring[i].cross(ring[(i + 1) % ring.size()]);
  return 0.5 * n;
}

using Key = std::tuple<double, double, double>;
Key key(const Vec3& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace

Solid extrude(const PolygonWithHoles& f, double ground, double roof) {
  Solid s;
  Face bottom, top;
  bottom.rings.push_back(lift(f.outer, ground, true));  // seen from below: reversed
  top.rings.push_back(lift(f.outer, roof, false));
  for (const Ring& h : f.holes) {
    bottom.rings.push_back(lift(h, ground, true));
    top.rings.push_back(lift(h, roof, false));
  }
  s.faces.push_back(std::move(bottom));
  s.faces.push_back(std::move(top));
  auto walls = [&](const Ring& ring) {
    for (std::size_t i = 0; i < ring.size(); ++i) {
      const Vec2& a = ring[i];
      const Vec2& b = ring[(i + 1) % ring.size()];
      // The interior is on the left of a -> b, so a_g, b_g, b_r, a_r faces outward.
      s.faces.push_back({{{Vec3(a.x(), a.y(), ground), Vec3(b.x(), b.y(), ground), Vec3(b.x(), b.y(), roof), Vec3(a.x(), a.y(), roof)}}});
    }
  };
  walls(f.outer);
  for (const Ring& h : f.holes) walls(h);
  return s;
}

double volume(const Solid& s) {
  double v = 0;
  for (const Face& f : s.faces)
    for (const Ring3& r : f.rings) v += r.front().dot(area_vector(r)) / 3.0;
  return v;
}

std::string shell_problem(const Solid& s, double tolerance) {
  std::map<std::pair<Key, Key>, int> directed;
  for (std::size_t fi = 0; fi < s.faces.size(); ++fi) {
    const Face& f = s.faces[fi];
    const std::string where = "face " + std::to_string(fi);
    if (f.rings.empty()) return where + ": no ring";
    Vec3 normal = Vec3::Zero();
    for (const Ring3& r : f.rings) normal += area_vector(r);
    if (normal.norm() <= tolerance * tolerance) return where + ": degenerate (zero area)";
    normal.normalize();
    const double offset = normal.dot(f.rings.front().front());
    for (const Ring3& r : f.rings) {
      if (r.size() < 3) return where + ": ring with fewer than 3 vertices";
      for (std::size_t i = 0; i < r.size(); ++i) {
        const Vec3& a = r[i];
        const Vec3& b = r[(i + 1) % r.size()];
        if ((a - b).norm() <= tolerance) return where + ": duplicate consecutive vertex";
        if (std::abs(normal.dot(a) - offset) > tolerance * (1 + std::abs(offset))) return where + ": not planar";
        if (++directed[{key(a), key(b)}] > 1) return where + ": an edge is used twice in the same direction (not 2-manifold or wrongly oriented)";
      }
    }
  }
  for (const auto& [edge, count] : directed) {
    if (!directed.count({edge.second, edge.first})) return "the shell is not closed: an edge has no opposite";
  }
  if (volume(s) <= 0) return "faces point inward (negative volume)";
  return {};
}

}  // namespace lodforge
