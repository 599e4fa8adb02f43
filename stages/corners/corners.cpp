#include "corners/corners.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <set>
#include <tuple>
#include <unordered_map>

#include <Eigen/Dense>

#include "geometry/polygon.hpp"
#include "labeling/mrf.hpp"
#include "models/statistics.hpp"

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

// The length-weighted mean offset along `normal` of the run's edge midpoints within `band` of
// `around` (all of them by default); `fallback` when none is.
double mean_offset(const Ring& ring, int first, int count, const Vec2& normal, double fallback,
                   double around = 0, double band = std::numeric_limits<double>::infinity()) {
  double weighted = 0, total = 0;
  for (int k = 0; k < count; ++k) {
    const std::size_t i = (first + k) % ring.size();
    const Vec2 e = edge_vector(ring, i);
    const double offset = normal.dot(ring[i] + 0.5 * e);
    if (std::abs(offset - around) > band) continue;
    weighted += e.norm() * offset;
    total += e.norm();
  }
  return total > 0 ? weighted / total : fallback;
}

Line fit_line(const Ring& ring, int first, int count, const Vec2& normal) {
  return {normal, mean_offset(ring, first, count, normal, normal.dot(ring[first]))};
}

// The line fitted again (twice) to the run's edges that lie within `band` of it: a long wall's
// line without the short end walls its run took in.
Line trimmed_fit(const Ring& ring, int first, int count, Line line, double band) {
  for (int iteration = 0; iteration < 2; ++iteration)
    line.offset = mean_offset(ring, first, count, line.normal, line.offset, line.offset, band);
  return line;
}

// True when a parabola across the run's middle (its ends, a window each, left out) explains at
// least min_explained of the contour's spread about a straight line: an arc bends one way over
// its whole length, a wobble of several half-waves along a long wall does not.
bool bends_consistently(const Ring& ring, int first, int count, const Line& line, double trim, double min_explained) {
  if (min_explained <= 0) return true;
  const Vec2 along(-line.normal.y(), line.normal.x());
  const double total = run_length(ring, first, count);
  Eigen::Matrix3d quadratic = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  double position = 0, origin = 0, sum_v2 = 0;
  bool have_origin = false;
  for (int k = 0; k < count; ++k) {
    const std::size_t i = (first + k) % ring.size();
    const Vec2 e = edge_vector(ring, i);
    const double len = e.norm();
    position += len;
    if (position < trim || position > total - trim) continue;
    const Vec2 mid = ring[i] + 0.5 * e;
    if (!have_origin) { origin = along.dot(mid); have_origin = true; }
    const double u = along.dot(mid) - origin, v = line.normal.dot(mid) - line.offset;
    const Eigen::Vector3d basis(1.0, u, u * u);
    quadratic += len * basis * basis.transpose();
    rhs += len * v * basis;
    sum_v2 += len * v * v;
  }
  if (quadratic(0, 0) <= 0) return false;
  // Spread about the best straight line (offset and tilt) and about the best parabola.
  const auto residual = [&](int terms) {
    const Eigen::VectorXd c = quadratic.topLeftCorner(terms, terms).ldlt().solve(rhs.head(terms));
    return c.dot(quadratic.topLeftCorner(terms, terms) * c) - 2 * c.dot(rhs.head(terms));
  };
  // Both residuals less the same sum of v^2 (which cancels in their difference).
  const double straight = residual(2), bent = residual(3);
  const double spread = sum_v2 + straight;  // about the straight line
  return spread > 0 && (straight - bent) >= min_explained * spread;
}

