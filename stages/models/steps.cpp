#include "models/steps.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "geometry/polygon.hpp"
#include "geometry/segment_grid.hpp"
#include "models/rectangle.hpp"

namespace lodforge {

namespace {

// Walls meeting within this (the sine of 10 degrees) of parallel do not meet.
const double kMinMeetSin = std::sin(10.0 * M_PI / 180.0);

// Where the line through p along u meets the line through q along v; none when nearly parallel
// (or either direction vanishes, or is not finite).
std::optional<Vec2> meet(const Vec2& p, const Vec2& u, const Vec2& q, const Vec2& v) {
  const double det = cross(u, v);
  if (!(std::abs(det) > kMinMeetSin * u.norm() * v.norm())) return std::nullopt;
  return p + cross(q - p, v) / det * u;
}

// A ring's cheapest step: the vertex i whose walls (i-1, i) and (i+1, i+2) merge, and where the
// merged wall meets the walls before and after.
struct Step {
  double cost = std::numeric_limits<double>::infinity();
  std::size_t i = 0;
  Vec2 from = Vec2::Zero(), to = Vec2::Zero();
};

Step cheapest_step(const Ring& ring, double cos_parallel) {
  Step best;
  const std::size_t n = ring.size();
  if (n < 6) return best;
  const auto at = [&](std::size_t k) { return ring[k % n]; };
  for (std::size_t i = 0; i < n; ++i) {
    // Walls a = (i-1, i), b = (i, i+1) and c = (i+1, i+2), with (i-2, i-1) before and (i+2, i+3) after.
    const Vec2 p0 = at(i + n - 2), p1 = at(i + n - 1), p2 = at(i), p3 = at(i + 1), p4 = at(i + 2), p5 = at(i + 3);
    const Vec2 a = p2 - p1, c = p4 - p3;
    const double la = a.norm(), lc = c.norm();
    if (la <= 0 || lc <= 0 || a.dot(c) < cos_parallel * la * lc) continue;
    const Vec2 u = (a + c).normalized();  // the length-weighted direction
    const Vec2 normal(-u.y(), u.x());
    const double offset = std::abs(normal.dot(0.5 * (p3 + p4) - 0.5 * (p1 + p2)));
    const double cost = 2.0 * la * lc / (la + lc) * offset;
    if (!(cost < best.cost)) continue;
    const Vec2 through = (la * 0.5 * (p1 + p2) + lc * 0.5 * (p3 + p4)) / (la + lc);
    const std::optional<Vec2> from = meet(p0, p1 - p0, through, u), to = meet(through, u, p4, p5 - p4);
    if (!from || !to || !from->allFinite() || !to->allFinite()) continue;
    best = {cost, i, *from, *to};
  }
  return best;
}

// A ring's values per vertex from vertex i+3 round to vertex i-2: with a step at i merged, the
// meeting points follow them in place of vertices i-1 .. i+2.
template <class T>
std::vector<T> rotate_past(const std::vector<T>& values, std::size_t i) {
  const std::size_t n = values.size();
  std::vector<T> out;
  out.reserve(n - 2);
  for (std::size_t k = 0; k + 4 < n; ++k) out.push_back(values[(i + 3 + k) % n]);
  return out;
}

// The ring with its step merged.
Ring merged_ring(const Ring& ring, const Step& step) {
  Ring merged = rotate_past(ring, step.i);
  merged.push_back(step.from);
  merged.push_back(step.to);
  return merged;
}

// Of every ring, the cheapest step: the ring's index (-1: none) and the step.
std::pair<int, Step> cheapest_of(const PolygonWithHoles& polygon, double cos_parallel) {
  std::pair<int, Step> best{-1, Step{}};
  const std::vector<const Ring*> rings = rings_of(polygon);
  for (std::size_t r = 0; r < rings.size(); ++r) {
    const Step s = cheapest_step(*rings[r], cos_parallel);
    if (s.cost < best.second.cost) best = {int(r), s};
  }
  return best;
}

// The most walls a rounding is drawn with between its two walls: at 0.1 m a rounding of 2 m is
// drawn with 5-10 (as a few steps, or walls along the arc), at 0.25 m with 1-4.
constexpr std::size_t kMaxRoundingWalls = 12;

// A ring's rounded corners: the first vertex of the walls through which each meets (after wall a),
// how many walls, and the point where its two walls meet. Its square corners: two walls at least
// min_wall long within square_cos of square, met directly or through walls shorter than max_cut
// together, inside their corner; *square counts them, *corners (when given) gets the point where
// each one's walls meet.
struct RoundedCorner {
  std::size_t first;  // the vertex after wall a's start: wall a ends there
  std::size_t walls;  // the short walls between wall a and wall b
  double length;      // ... together
  Vec2 corner;
};
std::vector<RoundedCorner> rounded_corners(const Ring& ring, double min_wall, double max_cut, double square_cos, std::size_t* square,
                                           std::vector<Vec2>* corners = nullptr) {
  const std::size_t n = ring.size();
  std::vector<RoundedCorner> rounded;
  *square = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 a0 = ring[i], wall_a = ring[(i + 1) % n] - a0;
    if (wall_a.norm() < min_wall) continue;
    double chain = 0;
    for (std::size_t k = 0; k <= kMaxRoundingWalls && k + 3 <= n; ++k) {  // k short walls after wall a
      if (k > 0) chain += (ring[(i + k + 1) % n] - ring[(i + k) % n]).norm();
      if (chain >= max_cut) break;
      const Vec2 b0 = ring[(i + k + 1) % n], wall_b = ring[(i + k + 2) % n] - b0;
      if (wall_b.norm() < min_wall || std::abs(wall_a.dot(wall_b)) > square_cos * wall_a.norm() * wall_b.norm()) continue;
      const double det = cross(wall_a, wall_b);
      if (det == 0) continue;
      const Vec2 corner = a0 + (cross(b0 - a0, wall_b) / det) * wall_a;
      if (!corner.allFinite()) continue;
      if (k == 0) {
        ++*square;
        if (corners) corners->push_back(b0);
        break;
      }
      // Every vertex of the walls between (the end of wall a .. the start of wall b) inside the
      // corner: on the side of wall a's line that wall b goes to, on the side of wall b's line that
      // wall a comes from, and near the corner. (Wall a's end lies on its own line and wall b's
      // start on its own: not tested against them, where rounding could put them a hair outside.)
      bool inside = true;
      for (std::size_t j = 1; j <= k + 1 && inside; ++j) {
        const Vec2 q = ring[(i + j) % n];
        inside = (j == 1 || cross(wall_a, q - a0) * det >= 0) && (j == k + 1 || cross(wall_b, q - b0) * det >= 0) &&
                 (q - corner).norm() <= chain;
      }
      if (!inside) continue;
      ++*square;
      if (corners) corners->push_back(corner);
      rounded.push_back({(i + 1) % n, k, chain, corner});
      break;
    }
  }
  return rounded;
}

// The area between a corner and the `walls` walls of the ring from vertex `first` on, each wall's
// triangle with the corner counted as it lies (a chain that bows out and back in counts both).
double area_off_corner(const Ring& ring, std::size_t first, std::size_t walls, const Vec2& corner) {
  const std::size_t n = ring.size();
  double twice = 0;
  for (std::size_t j = 0; j < walls; ++j) twice += std::abs(cross(ring[(first + j) % n] - corner, ring[(first + j + 1) % n] - corner));
  return 0.5 * twice;
}

// Replaces `count` vertices of the ring from `first` on (cyclically) by `points`, in place: the
// other vertices keep their order (and, where there are no more points than vertices replaced,
// their places in the ring).
void replace_vertices(Ring& ring, std::size_t first, std::size_t count, const std::vector<Vec2>& points) {
  const std::size_t n = ring.size();
  if (points.size() > count) {  // (more: the points where `first` was, the others dropped)
    Ring out;
    out.reserve(n - count + points.size());
    for (std::size_t j = 0; j < n; ++j) {
      if (j == first % n) out.insert(out.end(), points.begin(), points.end());
      else if ((j + n - first % n) % n >= count) out.push_back(ring[j]);
    }
    ring = std::move(out);
    return;
  }
  std::vector<std::size_t> at;
  for (std::size_t j = 0; j < count; ++j) at.push_back((first + j) % n);
  for (std::size_t j = 0; j < points.size(); ++j) ring[at[j]] = points[j];
  std::vector<std::size_t> gone(at.begin() + long(points.size()), at.end());
  std::sort(gone.rbegin(), gone.rend());
  for (std::size_t g : gone) ring.erase(ring.begin() + long(g));
}

// A chain of walls to square on a ring, from the vertex where wall a, on the lattice, ends
// through `walls` walls to the vertex where wall c, on the lattice, starts.
struct Chain {
  std::size_t walls = 0;
  bool rounding = false;  // taken by its length (max_chain), not by the noise
  bool knob = false;      // ... as a bump between walls on about one line (a rounded knob or notch)
};

// The chain from vertex i to square, if any: walls off the lattice between two walls on it,
// (1) together shorter than max_chain, a and c at least min_wall long (the short walls on the
// lattice between them part of the chain: a rounding drawn as a few steps), or (2) one wall whose
// direction the noise does not tell from the lattice's (a and c any length).
std::optional<Chain> chain_from(const Ring& ring, std::size_t i, double on_sin, const Vec2& axis, double noise, double correlation,
                                double k, double max_chain, double min_wall) {
  const std::size_t n = ring.size();
  const auto wall = [&](std::size_t j) { return ring[(j + 1) % n] - ring[j % n]; };  // wall j: vertex j to j+1
  const auto off_sin = [&](const Vec2& e) {
    const double length = e.norm();
    return length > 0 ? std::abs(cross(e / length, nearest_lattice_axis(e / length, axis))) : 0.0;
  };
  const Vec2 a = wall(i + n - 1);
  if (!(a.norm() > 0) || off_sin(a) > on_sin) return std::nullopt;
  if (max_chain > 0 && a.norm() >= min_wall) {
    // Shorter than max_chain to a wall square to a's (a corner), or to a wall parallel to it (a
    // step) spanning less than max_chain along a's axis and less than 1.5 max_chain and min_wall
    // across it: a rounding of radius R = max_chain / 2 spreads a step that far along its walls,
    // and no farther; it leaves a step d high a straight riser d - 2R long, which the outline
    // draws into the roundings' oblique wall where shorter than R and min_wall (the annex of a row
    // house, narrower than 2R, rounded to a wedge), and keeps on the lattice where longer.
    // Or, back to a's line, a knob or a notch a rounding drew as a bump: spanning less than twice
    // max_chain and min_wall along it (a knob narrower than max_chain and min_wall, whose top kept
    // no wall on the lattice, and the roundings at its sides), and reaching less than max_chain
    // and min_wall off the line.
    const Vec2 along = nearest_lattice_axis(a / a.norm(), axis);
    double reach = 0;  // the chain's farthest vertex off a's line so far
    const auto rounded_step = [&](std::size_t m) {  // the chain up to vertex i + m, as a step's
      const Vec2 d = ring[(i + m) % n] - ring[i % n];
      return std::abs(along.dot(d)) < max_chain && std::abs(cross(along, d)) < 1.5 * max_chain + min_wall;
    };
    const auto rounded_knob = [&](std::size_t m, bool back) {  // ... as a knob's, so far (back: and back at a's line)
      const Vec2 d = ring[(i + m) % n] - ring[i % n];
      return std::abs(along.dot(d)) < 2 * max_chain + min_wall && reach < max_chain + min_wall &&
             (!back || std::abs(cross(along, d)) <= 0.5 * reach);
    };
    double length = 0;
    bool oblique = false;
    for (std::size_t m = 0; m + 3 <= n && m <= kMaxRoundingWalls; ++m) {
      const Vec2 w = wall(i + m);
      const bool on = !(w.norm() > 0) || off_sin(w) <= on_sin;  // (a wall of no length is no oblique one)
      if (on && w.norm() > 0 && w.norm() >= min_wall) {
        const bool step = std::abs(along.dot(w)) > 0.5 * w.norm();
        if (oblique && step && rounded_knob(m, true)) return Chain{m, true, true};
        if (oblique && (step ? rounded_step(m) : length < max_chain)) return Chain{m, true};
        break;
      }
      oblique = oblique || !on;
      length += w.norm();
      reach = std::max(reach, std::abs(cross(along, ring[(i + m + 1) % n] - ring[i % n])));
      if (length >= max_chain && !rounded_step(m + 1) && !rounded_knob(m + 1, false)) break;
    }
  }
  if (!(k > 0) || !(noise > 0)) return std::nullopt;
  const Vec2 b = wall(i), c = wall(i + 1);
  if (!(b.norm() > 0) || !(c.norm() > 0) || off_sin(c) > on_sin) return std::nullopt;
  const double sin_turn = off_sin(b);
  if (sin_turn <= on_sin) return std::nullopt;
  const double uncertainty = noise * std::sqrt(3 * correlation / std::max(b.norm(), correlation));
  if (sin_turn * 0.5 * b.norm() > k * uncertainty) return std::nullopt;
  return Chain{1, false};
}

// The rectangle a bump between walls a (ending at vertex i) and c (starting at vertex i + m) on
// about one line is drawn as, under a rounding: its four corners from a's line to c's, as deep
// off a's line (on the side of the chain's farthest vertex) as that vertex, keeping the area
// between the chain and a's line and its first moment along it (the strip under c's line, where
// c's line lies off a's, counted); none where the chain crosses a's line and c's (by more than a
// hundredth of its depth), the bump is shallower than half min_wall, or the rectangle does not
// fit within the chain's span or is narrower than min_wall (a needle, no knob).
std::optional<std::vector<Vec2>> knob_of(const Ring& ring, std::size_t i, std::size_t m, const Vec2& along, Vec2 across,
                                         double min_wall) {
  const std::size_t n = ring.size();
  const Vec2 p0 = ring[(i + n - 1) % n], p1 = ring[i % n], p2 = ring[(i + m) % n], p3 = ring[(i + m + 1) % n];
  double farthest = 0;
  for (std::size_t j = 1; j < m; ++j) {
    const double h = across.dot(ring[(i + j) % n] - p1);
    if (std::abs(h) > std::abs(farthest)) farthest = h;
  }
  if (farthest < 0) across = -across;  // (the bump on the other side)
  double area = 0, moment = 0, deepest = 0, shallowest = 0;
  for (std::size_t j = 0; j < m; ++j) {
    const Vec2 q0 = ring[(i + j) % n] - p1, q1 = ring[(i + j + 1) % n] - p1;
    const double u0 = along.dot(q0), u1 = along.dot(q1), h0 = across.dot(q0), h1 = across.dot(q1);
    area += 0.5 * (h0 + h1) * (u1 - u0);
    moment += (u1 - u0) * (h0 * (2 * u0 + u1) + h1 * (u0 + 2 * u1)) / 6;  // (the trapezoid's first moment along the line)
    if (j + 1 < m) deepest = std::max(deepest, h1), shallowest = std::min(shallowest, h1);
  }
  const double end = along.dot(p2 - p1), offset = across.dot(p2 - p1);
  if (!(area > 0) || !(end > 0) || !(deepest > std::max(0.0, offset)) || deepest < 0.5 * min_wall ||
      shallowest < std::min(0.0, offset) - 0.01 * deepest)
    return std::nullopt;
  // Under the rectangle (near to far, `deepest` high) and then c's line (far to end, `offset`):
  // area deepest * width + offset * (end - far), first moment deepest * width * centre +
  // offset * (end^2 - far^2) / 2, solved by a few substitutions from the rectangle on a's line
  // (offset is small against deepest).
  double width = area / deepest, centre = moment / area;
  for (int k = 0; k < 8 && width > 0; ++k) {
    const double far = centre + 0.5 * width;
    width = (area - offset * (end - far)) / deepest;
    if (width > 0) centre = (moment - 0.5 * offset * (end * end - far * far)) / (deepest * width);
  }
  const double near = centre - 0.5 * width, far = centre + 0.5 * width;
  if (!(width >= min_wall) || near < 0 || far > end) return std::nullopt;
  const Vec2 top_near = p1 + near * along + deepest * across, top_far = p1 + far * along + deepest * across;
  const std::optional<Vec2> from = meet(p0, p1 - p0, top_near, across), to = meet(top_far, across, p2, p3 - p2);
  if (!from || !to || !from->allFinite() || !to->allFinite() || (*from - p0).dot(p1 - p0) <= 0 || (p3 - *to).dot(p3 - p2) <= 0 ||
      across.dot(top_near - *from) <= 0 || across.dot(top_far - *to) <= 0)  // (a's or c's line tilted past the top)
    return std::nullopt;
  return std::vector<Vec2>{*from, top_near, top_far, *to};
}

// square_connectors on one ring; true when a wall was squared.
bool square_ring(Ring& ring, const Vec2& lattice, double on_deg, double noise, double correlation, double k, double max_chain,
                 double min_wall) {
  const Vec2 axis = lattice.normalized();
  const double on_sin = std::sin(on_deg * M_PI / 180.0);
  bool any = false;
  // (Each change leaves fewer walls off the lattice: a step's new wall lies on it, a corner drops
  // the walls. The bound on the passes is a guard.)
  for (std::size_t pass = 0, passes = ring.size(); pass < passes && ring.size() >= 5; ++pass) {
    bool changed = false;
    const std::size_t n = ring.size();
    for (std::size_t i = 0; i < n && !changed; ++i) {
      const std::optional<Chain> chain = chain_from(ring, i, on_sin, axis, noise, correlation, k, max_chain, min_wall);
      if (!chain) continue;
      // Walls a = (i-1, i) and c = (i+m, i+m+1), the chain's m walls between.
      const std::size_t m = chain->walls;
      const Vec2 p0 = ring[(i + n - 1) % n], p1 = ring[i], p2 = ring[(i + m) % n], p3 = ring[(i + m + 1) % n];
      const Vec2 a = p1 - p0, c = p3 - p2;
      // The axes a and c lie along (each within on_deg of one).
      const Vec2 along_a = nearest_lattice_axis(a.normalized(), axis), along_c = nearest_lattice_axis(c.normalized(), axis);
      const double same = along_a.dot(along_c);
      // Where the lines of a and c meet the line through `point` along `direction`: past a's start
      // and before c's end, else none.
      const auto ends_through = [&](const Vec2& point, const Vec2& direction) -> std::optional<std::vector<Vec2>> {
        const std::optional<Vec2> from = meet(p0, a, point, direction), to = meet(point, direction, p3, c);
        if (!from || !to || !from->allFinite() || !to->allFinite() || (*from - p0).dot(a) <= 0 || (p3 - *to).dot(c) <= 0)
          return std::nullopt;
        return std::vector<Vec2>{*from, *to};
      };
      // The chain (with a's end and c's start) replaced by `points` where the ring stays valid and
      // its area changes by no more than max_area_change: true when it was. (One that would cross
      // the ring elsewhere is left, not the ring's other squarings.)
      const auto replaced_if_valid = [&](const std::vector<Vec2>& points, double max_area_change) {
        Ring replaced = ring;
        replace_vertices(replaced, i, m + 1, points);
        if (std::abs(signed_area(replaced) - signed_area(ring)) > max_area_change || !ring_problem(replaced).empty()) return false;
        ring = std::move(replaced);
        return true;
      };
      if (same > 0.5) {
        // A step along the lattice, square to a's axis, where it keeps the area between the
        // chain and the lines of a and c: at a single wall's middle (between walls on the
        // lattice the two triangles it swaps are equal).
        Vec2 across(-along_a.y(), along_a.x());
        if (across.dot(p2 - p1) < 0) across = -across;
        if (chain->knob) {
          // A bump that reaches one way off a's line, back at it: drawn as a rectangle as deep as
          // it reaches (its deepest vertex), keeping its area and its centre along the line.
          const std::optional<std::vector<Vec2>> knob = knob_of(ring, i, m, along_a, across, min_wall);
          if (!knob || !replaced_if_valid(*knob, std::numeric_limits<double>::infinity())) continue;
          changed = any = true;
          continue;
        }
        Vec2 riser = 0.5 * (p1 + p2);
        if (m > 1) {
          // Along a's axis from p1 (u) and across it (the offset), the area under the chain;
          // under a step at u it is offset * (end - u).
          double area = 0;
          for (std::size_t j = 0; j < m; ++j) {
            const Vec2 q0 = ring[(i + j) % n] - p1, q1 = ring[(i + j + 1) % n] - p1;
            area += 0.5 * across.dot(q0 + q1) * along_a.dot(q1 - q0);
          }
          const double end = along_a.dot(p2 - p1), offset = across.dot(p2 - p1);
          const double u = offset > 0 ? end - area / offset : -1.0;
          if (!(u >= 0 && u <= end)) continue;  // (a notch or a knob between walls on one line: no step)
          riser = p1 + u * along_a;
        }
        const std::optional<std::vector<Vec2>> ends = ends_through(riser, across);
        if (!ends) continue;
        replace_vertices(ring, i, m + 1, *ends);
      } else if (std::abs(same) < 0.5) {
        // The corner where a and c meet (square to each other); for a chain taken as a rounding,
        // where it moves no more area than the triangle of a rounding of radius max_chain / 2
        // between its tangent points: more, and the chain drew a step or a wing beside the corner
        // that the rounding merged into it.
        const std::optional<Vec2> corner = meet(p0, a, p3, c);
        if (!corner || !corner->allFinite() || (*corner - p0).dot(a) <= 0 || (p3 - *corner).dot(c) <= 0) continue;
        if (chain->rounding && area_off_corner(ring, i, m, *corner) > 0.5 * std::pow(0.5 * max_chain, 2)) continue;
        replace_vertices(ring, i, m + 1, {*corner});
      } else if (chain->rounding) {
        // A U-turn between a and c under a rounding: the end of a wing, or the bottom of a yard,
        // narrower than the roundings that met across it (no wall on the lattice left between
        // them). Its end wall square to a's axis through the chain's farthest vertex along a
        // (where a rounding keeps the end of a wing at least its diameter wide), its corners where
        // a's and c's lines meet it; where the chain stays between those lines (within a tenth of
        // the rounding's radius) and the end moves no more area than the triangles of two
        // roundings of radius max_chain / 2 between their tangent points (more: an outline's
        // vertex past the contour, no rounding's). Not where a and c lie less than min_wall
        // apart: a needle, whose end remove_spikes takes.
        const Vec2 across(-along_a.y(), along_a.x());
        const double width = across.dot(p2 - p1), slack = 0.05 * max_chain;
        if (!(std::abs(width) >= min_wall)) continue;
        double reach = 0;
        Vec2 apex = p1;
        bool inside = true;
        for (std::size_t j = 1; j <= m && inside; ++j) {
          const Vec2 q = ring[(i + j) % n];
          const double d = along_a.dot(q - p1), t = across.dot(q - p1);
          inside = t >= std::min(0.0, width) - slack && t <= std::max(0.0, width) + slack;
          if (d > reach) reach = d, apex = q;
        }
        if (!inside || !(reach > 0)) continue;
        const std::optional<std::vector<Vec2>> ends = ends_through(apex, across);
        if (!ends || !replaced_if_valid(*ends, std::pow(0.5 * max_chain, 2))) continue;
      } else {
        continue;  // (a and c facing each other: the end of a spike, no connector)
      }
      changed = any = true;
    }
    if (!changed) break;
  }
  return any;
}

}  // namespace

