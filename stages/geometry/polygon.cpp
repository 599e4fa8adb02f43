#include "geometry/polygon.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <vector>

namespace lodforge {

double signed_area(const Ring& ring) {
  double twice = 0.0;
  for (std::size_t i = 0; i < ring.size(); ++i) {
    twice += cross(ring[i], ring[(i + 1) % ring.size()]);
  }
  return 0.5 * twice;
}

double area(const PolygonWithHoles& polygon) {
  double a = std::abs(signed_area(polygon.outer));
  for (const Ring& hole : polygon.holes) a -= std::abs(signed_area(hole));
  return a;
}

std::vector<const Ring*> rings_of(const PolygonWithHoles& polygon) {
  std::vector<const Ring*> out{&polygon.outer};
  for (const Ring& h : polygon.holes) out.push_back(&h);
  return out;
}

Ring& ring_at(PolygonWithHoles& polygon, std::size_t r) { return r == 0 ? polygon.outer : polygon.holes[r - 1]; }

std::size_t vertex_count(const PolygonWithHoles& polygon) {
  std::size_t n = polygon.outer.size();
  for (const Ring& hole : polygon.holes) n += hole.size();
  return n;
}

double perimeter(const Ring& ring) {
  double length = 0.0;
  for (std::size_t i = 0; i < ring.size(); ++i) length += edge_vector(ring, i).norm();
  return length;
}

bool point_in_ring(const Vec2& p, const Ring& ring) {
  bool inside = false;
  for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++) {
    const Vec2& a = ring[i];
    const Vec2& b = ring[j];
    if ((a.y() > p.y()) != (b.y() > p.y())) {
      const double x = a.x() + (p.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y());
      if (p.x() < x) inside = !inside;
    }
  }
  return inside;
}

namespace {

int orientation(const Vec2& a, const Vec2& b, const Vec2& c) {
  const double v = cross(b - a, c - a);
  const double scale = std::max({(b - a).squaredNorm(), (c - a).squaredNorm(), 1e-300});
  if (std::abs(v) <= 1e-12 * scale) return 0;
  return v > 0 ? 1 : -1;
}

bool on_segment(const Vec2& a, const Vec2& b, const Vec2& p) {
  return std::min(a.x(), b.x()) <= p.x() && p.x() <= std::max(a.x(), b.x()) &&
         std::min(a.y(), b.y()) <= p.y() && p.y() <= std::max(a.y(), b.y());
}

struct Segment {
  Vec2 a, b;
  int ring, index;
  double min_x() const { return std::min(a.x(), b.x()); }
  double max_x() const { return std::max(a.x(), b.x()); }
};

bool adjacent_in_ring(const Segment& s, const Segment& t, const std::vector<std::size_t>& sizes) {
  if (s.ring != t.ring) return false;
  const int n = static_cast<int>(sizes[s.ring]);
  return (s.index + 1) % n == t.index || (t.index + 1) % n == s.index;
}

// The first pair of non-adjacent segments that touch, or adjacent ones that fold back on each
// other (`fold`). Sweep over x, O(n log n + k).
struct Crossing {
  int ring = -1, index = -1;              // the first segment (ring, edge from vertex index)
  int other_ring = -1, other_index = -1;  // the second
  bool fold = false;
};

std::optional<Crossing> find_crossing(const std::vector<Ring>& rings) {
  std::vector<Segment> segments;
  std::vector<std::size_t> sizes;
  for (std::size_t r = 0; r < rings.size(); ++r) {
    sizes.push_back(rings[r].size());
    for (std::size_t i = 0; i < rings[r].size(); ++i) {
      segments.push_back({rings[r][i], rings[r][(i + 1) % rings[r].size()], static_cast<int>(r),
                          static_cast<int>(i)});
    }
  }
  std::sort(segments.begin(), segments.end(),
            [](const Segment& s, const Segment& t) { return s.min_x() < t.min_x(); });
  for (std::size_t i = 0; i < segments.size(); ++i) {
    const Segment& s = segments[i];
    for (std::size_t j = i + 1; j < segments.size() && segments[j].min_x() <= s.max_x(); ++j) {
      const Segment& t = segments[j];
      if (adjacent_in_ring(s, t, sizes)) {
        // Adjacent edges share one vertex; they are invalid only if they fold back on each other.
        const bool s_first = (s.index + 1) % static_cast<int>(sizes[s.ring]) == t.index;
        const Segment& first = s_first ? s : t;
        const Segment& second = s_first ? t : s;
        if (sizes[s.ring] > 2 && orientation(first.a, first.b, second.b) == 0 &&
            (first.b - first.a).dot(second.b - second.a) < 0)
          return Crossing{first.ring, first.index, second.ring, second.index, true};
        continue;
      }
      if (segments_intersect(s.a, s.b, t.a, t.b)) return Crossing{s.ring, s.index, t.ring, t.index, false};
    }
  }
  return std::nullopt;
}

std::string first_crossing(const std::vector<Ring>& rings) {
  const std::optional<Crossing> c = find_crossing(rings);
  if (!c) return {};
  if (c->fold) return "ring " + std::to_string(c->ring) + " folds back at vertex " + std::to_string(c->other_index);
  const Vec2& a = rings[c->ring][c->index];
  return c->ring == c->other_ring ? "ring " + std::to_string(c->ring) + " crosses itself near (" +
                                        std::to_string(a.x()) + ", " + std::to_string(a.y()) + ")"
                                  : "rings " + std::to_string(c->ring) + " and " + std::to_string(c->other_ring) +
                                        " touch or cross";
}

}  // namespace

