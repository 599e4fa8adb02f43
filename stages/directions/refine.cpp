#include "directions/refine.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "labeling/mrf.hpp"

namespace lodforge {

namespace {

struct Fit {
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();  // pooled within-run scatter
  Vec2 chord_sum = Vec2::Zero();                      // fallback when the scatter is degenerate
  bool used = false;
};

// Within-run scatter of the length-weighted edge midpoints, ends trimmed.
Eigen::Matrix2d run_scatter(const Ring& ring, int first, int count, double trim) {
  const std::size_t n = ring.size();
  std::vector<double> position(count + 1, 0.0);
  for (int k = 0; k < count; ++k) position[k + 1] = position[k] + edge_vector(ring, (first + k) % n).norm();
  const double length = position[count];
  const double effective_trim = std::min(trim, 0.25 * length);
  double w_sum = 0;
  Vec2 mean = Vec2::Zero();
  std::vector<std::pair<Vec2, double>> points;
  for (int k = 0; k < count; ++k) {
    const double mid = 0.5 * (position[k] + position[k + 1]);
    if (mid < effective_trim || mid > length - effective_trim) continue;
    const std::size_t i = (first + k) % n;
    const double w = position[k + 1] - position[k];
    points.push_back({ring[i] + 0.5 * edge_vector(ring, i), w});
    mean += w * points.back().first;
    w_sum += w;
  }
  Eigen::Matrix2d s = Eigen::Matrix2d::Zero();
  if (points.size() < 2 || w_sum <= 0) return s;
  mean /= w_sum;
  for (const auto& [p, w] : points) s += w * (p - mean) * (p - mean).transpose();
  return s;
}

// The unit normal of the best-fitting orientation of a scatter, on the side of `hint`.
Vec2 normal_of(const Eigen::Matrix2d& scatter, const Vec2& hint) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(scatter);
  Vec2 n = eig.eigenvectors().col(0);  // smallest eigenvalue: across the lines
  return n.dot(hint) < 0 ? Vec2(-n) : n;
}

bool well_posed(const Eigen::Matrix2d& scatter) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(scatter);
  return eig.eigenvalues()[1] > 0 && eig.eigenvalues()[1] > 4 * eig.eigenvalues()[0];
}

// Rotation by k quarter turns.
Eigen::Matrix2d quarter_turns(int k) {
  const int m = ((k % 4) + 4) % 4;
  const double c[4] = {1, 0, -1, 0}, s[4] = {0, 1, 0, -1};
  Eigen::Matrix2d r;
  r << c[m], -s[m], s[m], c[m];
  return r;
}

double angle_deg(const Vec2& n) { return std::atan2(n.y(), n.x()) * 180.0 / M_PI; }

}  // namespace

void refine_directions(const std::vector<Ring>& rings, EdgeLabels& labels, std::vector<Vec2>& directions,
                       double pixel_size, const RefineOptions& o) {
  const std::size_t count = directions.size();
  std::vector<Fit> fits(count);
  for (std::size_t r = 0; r < rings.size(); ++r) {
    for (auto [first, length] : label_runs(labels[r])) {
      Fit& f = fits[labels[r][first]];
      f.used = true;
      f.scatter += run_scatter(rings[r], first, length, o.trim_px * pixel_size);
      f.chord_sum += rings[r][(first + length) % rings[r].size()] - rings[r][first];
    }
  }
  // 1. Each used direction on its own; merge the ones that coincide.
  std::vector<int> remap(count, -1);
  std::vector<Vec2> result;
  std::vector<Eigen::Matrix2d> scatter;
  const double merge_cos = std::cos(o.merge_angle_deg * M_PI / 180.0);
  for (std::size_t l = 0; l < count; ++l) {
    if (!fits[l].used) continue;
    Vec2 n = directions[l];
    if (well_posed(fits[l].scatter)) n = normal_of(fits[l].scatter, directions[l]);
    else if (fits[l].chord_sum.norm() > 0 && outward_normal(fits[l].chord_sum).dot(directions[l]) > 0.5)
      n = outward_normal(fits[l].chord_sum);
    for (std::size_t k = 0; k < result.size() && remap[l] < 0; ++k) {
      if (result[k].dot(n) > merge_cos) {
        remap[l] = int(k);
        scatter[k] += fits[l].scatter;
        if (well_posed(scatter[k])) result[k] = normal_of(scatter[k], result[k]);
      }
    }
    if (remap[l] < 0) {
      remap[l] = int(result.size());
      result.push_back(n);
      scatter.push_back(fits[l].scatter);
    }
  }
  for (auto& ring : labels) for (int& x : ring) x = remap[x];
  // 2. Groups of directions within snap_deg of a common quarter-turn lattice share one fit.
  if (o.snap_deg > 0) {
    std::vector<int> group(result.size(), -1);
    for (std::size_t a = 0; a < result.size(); ++a) {
      if (group[a] >= 0) continue;
      group[a] = int(a);
      std::vector<std::pair<std::size_t, int>> members{{a, 0}};
      for (std::size_t b = a + 1; b < result.size(); ++b) {
        if (group[b] >= 0) continue;
        const double diff = angle_deg(result[b]) - angle_deg(result[a]);
        const int k = int(std::lround(diff / 90.0));
        if (std::abs(diff - 90.0 * k) <= o.snap_deg) {
          group[b] = int(a);
          members.push_back({b, k});
        }
      }
      if (members.size() < 2) continue;
      // Rotate every member's scatter into a's frame, pool, fit, rotate back.
      Eigen::Matrix2d pooled = Eigen::Matrix2d::Zero();
      for (auto [m, k] : members) pooled += quarter_turns(-k) * scatter[m] * quarter_turns(-k).transpose();
      if (!well_posed(pooled)) continue;
      const Vec2 reference = normal_of(pooled, result[a]);
      for (auto [m, k] : members) result[m] = quarter_turns(k) * reference;
    }
  }
  directions.swap(result);
}