std::optional<PolygonWithHoles> square_connectors(const PolygonWithHoles& polygon, const Vec2& lattice, double on_deg,
                                                  double noise, double correlation, double k, double max_chain, double min_wall) {
  if (lattice.squaredNorm() <= 0 || !((k > 0 && noise > 0) || max_chain > 0)) return std::nullopt;
  double extent = 0;
  for (const Vec2& p : polygon.outer) extent = std::max(extent, p.cwiseAbs().maxCoeff());
  const double eps = 1e-9 * std::max(1.0, extent);
  // Ring by ring, each kept where the polygon stays valid with it: a squaring that would cross
  // another wall costs its own ring's, not the others'.
  PolygonWithHoles out = polygon;
  bool any = false;
  for (std::size_t r = 0; r <= polygon.holes.size(); ++r) {
    PolygonWithHoles candidate = out;
    Ring& ring = ring_at(candidate, r);
    if (!square_ring(ring, lattice, on_deg, noise, correlation, k, max_chain, min_wall)) continue;
    ring = remove_degenerate_vertices(ring, eps);  // (a step between walls on one line has no width)
    if (!polygon_problem(candidate).empty()) continue;
    out = std::move(candidate);
    any = true;
  }
  if (!any) return std::nullopt;
  return out;
}

namespace {

// The lattice axis wall i of the ring (vertex i to i + 1) turns onto when it is a rounded step's
// tread, as level_rounded_treads takes one; none when it is not.
std::optional<Vec2> tread_axis(const Ring& ring, std::size_t i, const Vec2& axis, double on_sin, double radius, double max_shift) {
  const std::size_t n = ring.size();
  const Vec2 a = ring[i] - ring[(i + n - 1) % n], w = ring[(i + 1) % n] - ring[i], c = ring[(i + 2) % n] - ring[(i + 1) % n];
  const double length = w.norm();
  if (!(length >= 2 * radius) || !(a.norm() > 0) || !(c.norm() > 0)) return std::nullopt;
  const Vec2 along = nearest_lattice_axis(w / length, axis);
  const double off = std::abs(cross(w / length, along));
  const double turn_in = cross(a.normalized(), w / length), turn_out = cross(w / length, c.normalized());
  // (A wall square to both its neighbours, within on_deg, is one of a frame of walls of their own
  // off the lattice.)
  const bool framed = std::abs(a.normalized().dot(w / length)) <= on_sin && std::abs(c.normalized().dot(w / length)) <= on_sin;
  const bool tread = off > on_sin && 0.5 * length * off <= max_shift && std::abs(turn_in) > on_sin && std::abs(turn_out) > on_sin &&
                     (turn_in > 0) != (turn_out > 0) && !framed;
  return tread ? std::optional<Vec2>(along) : std::nullopt;
}

// The ring with walls i turned onto along[i] about their middles (where along[i] is not zero) and
// the walls between two such turned onto parallel axes drawn square to them through their middles
// (a step's riser), its vertices where consecutive walls' lines meet; none where two lines do not
// meet, a vertex moves farther than max_move, a wall turns back, or the ring is not valid.
std::optional<Ring> with_walls_turned(const Ring& ring, const std::vector<Vec2>& along, double max_move) {
  const std::size_t n = ring.size();
  std::vector<Vec2> point(n), direction(n);
  std::vector<char> changed(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 w = ring[(i + 1) % n] - ring[i];
    point[i] = 0.5 * (ring[i] + ring[(i + 1) % n]);
    direction[i] = w;
    const Vec2& before = along[(i + n - 1) % n];
    const Vec2& after = along[(i + 1) % n];
    changed[i] = along[i].squaredNorm() > 0 ||
                 (before.squaredNorm() > 0 && after.squaredNorm() > 0 && std::abs(before.dot(after)) > 0.5);
    if (along[i].squaredNorm() > 0) direction[i] = along[i];
    else if (changed[i]) direction[i] = Vec2(-before.y(), before.x());
  }
  // (The corners between two walls left as they were stay where they are.)
  Ring turned = ring;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t b = (i + n - 1) % n;
    if (!changed[b] && !changed[i]) continue;
    const std::optional<Vec2> corner = meet(point[b], direction[b], point[i], direction[i]);
    if (!corner || !corner->allFinite() || (*corner - ring[i]).norm() > max_move) return std::nullopt;
    turned[i] = *corner;
  }
  for (std::size_t i = 0; i < n; ++i)
    if ((turned[(i + 1) % n] - turned[i]).dot(ring[(i + 1) % n] - ring[i]) <= 0) return std::nullopt;
  if (!ring_problem(turned).empty()) return std::nullopt;
  return turned;
}

}  // namespace

