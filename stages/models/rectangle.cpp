#include "models/rectangle.hpp"

#include "geometry/polygon.hpp"
#include "geometry/segment_grid.hpp"
#include "models/statistics.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <memory>

namespace lodforge {

namespace {

struct Moments {
  double area = 0;
  Vec2 centroid = Vec2::Zero();
  Eigen::Matrix2d central = Eigen::Matrix2d::Zero();  // integral of (p - c)(p - c)^T over the area
};

// Area, centroid and central second moments of a simple ring (Green's theorem), computed about
// its first vertex for numerical range.
Moments moments_of(const Ring& ring) {
  Moments m;
  const Vec2 o = ring.front();
  double a2 = 0, cx = 0, cy = 0, ixx = 0, iyy = 0, ixy = 0;  // about o
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const Vec2 p = ring[i] - o, q = ring[(i + 1) % ring.size()] - o;
    const double c = p.x() * q.y() - q.x() * p.y();
    a2 += c;
    cx += (p.x() + q.x()) * c;
    cy += (p.y() + q.y()) * c;
    ixx += (p.x() * p.x() + p.x() * q.x() + q.x() * q.x()) * c;
    iyy += (p.y() * p.y() + p.y() * q.y() + q.y() * q.y()) * c;
    ixy += (p.x() * q.y() + 2 * p.x() * p.y() + 2 * q.x() * q.y() + q.x() * p.y()) * c;
  }
  m.area = a2 / 2;
  if (m.area <= 0) return m;
  const Vec2 c(cx / (3 * a2), cy / (3 * a2));
  m.centroid = o + c;
  m.central << ixx / 12 - m.area * c.x() * c.x(), ixy / 24 - m.area * c.x() * c.y(),
               ixy / 24 - m.area * c.x() * c.y(), iyy / 12 - m.area * c.y() * c.y();
  return m;
}

Ring rectangle_of(const Moments& m, const Vec2& normal) {
  const Vec2 n = normal.normalized(), t(-n.y(), n.x());
  const double along = t.dot(m.central * t), across = n.dot(m.central * n);
  if (m.area <= 0 || along <= 0 || across <= 0) return {};
  // A w x h rectangle: area w h, moments h w^3 / 12 and w h^3 / 12.
  const double w = std::sqrt(12 * along / m.area), h = std::sqrt(12 * across / m.area);
  const Vec2 c = m.centroid, u = 0.5 * w * t, v = 0.5 * h * n;
  return {c - u - v, c - u + v, c + u + v, c + u - v};  // counter-clockwise (t is n turned left)
}

// The rectangle with each side moved to the weighted median offset of the contour's edge
// midpoints nearest to it (along its normal): a side along a wall lies on the wall, where the
// moments put it out by an annex or a notch elsewhere along it.
Ring refit_sides(const Ring& ring, const Ring& rectangle) {
  if (rectangle.size() != 4) return rectangle;
  const Vec2 c = 0.25 * (rectangle[0] + rectangle[1] + rectangle[2] + rectangle[3]);
  const Vec2 t = (rectangle[3] - rectangle[0]).normalized(), n = (rectangle[1] - rectangle[0]).normalized();
  const double a = 0.5 * (rectangle[3] - rectangle[0]).norm(), b = 0.5 * (rectangle[1] - rectangle[0]).norm();
  std::vector<std::pair<double, double>> sides[4];  // -t, +t, -n, +n: (offset, weight)
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const Vec2 e = edge_vector(ring, i), q = ring[i] + 0.5 * e - c;
    const double x = t.dot(q), y = n.dot(q);
    const double d[4] = {std::abs(x + a), std::abs(x - a), std::abs(y + b), std::abs(y - b)};
    const int k = int(std::min_element(d, d + 4) - d);
    sides[k].push_back({k < 2 ? x : y, e.norm()});
  }
  double bounds[4] = {-a, a, -b, b};
  for (int k = 0; k < 4; ++k) if (!sides[k].empty()) bounds[k] = weighted_quantile(std::move(sides[k]), 0.5);
  if (!(bounds[0] < bounds[1]) || !(bounds[2] < bounds[3])) return rectangle;
  return {c + bounds[0] * t + bounds[2] * n, c + bounds[0] * t + bounds[3] * n, c + bounds[1] * t + bounds[3] * n,
          c + bounds[1] * t + bounds[2] * n};
}

}  // namespace