// The open polyline smoothed along its length: each inner point moved to the value at it of a
// parabola in arc length fitted to the points within two sigma of it (Gaussian weights of width
// sigma, each point weighted by the edges around it; the window symmetric about the point, so
// narrowed towards the ends, which stay fixed). A local parabola keeps an arc's radius where a
// moving mean would shrink it, and averages out a wobble shorter than the window.
std::vector<Vec2> smoothed_open(const std::vector<Vec2>& points, double sigma) {
  const std::size_t n = points.size();
  if (sigma <= 0 || n < 3) return points;
  std::vector<double> at(n, 0.0), weight(n, 0.0);  // arc length, half the edges around each point
  for (std::size_t i = 1; i < n; ++i) {
    const double len = (points[i] - points[i - 1]).norm();
    at[i] = at[i - 1] + len;
    weight[i - 1] += 0.5 * len;
    weight[i] += 0.5 * len;
  }
  std::vector<Vec2> out = points;
  std::size_t lo = 0, hi = 0;
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const double radius = std::min({2 * sigma, at[i], at[n - 1] - at[i]});
    while (at[lo] < at[i] - radius) ++lo;
    if (hi < lo) hi = lo;
    while (hi + 1 < n && at[hi + 1] <= at[i] + radius) ++hi;
    Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
    Eigen::Matrix<double, 3, 2> rhs = Eigen::Matrix<double, 3, 2>::Zero();
    for (std::size_t j = lo; j <= hi; ++j) {
      const double u = (at[j] - at[i]) / sigma, w = weight[j] * std::exp(-0.5 * u * u);
      const Eigen::Vector3d basis(1.0, u, u * u);
      normal += w * basis * basis.transpose();
      rhs += w * basis * Eigen::RowVector2d(points[j].x(), points[j].y());
    }
    const Eigen::Matrix<double, 3, 2> c = normal.ldlt().solve(rhs);
    if (c.allFinite() && hi > lo + 2) out[i] = Vec2(c(0, 0), c(0, 1));
  }
  return out;
}

// The mean departures of the run's contour from `line` over consecutive windows of `window`
// length (the run's ends, a window each, left out: corners are rounded there, by the raster).
std::vector<double> window_departures(const Ring& ring, int first, int count, const Line& line, double window) {
  std::vector<double> means;
  const double total = run_length(ring, first, count);
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
      means.push_back(window_sum / window_length);
      window_length = window_sum = 0;
    }
  }
  return means;
}

// A bay or a bow on a straight wall: the run's edges [first, first + count) (relative to the
// run) that depart from the wall's line, and that line.
struct Bay {
  int first = 0, count = -1;  // (count -1: no bay, the whole run curves)
  Line wall;
};

// True when the run's contour departs from its line by more than curve_px, and curve_noise_factor
// times the building's boundary noise, on average over two consecutive windows of curve_window_px
// and curve_window_m, both to the same side: a boundary wobble averages out over a window or
// turns to the other side in the next, a curved wall does neither. And then when it bends one way
// over the whole run (bends_consistently). Or else, when about the line of its straight part (the
// median offset of its contour) no window departs to the other side by more than
// curve_other_side of the threshold (a wobble that departs that far one way departs the other way
// too, half a wave on), a bay or a bow on a straight wall, which a parabola over the whole run
// does not explain: *bay is then the stretch of the run that departs to its side by more than
// the noise, around the window that departs farthest, and the rest of the run is that wall.
bool is_curved(const Ring& ring, int first, int count, const Line& line, const CornerOptions& o, double pixel_size,
               double noise, Bay* bay) {
  if (o.curve_px <= 0) return false;
  const double window = std::max(o.curve_window_px * pixel_size, o.curve_window_m);
  const double threshold = std::max(o.curve_px * pixel_size, o.curve_noise_factor * noise);
  int side = 0;  // the side the previous window departed to beyond the threshold (0: none)
  for (const double mean : window_departures(ring, first, count, line, window)) {
    const int now = std::abs(mean) > threshold ? (mean > 0 ? 1 : -1) : 0;
    if (now != 0 && now == side) {
      if (bends_consistently(ring, first, count, line, window, o.curve_min_explained)) return true;
      if (o.curve_other_side <= 0) return false;
      std::vector<std::pair<double, double>> offsets;  // (offset, length) of each edge's midpoint
      std::vector<double> away(count);                  // each edge's departure to the bay's side
      for (int k = 0; k < count; ++k) {
        const std::size_t i = (first + k) % ring.size();
        const Vec2 e = edge_vector(ring, i);
        offsets.emplace_back(line.normal.dot(ring[i] + 0.5 * e), e.norm());
        away[k] = now * offsets.back().first;
      }
      const Line wall{line.normal, weighted_quantile(std::move(offsets), 0.5)};
      for (double& a : away) a -= now * wall.offset;
      double beyond = 0, other = 0;  // the windows' farthest departures to the bay's side and the other
      for (const double m : window_departures(ring, first, count, wall, window)) {
        beyond = std::max(beyond, now * m);
        other = std::max(other, -now * m);
      }
      if (beyond <= threshold || other > o.curve_other_side * threshold) return false;
      // The bay: the edges departing by more than the noise (at least a pixel) around the farthest one.
      const int peak = int(std::max_element(away.begin(), away.end()) - away.begin());
      const double edge_of_bay = std::max(pixel_size, noise);
      int lo = peak, hi = peak + 1;
      while (lo > 0 && away[lo - 1] > edge_of_bay) --lo;
      while (hi < count && away[hi] > edge_of_bay) ++hi;
      *bay = {lo, hi - lo, wall};
      return true;
    }
    side = now;
  }
  return false;
}