std::optional<PolygonWithHoles> level_rounded_treads(const PolygonWithHoles& polygon, const Vec2& lattice, double on_deg,
                                                     double radius, double shift_ratio) {
  if (lattice.squaredNorm() <= 0 || !(radius > 0) || !(shift_ratio > 0)) return std::nullopt;
  const Vec2 axis = lattice.normalized();
  const double on_sin = std::sin(on_deg * M_PI / 180.0);
  const double max_shift = shift_ratio * radius;
  // (A riser drawn square moves its corners along a tread by up to its own length: R or so.)
  const double max_move = 2 * max_shift + 2 * radius;
  // (Only against a lattice the outline's longest wall lies on: a lattice fitted off the walls, a
  // staircase's diagonal pulling it, would turn true treads off.)
  const Ring& outer = polygon.outer;
  if (outer.size() < 3) return std::nullopt;
  const auto wall_of = [&](std::size_t i) { return outer[(i + 1) % outer.size()] - outer[i]; };
  std::size_t longest = 0;
  for (std::size_t i = 1; i < outer.size(); ++i)
    if (wall_of(i).squaredNorm() > wall_of(longest).squaredNorm()) longest = i;
  if (!(angle_between_lattices_deg(wall_of(longest).normalized(), axis) <= on_deg)) return std::nullopt;
  std::optional<PolygonWithHoles> out;  // (copied when a ring changes)
  for (std::size_t r = 0; r <= polygon.holes.size(); ++r) {
    Ring ring = r == 0 ? polygon.outer : polygon.holes[r - 1];
    const std::size_t n = ring.size();
    if (n < 5) continue;
    std::vector<Vec2> along(n, Vec2::Zero());  // (zero: not a tread)
    std::vector<std::size_t> treads;
    for (std::size_t i = 0; i < n; ++i)
      if (const std::optional<Vec2> onto = tread_axis(ring, i, axis, on_sin, radius, max_shift)) along[i] = *onto, treads.push_back(i);
    if (treads.empty()) continue;
    // All at once (a staircase's risers squared between its treads), or else tread by tread,
    // each kept where the ring stays valid with it.
    if (std::optional<Ring> turned = with_walls_turned(ring, along, max_move)) {
      ring = std::move(*turned);
    } else {
      bool any = false;
      for (std::size_t i : treads) {
        const std::optional<Vec2> onto = tread_axis(ring, i, axis, on_sin, radius, max_shift);  // (on the ring as turned so far)
        if (!onto) continue;
        std::vector<Vec2> one(n, Vec2::Zero());
        one[i] = *onto;
        if (std::optional<Ring> turned = with_walls_turned(ring, one, max_move)) ring = std::move(*turned), any = true;
      }
      if (!any) continue;
    }
    PolygonWithHoles candidate = out ? *out : polygon;
    ring_at(candidate, r) = std::move(ring);
    if (!polygon_problem(candidate).empty()) continue;
    out = std::move(candidate);
  }
  return out;
}