Ring moment_rectangle(const Ring& ring, const Vec2& normal) {
  if (ring.size() < 3) return {};
  return refit_sides(ring, rectangle_of(moments_of(ring), normal));
}

namespace {

bool same_points(const std::vector<Vec2>& a, const std::vector<Vec2>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(Vec2)) == 0);
}

// Whether rings kept by value are the given ones, bit for bit.
bool same_rings(const std::vector<Ring>& kept, const std::vector<const Ring*>& rings) {
  if (kept.size() != rings.size()) return false;
  for (std::size_t r = 0; r < rings.size(); ++r)
    if (!same_points(kept[r], *rings[r])) return false;
  return true;
}

// The last N entries of a per-thread memo (Entry has a `used` stamp, 0 while empty), the least
// recently used making room.
template <class Entry, std::size_t N>
class Recent {
 public:
  template <class Same>
  Entry* find(const Same& same) {
    for (Entry& e : entries_)
      if (e.used > 0 && same(e)) {
        e.used = ++clock_;
        return &e;
      }
    return nullptr;
  }
  // The entry to fill, empty until kept() once whole (a copy that throws leaves none half written).
  Entry& room() {
    Entry& e = *std::min_element(entries_.begin(), entries_.end(), [](const Entry& a, const Entry& b) { return a.used < b.used; });
    e.used = 0;
    return e;
  }
  Entry& kept(Entry& e) {
    e.used = ++clock_;
    return e;
  }

 private:
  std::array<Entry, N> entries_;
  std::uint64_t clock_ = 0;
};

// A measure of a contour ring against an outline: the model choice measures the same outline
// against the same contour from several of its steps (an outline's contour fit, then its
// rectangle test and its step path; the best rectangle's fit, then its rectangle test), about two
// in five of its measures on the campus at 0.25 m under a metre of wobble, all within the last
// eight. Kept by value and compared bit for bit: a measure found among them is the one
// boundary_distances would make.
struct Measure {
  std::vector<std::pair<double, double>> distances;
  std::vector<std::size_t> nearest;
};
struct KeptMeasure {
  Ring ring;
  std::vector<Ring> outline;  // outer ring, then holes
  Measure measure;
  std::uint64_t used = 0;
};

// A grid over a polygon of many edges (a building's contour: the model choice measures how far
// each outline it weighs reaches from it, and the corners' rounding against it), the last two
// kept, compared bit for bit: a grid found among them is the one built again would be.
struct KeptGrid {
  std::vector<Ring> rings;
  std::unique_ptr<SegmentGrid> grid;
  std::uint64_t used = 0;
};
constexpr std::size_t kKeptGridEdges = 256;  // (an outline's few dozen edges are built each time)