bool segments_intersect(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  const int o1 = orientation(a, b, c), o2 = orientation(a, b, d);
  const int o3 = orientation(c, d, a), o4 = orientation(c, d, b);
  if (o1 != o2 && o3 != o4) return true;
  if (o1 == 0 && on_segment(a, b, c)) return true;
  if (o2 == 0 && on_segment(a, b, d)) return true;
  if (o3 == 0 && on_segment(c, d, a)) return true;
  if (o4 == 0 && on_segment(c, d, b)) return true;
  return false;
}

std::string ring_problem(const Ring& ring) {
  if (ring.size() < 3) return "ring has fewer than 3 vertices";
  for (std::size_t i = 0; i < ring.size(); ++i) {
    if (!std::isfinite(ring[i].x()) || !std::isfinite(ring[i].y())) return "non-finite vertex";
    if (edge_vector(ring, i).squaredNorm() == 0.0) return "zero-length edge";
  }
  if (std::string crossing = first_crossing({ring}); !crossing.empty()) return crossing;
  if (signed_area(ring) == 0.0) return "ring has zero area";
  return {};
}

PolygonWithHoles holes_that_fit(const PolygonWithHoles& polygon) {
  PolygonWithHoles kept{polygon.outer, {}};
  for (const Ring& hole : polygon.holes) {
    kept.holes.push_back(hole);
    if (!polygon_problem(kept).empty()) kept.holes.pop_back();
  }
  return kept;
}

Vec2 interior_point(const Ring& ring) {
  std::vector<double> heights;
  for (const Vec2& p : ring) heights.push_back(p.y());
  std::sort(heights.begin(), heights.end());
  heights.erase(std::unique(heights.begin(), heights.end()), heights.end());
  if (heights.size() < 2) return ring.empty() ? Vec2(0, 0) : ring.front();
  const double middle = 0.5 * (heights.front() + heights.back());
  std::size_t k = std::size_t(std::upper_bound(heights.begin(), heights.end(), middle) - heights.begin());
  k = std::clamp<std::size_t>(k, 1, heights.size() - 1);
  const double y = 0.5 * (heights[k - 1] + heights[k]);
  std::vector<double> crossings;
  for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++) {
    const Vec2 &a = ring[i], &b = ring[j];
    if ((a.y() > y) != (b.y() > y)) crossings.push_back(a.x() + (y - a.y()) * (b.x() - a.x()) / (b.y() - a.y()));
  }
  std::sort(crossings.begin(), crossings.end());
  double x = ring.front().x(), widest = -1;
  for (std::size_t i = 0; i + 1 < crossings.size(); i += 2)
    if (crossings[i + 1] - crossings[i] > widest) widest = crossings[i + 1] - crossings[i], x = 0.5 * (crossings[i] + crossings[i + 1]);
  return {x, y};
}

std::vector<std::size_t> covered_holes(const std::vector<Ring>& rings, const PolygonWithHoles& polygon) {
  std::vector<std::size_t> covered;
  for (std::size_t r = 1; r < rings.size(); ++r) {
    if (rings[r].size() < 3) continue;
    const Vec2 p = interior_point(rings[r]);
    if (point_in_ring(p, polygon.outer) &&
        std::none_of(polygon.holes.begin(), polygon.holes.end(), [&p](const Ring& hole) { return point_in_ring(p, hole); }))
      covered.push_back(r);
  }
  return covered;
}