std::optional<PolygonWithHoles> sharpen_rounded_corners(const PolygonWithHoles& polygon, double max_cut, double square_deg,
                                                        double min_share, double radius) {
  if (!(max_cut > 0) || !(min_share > 0)) return std::nullopt;
  const double square_cos = std::sin(square_deg * M_PI / 180.0);  // |cos| of two walls within square_deg of square
  std::optional<PolygonWithHoles> out;  // (copied when a ring is sharpened)
  const std::vector<const Ring*> rings = rings_of(polygon);
  for (std::size_t r = 0; r < rings.size(); ++r) {
    const Ring& ring = *rings[r];
    const std::size_t n = ring.size();
    if (n < 5) continue;
    std::size_t square = 0;
    // Under a measured rounding (radius), roundings up to 2.5 radii long too: one drawn as a
    // staircase along its arc is 2 radii long, some noise on top; those longer than max_cut only
    // where their corner moves no more area than the triangle between a rounding's tangent points.
    const double max_chain = radius > 0 ? std::max(max_cut, 2.5 * radius) : max_cut;
    std::vector<RoundedCorner> rounded = rounded_corners(ring, max_cut, max_chain, square_cos, &square);
    if (max_chain > max_cut) {
      std::vector<RoundedCorner> kept;
      for (const RoundedCorner& c : rounded)
        if (c.length < max_cut || area_off_corner(ring, c.first, c.walls, c.corner) <= 0.5 * radius * radius) kept.push_back(c);
      rounded = std::move(kept);
    }
    if (rounded.size() < 2 || double(rounded.size()) < min_share * double(square)) continue;
    // Each rounded corner's walls between become the corner: the first vertex moved there, the
    // others dropped. (A corner's vertices are those of the short walls between two long ones:
    // no two corners share one.)
    std::vector<char> dropped(n, 0);
    std::vector<std::optional<Vec2>> moved(n);
    for (const RoundedCorner& c : rounded) {
      moved[c.first] = c.corner;
      for (std::size_t j = 1; j <= c.walls; ++j) dropped[(c.first + j) % n] = 1;
    }
    PolygonWithHoles candidate = out ? *out : polygon;  // (the rings before it as sharpened, this one as given)
    Ring& sharp = ring_at(candidate, r);
    sharp.clear();
    for (std::size_t j = 0; j < n; ++j)
      if (!dropped[j]) sharp.push_back(moved[j] ? *moved[j] : ring[j]);
    if (polygon_problem(candidate).empty()) out = std::move(candidate);
  }
  return out;
}