Measure measure_distances(const Ring& ring, const PolygonWithHoles& polygon) {
  Measure measure;
  std::optional<SegmentGrid> own;
  const SegmentGrid& grid = grid_over(rings_of(polygon), own);
  if (grid.segments().empty()) return measure;
  std::vector<std::pair<double, double>>& distances = measure.distances;
  distances.reserve(ring.size());
  measure.nearest.reserve(ring.size());
  // More than 24 segments (a contour of pixel edges, against which an outline is measured, or an
  // outline of a few dozen walls) are bucketed in a uniform grid (SegmentGrid): each midpoint
  // looks at the cells around its own, ring by ring, until a ring lies farther than the nearest
  // segment found. Fewer are all looked at, their boxes first. (Past 24 the grid costs less: 3.5 %
  // fewer instructions in all on the campus at 0.25 m under a metre of wobble than past 64, 16 and
  // 32 about the same; the distances, and the nearest segment of equals, are the same either way.)
  const std::vector<SegmentGrid::Segment>& segments = grid.segments();
  std::vector<std::size_t> seen(segments.size(), std::size_t(-1));  // the midpoint that last measured each segment
  std::size_t nearest = 0;  // the previous midpoint's nearest segment: a first bound for the next
  // Where the grid was last looked at: the midpoint, and how near to it any segment but its
  // nearest may lie (at least). A midpoint nearer to that segment than `clearance` less the way
  // it moved since (and a margin for rounding: a micrometre, and a millionth of a micrometre per
  // metre of its coordinates) has it for its only nearest segment, as looking again would find:
  // the midpoints along a wall keep its segment, dozens in a row.
  Vec2 looked_at = Vec2::Zero();
  double clearance = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const Vec2 e = edge_vector(ring, i), mid = ring[i] + 0.5 * e;
    // The nearest segment; of equals, the previous midpoint's, else the first.
    const std::size_t previous = nearest;
    double best = distance_to_segment(mid, segments[previous].a, segments[previous].b);
    const double moved = (mid - looked_at).norm(), margin = 1e-6 + 1e-12 * mid.cwiseAbs().sum() + 1e-9 * clearance;
    if (best + moved + margin < clearance) {
      distances.push_back({best, e.norm()});
      measure.nearest.push_back(nearest);
      continue;
    }
    seen[previous] = i;
    // The grid looked at out to `reach`: the previous nearest's distance and a cell more, or the
    // second nearest's where less; every segment it does not see lies farther than reach. (A
    // segment whose distance is not a number here, one so long that its squares overflow, may
    // have one at the next midpoint: nothing is kept without looking there.)
    double second = std::numeric_limits<double>::infinity();
    bool unsure = false;
    const double cap = best + grid.cell();
    double reach = cap;
    grid.visit(mid, reach, [&](std::size_t k) {
      if (seen[k] == i) return;
      seen[k] = i;
      // A segment whose box lies farther than the reach cannot be nearer, nor second. (The slack
      // keeps every segment at the best distance: the square of a rounded distance may fall just
      // short of the squared gap to a vertex it ties at, and the tie rule must see them all.)
      const Vec2 gap = (segments[k].low - mid).cwiseMax(mid - segments[k].high).cwiseMax(0.0);
      const double bound = reach * reach * (1 + 1e-9);
      if (gap.squaredNorm() > bound) return;
      const double squared = squared_distance_to_segment(mid, segments[k].a, segments[k].b);
      if (squared > bound) return;  // (farther than the reach)
      const double d = std::sqrt(squared);
      if (d < best || (d == best && nearest != previous && k < nearest)) {
        second = std::min(second, best);
        best = d, nearest = k;
      } else if (std::isnan(d)) {
        unsure = true;
      } else {
        second = std::min(second, d);
      }
      reach = std::min(cap, second);
    });
    looked_at = mid;
    clearance = unsure ? -std::numeric_limits<double>::infinity() : reach;
    distances.push_back({best, e.norm()});
    measure.nearest.push_back(nearest);
  }
  return measure;
}

}  // namespace

const SegmentGrid& grid_over(const std::vector<const Ring*>& rings, std::optional<SegmentGrid>& own) {
  std::size_t edge_count = 0;
  for (const Ring* r : rings) edge_count += r->size();
  const auto built = [&] {
    std::vector<SegmentGrid::Segment> edges;
    for (const Ring* r : rings) SegmentGrid::add_ring(*r, edges);
    return SegmentGrid(std::move(edges), 24);
  };
  if (edge_count < kKeptGridEdges) return own.emplace(built());
  thread_local Recent<KeptGrid, 2> memo;
  if (KeptGrid* found = memo.find([&](const KeptGrid& e) { return same_rings(e.rings, rings); })) return *found->grid;
  KeptGrid& e = memo.room();
  e.rings.clear();
  for (const Ring* r : rings) e.rings.push_back(*r);
  e.grid = std::make_unique<SegmentGrid>(built());
  return *memo.kept(e).grid;
}

