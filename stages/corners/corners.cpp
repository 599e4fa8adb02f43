#include "corners/corners.hpp"

#include <cmath>

#include "geometry/polygon.hpp"
#include "labeling/mrf.hpp"

namespace lodforge {

namespace {

double run_length(const Ring& ring, int first, int count) {
  double length = 0;
  for (int k = 0; k < count; ++k) length += edge_vector(ring, (first + k) % ring.size()).norm();
  return length;
}

struct Line {
  Vec2 normal;    // unit
  double offset;  // normal . x = offset
  Vec2 project(const Vec2& p) const { return p - (normal.dot(p) - offset) * normal; }
};

Line fit_line(const Ring& ring, int first, int count, const Vec2& normal) {
  double weighted = 0, total = 0;
  for (int k = 0; k < count; ++k) {
    const std::size_t i = (first + k) % ring.size();
    const Vec2 e = edge_vector(ring, i);
    const double len = e.norm();
    weighted += len * normal.dot(ring[i] + 0.5 * e);
    total += len;
  }
  return {normal, total > 0 ? weighted / total : normal.dot(ring[first])};
}

// True when the run's contour departs from its line by more than curve_px on average over some
// window of curve_window_px (a boundary wobble averages out over a window, a curved wall does not).
bool is_curved(const Ring& ring, int first, int count, const Line& line, const CornerOptions& o, double pixel_size) {
  if (o.curve_px <= 0) return false;
  const double window = o.curve_window_px * pixel_size, total = run_length(ring, first, count);
  // The run's ends (a window each) are left out: corners are rounded there, by the raster.
  double position = 0, window_length = 0, window_sum = 0;
  for (int k = 0; k < count; ++k) {
    const std::size_t i = (first + k) % ring.size();
    const Vec2 e = edge_vector(ring, i);
    const double len = e.norm();
    position += len;
    if (position < window || position > total - window) continue;
    window_sum += len * (line.normal.dot(ring[i] + 0.5 * e) - line.offset);
    window_length += len;
    if (window_length >= window) {
      if (std::abs(window_sum / window_length) > o.curve_px * pixel_size) return true;
      window_length = window_sum = 0;
    }
  }
  return false;
}

// Appends run [first, first + count) to out, split where its contour steps between two parallel
// offsets at least `split` apart (each part at least 4 * split long, and the two offsets
// explaining 95 % of the contour's spread about one line, which a wobble or an arc does not),
// recursively, three levels at most.
void split_parallel(const Ring& ring, int first, int count, const Vec2& normal, double split, int depth,
                    std::vector<std::pair<int, int>>& out) {
  if (split <= 0 || depth > 3 || count < 4) { out.push_back({first, count}); return; }
  std::vector<double> w(count), s(count);  // prefix sums of length and length * offset
  double W = 0, S = 0, Q = 0;
  for (int k = 0; k < count; ++k) {
    const std::size_t i = (first + k) % ring.size();
    const Vec2 e = edge_vector(ring, i);
    const double len = e.norm(), offset = normal.dot(ring[i] + 0.5 * e);
    W += len; S += len * offset; Q += len * offset * offset;
    w[k] = W; s[k] = S;
  }
  const double whole = Q - S * S / W;
  int best = -1;
  double best_sse = whole;
  for (int k = 1; k < count; ++k) {  // parts [0, k) and [k, count)
    const double wl = w[k - 1], sl = s[k - 1], wr = W - wl, sr = S - sl;
    if (wl < 4 * split || wr < 4 * split) continue;
    const double sse = Q - sl * sl / wl - sr * sr / wr;
    if (sse < best_sse) { best_sse = sse; best = k; }
  }
  if (best > 0) {
    const double wl = w[best - 1], sl = s[best - 1];
    const double step = std::abs(sl / wl - (S - sl) / (W - wl));
    if (step >= split && best_sse <= 0.05 * whole) {
      split_parallel(ring, first, best, normal, split, depth + 1, out);
      split_parallel(ring, int((first + best) % ring.size()), count - best, normal, split, depth + 1, out);
      return;
    }
  }
  out.push_back({first, count});
}

}  // namespace

void absorb_short_runs(const Ring& ring, std::vector<int>& labels, double min_length) {
  for (int guard = 0; guard < int(ring.size()); ++guard) {
    const auto runs = label_runs(labels);
    if (runs.size() <= 4) return;  // never below a quadrilateral
    int shortest = -1;
    double shortest_length = min_length;
    for (int r = 0; r < int(runs.size()); ++r) {
      const double len = run_length(ring, runs[r].first, runs[r].second);
      if (len < shortest_length) { shortest_length = len; shortest = r; }
    }
    if (shortest < 0) return;
    const int n = int(runs.size());
    const auto& prev = runs[(shortest + n - 1) % n];
    const auto& next = runs[(shortest + 1) % n];
    const bool to_prev = run_length(ring, prev.first, prev.second) >= run_length(ring, next.first, next.second);
    const int label = labels[to_prev ? prev.first : next.first];
    for (int k = 0; k < runs[shortest].second; ++k) labels[(runs[shortest].first + k) % labels.size()] = label;
  }
}

Ring extract_corners(const Ring& ring, const std::vector<int>& labels, const std::vector<Vec2>& directions,
                     double pixel_size, const CornerOptions& o, std::string* problem) {
  std::vector<int> own = labels;
  absorb_short_runs(ring, own, o.min_run_px * pixel_size);
  std::vector<std::pair<int, int>> runs;
  for (auto [first, count] : label_runs(own))
    split_parallel(ring, first, count, directions[own[first]], o.split_px * pixel_size, 0, runs);
  const int n = int(runs.size());
  std::vector<Line> lines;
  for (auto [first, count] : runs) lines.push_back(fit_line(ring, first, count, directions[own[first]]));
  std::vector<bool> curved(n);
  bool any_curved = false;
  for (int r = 0; r < n; ++r) any_curved |= curved[r] = is_curved(ring, runs[r].first, runs[r].second, lines[r], o, pixel_size);
  if (n < 3 && !(n == 2 && any_curved)) {  // two runs make a polygon only when one is a curve
    *problem = "only " + std::to_string(runs.size()) + " straight runs, a polygon needs 3";
    return {};
  }
  const double parallel_sin = std::sin(o.parallel_angle_deg * M_PI / 180.0);
  Ring out;
  for (int r = 0; r < n; ++r) {
    if (curved[r]) {  // the run's own contour, simplified, between its ends
      std::vector<Vec2> points;
      for (int k = 0; k <= runs[r].second; ++k) points.push_back(ring[(runs[r].first + k) % ring.size()]);
      const std::vector<char> keep = douglas_peucker_open(points, pixel_size);
      for (std::size_t k = 1; k + 1 < points.size(); ++k) if (keep[k]) out.push_back(points[k]);
    }
    const Line& a = lines[r];
    const Line& b = lines[(r + 1) % n];
    const Vec2 junction = ring[runs[(r + 1) % n].first];  // where run r ends and r+1 starts
    // Next to a curve, the junction itself, or its foot on the straight neighbour's line.
    const bool curve_before = curved[r], curve_after = curved[(r + 1) % n];
    if (curve_before || curve_after) {
      out.push_back(curve_before && curve_after ? junction : curve_before ? b.project(junction) : a.project(junction));
      continue;
    }
    const double det = cross(a.normal, b.normal);
    bool use_step = std::abs(det) < parallel_sin;
    if (!use_step) {
      // Solve a.normal . x = a.offset, b.normal . x = b.offset.
      const Vec2 corner((a.offset * b.normal.y() - b.offset * a.normal.y()) / det,
                        (a.normal.x() * b.offset - b.normal.x() * a.offset) / det);
      if ((corner - junction).norm() <= o.max_corner_shift_m) out.push_back(corner);
      else use_step = true;
    }
    if (use_step) {
      out.push_back(a.project(junction));
      out.push_back(b.project(junction));
    }
  }
  out = remove_degenerate_vertices(out, 1e-3 * pixel_size);
  if (out.size() < 3) {
    *problem = "corners collapse to fewer than 3 vertices";
    return {};
  }
  return out;
}

}  // namespace lodforge