double corner_rounding_gap(const PolygonWithHoles& outline, const std::vector<Ring>& contour, double min_wall, double max_cut,
                           double square_deg, double least_gap, std::size_t* count) {
  const double square_cos = std::sin(square_deg * M_PI / 180.0);
  std::vector<Vec2> corners;
  for (const Ring* ring : rings_of(outline)) {
    std::size_t square = 0;
    rounded_corners(*ring, min_wall, max_cut, square_cos, &square, &corners);
  }
  if (count) *count = corners.size();
  if (corners.size() < 3) return 0.0;
  // Each corner's squared distance to the contour (the grid the model choice measures outlines
  // against too).
  std::vector<const Ring*> rings;
  for (const Ring& ring : contour) rings.push_back(&ring);
  std::optional<SegmentGrid> own;
  const SegmentGrid& grid = grid_over(rings, own);
  std::vector<double> gaps;
  gaps.reserve(corners.size());
  for (const Vec2& corner : corners) gaps.push_back(grid.nearest_squared(corner));
  // The median (the upper one of an even count) lies beyond least_gap when that many corners do.
  const double least = least_gap * least_gap;
  const std::size_t needed = corners.size() - corners.size() / 2;
  if (std::size_t(std::count_if(gaps.begin(), gaps.end(), [&](double g) { return g <= least; })) > corners.size() - needed) return 0.0;
  for (double& gap : gaps) gap = std::sqrt(gap);
  const auto middle = gaps.begin() + long(gaps.size() / 2);
  std::nth_element(gaps.begin(), middle, gaps.end());
  return std::isfinite(*middle) ? *middle : 0.0;  // (a contour without a segment)
}

