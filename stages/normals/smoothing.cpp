#include "normals/smoothing.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <vector>

namespace lodforge {

std::vector<Vec2> edge_normals(const Ring& ring) {
  std::vector<Vec2> normals(ring.size());
  for (std::size_t i = 0; i < ring.size(); ++i) normals[i] = outward_normal(edge_vector(ring, i));
  return normals;
}

namespace {

// exp(-angle / sigma_a^2) of two unit normals, the angle in degrees, from a chord: |a - b| =
// 2 sin(angle / 2) up to a quarter turn, |a + b| = 2 cos(angle / 2) beyond, each at most
// sqrt(2), where the arc sine is smooth. Two tables of the function over those chords, read with
// linear interpolation (within about 1e-9 of it at sigma_a = 10 degrees, the error growing as
// sigma_a^-4), so that no pair costs an arc cosine and an exponential. The normals are unit
// vectors (a zero one would read as 60 degrees off a unit one, not 90). The tables are kept per
// thread for the last width asked.
class AngleWeight {
 public:
  explicit AngleWeight(double sigma_a2) : sigma_a2_(sigma_a2), near_(kSize + 2), far_(kSize + 2) {
    for (std::size_t k = 0; k < near_.size(); ++k) {
      const double half = std::asin(std::min(1.0, 0.5 * kMaxChord * double(k) / kSize));  // half the angle, or its complement
      near_[k] = std::exp(-2.0 * half * 180.0 / M_PI / sigma_a2);
      far_[k] = std::exp(-(M_PI - 2.0 * half) * 180.0 / M_PI / sigma_a2);
    }
  }
  double sigma_a2() const { return sigma_a2_; }
  double operator()(const Vec2& a, const Vec2& b) const {
    const bool near = a.dot(b) >= 0;
    const std::vector<double>& table = near ? near_ : far_;
    const double chord = near ? (a - b).norm() : (a + b).norm();
    if (std::isnan(chord)) return chord;  // (a normal of an infinite coordinate: as the arc cosine did)
    const double x = std::min(chord, kMaxChord) * (kSize / kMaxChord);
    const std::size_t k = std::size_t(x);
    const double t = x - double(k);
    return table[k] + t * (table[k + 1] - table[k]);
  }

 private:
  static constexpr std::size_t kSize = 8192;
  static constexpr double kMaxChord = 1.4142135623730951;  // sqrt(2): a quarter turn
  double sigma_a2_;
  std::vector<double> near_, far_;
};

const AngleWeight& angle_weight(double sigma_a2) {
  thread_local std::unique_ptr<AngleWeight> table;
  if (!table || table->sigma_a2() != sigma_a2) table = std::make_unique<AngleWeight>(sigma_a2);
  return *table;
}

// How many times neighbourhood_m and sigma_d_m are widened: to at least min_neighbourhood_px (a
// staircase averages to its wall's direction), but at most max_neighbourhood_m (walls that short
// keep their own normals), never below least_neighbourhood_px; and to at least noise_neighbourhood
// noises, within the same bound.
double neighbourhood_scale(double pixel_size, const SmoothingOptions& o, double noise_m) {
  double floor_m = o.min_neighbourhood_px * pixel_size;
  double noise_floor_m = o.noise_neighbourhood * std::max(0.0, noise_m);
  if (o.max_neighbourhood_m > 0) {
    floor_m = std::max(std::min(floor_m, o.max_neighbourhood_m), std::min(floor_m, o.least_neighbourhood_px * pixel_size));
    noise_floor_m = std::min(noise_floor_m, o.max_neighbourhood_m);
  }
  return std::max(1.0, std::max(floor_m, noise_floor_m) / std::max(o.neighbourhood_m, 1e-12));
}

}  // namespace

double smoothing_neighbourhood_m(double pixel_size, const SmoothingOptions& o, double noise_m) {
  return o.neighbourhood_m * neighbourhood_scale(pixel_size, o, noise_m);
}

namespace {

// Eq. 2's passes over normals at arc lengths mid (ascending along a closed contour of length
// total): neighbours closer than threshold along it, their weights exp(-d / sigma_d2) times the
// angle weight.
std::vector<Vec2> smooth_along(std::vector<Vec2> normals, const std::vector<double>& mid, double total, double threshold,
                               double sigma_d2, const AngleWeight& angle, int passes) {
  const std::size_t n = normals.size();
  auto arc = [&](std::size_t i, std::size_t k) {
    const double d = std::abs(mid[i] - mid[k]);
    return std::min(d, total - d);
  };
  auto weight = [&](std::size_t i, std::size_t k, double d) { return std::exp(-d / sigma_d2) * angle(normals[i], normals[k]); };
  // The weight of a pair is symmetric (the same arc, the same angle: bit for bit), so each pass
  // computes the weights of every edge to its successors once, and an edge's predecessors take
  // theirs from there; the sums are made in the same order as computing each weight on the spot.
  std::vector<double> ahead;              // per edge, the weights to its successors in the neighbourhood
  std::vector<std::size_t> first(n + 1);  // edge i's weights: ahead[first[i] .. first[i + 1])
  std::vector<Vec2> next(n);
  // The neighbourhoods and their distance weights are the same in every pass: walked once. (A
  // traced contour's edges are a pixel or a diagonal long, so the same arc lengths come back
  // again and again: each one's weight is remembered, by its bits, in a small table.)
  std::vector<double> distance_weight;
  constexpr std::size_t kRemembered = 256;
  std::array<std::uint64_t, kRemembered> arc_bits;
  std::array<double, kRemembered> arc_weight;
  // (Empty slots hold a negative NaN's bits, which no arc length has: an arc is an absolute value.)
  arc_bits.fill(~std::uint64_t(0));
  arc_weight.fill(std::numeric_limits<double>::quiet_NaN());
  for (std::size_t i = 0; i < n; ++i) {
    first[i] = distance_weight.size();
    // Walk forward until the neighbourhood ends (or half the ring is walked).
    std::size_t steps = 0;
    for (std::size_t k = (i + 1) % n; k != i && steps < n / 2; k = (k + 1) % n, ++steps) {
      const double d = arc(i, k);
      if (d >= threshold) break;
      std::uint64_t bits;
      std::memcpy(&bits, &d, sizeof bits);
      const std::size_t slot = std::size_t((bits * 0x9E3779B97F4A7C15ull) >> 56);
      if (arc_bits[slot] != bits) arc_bits[slot] = bits, arc_weight[slot] = std::exp(-d / sigma_d2);
      distance_weight.push_back(arc_weight[slot]);
    }
  }
  first[n] = distance_weight.size();
  ahead.resize(distance_weight.size());
  std::vector<Vec2> twice(2 * n);  // the normals twice round: a successor i + 1 + s read without a modulo
  for (int pass = 0; pass < passes; ++pass) {
    std::copy(normals.begin(), normals.end(), twice.begin());
    std::copy(normals.begin(), normals.end(), twice.begin() + long(n));
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t s = 0; first[i] + s < first[i + 1]; ++s)
        ahead[first[i] + s] = distance_weight[first[i] + s] * angle(normals[i], twice[i + 1 + s]);
    for (std::size_t i = 0; i < n; ++i) {
      Vec2 sum = normals[i];  // w(i, i) = 1
      for (std::size_t s = 0; first[i] + s < first[i + 1]; ++s) sum += ahead[first[i] + s] * twice[i + 1 + s];
      // Walk backward: edge i is the s-th successor of edge k = i - s.
      for (std::size_t s = 1; s <= (n - 1) / 2; ++s) {
        const std::size_t k = i >= s ? i - s : i + n - s;
        double w;
        if (first[k] + s <= first[k + 1]) {
          w = ahead[first[k] + s - 1];
        } else {
          const double d = arc(i, k);
          if (d >= threshold) break;
          w = weight(i, k, d);
        }
        sum += w * normals[k];
      }
      const double len = sum.norm();
      next[i] = len > 1e-12 ? Vec2(sum / len) : normals[i];
    }
    normals.swap(next);
  }
  return normals;
}

}  // namespace

