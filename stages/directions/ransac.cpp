#include "directions/ransac.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>
#include <random>

namespace lodforge {

namespace {

struct Candidate {
  Vec2 direction = Vec2::Zero();
  double support = 0;
};

// (normals, w: the edges not yet taken by a direction, in their order.)
Candidate evaluate(const Vec2& d, const std::vector<Vec2>& normals, const std::vector<double>& w, double cos_threshold) {
  Candidate c{d, 0};
  for (std::size_t k = 0; k < normals.size(); ++k) {
    if (normals[k].dot(d) > cos_threshold) c.support += w[k];
  }
  return c;
}

// Eq. 4: the normalized sum of the inlier normals, iterated to a fixed inlier set.
Vec2 refine(Vec2 d, const std::vector<Vec2>& normals, const std::vector<double>& w, double cos_threshold) {
  for (int iteration = 0; iteration < 5; ++iteration) {
    Vec2 sum = Vec2::Zero();
    for (std::size_t k = 0; k < normals.size(); ++k) {
      if (normals[k].dot(d) > cos_threshold) sum += w[k] * normals[k];
    }
    if (sum.norm() < 1e-12) break;
    const Vec2 next = sum.normalized();
    if ((next - d).norm() < 1e-9) break;
    d = next;
  }
  return d;
}

// True when d is within tolerance of a quarter turn (90°, 180°, 270°) of a found direction.
bool on_lattice(const Vec2& d, const std::vector<DominantDirection>& found, double tolerance_deg) {
  for (const DominantDirection& f : found) {
    const double diff = std::atan2(cross(f.normal, d), f.normal.dot(d)) * 180.0 / M_PI;
    if (std::abs(diff) > 45.0 && angle_between_lattices_deg(f.normal, d) <= tolerance_deg) return true;
  }
  return false;
}

// When RANSAC's best candidate is noise, a short wall square to the walls found (the ends of a
// long thin building) may still be there, less supported than the noise: the best supported
// quarter turn of a found direction that none of them is near yet, with lattice_min_support_m,
// refined, and with square_min_gathered of its support within a quarter of the inlier angle (a
// wall's normals gather about its direction, an arc's spread evenly over the cone).
std::optional<Vec2> square_wall(const std::vector<Vec2>& normals, const std::vector<double>& weights,
                                const std::vector<DominantDirection>& found, const RansacOptions& o) {
  const double cos_threshold = std::cos(o.inlier_angle_deg * M_PI / 180.0);
  const double near_cos = std::cos(o.lattice_angle_deg * M_PI / 180.0);
  Candidate square;
  for (const DominantDirection& f : found)
    for (const Vec2& q : {Vec2(-f.normal.y(), f.normal.x()), Vec2(-f.normal), Vec2(f.normal.y(), -f.normal.x())}) {
      const bool taken = std::any_of(found.begin(), found.end(), [&](const DominantDirection& g) { return g.normal.dot(q) >= near_cos; });
      if (taken) continue;
      const Candidate c = evaluate(q, normals, weights, cos_threshold);
      if (c.support > square.support) square = c;
    }
  if (square.support < o.lattice_min_support_m) return std::nullopt;
  const Vec2 refined = refine(square.direction, normals, weights, cos_threshold);
  const double narrow = std::cos(o.inlier_angle_deg * M_PI / 180.0 / 4.0);
  const double gathered = evaluate(refined, normals, weights, narrow).support;
  const double support = evaluate(refined, normals, weights, cos_threshold).support;
  if (!on_lattice(refined, found, o.lattice_angle_deg) || gathered < o.square_min_gathered * support) return std::nullopt;
  return refined;
}

}  // namespace

std::vector<DominantDirection> detect_directions(const std::vector<Vec2>& normals,
                                                 const std::vector<double>& weights,
                                                 const RansacOptions& o) {
  std::vector<DominantDirection> directions;
  if (normals.empty()) return directions;
  const double cos_threshold = std::cos(o.inlier_angle_deg * M_PI / 180.0);
  const double total = std::accumulate(weights.begin(), weights.end(), 0.0);
  std::vector<char> remaining(normals.size(), 1);
  // The edges not yet taken, in their order (each candidate is evaluated over them alone: the same
  // sums, in the same order, as over every edge skipping the taken ones).
  std::vector<Vec2> pool_normals;
  std::vector<double> pool_weights;
  std::mt19937_64 rng(o.seed);
  while (static_cast<int>(directions.size()) < o.max_directions) {
    pool_normals.clear();
    pool_weights.clear();
    double remaining_weight = 0;
    for (std::size_t k = 0; k < normals.size(); ++k) {
      if (remaining[k]) {
        pool_normals.push_back(normals[k]);
        pool_weights.push_back(weights[k]);
        remaining_weight += weights[k];
      }
    }
    if (pool_normals.empty()) break;
    Candidate best;
    for (int drawn = 1; drawn <= o.max_candidates; ++drawn) {
      const Vec2& drawn_normal = pool_normals[std::uniform_int_distribution<std::size_t>(0, pool_normals.size() - 1)(rng)];
      const Candidate c = evaluate(drawn_normal, pool_normals, pool_weights, cos_threshold);
      if (c.support > best.support) best = c;
      // Eq. 3 with the probability of never having drawn from the best set, as in Schnabel et
      // al. (the paper prints the ratio without the complement, which never falls).
      const double p_missing = std::pow(1.0 - best.support / remaining_weight, drawn);
      if (p_missing < o.missing_probability) break;
    }
    Vec2 d = refine(best.direction, pool_normals, pool_weights, cos_threshold);
    // The paper stops below |n|/16; a short wall square to a found direction (the ends of a
    // long thin building) is kept with less, noise rarely lines up like that.
    bool enough = best.support >= o.min_support_fraction * total ||
                  (o.lattice_angle_deg > 0 && best.support >= o.lattice_min_support_m &&
                   on_lattice(d, directions, o.lattice_angle_deg));
    if (!enough && o.lattice_angle_deg > 0) {
      // The best candidate is noise, but a short wall square to the walls found may still be there.
      const std::optional<Vec2> square = square_wall(pool_normals, pool_weights, directions, o);
      enough = square.has_value();
      if (enough) d = *square;
    }
    if (!enough) break;
    double support = 0;
    for (std::size_t k = 0; k < normals.size(); ++k) {
      if (remaining[k] && normals[k].dot(d) > cos_threshold) { remaining[k] = 0; support += weights[k]; }
    }
    if (support <= 0) break;
    directions.push_back({d, support});
  }
  return directions;
}

}  // namespace lodforge