std::optional<PolygonWithHoles> merge_cheapest_step(const PolygonWithHoles& polygon, double parallel_deg) {
  const auto [r, step] = cheapest_of(polygon, std::cos(parallel_deg * M_PI / 180.0));
  if (r < 0) return std::nullopt;
  PolygonWithHoles out = polygon;
  Ring& ring = ring_at(out, r);
  ring = merged_ring(ring, step);
  return out;
}

namespace {

// A ring's staircases as lines (the ring itself when it has none).
Ring staircases_of(const Ring& ring, int min_corners, double square_deg) {
  const std::size_t n = ring.size();
  if (n < 6) return ring;
  std::vector<int> sign(n, 0);  // per vertex: +1 / -1 for a square left / right turn, 0 otherwise
  for (std::size_t k = 0; k < n; ++k) {
    const Vec2 before = ring[k] - ring[(k + n - 1) % n], after = ring[(k + 1) % n] - ring[k];
    if (std::abs(turn_deg(before, after) - 90.0) <= square_deg) sign[k] = cross(before, after) > 0 ? 1 : -1;
  }
  // Vertex k continues a staircase begun before it when both turn square, the other way.
  const auto continues = [&](std::size_t k) { return sign[k] != 0 && sign[(k + n - 1) % n] == -sign[k]; };
  std::size_t start = 0;
  while (start < n && continues(start)) ++start;
  if (start == n) return ring;
  Ring out;
  out.reserve(n);
  for (std::size_t k = 0; k < n;) {
    const std::size_t first = (start + k) % n;
    std::size_t count = 1;
    while (sign[first] != 0 && k + count < n && continues((start + k + count) % n)) ++count;
    if (int(count) >= min_corners) {
      // The line through the middles of the steps' walls (weighted by their lengths: their mean,
      // their principal direction), which cuts off as much as it leaves.
      Vec2 mean = Vec2::Zero();
      double total = 0;
      for (std::size_t j = 0; j + 1 < count; ++j) {
        const Vec2 a = ring[(first + j) % n], b = ring[(first + j + 1) % n];
        mean += (b - a).norm() * 0.5 * (a + b);
        total += (b - a).norm();
      }
      mean /= total;
      double xx = 0, xy = 0, yy = 0;
      for (std::size_t j = 0; j + 1 < count; ++j) {
        const Vec2 a = ring[(first + j) % n], b = ring[(first + j + 1) % n];
        const Vec2 d = 0.5 * (a + b) - mean;
        const double w = (b - a).norm();
        xx += w * d.x() * d.x(), xy += w * d.x() * d.y(), yy += w * d.y() * d.y();
      }
      const double angle = 0.5 * std::atan2(2 * xy, xx - yy);
      const Vec2 u(std::cos(angle), std::sin(angle));
      const std::size_t last = (first + count - 1) % n;
      const Vec2 before = ring[(first + n - 1) % n], after = ring[(last + 1) % n];
      const std::optional<Vec2> from = meet(before, ring[first] - before, mean, u), to = meet(mean, u, ring[last], after - ring[last]);
      const double reach = (ring[last] - ring[first]).norm();
      if (from && to && (*from - ring[first]).norm() <= reach && (*to - ring[last]).norm() <= reach && from->allFinite() &&
          to->allFinite()) {
        out.push_back(*from);
        out.push_back(*to);
        k += count;
        continue;
      }
    }
    for (std::size_t j = 0; j < count; ++j) out.push_back(ring[(first + j) % n]);
    k += count;
  }
  return out;
}

}  // namespace