std::vector<std::pair<double, double>> boundary_distances(const Ring& ring, const PolygonWithHoles& polygon,
                                                          std::vector<std::size_t>* nearest_segments) {
  thread_local Recent<KeptMeasure, 8> memo;
  const std::vector<const Ring*> outline = rings_of(polygon);
  const KeptMeasure* found = memo.find([&](const KeptMeasure& e) { return same_rings(e.outline, outline) && same_points(e.ring, ring); });
  if (!found) {
    Measure measure = measure_distances(ring, polygon);
    KeptMeasure& e = memo.room();
    e.ring = ring;
    e.outline.clear();
    for (const Ring* r : outline) e.outline.push_back(*r);
    e.measure = std::move(measure);
    found = &memo.kept(e);
  }
  if (nearest_segments) *nearest_segments = found->measure.nearest;
  return found->measure.distances;
}

double mean_distance(const std::vector<std::pair<double, double>>& distances) {
  double sum = 0, weight = 0;
  for (const auto& [d, w] : distances) {
    sum += w * d;
    weight += w;
  }
  return weight > 0 ? sum / weight : 0.0;
}

double mean_distance_to_boundary(const Ring& ring, const PolygonWithHoles& polygon) {
  return mean_distance(boundary_distances(ring, polygon));
}

bool leaves_a_stretch(const std::vector<std::pair<double, double>>& simple, const std::vector<std::pair<double, double>>& fine,
                      double noise, double correlation, double k) {
  const std::size_t n = simple.size();
  if (n == 0 || fine.size() != n || noise <= 0 || correlation <= 0) return false;
  // Prefix sums over the ring twice round: length, and length times the excess distance.
  std::vector<double> length(2 * n + 1, 0.0), excess(2 * n + 1, 0.0);
  for (std::size_t i = 0; i < 2 * n; ++i) {
    const std::size_t e = i % n;
    length[i + 1] = length[i] + simple[e].second;
    excess[i + 1] = excess[i] + simple[e].second * (simple[e].first - fine[e].first);
  }
  const double perimeter = length[n];
  if (!std::isfinite(perimeter)) return false;
  for (double window = correlation; window <= 0.5 * perimeter; window *= 2) {
    // A stretch at least `window` long (each is, grown to it, the ring being twice that at least,
    // lengths not negative) has an excess beyond the bound, k * noise * sqrt(correlation * l)
    // before the division by l, only where it exceeds that at l = window: below it (less a margin
    // far above the rounding of either side) it is passed over without the division and the root.
    const double least = k > 0 ? (1 - 1e-9) * k * noise * std::sqrt(correlation * window) : -std::numeric_limits<double>::infinity();
    std::size_t end = 0;
    for (std::size_t first = 0; first < n; ++first) {
      end = std::max(end, first + 1);
      while (end < first + n && length[end] - length[first] < window) ++end;
      const double l = length[end] - length[first];
      if (l <= 0 || (l >= window && excess[end] - excess[first] <= least)) continue;
      if ((excess[end] - excess[first]) / l > k * noise * std::sqrt(correlation / l)) return true;
    }
  }
  return false;
}

namespace {

// The ellipse of the ring's centroid and second moments per unit area: centre, semi-axes a >= b
// along u and v (u turned left is v). None for a degenerate ring or a clockwise one.
struct Ellipse {
  Vec2 centre, u, v;
  double a, b;
};
std::optional<Ellipse> ellipse_of(const Ring& ring) {
  if (ring.size() < 3) return std::nullopt;
  const Moments m = moments_of(ring);
  if (m.area <= 0) return std::nullopt;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(m.central);
  // An ellipse of semi-axes a, b: area pi a b, second moments a^2 / 4 and b^2 / 4 of it along its axes.
  const double a = 2 * std::sqrt(std::max(0.0, eig.eigenvalues()[1]) / m.area), b = 2 * std::sqrt(std::max(0.0, eig.eigenvalues()[0]) / m.area);
  if (!(a > 0) || !(b > 0)) return std::nullopt;
  const Vec2 u = eig.eigenvectors().col(1);
  return Ellipse{m.centroid, u, Vec2(-u.y(), u.x()), a, b};
}

}  // namespace

double moment_ellipse_fit(const Ring& ring) {
  const std::optional<Ellipse> e = ellipse_of(ring);
  if (!e) return std::numeric_limits<double>::infinity();
  Ring ellipse;
  for (int k = 0; k < 90; ++k) {
    const double t = 2 * M_PI * k / 90;
    ellipse.push_back(e->centre + e->a * std::cos(t) * e->u + e->b * std::sin(t) * e->v);
  }
  return mean_distance_to_boundary(ring, {ellipse, {}});
}