// Appends run [first, first + count) to out, split where its contour steps between parallel
// offsets (a row of houses stepping back and forth under one label). The pieces are parallel to
// each other but not necessarily to the label's direction, which a stepped wall tilts when it is
// fitted: each piece has its own offset, all share one slope about that direction. The run is cut
// greedily, each cut where it removes most of the spread about the pieces' lines (pieces at
// least 4 * split long, up to 8 pieces), and the fewest pieces that explain the contour are
// kept: what is left of the spread about the run's own line at most split_max_residual of it, or
// no more than the noise leaves (split_max_rms_noise), and at most split_max_rms_px, with
// neighbouring pieces at least `split` apart (on a clean wall, split_noise times the noise the
// pieces leave, or the mask's, below). A wobble or an arc is not explained that well by a few
// offsets that far apart.
void split_parallel(const Ring& ring, int first, int count, const Vec2& normal, const CornerOptions& o,
                    double pixel_size, double noise, double mask_noise, std::vector<std::pair<int, int>>& out) {
  constexpr int max_pieces = 8;
  const double split = std::max({o.split_px * pixel_size, o.split_m, o.split_noise * noise});
  if (o.split_px <= 0 || count < 4) { out.push_back({first, count}); return; }
  // Length-weighted prefix sums of each edge's position t along the run and offset y across it
  // (both from the run's first edge, for range).
  const Vec2 along(-normal.y(), normal.x());
  const Vec2 origin = ring[first % ring.size()];
  std::vector<LineMoments> sums(count + 1);
  for (int k = 0; k < count; ++k) {
    const std::size_t i = (first + k) % ring.size();
    const Vec2 e = edge_vector(ring, i);
    const Vec2 mid = ring[i] + 0.5 * e - origin;
    const double len = e.norm(), t = along.dot(mid), y = normal.dot(mid);
    sums[k + 1] = sums[k] + LineMoments::of(len, t, y);
  }
  ParallelPieces pieces(sums);
  const double whole = pieces.spread(), w_total = sums.back().w;
  const double noise_rms = o.split_max_rms_noise * noise, max_rms = std::max(o.split_max_rms_px * pixel_size, noise_rms);
  while (int(pieces.cuts().size()) - 1 < max_pieces) {
    const std::size_t best_cut = pieces.best_cut(4 * split);
    if (best_cut == 0) break;
    pieces.cut(best_cut);
    // The parts explain the run: they leave little of its spread, or no more than the noise does.
    const double total = pieces.spread();
    const bool explained = total <= o.split_max_residual * whole || total <= noise_rms * noise_rms * w_total;
    if (!explained || total > max_rms * max_rms * w_total) continue;
    // Neighbouring pieces' lines (the shared slope, each its own offset) at least `split` apart.
    // Where the pieces leave no more than split_max_rms_px (a clean wall, its pixels'
    // quantization), the noise in that is what they leave, where less, but at least the mask's
    // (mask_noise, when known): a building's noise measured about one line along each wall is
    // its steps' own on a clean row of houses, and then lies above its mask's.
    const double left_rms = std::sqrt(std::max(0.0, total) / w_total);
    const double step_noise =
        mask_noise > 0 && left_rms <= o.split_max_rms_px * pixel_size ? std::min(noise, std::max(mask_noise, left_rms)) : noise;
    const double apart_by = std::max({o.split_px * pixel_size, o.split_m, o.split_noise * step_noise});
    const std::vector<std::size_t>& cuts = pieces.cuts();
    bool apart = true;
    for (std::size_t p = 1; p + 1 < cuts.size(); ++p)
      apart &= std::abs(pieces.offset(cuts[p - 1], cuts[p]) - pieces.offset(cuts[p], cuts[p + 1])) >= apart_by;
    if (!apart) continue;
    for (std::size_t p = 0; p + 1 < cuts.size(); ++p)
      out.push_back({int((first + int(cuts[p])) % int(ring.size())), int(cuts[p + 1] - cuts[p])});
    return;
  }
  out.push_back({first, count});
}