std::string polygon_problem(const PolygonWithHoles& polygon) {
  if (std::string p = ring_problem(polygon.outer); !p.empty()) return "outer ring: " + p;
  if (signed_area(polygon.outer) <= 0) return "outer ring is not counter-clockwise";
  std::vector<Ring> rings{polygon.outer};
  for (std::size_t h = 0; h < polygon.holes.size(); ++h) {
    const Ring& hole = polygon.holes[h];
    if (std::string p = ring_problem(hole); !p.empty()) return "hole " + std::to_string(h) + ": " + p;
    if (signed_area(hole) >= 0) return "hole " + std::to_string(h) + " is not clockwise";
    if (!point_in_ring(hole.front(), polygon.outer)) {
      return "hole " + std::to_string(h) + " lies outside the outer ring";
    }
    rings.push_back(hole);
  }
  if (rings.size() > 1) {
    if (std::string p = first_crossing(rings); !p.empty()) return p;
    for (std::size_t h = 0; h < polygon.holes.size(); ++h) {
      for (std::size_t k = 0; k < polygon.holes.size(); ++k) {
        if (h != k && point_in_ring(polygon.holes[h].front(), polygon.holes[k])) {
          return "hole " + std::to_string(h) + " lies inside hole " + std::to_string(k);
        }
      }
    }
  }
  return {};
}

namespace {

// Whether vertex i is a needle's tip: its corner sharper than the angle whose cosine is min_cos.
bool is_needle(const Ring& ring, std::size_t i, double min_cos) {
  const std::size_t n = ring.size();
  const Vec2 u = ring[(i + n - 1) % n] - ring[i], v = ring[(i + 1) % n] - ring[i];
  const double lu = u.norm(), lv = v.norm();
  return lu > 0 && lv > 0 && u.dot(v) > min_cos * lu * lv;
}

// The ring with needle tip i and its shorter arm replaced by the point where the lines of the
// longer arm and of the edge beyond the shorter one meet: a short wall turning back at the end
// of a long one. Empty when the ring has fewer than 5 vertices, the shorter arm is more than half
// the longer, the lines are parallel, or they meet farther than twice the shorter arm from the tip.
Ring join_past_short_arm(const Ring& ring, std::size_t i) {
  const std::size_t n = ring.size();
  if (n < 5) return {};
  const std::size_t before = (i + n - 1) % n, after = (i + 1) % n;
  const double arm_before = (ring[before] - ring[i]).norm(), arm_after = (ring[after] - ring[i]).norm();
  if (2 * std::min(arm_before, arm_after) > std::max(arm_before, arm_after)) return {};  // a needle of two long arms
  const bool short_after = arm_after <= arm_before;
  // The longer arm's line (p0, p1), the line beyond the shorter arm (q0, q1), the vertices replaced.
  const Vec2 p0 = short_after ? ring[before] : ring[after], p1 = ring[i];
  const Vec2 q0 = short_after ? ring[after] : ring[before];
  const Vec2 q1 = short_after ? ring[(i + 2) % n] : ring[(i + n - 2) % n];
  const Vec2 dp = p1 - p0, dq = q1 - q0;
  const double det = cross(dp, dq);
  if (std::abs(det) <= 1e-12 * dp.norm() * dq.norm()) return {};
  const Vec2 x = p0 + (cross(q0 - p0, dq) / det) * dp;
  if ((x - ring[i]).norm() > 2 * (q0 - ring[i]).norm()) return {};
  Ring out = ring;
  out[i] = x;
  out.erase(out.begin() + std::ptrdiff_t(short_after ? after : before));
  return out;
}

}  // namespace

std::size_t remove_spikes(PolygonWithHoles& polygon, double max_angle_deg, double max_side) {
  const double min_cos = std::cos(max_angle_deg * M_PI / 180.0);
  const double max_area_change = max_side * max_side;
  std::size_t changes = 0;
  // (The area a change moves is its net change: a drop takes the needle's triangle off, a join
  // the triangle between the tip, the short arm's end and the new corner, each on one side.)
  for (std::size_t r = 0; r <= polygon.holes.size(); ++r) {
    for (bool changed = true; changed;) {  // each change makes new corners: again until none is taken
      changed = false;
      for (std::size_t i = 0; !changed && ring_at(polygon, r).size() > 3 && i < ring_at(polygon, r).size(); ++i) {
        const Ring& ring = ring_at(polygon, r);  // (looked up again: a change replaces the polygon's holes)
        if (!is_needle(ring, i, min_cos)) continue;
        std::array<Ring, 2> candidates{join_past_short_arm(ring, i), ring};
        candidates[1].erase(candidates[1].begin() + std::ptrdiff_t(i));
        const double area_before = area(polygon);
        for (Ring& candidate : candidates) {
          if (candidate.size() < 3) continue;
          PolygonWithHoles trial = polygon;
          ring_at(trial, r) = std::move(candidate);
          if (std::abs(area(trial) - area_before) <= max_area_change && polygon_problem(trial).empty()) {
            polygon = std::move(trial);
            changed = true;
            ++changes;
            break;
          }
        }
      }
    }
  }
  return changes;
}

