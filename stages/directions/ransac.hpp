// Stage 3: dominant directions by RANSAC on the smoothed normals (paper eq. 3–4).
// No Manhattan assumption: any number of directions in any orientation.
#pragma once
#include <cstdint>
#include <vector>

#include "common/option.hpp"
#include "geometry/types.hpp"

namespace lodforge {

struct RansacOptions {
  double inlier_angle_deg = 20.0;  // thre_a (NOTES.md: 15° missed 45° cuts, 20° found them)
  double missing_probability = 0.01;  // thre_p: stop sampling when p_m falls below
  double min_support_fraction = 1.0 / 16.0;  // stop when the best set is below |n|/16
  double lattice_angle_deg = 10.0;   // a direction this close to a quarter turn of a found one ...
  double lattice_min_support_m = 1.0;  // ... needs only this much support (short walls of thin buildings)
  double square_min_gathered = 0.35;   // ... and, found only by looking square to the others, this share of it within a quarter of the inlier angle
  int max_candidates = 500;        // per direction, bounds the work
  int max_directions = 16;
  std::uint64_t seed = 42;

  template <class V>
  void visit(V& v) {
    v("inlier_angle_deg", inlier_angle_deg, "thre_a: inlier angle to a direction (degrees)", Check::between(0.1, 90));
    v("missing_probability", missing_probability, "thre_p: stop sampling when the chance of missing a better set is below this", Check::between(1e-9, 1));
    v("min_support_fraction", min_support_fraction, "stop when a direction's support is below this share of the edges", Check::between(0, 1));
    v("lattice_angle_deg", lattice_angle_deg, "a direction within this of a quarter turn of a found one is accepted with less support (degrees, 0 = off)", Check::between(0, 45));
    v("lattice_min_support_m", lattice_min_support_m, "the support such a direction needs (m of contour)", Check::at_least(0));
    v("square_min_gathered", square_min_gathered, "when the best candidate is noise, a quarter turn of a found direction is still taken (a long building's short ends) with lattice_min_support_m and this share of its support within a quarter of inlier_angle_deg: a wall's normals gather, an arc's spread evenly (1 = never)", Check::between(0, 1));
    v("max_candidates", max_candidates, "candidate directions drawn per dominant direction at most", Check::at_least(1));
    v("max_directions", max_directions, "dominant directions per building at most", Check::at_least(1));
    v("seed", seed, "random seed (results are deterministic for a seed)", Check::at_least(0));
  }
};

struct DominantDirection {
  Vec2 normal;     // unit outward normal
  double support;  // summed length of the inlier edges (m)
};

// normals: smoothed unit normals; weights: their edge lengths.
std::vector<DominantDirection> detect_directions(const std::vector<Vec2>& normals,
                                                 const std::vector<double>& weights,
                                                 const RansacOptions& options);

}  // namespace lodforge