// Turns each straight wall onto the building's lattice (its main direction and quarter turns)
// when it lies within snap_max_deg of it and the turn moves the wall's ends by no more than
// snap_shift_m, or snap_noise times the uncertainty of its fitted direction at its ends, which a
// noise of standard deviation `noise` correlated over snap_correlation_m leaves on a wall of
// length L: noise * sqrt(3 * correlation / L). A short noisy wall turns readily, a long one only
// as far as its fit is unsure. The wall's offset is fitted again with its new direction.
void snap_to_lattice(const Ring& ring, const std::vector<std::pair<int, int>>& runs, std::vector<Line>& lines,
                     const Vec2& lattice, const CornerOptions& o, double pixel_size, double noise) {
  if (o.snap_max_deg <= 0) return;
  const double min_cos = std::cos(o.snap_max_deg * M_PI / 180.0);
  const double correlation = noise_correlation_m(o, pixel_size);
  for (std::size_t r = 0; r < runs.size(); ++r) {
    const Vec2 target = nearest_lattice_axis(lines[r].normal, lattice);
    const double cos_turn = std::clamp(target.dot(lines[r].normal), -1.0, 1.0);
    if (cos_turn < min_cos || cos_turn > 1 - 1e-15) continue;
    const double length = run_length(ring, runs[r].first, runs[r].second);
    const double uncertainty = noise * std::sqrt(3 * correlation / std::max(length, correlation));
    const double shift = std::sqrt(1 - cos_turn * cos_turn) * 0.5 * length;
    if (shift <= std::max(o.snap_shift_m, o.snap_noise * uncertainty)) lines[r] = fit_line(ring, runs[r].first, runs[r].second, target);
  }
}

// True when the line lies exactly on the lattice (turned onto it, or fitted with it).
bool on_lattice(const Line& line, const Vec2& lattice) {
  return nearest_lattice_axis(line.normal, lattice).dot(line.normal) > 1 - 1e-12;
}

