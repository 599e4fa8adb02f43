#include "corners/corners.hpp"

#include <algorithm>
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

// Appends run [first, first + count) to out, split where its contour steps between parallel
// offsets (a row of houses stepping back and forth under one label). The run is cut greedily,
// each cut where it removes most of the spread about the pieces' own offsets (pieces at least
// 4 * split long, up to 8 pieces), and the fewest pieces that explain the contour are kept:
// what is left of the spread about one line at most split_max_residual of it and at most
// split_max_rms_px (the staircase of a slanted wall alone leaves ~0.3 px), with neighbouring
// offsets at least `split` apart. A wobble or an arc is not explained that well by a few
// offsets that far apart.
void split_parallel(const Ring& ring, int first, int count, const Vec2& normal, const CornerOptions& o,
                    double pixel_size, std::vector<std::pair<int, int>>& out) {
  constexpr int max_pieces = 8;
  const double split = std::max(o.split_px * pixel_size, o.split_m);
  if (o.split_px <= 0 || count < 4) { out.push_back({first, count}); return; }
  std::vector<double> w(count + 1, 0.0), s(count + 1, 0.0), q(count + 1, 0.0);  // prefix sums
  for (int k = 0; k < count; ++k) {
    const std::size_t i = (first + k) % ring.size();
    const Vec2 e = edge_vector(ring, i);
    const double len = e.norm(), offset = normal.dot(ring[i] + 0.5 * e);
    w[k + 1] = w[k] + len; s[k + 1] = s[k] + len * offset; q[k + 1] = q[k] + len * offset * offset;
  }
  auto sse = [&](int a, int b) {  // spread of edges [a, b) about their own offset
    const double W = w[b] - w[a], S = s[b] - s[a];
    return W > 0 ? q[b] - q[a] - S * S / W : 0.0;
  };
  auto offset = [&](int a, int b) { return (s[b] - s[a]) / (w[b] - w[a]); };
  const double whole = sse(0, count), max_rms = o.split_max_rms_px * pixel_size;
  std::vector<int> cuts = {0, count};  // piece p is [cuts[p], cuts[p + 1])
  double total = whole;
  while (int(cuts.size()) - 1 < max_pieces) {
    int best_cut = -1;
    double best_gain = 0;
    for (std::size_t p = 0; p + 1 < cuts.size(); ++p) {
      const int a = cuts[p], b = cuts[p + 1];
      const double own = sse(a, b);
      for (int k = a + 1; k < b; ++k) {
        if (w[k] - w[a] < 4 * split || w[b] - w[k] < 4 * split) continue;
        const double gain = own - sse(a, k) - sse(k, b);
        if (gain > best_gain) { best_gain = gain; best_cut = k; }
      }
    }
    if (best_cut < 0) break;
    cuts.insert(std::upper_bound(cuts.begin(), cuts.end(), best_cut), best_cut);
    total -= best_gain;
    if (total > o.split_max_residual * whole || total > max_rms * max_rms * w[count]) continue;
    bool apart = true;
    for (std::size_t p = 1; p + 1 < cuts.size(); ++p)
      apart &= std::abs(offset(cuts[p - 1], cuts[p]) - offset(cuts[p], cuts[p + 1])) >= split;
    if (!apart) break;
    for (std::size_t p = 0; p + 1 < cuts.size(); ++p)
      out.push_back({int((first + cuts[p]) % ring.size()), cuts[p + 1] - cuts[p]});
    return;
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
    split_parallel(ring, first, count, directions[own[first]], o, pixel_size, runs);
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
