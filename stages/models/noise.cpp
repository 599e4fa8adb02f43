#include "models/noise.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "corners/corners.hpp"
#include "labeling/mrf.hpp"
#include "models/statistics.hpp"

namespace lodforge {

namespace {

// erf^-1 by bisection (only called once per building, with a fixed argument in (0, 1)).
double inverse_erf(double y) {
  double lo = 0, hi = 6;
  for (int k = 0; k < 60; ++k) {
    const double mid = 0.5 * (lo + hi);
    (std::erf(mid) < y ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

double lattice_noise(const std::vector<Ring>& rings, const std::vector<std::vector<Vec2>>& normals, const Vec2& lattice,
                     double pixel_size, const NoiseOptions& o, double* arc_noise) {
  const Vec2 axes[4] = {lattice, Vec2(-lattice.y(), lattice.x()), -lattice, Vec2(lattice.y(), -lattice.x())};
  std::vector<std::pair<double, double>> residuals, arc_residuals;  // |distance|, weight
  for (std::size_t r = 0; r < rings.size(); ++r) {
    const Ring& ring = rings[r];
    const std::size_t n = ring.size();
    if (n < 4) continue;
    std::vector<int> labels(n);
    for (std::size_t i = 0; i < n; ++i) {
      int best = 0;
      for (int a = 1; a < 4; ++a) if (normals[r][i].dot(axes[a]) > normals[r][i].dot(axes[best])) best = a;
      labels[i] = best;
    }
    absorb_short_runs(ring, labels, std::max(o.min_run_m, 2 * pixel_size));
    for (auto [first, count] : label_runs(labels)) {
      // The run's middle (ends trimmed, where corners are rounded), fitted by a line of its own
      // direction held within max_tilt_deg of the lattice: a wall a little off the lattice is
      // still fitted, a wobble's flanks are not.
      std::vector<double> position(count + 1, 0.0);
      for (int k = 0; k < count; ++k) position[k + 1] = position[k] + edge_vector(ring, (first + k) % n).norm();
      const double length = position[count], trim = std::min(o.trim_m, length / 4);
      std::vector<std::pair<Vec2, double>> middle;  // midpoint, weight
      Vec2 mean = Vec2::Zero();
      double total = 0;
      for (int k = 0; k < count; ++k) {
        if (position[k] < trim || position[k + 1] > length - trim) continue;
        const std::size_t i = (first + k) % n;
        const Vec2 e = edge_vector(ring, i);
        middle.push_back({ring[i] + 0.5 * e - ring[first], e.norm()});
        mean += e.norm() * middle.back().first;
        total += e.norm();
      }
      if (middle.size() < 2 || total <= 0) continue;
      mean /= total;
      Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
      for (const auto& [p, w] : middle) scatter += w * (p - mean) * (p - mean).transpose();
      // Its own direction, within max_tilt_deg of its lattice direction.
      const Vec2 axis = axes[labels[first]];
      Vec2 normal = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(scatter).eigenvectors().col(0);
      if (normal.dot(axis) < 0) normal = -normal;
      const double tilt = std::atan2(cross(axis, normal), axis.dot(normal)), max_tilt = o.max_tilt_deg * M_PI / 180.0;
      if (std::abs(tilt) > max_tilt) {
        const double t = std::copysign(max_tilt, tilt);
        normal = Vec2(std::cos(t) * axis.x() - std::sin(t) * axis.y(), std::sin(t) * axis.x() + std::cos(t) * axis.y());
      }
      for (const auto& [p, w] : middle) residuals.push_back({std::abs(normal.dot(p - mean)), w});
      if (arc_noise) {
        // The same middle fitted by a parabola across its line (in the run's length as unit, for
        // the range): an arc's spread about the line goes; a wobble's stays where the run spans
        // several of its half-waves (on a run shorter than a wavelength, part of it goes too).
        // Fewer than 8 points: the line's residuals (a parabola through 3 points leaves none).
        const Vec2 tangent(-normal.y(), normal.x());
        std::vector<Eigen::Vector3d> rows;  // 1, t, t^2
        std::vector<double> offsets;        // across the line
        for (const auto& [p, w] : middle) {
          const double t = tangent.dot(p - mean) / std::max(length, 1e-9);
          rows.emplace_back(1.0, t, t * t);
          offsets.push_back(normal.dot(p - mean));
        }
        Eigen::Vector3d c = Eigen::Vector3d::Zero();
        if (middle.size() >= 8) {
          Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
          Eigen::Vector3d atb = Eigen::Vector3d::Zero();
          for (std::size_t k = 0; k < middle.size(); ++k) {
            ata += middle[k].second * rows[k] * rows[k].transpose();
            atb += middle[k].second * offsets[k] * rows[k];
          }
          c = ata.ldlt().solve(atb);
          if (!c.allFinite()) c.setZero();
        }
        for (std::size_t k = 0; k < middle.size(); ++k) {
          const double t = rows[k][1];
          arc_residuals.push_back({std::abs(offsets[k] - c[0] - c[1] * t - c[2] * t * t), middle[k].second});
        }
      }
    }
  }
  // A Gaussian's |x| has its quantile q at z((1 + q) / 2) standard deviations.
  const double z = std::sqrt(2.0) * inverse_erf(o.quantile);
  if (arc_noise) *arc_noise = weighted_quantile(std::move(arc_residuals), o.quantile) / z;
  return weighted_quantile(std::move(residuals), o.quantile) / z;
}

}  // namespace lodforge