std::vector<std::pair<double, double>> moment_ellipse_distances(const Ring& ring) {
  const std::optional<Ellipse> e = ellipse_of(ring);
  if (!e) return {};
  // f = x^2 / a^2 + y^2 / b^2 - 1 in the ellipse's frame, its distance about |f| / |grad f|.
  const double ia2 = 1 / (e->a * e->a), ib2 = 1 / (e->b * e->b);
  std::vector<std::pair<double, double>> distances;
  distances.reserve(ring.size());
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const Vec2 edge = edge_vector(ring, i), d = ring[i] + 0.5 * edge - e->centre;
    const double x = d.dot(e->u), y = d.dot(e->v);
    const double gx = x * ia2, gy = y * ib2, f = x * gx + y * gy - 1, gradient = 2 * std::sqrt(gx * gx + gy * gy);
    distances.emplace_back(gradient > 0 ? std::abs(f) / gradient : e->b, edge.norm());
  }
  return distances;
}

Ring moment_ellipse(const Ring& ring, double turn_deg) {
  const std::optional<Ellipse> e = ellipse_of(ring);
  if (!e || !(turn_deg > 0)) return {};
  // The point whose outward normal is (cos t, sin t) in the ellipse's frame: (a^2 cos t, b^2 sin t) / s.
  // (At most 360: every vertex turning by a degree at least, which has_arc reads as an arc.)
  const int n = std::clamp(int(std::ceil(360.0 / turn_deg - 1e-9)), 8, 360);
  const double a2 = e->a * e->a, b2 = e->b * e->b;
  Ring ellipse;  // (about its centre, until scaled)
  for (int k = 0; k < n; ++k) {
    const double t = 2 * M_PI * k / n, c = std::cos(t), s = std::sin(t);
    const double norm = std::sqrt(a2 * c * c + b2 * s * s);
    ellipse.push_back((a2 * c / norm) * e->u + (b2 * s / norm) * e->v);
  }
  // Its chords cut the ellipse's area a little: scaled about the centre to the ellipse's, pi a b
  // (the ring's own where the ring is an ellipse; a wobbling disc's a few thousandths more).
  const double drawn = signed_area(ellipse);
  if (!(drawn > 0)) return {};
  const double scale = std::sqrt(M_PI * e->a * e->b / drawn);
  for (Vec2& p : ellipse) p = e->centre + scale * p;
  return ellipse;
}

Ring best_rectangle(const Ring& ring, const std::vector<Vec2>& normals, double* fit) {
  *fit = std::numeric_limits<double>::infinity();
  if (ring.size() < 3) return {};
  const Moments m = moments_of(ring);
  if (m.area <= 0) return {};
  std::vector<Vec2> candidates = normals;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(m.central);
  candidates.push_back(eig.eigenvectors().col(0));
  for (int k = 0; k < 30; ++k) candidates.emplace_back(std::cos(k * M_PI / 60), std::sin(k * M_PI / 60));
  // The edge midpoints relative to the centroid, with their lengths.
  std::vector<std::pair<Vec2, double>> mids;
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const Vec2 e = edge_vector(ring, i);
    mids.push_back({ring[i] + 0.5 * e - m.centroid, e.norm()});
  }
  Vec2 best_normal = Vec2::Zero();
  for (const Vec2& candidate : candidates) {
    const Vec2 n = candidate.normalized(), t(-n.y(), n.x());
    const double along = t.dot(m.central * t), across = n.dot(m.central * n);
    if (along <= 0 || across <= 0) continue;
    // The distance to the boundary of the box of half sides a, b in its own frame.
    const double a = 0.5 * std::sqrt(12 * along / m.area), b = 0.5 * std::sqrt(12 * across / m.area);
    double sum = 0, weight = 0;
    for (const auto& [p, w] : mids) {
      const double u = std::abs(t.dot(p)) - a, v = std::abs(n.dot(p)) - b;
      // (Beside one side, the distance to it: hypot(x, 0) is |x| exactly; the square root only
      // off a corner.)
      const double d = u <= 0 ? (v <= 0 ? std::min(-u, -v) : v) : v <= 0 ? u : std::hypot(u, v);
      sum += w * d;
      weight += w;
    }
    const double d = weight > 0 ? sum / weight : 0.0;
    if (d < *fit) { *fit = d; best_normal = n; }
  }
  if (best_normal.squaredNorm() <= 0) return {};
  Ring best = refit_sides(ring, rectangle_of(m, best_normal));
  *fit = mean_distance_to_boundary(ring, {best, {}});
  return best;
}