// Consecutive runs, one off the lattice at least, that zigzag about one line of the lattice become
// one wall on that line: a wall that wobbles gets its flanks labeled with the directions of their
// slopes, and its crests with the wall's own. A window of runs joins when the line from its start
// to its end is within max_deg of the lattice and its contour lies about the best line of that
// lattice direction within max_rms (RMS, by length) and max_dev (everywhere). Each off-lattice run
// in turn grows the largest such window around it, to the right first; at least 4 runs are left.
// Two consecutive runs off the lattice within square_deg of square to each other stop a window.
void merge_zigzags(const Ring& ring, std::vector<std::pair<int, int>>& runs, std::vector<Line>& lines, const Vec2& lattice,
                   double max_deg, double max_rms, double max_dev, double square_deg) {
  if (max_deg <= 0 || max_rms <= 0) return;
  const double min_cos = std::cos(max_deg * M_PI / 180.0), square_cos = std::sin(square_deg * M_PI / 180.0);
  const int size = int(ring.size());
  constexpr int kMaxWindow = 64;  // runs in one window at most (bounds the work on long rings)
  static_assert(kMaxWindow < 128, "a window's run count is 7 bits of its verdict's key");
  // Each window's verdict, by its first edge, its edges and its runs: runs only merge, and a merged
  // run spans more than each run it took in, so a window of the same edges and as many runs holds
  // the same runs and their lines, and fits as it did (the search starts over after every merge
  // and tries the windows that failed before it again).
  struct Verdict {
    bool fits;
    Vec2 normal;
  };
  std::unordered_map<std::uint64_t, Verdict> verdicts;
  // The lattice normal of the window [a, a + count) of runs, when its chord is near the lattice and
  // its contour lies within the bounds about that line.
  const auto judge = [&](std::size_t a, int count, int first, int edges, Vec2* normal) {
    // Two consecutive walls off the lattice and square to each other are a second lattice (the
    // teeth of a staggered row of houses), not a wobble, whose flanks are not square.
    for (int k = 0; k + 1 < count; ++k) {
      const Line& p = lines[(a + k) % runs.size()];
      const Line& q = lines[(a + k + 1) % runs.size()];
      if (!on_lattice(p, lattice) && !on_lattice(q, lattice) && std::abs(p.normal.dot(q.normal)) < square_cos) return false;
    }
    const Vec2 chord = ring[(first + edges) % size] - ring[first];
    if (chord.norm() <= 0) return false;
    const Vec2 across = outward_normal(chord);  // (outward, as every line's normal: rings are oriented)
    const Vec2 target = nearest_lattice_axis(across, lattice);
    if (std::abs(target.dot(across)) < min_cos) return false;
    const Line line = fit_line(ring, first, edges, target);
    double sum = 0, total = 0;
    for (int k = 0; k < edges; ++k) {
      const int i = (first + k) % size;
      const Vec2 e = edge_vector(ring, std::size_t(i));
      const double d = line.normal.dot(ring[i] + 0.5 * e) - line.offset, len = e.norm();
      if (std::abs(line.normal.dot(ring[i]) - line.offset) > max_dev) return false;
      sum += len * d * d;
      total += len;
    }
    if (total <= 0 || std::sqrt(sum / total) > max_rms) return false;
    *normal = target;
    return true;
  };
  const auto fits = [&](std::size_t a, int count, Vec2* normal) {
    const int first = runs[a].first;
    int edges = 0;
    for (int k = 0; k < count; ++k) edges += runs[(a + k) % runs.size()].second;
    // (The key: first, edges and count in 32, 25 and 7 bits; a ring of more edges is not remembered.)
    if (edges >= 1 << 25) return judge(a, count, first, edges, normal);
    const std::uint64_t key = std::uint64_t(std::uint32_t(first)) << 32 | std::uint64_t(edges) << 7 | std::uint64_t(count);
    if (const auto known = verdicts.find(key); known != verdicts.end()) {
      if (known->second.fits) *normal = known->second.normal;
      return known->second.fits;
    }
    Vec2 found(0, 0);
    const bool ok = judge(a, count, first, edges, &found);
    verdicts.emplace(key, Verdict{ok, found});
    if (ok) *normal = found;
    return ok;
  };
  for (std::size_t r = 0; r < runs.size() && runs.size() > 4;) {
    if (on_lattice(lines[r], lattice)) { ++r; continue; }
    // The largest window around r: grown to the right, then to the left, while it fits.
    std::size_t a = r;
    int count = 1;
    Vec2 normal(0, 0), found(0, 0);
    while (count < kMaxWindow && int(runs.size()) - count > 3 && fits(a, count + 1, &found)) ++count, normal = found;
    while (count < kMaxWindow && int(runs.size()) - count > 3) {
      const std::size_t before = (a + runs.size() - 1) % runs.size();
      if (!fits(before, count + 1, &found)) break;
      a = before, ++count, normal = found;
    }
    if (count < 2) { ++r; continue; }
    for (int k = 1; k < count; ++k) runs[a].second += runs[(a + k) % runs.size()].second;
    lines[a] = fit_line(ring, runs[a].first, runs[a].second, normal);
    for (int k = 1; k < count; ++k) {  // erase the absorbed runs (they follow a, cyclically)
      const std::size_t i = (a + 1) % runs.size();
      runs.erase(runs.begin() + long(i));
      lines.erase(lines.begin() + long(i));
      if (i < a) --a;
    }
    r = 0;  // (indices moved; runs on the lattice are passed over quickly)
  }
}