bool inside_convex(const Vec2& p, const Ring& convex, double margin) {
  for (std::size_t k = 0; k < convex.size(); ++k) {
    const Vec2 &a = convex[k], &b = convex[(k + 1) % convex.size()];
    const double side = (b - a).norm();
    if (side > 0 && cross(b - a, p - a) < margin * side) return false;
  }
  return true;
}

Ring flatten_along_line(const Ring& ring, const Vec2& a, const Vec2& b, double depth, const std::function<bool(const Vec2&)>& filled,
                        double sample_step) {
  const std::size_t n = ring.size();
  const double length = (b - a).norm();
  if (n < 4 || !(length > 0) || !(depth > 0)) return ring;
  const Vec2 u = (b - a) / length;
  const double eps = 1e-9 * std::max(1.0, std::max(length, (ring[0] - a).norm()));
  std::vector<double> offset(n);
  std::vector<std::size_t> on;  // the vertices on the line, in order
  for (std::size_t i = 0; i < n; ++i) {
    offset[i] = std::abs(cross(u, ring[i] - a));
    if (offset[i] <= eps) on.push_back(i);
  }
  if (on.size() < 2) return ring;
  std::vector<char> drop(n, 0);
  const double ring_area = filled ? signed_area(ring) : 0.0;
  for (std::size_t k = 0; k < on.size(); ++k) {
    const std::size_t i = on[k], j = on[(k + 1) % on.size()];
    const std::size_t between = (j + n - i - 1) % n;  // (j after i, going round)
    if (between == 0 || between + 2 > n) continue;
    bool shallow = true;
    for (std::size_t s = 1; s <= between && shallow; ++s) shallow = offset[(i + s) % n] <= depth;
    // (A dip: the path from i to j and the line back from j to i turn against the ring, its area
    // outside it; sampled on a grid of sample_step, coarser where that would take more than 400
    // points, the points inside the dip, at least one, at least 95 % of them filled.)
    const auto dip_filled = [&] {
      Ring loop;
      for (std::size_t s = 0; s <= between + 1; ++s) loop.push_back(ring[(i + s) % n]);
      const double loop_area = signed_area(loop);
      if (!(loop_area * ring_area < 0)) return false;
      Vec2 low = loop[0], high = loop[0];
      for (const Vec2& v : loop) low = low.cwiseMin(v), high = high.cwiseMax(v);
      const double step = std::max(sample_step, std::sqrt(std::abs(loop_area) / 400));
      if (!(step > 0)) return false;
      std::size_t inside = 0, full = 0;
      for (double y = low.y() + 0.5 * step; y < high.y(); y += step)
        for (double x = low.x() + 0.5 * step; x < high.x(); x += step) {
          const Vec2 p(x, y);
          if (!point_in_ring(p, loop)) continue;
          ++inside;
          full += filled(p);
        }
      return inside > 0 && double(full) >= 0.95 * double(inside);
    };
    if (shallow || (filled && dip_filled()))
      for (std::size_t s = 1; s <= between; ++s) drop[(i + s) % n] = 1;
  }
  Ring out;
  for (std::size_t i = 0; i < n; ++i)
    if (!drop[i]) out.push_back(ring[i]);
  return out.size() >= 3 ? out : ring;
}

Ring remove_degenerate_vertices(const Ring& ring, double eps) {
  Ring out = ring;
  bool changed = true;
  while (changed && out.size() >= 3) {
    changed = false;
    Ring kept;
    kept.reserve(out.size());
    const std::size_t n = out.size();
    for (std::size_t i = 0; i < n; ++i) {
      const Vec2& prev = kept.empty() ? out[(i + n - 1) % n] : kept.back();
      const Vec2& cur = out[i];
      const Vec2& next = out[(i + 1) % n];
      if ((cur - prev).norm() < eps) { changed = true; continue; }
      const Vec2 chord = next - prev;
      const double length = chord.norm();
      const bool collinear = length > eps && std::abs(cross(chord, cur - prev)) / length < eps &&
                             (cur - prev).dot(next - cur) > 0;
      if (collinear) { changed = true; continue; }
      kept.push_back(cur);
    }
    out.swap(kept);
  }
  return out;
}