bool drop_insignificant_directions(const std::vector<Ring>& rings, const EdgeLabels& labels, std::vector<Vec2>& directions,
                                   const Vec2& main, double noise, const RefineOptions& o) {
  if (o.min_wall_m <= 0 || directions.size() <= 2) return false;
  std::vector<std::vector<double>> run_lengths(directions.size());
  for (std::size_t r = 0; r < rings.size(); ++r)
    for (auto [first, count] : label_runs(labels[r])) {
      double length = 0;
      for (int k = 0; k < count; ++k) length += edge_vector(rings[r], (first + k) % rings[r].size()).norm();
      run_lengths[labels[r][first]].push_back(length);
    }
  const double lattice_sin = std::sin(o.lattice_deg * M_PI / 180.0);
  std::vector<Vec2> kept;
  for (std::size_t l = 0; l < directions.size(); ++l) {
    // Off the lattice: the sine of its angle to the nearest of the lattice's four directions.
    const double off = std::abs(cross(directions[l], nearest_lattice_axis(directions[l], main)));
    bool significant = off <= lattice_sin;
    for (double length : run_lengths[l])
      significant |= length >= o.min_wall_m && length * off >= o.min_wall_noise * noise;
    if (!run_lengths[l].empty() && significant) kept.push_back(directions[l]);
  }
  if (kept.size() == directions.size()) return false;
  // The lattice's four directions stay available, whatever was dropped.
  const Vec2 quarter(-main.y(), main.x());
  const double lattice_cos = std::cos(o.lattice_deg * M_PI / 180.0);
  for (const Vec2& axis : {main, quarter, Vec2(-main), Vec2(-quarter)}) {
    bool present = false;
    for (const Vec2& d : kept) present |= d.dot(axis) > lattice_cos;
    if (!present) kept.push_back(axis);
  }
  directions.swap(kept);
  return true;
}

bool add_missing_axis(std::vector<Vec2>& directions, const Vec2& main, const RefineOptions& o) {
  if (o.missing_axis_deg <= 0 || main.squaredNorm() <= 0) return false;
  const double near = std::cos(o.missing_axis_deg * M_PI / 180.0);
  const Vec2 axes[2] = {main, Vec2(-main.y(), main.x())};
  bool present[2];
  for (int k = 0; k < 2; ++k)
    present[k] = std::any_of(directions.begin(), directions.end(), [&](const Vec2& d) { return std::abs(d.dot(axes[k])) >= near; });
  if (present[0] == present[1]) return false;  // (both there, or neither: no lattice axis to go by)
  const Vec2& missing = axes[present[0] ? 1 : 0];
  directions.push_back(missing);
  directions.push_back(-missing);
  return true;
}

int release_runs(const std::vector<Ring>& rings, EdgeLabels& labels, std::vector<Vec2>& directions, double pixel_size,
                 double building_noise, const RefineOptions& o) {
  if (o.release_px <= 0) return 0;
  int released = 0;
  for (std::size_t r = 0; r < rings.size(); ++r) {
    const Ring& ring = rings[r];
    for (auto [first, count] : label_runs(labels[r])) {
      const int label = labels[r][first];
      const Vec2 chord = ring[(first + count) % ring.size()] - ring[first];
      const double length_px = chord.norm() / pixel_size;
      if (length_px < 8 * o.release_px) continue;
      const Eigen::Matrix2d s = run_scatter(ring, first, count, o.trim_px * pixel_size) / (pixel_size * pixel_size * pixel_size);
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(s);  // as well_posed and normal_of
      if (!(eig.eigenvalues()[1] > 0 && eig.eigenvalues()[1] > 4 * eig.eigenvalues()[0])) continue;
      Vec2 own = eig.eigenvectors().col(0);  // across the run
      if (own.dot(directions[label]) < 0) own = -own;
      double weight = 0;  // run length, pixels (the scatter's weights, before trimming)
      for (int k = 0; k < count; ++k) weight += edge_vector(ring, (first + k) % ring.size()).norm() / pixel_size;
      const double cos_turn = std::clamp(own.dot(directions[label]), -1.0, 1.0);
      const double end_shift = std::sin(std::acos(cos_turn)) * 0.5 * length_px;
      const double noise = std::sqrt(std::max(eig.eigenvalues()[0], 0.0) / std::max(weight - 2 * o.trim_px, 1.0));
      if (cos_turn <= 0 || end_shift <= o.release_px || end_shift <= 2 * noise ||
          end_shift * pixel_size <= o.release_noise * building_noise)
        continue;
      directions.push_back(own);
      for (int k = 0; k < count; ++k) labels[r][(first + k) % ring.size()] = int(directions.size()) - 1;
      ++released;
    }
  }
  return released;
}

}  // namespace lodforge
