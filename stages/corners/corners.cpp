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
  const auto runs = label_runs(own);
  if (runs.size() < 3) {
    *problem = "only " + std::to_string(runs.size()) + " straight runs, a polygon needs 3";
    return {};
  }
  std::vector<Line> lines;
  for (auto [first, count] : runs) lines.push_back(fit_line(ring, first, count, directions[own[first]]));
  const double parallel_sin = std::sin(o.parallel_angle_deg * M_PI / 180.0);
  Ring out;
  const int n = int(runs.size());
  for (int r = 0; r < n; ++r) {
    const Line& a = lines[r];
    const Line& b = lines[(r + 1) % n];
    const Vec2 junction = ring[runs[(r + 1) % n].first];  // where run r ends and r+1 starts
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