namespace {

// Marks the vertices to keep in the open chain pts[first..last] (inclusive).
void simplify_chain(const std::vector<Vec2>& pts, std::size_t first, std::size_t last,
                    double tolerance, std::vector<char>& keep) {
  std::vector<std::pair<std::size_t, std::size_t>> stack{{first, last}};
  while (!stack.empty()) {
    auto [i, j] = stack.back();
    stack.pop_back();
    double worst = -1;
    std::size_t index = i;
    for (std::size_t k = i + 1; k < j; ++k) {
      const double d = distance_to_segment(pts[k], pts[i], pts[j]);
      if (d > worst) { worst = d; index = k; }
    }
    if (worst > tolerance) {
      keep[index] = 1;
      stack.push_back({i, index});
      stack.push_back({index, j});
    }
  }
}

}  // namespace

std::vector<char> douglas_peucker_open(const std::vector<Vec2>& points, double tolerance) {
  std::vector<char> keep(points.size(), 0);
  if (points.empty()) return keep;
  keep.front() = keep.back() = 1;
  if (points.size() > 2) simplify_chain(points, 0, points.size() - 1, tolerance, keep);
  return keep;
}

Ring douglas_peucker(const Ring& ring, double tolerance) {
  const std::size_t n = ring.size();
  if (n <= 3) return ring;
  // Anchor on the vertex farthest from vertex 0, split the ring into two chains.
  std::size_t far = 0;
  double far_distance = -1;
  for (std::size_t i = 1; i < n; ++i) {
    const double d = (ring[i] - ring[0]).squaredNorm();
    if (d > far_distance) { far_distance = d; far = i; }
  }
  std::vector<Vec2> pts(ring.begin(), ring.end());
  pts.push_back(ring[0]);
  std::vector<char> keep(pts.size(), 0);
  keep[0] = keep[far] = 1;
  simplify_chain(pts, 0, far, tolerance, keep);
  simplify_chain(pts, far, n, tolerance, keep);
  Ring out;
  for (std::size_t i = 0; i < n; ++i) if (keep[i]) out.push_back(ring[i]);
  if (out.size() < 3) {  // keep a triangle at least: add the vertex farthest from the chord
    std::size_t best = 0;
    double best_distance = -1;
    for (std::size_t i = 0; i < n; ++i) {
      const double d = distance_to_segment(ring[i], ring[0], ring[far]);
      if (d > best_distance && i != 0 && i != far) { best_distance = d; best = i; }
    }
    out = {ring[0]};
    if (best < far) { out.push_back(ring[best]); out.push_back(ring[far]); }
    else { out.push_back(ring[far]); out.push_back(ring[best]); }
  }
  return out;
}

bool untangle(Ring& ring, double max_width) {
  const double sign = signed_area(ring) >= 0 ? 1.0 : -1.0;
  Ring out = ring;
  for (std::size_t attempt = 0; attempt < ring.size(); ++attempt) {
    const std::optional<Crossing> c = find_crossing({out});
    if (!c) break;
    const int n = static_cast<int>(out.size());
    if (c->fold) {  // a spike: its tip goes
      out.erase(out.begin() + c->other_index);
      continue;
    }
    const int i = std::min(c->index, c->other_index), j = std::max(c->index, c->other_index);
    // Where edge i (i to i+1) meets edge j (j to j+1); for overlapping collinear edges, a shared point.
    const Vec2 u = out[(i + 1) % n] - out[i], v = out[(j + 1) % n] - out[j];
    const double det = cross(u, v);
    Vec2 x = out[(i + 1) % n];
    if (std::abs(det) > 1e-12 * u.norm() * v.norm()) x = out[i] + u * (cross(out[j] - out[i], v) / det);
    else if (on_segment(out[i], out[(i + 1) % n], out[j])) x = out[j];
    Ring first{x}, second{x};  // the two loops the crossing makes
    for (int k = i + 1; k <= j; ++k) first.push_back(out[k]);
    for (int k = j + 1; k != i + 1 + n; ++k) second.push_back(out[k % n]);
    first = remove_degenerate_vertices(first, 1e-9);
    second = remove_degenerate_vertices(second, 1e-9);
    const double a1 = first.size() >= 3 ? sign * signed_area(first) : 0.0;
    const double a2 = second.size() >= 3 ? sign * signed_area(second) : 0.0;
    Ring& keep = a1 >= a2 ? first : second;
    const Ring& cut = a1 >= a2 ? second : first;
    if (std::max(a1, a2) <= 0) return false;
    // A loop's mean width: its area over half its perimeter.
    if (cut.size() >= 3 && 2 * std::abs(signed_area(cut)) > max_width * perimeter(cut)) return false;
    out = std::move(keep);
  }
  if (!ring_problem(out).empty()) return false;
  ring = std::move(out);
  return true;
}

}  // namespace lodforge