std::optional<PolygonWithHoles> staircases_as_lines(const PolygonWithHoles& polygon, int min_corners, double square_deg) {
  if (min_corners <= 0) return std::nullopt;
  min_corners = std::max(3, min_corners);  // (two corners are one wall: no line through it)
  PolygonWithHoles out;
  bool changed = false;
  const std::vector<const Ring*> rings = rings_of(polygon);
  for (std::size_t r = 0; r < rings.size(); ++r) {
    Ring lines = staircases_of(*rings[r], min_corners, square_deg);
    changed = changed || lines.size() != rings[r]->size();
    (r == 0 ? out.outer : out.holes.emplace_back()) = std::move(lines);
  }
  if (!changed) return std::nullopt;
  return out;
}

StepPath::StepPath(const std::vector<Ring>& contour, PolygonWithHoles outline, double parallel_deg)
    : cos_parallel_(std::cos(parallel_deg * M_PI / 180.0)), outline_(std::move(outline)) {
  for (const Ring* ring : rings_of(outline_)) {
    wall_ids_.emplace_back();
    for (std::size_t k = 0; k < ring->size(); ++k) {
      wall_ids_.back().push_back(int(walls_.size()));
      walls_.push_back({(*ring)[k], (*ring)[(k + 1) % ring->size()]});
    }
  }
  alive_.assign(walls_.size(), 1);
  // The first distances as contour_fit measures them (walls numbered as boundary_distances does).
  for (const Ring& ring : contour) {
    ring_starts_.push_back(midpoints_.size());
    perimeters_.push_back(perimeter(ring));
    std::vector<std::size_t> nearest;
    const auto distances = boundary_distances(ring, outline_, &nearest);
    for (std::size_t i = 0; i < distances.size(); ++i) {
      midpoints_.push_back(ring[i] + 0.5 * edge_vector(ring, i));
      distances_.push_back(distances[i].first);
      weights_.push_back(distances[i].second);
      nearest_.push_back(int(nearest[i]));
    }
  }
  ring_starts_.push_back(midpoints_.size());
  index_midpoints();
}

void StepPath::index_midpoints() {
  const std::size_t n = midpoints_.size();
  if (n == 0) return;
  Vec2 low = midpoints_[0], high = low;
  for (const Vec2& m : midpoints_) low = low.cwiseMin(m), high = high.cwiseMax(m);
  if (!low.allFinite() || !high.allFinite()) return;  // (no grid: every midpoint each merge)
  // About eight midpoints a cell along the contour (a contour of n midpoints crosses about
  // sqrt(n) cells of a square grid of n / 8 cells over its box), at most 256 a side.
  const Vec2 extent = (high - low).cwiseMax(1e-9);
  cell_ = std::max({std::sqrt(extent.x() * extent.y() * 8.0 / double(n)), extent.x() / 256, extent.y() / 256});
  nx_ = std::max(1L, long(std::ceil(extent.x() / cell_))), ny_ = std::max(1L, long(std::ceil(extent.y() / cell_)));
  low_ = low;
  const std::size_t cells = std::size_t(nx_ * ny_);
  cell_start_.assign(cells + 1, 0);
  cell_of_.resize(n);
  for (std::size_t p = 0; p < n; ++p) {
    const long x = std::clamp(long(std::floor((midpoints_[p].x() - low_.x()) / cell_)), 0L, nx_ - 1);
    const long y = std::clamp(long(std::floor((midpoints_[p].y() - low_.y()) / cell_)), 0L, ny_ - 1);
    cell_of_[p] = std::size_t(y * nx_ + x);
    ++cell_start_[cell_of_[p] + 1];
  }
  for (std::size_t c = 0; c < cells; ++c) cell_start_[c + 1] += cell_start_[c];
  cell_items_.resize(n);
  std::vector<std::size_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (std::size_t p = 0; p < n; ++p) cell_items_[fill[cell_of_[p]]++] = p;
  cell_low_.assign(cells, Vec2::Constant(std::numeric_limits<double>::infinity()));
  cell_high_.assign(cells, Vec2::Constant(-std::numeric_limits<double>::infinity()));
  cell_bound_.assign(cells, 0.0);
  for (std::size_t p = 0; p < n; ++p) {
    const std::size_t c = cell_of_[p];
    cell_low_[c] = cell_low_[c].cwiseMin(midpoints_[p]), cell_high_[c] = cell_high_[c].cwiseMax(midpoints_[p]);
    const double d = distances_[p];
    if (!(d <= cell_bound_[c])) cell_bound_[c] = std::isnan(d) ? std::numeric_limits<double>::infinity() : d;
  }
  bound_ = *std::max_element(cell_bound_.begin(), cell_bound_.end());
  members_.assign(walls_.size(), {});
  for (std::size_t p = 0; p < n; ++p)
    if (nearest_[p] >= 0) members_[std::size_t(nearest_[p])].push_back(p);
  seen_.assign(n, 0);
}

namespace {

// The squared distance from p to the box of wall (a, b): no point of the wall is nearer.
double box_gap2(const Vec2& p, const std::pair<Vec2, Vec2>& wall) {
  const Vec2 gap = (wall.first.cwiseMin(wall.second) - p).cwiseMax(p - wall.first.cwiseMax(wall.second)).cwiseMax(0.0);
  return gap.squaredNorm();
}

}  // namespace

void StepPath::measure(std::size_t p, const int (&first)[3]) {
  double best = std::numeric_limits<double>::infinity();
  int which = -1;
  const auto consider = [&](std::size_t k) {
    if (!alive_[k] || box_gap2(midpoints_[p], walls_[k]) >= best * best) return;
    const double d = distance_to_segment(midpoints_[p], walls_[k].first, walls_[k].second);
    if (d < best || (d == best && int(k) < which)) best = d, which = int(k);
  };
  for (const int k : first) consider(std::size_t(k));  // (a near bound first: the box test then passes over most walls)
  for (std::size_t k = 0; k < walls_.size(); ++k) consider(k);
  distances_[p] = best;
  nearest_[p] = which;
}