// Walls with one direction whose offsets differ by less than `tolerance` become one wall (its
// line fitted to them): consecutive ones (collinear walls made one), and two joined by a riser no
// longer than twice the tolerance (a step smaller than the noise is the noise's).
void merge_parallel(const Ring& ring, std::vector<std::pair<int, int>>& runs, std::vector<Line>& lines, double tolerance,
                    double pixel_size) {
  auto same = [&](std::size_t a, std::size_t b) {
    return lines[a].normal.dot(lines[b].normal) > 1 - 1e-12 && std::abs(lines[a].offset - lines[b].offset) < tolerance;
  };
  bool merged = true;
  while (merged && runs.size() > 4) {
    merged = false;
    for (std::size_t r = 0; r < runs.size() && runs.size() > 4; ++r) {
      const std::size_t next = (r + 1) % runs.size(), after = (r + 2) % runs.size();
      int absorbed = 0;  // runs after r that join it
      if (same(r, next)) absorbed = 1;
      else if (same(r, after) && run_length(ring, runs[next].first, runs[next].second) <= 2 * tolerance + 2 * pixel_size) absorbed = 2;
      if (absorbed == 0) continue;
      for (int k = 1; k <= absorbed; ++k) runs[r].second += runs[(r + k) % runs.size()].second;
      lines[r] = fit_line(ring, runs[r].first, runs[r].second, lines[r].normal);
      for (int k = 0; k < absorbed; ++k) {  // erase the absorbed runs, the later index first
        const std::size_t i = (r + 1) % runs.size();
        runs.erase(runs.begin() + long(i));
        lines.erase(lines.begin() + long(i));
        if (i < r) --r;
      }
      merged = true;
    }
  }
}

// An oblique run shorter than max_cut between two square walls of the lattice is a corner that
// the segmentation rounded: it is dropped, its edges shared by its neighbours (their lines as
// they were fitted, without the rounding), which then meet at their intersection.
void drop_corner_cuts(const Ring& ring, std::vector<std::pair<int, int>>& runs, std::vector<Line>& lines,
                      const Vec2& lattice, double max_cut) {
  if (max_cut <= 0) return;
  for (std::size_t r = 0; r < runs.size() && runs.size() > 4;) {
    const std::size_t prev = (r + runs.size() - 1) % runs.size(), next = (r + 1) % runs.size();
    const bool cut = !on_lattice(lines[r], lattice) && on_lattice(lines[prev], lattice) && on_lattice(lines[next], lattice) &&
                     std::abs(lines[prev].normal.dot(lines[next].normal)) < 1e-9 &&
                     run_length(ring, runs[r].first, runs[r].second) < max_cut;
    if (!cut) { ++r; continue; }
    const int half = runs[r].second / 2, n = int(ring.size());
    runs[prev].second += half;
    runs[next].first = (runs[r].first + half) % n;
    runs[next].second += runs[r].second - half;
    runs.erase(runs.begin() + long(r));
    lines.erase(lines.begin() + long(r));
  }
}

}  // namespace

void absorb_short_runs(const Ring& ring, std::vector<int>& labels, double min_length) {
  // The runs as a cyclic list; the short ones ordered by length, then by their first edge (the
  // order of label_runs), so that the shortest, the first of equals, goes first. A merged run's
  // length is summed again edge by edge, as a run's is.
  struct Run {
    int first, count;
    double length;
    int prev, next;
  };
  std::vector<Run> runs;
  for (const auto& [first, count] : label_runs(labels)) runs.push_back({first, count, run_length(ring, first, count), 0, 0});
  int alive = int(runs.size());
  if (alive <= 4) return;  // never below a quadrilateral
  for (int r = 0; r < alive; ++r) {
    runs[r].prev = (r + alive - 1) % alive;
    runs[r].next = (r + 1) % alive;
  }
  std::set<std::tuple<double, int, int>> short_runs;  // length, first edge, run
  const auto track = [&](int r) {
    if (runs[r].length < min_length) short_runs.insert({runs[r].length, runs[r].first, r});
  };
  const auto untrack = [&](int r) { short_runs.erase({runs[r].length, runs[r].first, r}); };
  for (int r = 0; r < alive; ++r) track(r);
  const int n = int(labels.size());
  while (alive > 4 && !short_runs.empty()) {
    const int s = std::get<2>(*short_runs.begin());
    const int p = runs[s].prev, q = runs[s].next;
    const bool to_prev = runs[p].length >= runs[q].length;
    const int label = labels[runs[to_prev ? p : q].first];
    for (int k = 0; k < runs[s].count; ++k) labels[(runs[s].first + k) % n] = label;
    // The run s joins, and the other neighbour too when it has the same label.
    const bool with_prev = to_prev || labels[runs[p].first] == label;
    const bool with_next = !to_prev || labels[runs[q].first] == label;
    const int head = with_prev ? p : s, tail = with_next ? q : s;
    for (int r : {p, s, q}) untrack(r);
    int count = 0;
    for (int r = head;; r = runs[r].next) {
      count += runs[r].count;
      if (r == tail) break;
    }
    runs[head].count = count;
    runs[head].length = run_length(ring, runs[head].first, count);
    alive -= (head == s ? 0 : 1) + (tail == s ? 0 : 1);
    runs[head].next = runs[tail].next;
    runs[runs[tail].next].prev = head;
    track(head);
    if (!with_prev) track(p);
    if (!with_next) track(q);
  }
}