Ring rounded_ring(const Ring& ring, double radius) {
  Ring out;
  const std::size_t n = ring.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 before = edge_vector(ring, (i + n - 1) % n), after = edge_vector(ring, i), v = ring[i];
    const double turn = std::atan2(cross(before, after), before.dot(after));  // (signed: left > 0)
    const double half_tan = std::tan(0.5 * std::abs(turn));
    if (!(before.norm() > 0) || !(after.norm() > 0) || !(half_tan > 1e-9)) {
      out.push_back(v);
      continue;
    }
    const double tangent = std::min({radius * half_tan, 0.5 * before.norm(), 0.5 * after.norm()});
    const double r = tangent / half_tan;
    const Vec2 u = before.normalized(), left(-u.y(), u.x());
    const Vec2 start = v - tangent * u, centre = start + (turn > 0 ? r : -r) * left;
    for (int k = 0; k <= 8; ++k) out.push_back(centre + Eigen::Rotation2Dd(turn * k / 8) * (start - centre));
  }
  return out;
}

PolygonWithHoles rounded_polygon(const PolygonWithHoles& polygon, double radius) {
  PolygonWithHoles out{rounded_ring(polygon.outer, radius), {}};
  for (const Ring& hole : polygon.holes) out.holes.push_back(rounded_ring(hole, radius));
  return out;
}

Ring grown_for_rounding(const Ring& rectangle, double radius, double area) {
  if (rectangle.size() != 4 || !(radius > 0) || !(area > 0)) return rectangle;
  const Vec2 centre = 0.25 * (rectangle[0] + rectangle[1] + rectangle[2] + rectangle[3]);
  const Vec2 along = edge_vector(rectangle, 0), across = edge_vector(rectangle, 1);
  const double w = along.norm(), h = across.norm();
  if (!(w > 0) || !(h > 0)) return rectangle;
  // (w + 2d)(h + 2d) - (4 - pi) r^2 = area, r at most half the shorter side (rounded_ring's), taken
  // at the grown sides: twice, the second with the radius the first growth allows.
  double d = 0;
  for (int round = 0; round < 2; ++round) {
    const double r = std::min(radius, 0.5 * std::min(w, h) + d), lost = (4 - M_PI) * r * r;
    const double b = w + h, c = w * h - lost - area;  // 4 d^2 + 2 b d + c = 0
    d = (-2 * b + std::sqrt(std::max(0.0, 4 * b * b - 16 * c))) / 8;
  }
  const Vec2 u = along / w * (0.5 * w + d), v = across / h * (0.5 * h + d);
  return {centre - u - v, centre + u - v, centre + u + v, centre - u + v};
}

Ring rectangle_under_rounding(const Ring& ring, const Ring& rectangle, double radius, double* fit) {
  const auto rounded_fit = [&](const Ring& r) { return mean_distance(boundary_distances(ring, rounded_polygon(PolygonWithHoles{r, {}}, radius))); };
  Ring grown = grown_for_rounding(rectangle, radius, signed_area(ring));
  const double as_is = rounded_fit(rectangle), as_grown = rounded_fit(grown);
  if (fit) *fit = std::min(as_is, as_grown);
  return as_grown < as_is ? grown : rectangle;
}

double best_rectangle_fit(const Ring& ring, const std::vector<Vec2>& normals, double radius) {
  double fit = std::numeric_limits<double>::infinity();
  const Ring rectangle = best_rectangle(ring, normals, &fit);
  if (radius > 0 && !rectangle.empty()) rectangle_under_rounding(ring, rectangle, radius, &fit);
  return fit;
}

}  // namespace lodforge