std::vector<Vec2> smooth_normals(const Ring& ring, double pixel_size, const SmoothingOptions& o, double noise_m) {
  const std::size_t n = ring.size();
  std::vector<Vec2> normals = edge_normals(ring);
  if (n < 3) return normals;
  // Arc length position of every edge midpoint.
  std::vector<double> mid(n), length(n);
  double s = 0;
  for (std::size_t i = 0; i < n; ++i) {
    length[i] = edge_vector(ring, i).norm();
    mid[i] = s + 0.5 * length[i];
    s += length[i];
  }
  const double total = s;
  const double scale = neighbourhood_scale(pixel_size, o, noise_m);
  const double threshold = o.neighbourhood_m * scale;
  const double sigma_d2 = std::pow(o.sigma_d_m * scale, 2);
  const AngleWeight& angle = angle_weight(o.sigma_a_deg * o.sigma_a_deg);
  // Where the neighbourhood spans many edges (fine pixels, a wide noise), consecutive edges are
  // smoothed as blocks of at least threshold / block_neighbours (each closed at the edge that
  // reaches that length; a short last one joins the one before; their normals summed by length),
  // and each edge takes the normal interpolated between the two blocks about it.
  // (Under 1, or a contour of no finite length: every edge on its own.)
  const double block_m = o.block_neighbours >= 1 ? threshold / o.block_neighbours : 0.0;
  if (!(o.block_neighbours >= 1) || !(block_m >= 2.0 * total / double(n)))
    return smooth_along(std::move(normals), mid, total, threshold, sigma_d2, angle, o.passes);
  std::vector<std::size_t> block_of(n);
  std::vector<Vec2> block_normals;
  std::vector<double> block_mid;
  double block_start = 0, filled = 0;
  Vec2 sum = Vec2::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    block_of[i] = block_normals.size();
    sum += length[i] * normals[i];
    filled += length[i];
    const bool last = i + 1 == n;
    // (A short last block joins the one before.)
    if ((filled >= block_m && !(total - (mid[i] + 0.5 * length[i]) < 0.5 * block_m && !last)) || last) {
      const double norm = sum.norm();
      block_normals.push_back(norm > 1e-12 ? Vec2(sum / norm) : normals[i]);
      block_mid.push_back(block_start + 0.5 * filled);
      block_start += filled;
      filled = 0;
      sum = Vec2::Zero();
    }
  }
  const std::size_t m = block_normals.size();
  if (m < 3) return smooth_along(std::move(normals), mid, total, threshold, sigma_d2, angle, o.passes);
  const std::vector<Vec2> smoothed = smooth_along(std::move(block_normals), block_mid, total, threshold, sigma_d2, angle, o.passes);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t b = block_of[i];
    // The blocks before and after the edge's midpoint, along the ring (cyclically).
    const bool after = mid[i] >= block_mid[b];
    const std::size_t a = after ? b : (b + m - 1) % m, c = after ? (b + 1) % m : b;
    double span = block_mid[c] - block_mid[a], into = mid[i] - block_mid[a];
    if (span <= 0) span += total;
    if (into < 0) into += total;
    const double t = std::clamp(into / span, 0.0, 1.0);
    const Vec2 v = (1 - t) * smoothed[a] + t * smoothed[c];
    const double len = v.norm();
    normals[i] = len > 1e-12 ? Vec2(v / len) : smoothed[b];
  }
  return normals;
}

}  // namespace lodforge