std::vector<std::pair<int, int>> zigzags_merged(const Ring& ring, std::vector<std::pair<int, int>> runs, const std::vector<Vec2>& normals,
                                                const Vec2& lattice, double max_deg, double max_rms, double max_dev, double square_deg) {
  std::vector<Line> lines;
  for (std::size_t r = 0; r < runs.size(); ++r) lines.push_back(fit_line(ring, runs[r].first, runs[r].second, normals[r]));
  merge_zigzags(ring, runs, lines, lattice, max_deg, max_rms, max_dev, square_deg);
  return runs;
}

Ring extract_corners(const Ring& ring, const std::vector<int>& labels, const std::vector<Vec2>& directions,
                     double pixel_size, const CornerOptions& o, std::string* problem, const CornerContext& context,
                     bool* curved_out) {
  const double noise = context.noise;
  const double regularity = context.regularity();  // (snaps and curves: noise.regularity_ceiling)
  std::vector<int> own = labels;
  absorb_short_runs(ring, own, o.min_run_px * pixel_size);
  std::vector<std::pair<int, int>> runs;
  for (auto [first, count] : label_runs(own))
    split_parallel(ring, first, count, directions[own[first]], o, pixel_size, noise, context.mask_noise, runs);
  std::vector<Line> lines;
  for (auto [first, count] : runs) lines.push_back(fit_line(ring, first, count, directions[own[first]]));
  if (context.lattice.squaredNorm() > 0) {
    snap_to_lattice(ring, runs, lines, context.lattice, o, pixel_size, regularity);
    merge_zigzags(ring, runs, lines, context.lattice, o.zigzag_max_deg, std::max(pixel_size, o.zigzag_rms_noise * noise),
                  std::max(2 * pixel_size, o.zigzag_max_noise * noise), o.parallel_angle_deg);
    merge_parallel(ring, runs, lines, std::max(o.merge_offset_m, o.merge_noise * noise), pixel_size);
    drop_corner_cuts(ring, runs, lines, context.lattice, o.max_cut_m);
  }
  std::vector<bool> curved;
  bool any_curved = false;
  {
    // Each curved run, or its bay alone between the two parts of its wall (each a window long at
    // least; a shorter one joins the bay).
    const double window = std::max(o.curve_window_px * pixel_size, o.curve_window_m);
    std::vector<std::pair<int, int>> split_runs;
    std::vector<Line> split_lines;
    const auto add = [&](int first, int count, const Line& line, bool curve) {
      if (count <= 0) return;
      split_runs.push_back({first % int(ring.size()), count});
      split_lines.push_back(line);
      curved.push_back(curve);
    };
    for (std::size_t r = 0; r < runs.size(); ++r) {
      const auto [first, count] = runs[r];
      Bay bay;
      const bool curve = is_curved(ring, first, count, lines[r], o, pixel_size, regularity, &bay);
      any_curved |= curve;
      if (!curve || bay.count < 0) {
        add(first, count, lines[r], curve);
        continue;
      }
      int before = bay.first, after = count - bay.first - bay.count;
      if (run_length(ring, first, before) < window) before = 0;
      if (run_length(ring, first + bay.first + bay.count, after) < window) after = 0;
      add(first, before, bay.wall, false);
      add(first + before, count - before - after, lines[r], true);
      add(first + count - after, after, bay.wall, false);
    }
    runs = std::move(split_runs);
    lines = std::move(split_lines);
  }
  const int n = int(runs.size());
  if (curved_out) *curved_out = any_curved;
  const double parallel_sin = std::sin(o.parallel_angle_deg * M_PI / 180.0);
  // Two runs make a polygon when one is a curve, or when they are a thin building's two long
  // walls, whose ends (each run's end, on a short wall no direction was found for) become steps
  // square to them.
  const bool two_walls = n == 2 && !any_curved && std::abs(cross(lines[0].normal, lines[1].normal)) < parallel_sin;
  if (n < 3 && !(n == 2 && any_curved) && !two_walls) {
    *problem = "only " + std::to_string(runs.size()) + " straight runs, a polygon needs 3";
    return {};
  }
  if (two_walls)
    for (int r = 0; r < 2; ++r)
      lines[r] = trimmed_fit(ring, runs[r].first, runs[r].second, lines[r], std::max(2 * pixel_size, 3 * noise));
  const double square_sin = std::cos(o.parallel_angle_deg * M_PI / 180.0);  // within that of 90 degrees
  const double curve_tolerance = std::max(pixel_size, o.curve_tolerance_noise * noise);
  const double off_line = std::max(2 * pixel_size, 3 * noise);  // (as trimmed_fit's: beyond the noise)
  const double curve_window = std::max(o.curve_window_px * pixel_size, o.curve_window_m);
  Ring out;
  for (int r = 0; r < n; ++r) {
    if (curved[r]) {  // the run's own contour, simplified, between its ends
      std::vector<Vec2> points;
      for (int k = 0; k <= runs[r].second; ++k) points.push_back(ring[(runs[r].first + k) % ring.size()]);
      points = smoothed_open(points, o.curve_smoothing * curve_window);
      const std::vector<char> keep = douglas_peucker_open(points, curve_tolerance);
      for (std::size_t k = 1; k + 1 < points.size(); ++k) if (keep[k]) out.push_back(points[k]);
    }
    const Line& a = lines[r];
    const Line& b = lines[(r + 1) % n];
    const Vec2 junction = ring[runs[(r + 1) % n].first];  // where run r ends and r+1 starts
    // Next to a curve, the junction itself, or its foot on the straight neighbour's line; where
    // the straight run's contour leaves its line before the junction (the labeling gave the
    // curve's first stretch the wall's direction), the wall ends at the foot of the last of its
    // contour's vertices within off_line of the line, and that contour, simplified, leads on to
    // the junction (the foot of the junction there would lie off the contour, beyond the curve).
    const bool curve_before = curved[r], curve_after = curved[(r + 1) % n];
    if (curve_before && curve_after) {
      out.push_back(junction);
      continue;
    }
    if (curve_before || curve_after) {
      const Line& wall = curve_after ? a : b;
      const int run = curve_after ? r : (r + 1) % n;
      const int count = runs[run].second;
      const auto vertex = [&](int k) { return ring[std::size_t(runs[run].first + k) % ring.size()]; };
      // The run's vertices k = 0 .. count off the line next to the curve, counted from its end there.
      const auto from_curve = [&](int j) { return curve_after ? count - j : j; };
      int off = 0;
      while (off < count && std::abs(wall.normal.dot(vertex(from_curve(off))) - wall.offset) > off_line) ++off;
      // (None, or the whole run, whose contour would be drawn from both of its ends when a curve
      // lies there too: the foot of the junction, as before.)
      if (off == 0 || off == count) {
        out.push_back(wall.project(junction));
        continue;
      }
      // The stretch off the line, in the ring's order, its vertices kept by the simplification (its
      // ends always, the junction one of them), the one on the wall's side as its foot on the line.
      std::vector<Vec2> stretch;
      for (int k = std::min(from_curve(off), from_curve(0)); k <= std::max(from_curve(off), from_curve(0)); ++k) stretch.push_back(vertex(k));
      const std::vector<char> keep = douglas_peucker_open(stretch, curve_tolerance);
      const std::size_t on_wall = curve_after ? 0 : stretch.size() - 1;
      for (std::size_t k = 0; k < stretch.size(); ++k)
        if (keep[k]) out.push_back(k == on_wall ? wall.project(stretch[k]) : stretch[k]);
      continue;
    }
    const double det = cross(a.normal, b.normal);
    bool use_step = std::abs(det) < parallel_sin;
    if (!use_step) {
      // Solve a.normal . x = a.offset, b.normal . x = b.offset.
      const Vec2 corner((a.offset * b.normal.y() - b.offset * a.normal.y()) / det,
                        (a.normal.x() * b.offset - b.normal.x() * a.offset) / det);
      // Square corners are well posed: their intersection may lie farther (a rounded corner).
      const double max_shift = std::abs(det) >= square_sin ? o.square_corner_shift_m : o.max_corner_shift_m;
      if ((corner - junction).norm() <= max_shift) out.push_back(corner);
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
