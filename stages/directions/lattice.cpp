#include "directions/lattice.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>

#include "geometry/polygon.hpp"

namespace lodforge {

namespace {

// The point at arc length s along a closed ring (positions: the arc length at each vertex, and the
// perimeter last). *edge: where the search for s's edge starts (the edge of the previous query:
// a walk along the ring from there, queries that move forward by little at a time cost no search),
// and where s's edge is on return; it is the edge a binary search gives (the last vertex at or
// before s, the ring's last at most).
Vec2 point_at(const Ring& ring, const std::vector<double>& positions, double s, std::size_t* edge) {
  const double total = positions.back();
  s = std::fmod(s, total);
  if (s < 0) s += total;
  const std::size_t last = ring.size() - 1;
  std::size_t k = std::min(*edge, last);
  if (positions[k] > s) k = 0;  // (s wrapped past the ring's start)
  while (k < last && positions[k + 1] <= s) ++k;
  *edge = k;
  const double length = positions[k + 1] - positions[k];
  const double t = length > 0 ? (s - positions[k]) / length : 0.0;
  return ring[k] + t * edge_vector(ring, k);
}

// An angle in [0, 2π).
double wrap(double a) {
  a = std::fmod(a, 2 * M_PI);
  return a < 0 ? a + 2 * M_PI : a;
}

// The share of the samples' weight (directions times four, weights) within window of at.
double share_near(const std::vector<std::pair<double, double>>& samples, double at, double window) {
  double near = 0, total = 0;
  for (const auto& [a, w] : samples) {
    total += w;
    if (std::abs(std::remainder(a - at, 2 * M_PI)) <= window) near += w;
  }
  return total > 0 ? near / total : 0.0;
}

}  // namespace

double ChordLattice::share_at(const Vec2& lattice, double window_deg) const {
  return share_near(chords, wrap(4 * std::atan2(lattice.y(), lattice.x())), 4 * window_deg * M_PI / 180.0);
}

ChordLattice chord_lattice(const std::vector<Ring>& rings, const LatticeOptions& o) {
  if (o.chord_m <= 0) return {};
  // Each chord's direction times four (quarter turns become whole turns), weighted by its edge.
  std::vector<std::pair<double, double>> samples;
  for (const Ring& ring : rings) {
    const std::size_t n = ring.size();
    if (n < 3) continue;
    std::vector<double> positions(n + 1, 0.0);
    for (std::size_t i = 0; i < n; ++i) positions[i + 1] = positions[i] + edge_vector(ring, i).norm();
    const double span = std::min(o.chord_m, o.chord_share * positions[n]);
    if (span <= 0) continue;
    std::size_t ahead = 0, behind = 0;  // (the chords' ends move forward along the ring with i)
    for (std::size_t i = 0; i < n; ++i) {
      const double length = positions[i + 1] - positions[i];
      const double middle = positions[i] + length / 2;
      const Vec2 chord = point_at(ring, positions, middle + span / 2, &ahead) - point_at(ring, positions, middle - span / 2, &behind);
      if (length <= 0 || chord.squaredNorm() <= 0) continue;
      samples.push_back({wrap(4 * std::atan2(chord.y(), chord.x())), length});
    }
  }
  if (samples.empty()) return {};
  // The histogram's peak (bins of a degree of direction: the mean about it refines it), smoothed
  // by a circular Gaussian.
  const int bins = 90;
  const double bin = 2 * M_PI / bins;
  std::vector<double> histogram(bins, 0.0), smoothed(bins, 0.0);
  for (const auto& [a, w] : samples) histogram[std::min(bins - 1, int(a / bin))] += w;
  const double sigma = 4 * o.smooth_deg * M_PI / 180.0;
  const int reach = std::min(bins / 2, int(std::ceil(3 * sigma / bin)));
  std::vector<double> kernel(reach + 1);
  for (int k = 0; k <= reach; ++k) kernel[k] = std::exp(-0.5 * std::pow(k * bin / sigma, 2));
  for (int b = 0; b < bins; ++b) {
    if (histogram[b] == 0) continue;
    for (int k = -reach; k <= reach; ++k) smoothed[(b + k + bins) % bins] += histogram[b] * kernel[std::abs(k)];
  }
  const int peak = int(std::max_element(smoothed.begin(), smoothed.end()) - smoothed.begin());
  const double mode = (peak + 0.5) * bin;
  // The mean of the chords near the peak.
  Vec2 sum = Vec2::Zero();
  const double window = 4 * o.window_deg * M_PI / 180.0;
  for (const auto& [a, w] : samples)
    if (std::abs(std::remainder(a - mode, 2 * M_PI)) <= window) sum += w * Vec2(std::cos(a), std::sin(a));
  const double angle = (sum.squaredNorm() > 0 ? std::atan2(sum.y(), sum.x()) : mode) / 4;
  const double share = share_near(samples, mode, window);
  return {Vec2(std::cos(angle), std::sin(angle)), share, std::move(samples)};
}

LatticeLender lattice_lender(std::int64_t id, const std::vector<Ring>& rings, const ChordLattice& chord) {
  LatticeLender l;
  l.id = id;
  l.direction = chord.direction;
  l.share = chord.share;
  if (rings.empty() || rings[0].empty()) {
    l.centre = Vec2::Constant(std::numeric_limits<double>::quiet_NaN());
    return l;
  }
  Vec2 low = rings[0][0], high = rings[0][0];
  for (const Vec2& p : rings[0]) {
    l.centre += p;
    low = low.cwiseMin(p);
    high = high.cwiseMax(p);
  }
  l.centre /= double(rings[0].size());
  l.perimeter = perimeter(rings[0]);
  l.extent = (high - low).maxCoeff();
  l.low = low;
  l.high = high;
  return l;
}

double distance_to_box(const LatticeLender& lender, const Vec2& p) {
  return (lender.low - p).cwiseMax(p - lender.high).cwiseMax(Vec2::Zero()).norm();
}

PointsWithinRadius::PointsWithinRadius(std::vector<Vec2> points, double radius) : points_(std::move(points)), radius_(radius) {
  for (std::size_t j = 0; j < points_.size(); ++j)
    if (points_[j].allFinite() && radius_ > 0) cells_[cell_of(points_[j])].push_back(j);
}

std::pair<long, long> PointsWithinRadius::cell_of(const Vec2& p) const {
  return {long(std::floor(p.x() / radius_)), long(std::floor(p.y() / radius_))};
}

void PointsWithinRadius::near(const Vec2& p, std::vector<std::size_t>& out) const {
  out.clear();
  if (!p.allFinite() || radius_ <= 0) return;
  const auto [cx, cy] = cell_of(p);
  for (long y = cy - 1; y <= cy + 1; ++y)
    for (long x = cx - 1; x <= cx + 1; ++x)
      if (const auto it = cells_.find({x, y}); it != cells_.end())
        for (std::size_t j : it->second)
          if ((points_[j] - p).norm() <= radius_) out.push_back(j);
  std::sort(out.begin(), out.end());
}

bool PointsWithinRadius::any_near(const Vec2& p) const {
  // (As near, without collecting: the first point found will do.)
  if (!p.allFinite() || radius_ <= 0) return false;
  const auto [cx, cy] = cell_of(p);
  for (long y = cy - 1; y <= cy + 1; ++y)
    for (long x = cx - 1; x <= cx + 1; ++x)
      if (const auto it = cells_.find({x, y}); it != cells_.end())
        for (std::size_t j : it->second)
          if ((points_[j] - p).norm() <= radius_) return true;
  return false;
}

std::vector<NeighbourLattice> neighbour_lattices(const std::vector<Vec2>& centres, const std::vector<std::int64_t>& ids,
                                                std::vector<LatticeLender> lenders, double pixel_size, const LatticeOptions& o) {
  const std::size_t n = centres.size();
  std::vector<NeighbourLattice> out(n);
  const double radius = o.neighbour_radius_m;
  if (radius <= 0 || ids.size() != n) return out;
  // The lenders that count, in order of id, each with its weight and its lattice's angle times
  // four as a unit vector.
  const double min_span = pixel_size / std::tan(o.window_deg * M_PI / 180.0);
  std::erase_if(lenders, [&](const LatticeLender& l) {
    return l.share < o.min_share || l.direction.squaredNorm() == 0 || !l.centre.allFinite() ||
           (o.neighbour_max_extent_m > 0 && l.extent > o.neighbour_max_extent_m) ||
           std::min(o.chord_m, o.chord_share * l.perimeter) < min_span;
  });
  std::sort(lenders.begin(), lenders.end(), [](const LatticeLender& a, const LatticeLender& b) { return a.id < b.id; });
  std::vector<Vec2> quadrupled(lenders.size()), lender_centres(lenders.size());
  std::vector<double> weights(lenders.size());
  double largest = 0;  // extent
  for (std::size_t j = 0; j < lenders.size(); ++j) {
    const double a = 4.0 * std::atan2(lenders[j].direction.y(), lenders[j].direction.x());
    quadrupled[j] = Vec2(std::cos(a), std::sin(a));
    weights[j] = lenders[j].share * lenders[j].perimeter;
    lender_centres[j] = lenders[j].centre;
    largest = std::max(largest, lenders[j].extent);
  }
  const PointsWithinRadius within(lender_centres, radius);
  // Those whose boxes come within half the radius, where none's centre is near: their centres (a
  // mean of their vertices, in their boxes) lie within that and their diagonals (made when needed).
  std::optional<PointsWithinRadius> beside;
  std::vector<std::size_t> near;
  for (std::size_t i = 0; i < n; ++i) {
    double sx = 0, sy = 0, total = 0;
    // The lenders found (ascending: the sums in order of id), those by box only within half the radius.
    const auto add = [&](bool by_box) {
      for (std::size_t j : near) {
        if (lenders[j].id == ids[i] || (by_box && distance_to_box(lenders[j], centres[i]) > radius / 2)) continue;
        sx += weights[j] * quadrupled[j].x();
        sy += weights[j] * quadrupled[j].y();
        total += weights[j];
      }
    };
    within.near(centres[i], near);
    add(false);
    const bool by_box = total <= 0;
    if (by_box) {
      if (!beside) beside.emplace(lender_centres, radius / 2 + std::sqrt(2.0) * largest);
      beside->near(centres[i], near);
      add(true);
    }
    if (total <= 0 || std::hypot(sx, sy) < o.neighbour_agreement * total) continue;
    const double a = std::atan2(sy, sx) / 4.0;
    out[i] = {Vec2(std::cos(a), std::sin(a)), by_box};
  }
  return out;
}

}  // namespace lodforge