bool StepPath::merge_next() {
  const auto [r, step] = cheapest_of(outline_, cos_parallel_);
  if (r < 0) return false;
  Ring& ring = ring_at(outline_, r);
  std::vector<int>& ids = wall_ids_[std::size_t(r)];
  const std::size_t n = ring.size(), i = step.i;
  // Walls (i-2) and (i+2) keep their ids with new ends; (i-1), i and (i+1) go; one is new.
  const int before = ids[(i + n - 2) % n], after = ids[(i + 2) % n];
  const int gone[3] = {ids[(i + n - 1) % n], ids[i], ids[(i + 1) % n]};
  const int added = int(walls_.size());
  std::vector<int> merged_ids = rotate_past(ids, i);  // (its last: the wall from vertex i-2, now to `from`)
  merged_ids.push_back(added);
  merged_ids.push_back(after);
  walls_[std::size_t(before)].second = step.from;
  walls_.push_back({step.from, step.to});
  alive_.push_back(1);
  walls_[std::size_t(after)].first = step.to;
  for (const int g : gone) alive_[std::size_t(g)] = 0;
  ring = merged_ring(ring, step);
  ids = std::move(merged_ids);
  // Every other wall lies at least a midpoint's distance from it: the midpoint is nearer one of
  // the three new walls, or stays where it was. Unless its own wall changed: then the nearest new
  // wall, when no farther than it was, else every wall is measured again.
  const int changed[3] = {before, added, after};
  if (cell_start_.empty()) {
    for (std::size_t p = 0; p < midpoints_.size(); ++p) {
      const int k = nearest_[p];
      update(p, k == before || k == after || k == gone[0] || k == gone[1] || k == gone[2], changed);
    }
    return true;
  }
  // Each midpoint is updated as above, in any order (its update reads no other's): those nearest
  // a wall that changed or went first, from those walls' members, then, of the others, those in
  // a cell that may lie nearer a new wall than its bound (every other one passes over all three
  // walls by their boxes, as update does).
  ++merges_;
  members_.resize(walls_.size());
  // (All five walls' members taken before any is updated: a midpoint that moves from one of them
  // to another joins that wall's members anew, which must not be taken after it.)
  const int moved_from[5] = {before, after, gone[0], gone[1], gone[2]};
  std::vector<std::size_t> members[5];
  for (int w = 0; w < 5; ++w) members[w].swap(members_[std::size_t(moved_from[w])]);
  for (int w = 0; w < 5; ++w)
    for (const std::size_t p : members[w])
      if (nearest_[p] == moved_from[w] && seen_[p] != merges_) seen_[p] = merges_, update(p, true, changed);
  for (const int c : changed) {
    const std::pair<Vec2, Vec2>& wall = walls_[std::size_t(c)];
    const Vec2 wall_low = wall.first.cwiseMin(wall.second), wall_high = wall.first.cwiseMax(wall.second);
    // The cells within bound_ of the wall's box (a cell more, each way, for the rounding).
    // (Clamped to the grid: an infinite bound reaches every cell, as does one not a number.)
    const auto range = [&](double from, double to, double origin, long count, long* first, long* last) {
      const double a = std::floor((from - bound_ - origin) / cell_) - 1, b = std::floor((to + bound_ - origin) / cell_) + 1;
      *first = a == a ? long(std::clamp(a, 0.0, double(count))) : 0;
      *last = b == b ? long(std::clamp(b, -1.0, double(count - 1))) : count - 1;
    };
    long x0, x1, y0, y1;
    range(wall_low.x(), wall_high.x(), low_.x(), nx_, &x0, &x1);
    range(wall_low.y(), wall_high.y(), low_.y(), ny_, &y0, &y1);
    for (long y = y0; y <= y1; ++y)
      for (long x = x0; x <= x1; ++x) {
        const std::size_t cell = std::size_t(y * nx_ + x);
        if (cell_start_[cell] == cell_start_[cell + 1]) continue;
        // (No midpoint of the cell lies nearer the wall's box than the cell's box does.)
        const Vec2 gap = (wall_low - cell_high_[cell]).cwiseMax(cell_low_[cell] - wall_high).cwiseMax(0.0);
        if (gap.squaredNorm() >= cell_bound_[cell] * cell_bound_[cell]) continue;
        for (std::size_t i = cell_start_[cell]; i < cell_start_[cell + 1]; ++i) {
          const std::size_t p = cell_items_[i];
          if (seen_[p] != merges_) seen_[p] = merges_, update(p, false, changed);
        }
      }
  }
  return true;
}

void StepPath::update(std::size_t p, bool moved, const int (&changed)[3]) {
  const int was = nearest_[p];
  // The nearest of the three new walls, those farther than `bound` passed over.
  const double bound = moved ? std::numeric_limits<double>::infinity() : distances_[p];
  double best = bound;
  int which = -1;
  for (const int c : changed) {
    const std::pair<Vec2, Vec2>& wall = walls_[std::size_t(c)];
    if (!moved && box_gap2(midpoints_[p], wall) >= best * best) continue;
    const double d = distance_to_segment(midpoints_[p], wall.first, wall.second);
    if (d < best) best = d, which = c;
  }
  if (which >= 0 && (!moved || best <= distances_[p])) distances_[p] = best, nearest_[p] = which;
  else if (moved) measure(p, changed);
  if (cell_start_.empty()) return;
  const double d = distances_[p];
  double& cell_bound = cell_bound_[cell_of_[p]];
  if (!(d <= cell_bound)) cell_bound = std::isnan(d) ? std::numeric_limits<double>::infinity() : d, bound_ = std::max(bound_, cell_bound);
  // (A moved midpoint's wall had its members taken: it joins its nearest wall's again either way.)
  if ((moved || nearest_[p] != was) && nearest_[p] >= 0) members_[std::size_t(nearest_[p])].push_back(p);
}

double StepPath::fit() const {
  // As contour_fit sums it: each ring's mean distance, weighted by the ring's perimeter.
  double sum = 0, total = 0;
  for (std::size_t r = 0; r + 1 < ring_starts_.size(); ++r) {
    double ring_sum = 0, ring_weight = 0;
    for (std::size_t p = ring_starts_[r]; p < ring_starts_[r + 1]; ++p) {
      ring_sum += weights_[p] * distances_[p];
      ring_weight += weights_[p];
    }
    sum += perimeters_[r] * (ring_weight > 0 ? ring_sum / ring_weight : 0.0);
    total += perimeters_[r];
  }
  return total > 0 ? sum / total : 0.0;
}

}  // namespace lodforge
