#include "models/noise.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <optional>
#include <tuple>
#include <utility>

#include "corners/corners.hpp"
#include "geometry/polygon.hpp"
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

// Each edge's axis among the four: the nearest to its smoothed normal; with a hysteresis, a run
// keeps its axis until a normal turns more than 45 + hysteresis_deg degrees from it (walked from
// the edge nearest to an axis), and the axis it turns to then goes back to where the normals last
// came nearer to it than to the run's: the cut between two runs where the normals pass the
// bisector, as without a hysteresis. (Walked one way alone, a run would reach hysteresis_deg
// farther into the corner after it than into the one before: along a corner rounded by 2 m, a
// metre more of arc at its end, which turns its fitted line; a small house's lattice came out
// 2-7 degrees off, always the same way.)
std::vector<int> axis_labels(const std::vector<Vec2>& normals, const Vec2 (&axes)[4], double hysteresis_deg) {
  const std::size_t n = normals.size();
  const auto nearest = [&](std::size_t i) {
    int best = 0;
    for (int a = 1; a < 4; ++a) if (normals[i].dot(axes[a]) > normals[i].dot(axes[best])) best = a;
    return best;
  };
  std::vector<int> labels(n);
  for (std::size_t i = 0; i < n; ++i) labels[i] = nearest(i);
  if (hysteresis_deg <= 0 || n == 0) return labels;
  const double keep = std::cos((45.0 + hysteresis_deg) * M_PI / 180.0);
  std::size_t start = 0;
  for (std::size_t i = 1; i < n; ++i)
    if (normals[i].dot(axes[labels[i]]) > normals[start].dot(axes[labels[start]])) start = i;
  int current = labels[start];
  std::vector<int> held(n);
  std::vector<std::size_t> switches;  // where the walk took a new axis (its order along the walk)
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = (start + k) % n;
    if (normals[i].dot(axes[current]) < keep) {
      current = labels[i];
      switches.push_back(k);
    }
    held[i] = current;
  }
  // Each switch moved back over the edges nearer to its new axis than to the one it left (not past
  // the switch before it).
  for (std::size_t s = 0; s < switches.size(); ++s) {
    const std::size_t k = switches[s], floor = s > 0 ? switches[s - 1] + 1 : 1;
    const int to = held[(start + k) % n];
    for (std::size_t back = k; back-- > floor;) {
      const std::size_t i = (start + back) % n;
      const int from = held[i];
      if (from == to || normals[i].dot(axes[to]) <= normals[i].dot(axes[from])) break;
      held[i] = to;
    }
  }
  return held;
}

// A Gaussian's |x| has its quantile q at z((1 + q) / 2) standard deviations.
double gaussian_abs_quantile(double q) { return std::sqrt(2.0) * inverse_erf(q); }

// A run's middle: the midpoints (minus origin) and lengths of its edges farther than
// min(trim_m, a quarter of its length) along it from either end, where corners are rounded.
// *run_length, when asked: the whole run's length.
std::vector<std::pair<Vec2, double>> run_middle(const Ring& ring, int first, int count, double trim_m, const Vec2& origin,
                                                double* run_length = nullptr) {
  const std::size_t n = ring.size();
  std::vector<double> position(count + 1, 0.0);
  for (int k = 0; k < count; ++k) position[k + 1] = position[k] + edge_vector(ring, (first + k) % n).norm();
  const double length = position[count], trim = std::min(trim_m, length / 4);
  if (run_length) *run_length = length;
  std::vector<std::pair<Vec2, double>> middle;
  for (int k = 0; k < count; ++k) {
    if (position[k] < trim || position[k + 1] > length - trim) continue;
    const std::size_t i = (first + k) % n;
    const Vec2 e = edge_vector(ring, i);
    middle.push_back({ring[i] + 0.5 * e - origin, e.norm()});
  }
  return middle;
}

// Cuts of one run's samples (in order along it; t along, y across, w weight) into pieces at
// parallel offsets: the steps of a row of houses under one label, which tilt a line fitted
// through them. Greedy, as corners' split_parallel: each cut where it leaves the least spread
// about lines of one shared slope (one offset a piece, pieces at least 4 * apart_m long, up to 8),
// taken while the cut's two pieces lie at least apart_m apart. None where the run's RMS about a
// line along t (its axis: the walls of the lattice the fit starts from) is at most max_rms_m: its
// noise explains it. Returns the pieces' first indices after the first.
std::vector<std::size_t> step_cuts(const std::vector<double>& t, const std::vector<double>& y, const std::vector<double>& w,
                                   double apart_m, double max_rms_m) {
  const std::size_t m = t.size();
  if (m < 4 || !(apart_m > 0)) return {};
  std::vector<LineMoments> sums(m + 1);
  for (std::size_t k = 0; k < m; ++k) sums[k + 1] = sums[k] + LineMoments::of(w[k], t[k], y[k]);
  ParallelPieces pieces(sums);
  // (About a line along the axis: a line of its own would tilt toward the steps and explain them.)
  if (sums.back().syy() <= max_rms_m * max_rms_m * sums.back().w) return {};  // the noise explains the run
  while (pieces.cuts().size() - 1 < 8) {
    const std::size_t best_cut = pieces.best_cut(4 * apart_m);
    if (best_cut == 0) break;
    // The cut's two pieces' offsets about the shared slope: a step, or no more cuts.
    ParallelPieces cut = pieces;
    cut.cut(best_cut);
    const auto at = std::upper_bound(cut.cuts().begin(), cut.cuts().end(), best_cut);
    if (std::abs(cut.offset(*(at - 2), best_cut) - cut.offset(best_cut, *at)) < apart_m) break;
    pieces = std::move(cut);
  }
  const std::vector<std::size_t>& cuts = pieces.cuts();
  return std::vector<std::size_t>(cuts.begin() + 1, cuts.end() - 1);
}

}  // namespace

double lattice_noise(const std::vector<Ring>& rings, const std::vector<std::vector<Vec2>>& normals, const Vec2& lattice,
                     double pixel_size, const NoiseOptions& o, double* arc_noise, double* measured, const Ring* within) {
  const Vec2 axes[4] = {lattice, Vec2(-lattice.y(), lattice.x()), -lattice, Vec2(lattice.y(), -lattice.x())};
  std::vector<std::pair<double, double>> residuals, arc_residuals;  // |distance|, weight
  for (std::size_t r = 0; r < rings.size(); ++r) {
    const Ring& ring = rings[r];
    const std::size_t n = ring.size();
    if (n < 4) continue;
    std::vector<int> labels = axis_labels(normals[r], axes, 0.0);
    absorb_short_runs(ring, labels, std::max(o.min_run_m, 2 * pixel_size));
    for (auto [first, count] : label_runs(labels)) {
      // The run's middle (ends trimmed, where corners are rounded), fitted by a line of its own
      // direction held within max_tilt_deg of the lattice: a wall a little off the lattice is
      // still fitted, a wobble's flanks are not.
      double length = 0;
      std::vector<std::pair<Vec2, double>> middle = run_middle(ring, first, count, o.trim_m, ring[first], &length);  // midpoint, weight
      if (within && within->size() >= 3)
        std::erase_if(middle, [&](const std::pair<Vec2, double>& m) { return !inside_convex(m.first + ring[first], *within, pixel_size); });
      Vec2 mean = Vec2::Zero();
      double total = 0;
      for (const auto& [p, w] : middle) {
        mean += w * p;
        total += w;
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
  const double z = gaussian_abs_quantile(o.quantile);
  if (measured) {
    *measured = 0;
    for (const auto& r : residuals) *measured += r.second;
  }
  if (arc_noise) *arc_noise = weighted_quantile(std::move(arc_residuals), o.quantile) / z;
  return weighted_quantile(std::move(residuals), o.quantile) / z;
}

std::optional<Vec2> fit_lattice(const std::vector<Ring>& rings, const std::vector<std::vector<Vec2>>& normals,
                                const Vec2& start, double pixel_size, const LatticeOptions& lo, const NoiseOptions& no,
                                double correlation_m, double* uncertainty, double* spread_out, double step_noise_m) {
  if (uncertainty) *uncertainty = 0;
  if (spread_out) *spread_out = 0;
  const Vec2 axes[4] = {start, Vec2(-start.y(), start.x()), -start, Vec2(start.y(), -start.x())};
  // Every run's middle (ends trimmed, where corners are rounded), turned by its axis's quarter
  // turns onto the first axis: the edges' midpoints, weighted by their lengths, run by run.
  struct Sample {
    Vec2 q;
    double w;
    int run;
  };
  std::vector<Sample> samples;
  int runs = 0;
  for (std::size_t r = 0; r < rings.size(); ++r) {
    const Ring& ring = rings[r];
    const std::size_t n = ring.size();
    if (n < 4) continue;
    const std::vector<int> labels = axis_labels(normals[r], axes, lo.fit_hysteresis_deg);
    for (auto [first, count] : label_runs(labels)) {
      const std::vector<std::pair<Vec2, double>> middle = run_middle(ring, first, count, no.trim_m, rings[0][0]);
      for (auto [q, w] : middle) {
        for (int t = 0; t < labels[first]; ++t) q = Vec2(q.y(), -q.x());  // a quarter turn back per axis
        samples.push_back({q, w, runs});
      }
      if (!middle.empty()) ++runs;
    }
  }
  // A run stepping between parallel offsets (row houses) is fitted piece by piece, each its own
  // offset: steps of at least fit_step_noise noises (lattice.fit_step_noise).
  if (lo.fit_step_noise > 0 && step_noise_m > 0 && runs > 0) {
    const Vec2 along(-start.y(), start.x());
    std::vector<Sample> split;
    split.reserve(samples.size());
    int pieces = 0;
    for (std::size_t a = 0; a < samples.size();) {
      std::size_t b = a;
      while (b < samples.size() && samples[b].run == samples[a].run) ++b;
      std::vector<double> t, y, w;
      for (std::size_t k = a; k < b; ++k) {
        t.push_back(along.dot(samples[k].q));
        y.push_back(start.dot(samples[k].q));
        w.push_back(samples[k].w);
      }
      const std::vector<std::size_t> cuts =
          step_cuts(t, y, w, std::max(lo.fit_step_noise * step_noise_m, 2 * pixel_size), 2.0 * step_noise_m);
      std::size_t next_cut = 0;
      for (std::size_t k = a; k < b; ++k) {
        if (next_cut < cuts.size() && k - a == cuts[next_cut]) ++next_cut, ++pieces;
        split.push_back({samples[k].q, samples[k].w, pieces});
      }
      ++pieces;
      a = b;
    }
    samples.swap(split);
    runs = pieces;
  }
  if (runs < 2 || samples.size() < std::size_t(runs) + 3) return std::nullopt;  // a line per run needs points to spare
  // One direction for every run, each run its own offset: the scatter about the runs' means.
  // Samples farther from their run's line than fit_outlier_noise times the spread (an oblique
  // wall absorbed into a run, a corner) leave the fit, which is made again.
  std::vector<double> keep(samples.size(), 1.0);
  // Each run's mean over its samples in the fit; a run left out whole keeps the mean of all its
  // samples, about which its residuals stay its own.
  const auto run_means = [&] {
    std::vector<Vec2> mean(runs, Vec2::Zero());
    std::vector<double> total(runs, 0.0);
    for (std::size_t k = 0; k < samples.size(); ++k) {
      mean[samples[k].run] += keep[k] * samples[k].w * samples[k].q;
      total[samples[k].run] += keep[k] * samples[k].w;
    }
    for (int j = 0; j < runs; ++j) if (total[j] > 0) mean[j] /= total[j];
    return std::make_pair(mean, total);
  };
  const std::vector<Vec2> all_means = run_means().first;  // every sample in
  std::vector<Vec2> mean;
  const auto update_means = [&] {
    std::vector<double> total;
    std::tie(mean, total) = run_means();
    for (int j = 0; j < runs; ++j) if (total[j] <= 0) mean[j] = all_means[j];
  };
  Vec2 normal = start;
  double spread = 0;
  // The first pass fits nothing: its outliers are judged about the start direction, near the
  // walls, so that a long oblique wall a run took in (its normals within 45 + fit_hysteresis_deg
  // of the run's axis) leaves the fit before it can turn it; a first fit with it in turned
  // the lattice of a stepped Delft block 6 degrees off its walls, its spread twice the noise,
  // which kept the oblique wall in.
  for (int pass = 0; pass < 4; ++pass) {
    update_means();
    if (pass > 0) {
      Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
      for (std::size_t k = 0; k < samples.size(); ++k) {
        const Vec2 d = samples[k].q - mean[samples[k].run];
        scatter += keep[k] * samples[k].w * d * d.transpose();
      }
      const Vec2 fitted = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(scatter).eigenvectors().col(0);
      if (!fitted.allFinite()) return std::nullopt;
      normal = fitted.dot(start) < 0 ? Vec2(-fitted) : fitted;
    }
    std::vector<std::pair<double, double>> residuals, kept;  // of every sample, of those in the fit
    residuals.reserve(samples.size());
    for (std::size_t k = 0; k < samples.size(); ++k) {
      residuals.push_back({std::abs(normal.dot(samples[k].q - mean[samples[k].run])), samples[k].w});
      if (keep[k] > 0) kept.push_back(residuals.back());
    }
    if (kept.empty()) return std::nullopt;
    spread = weighted_quantile(std::move(kept), no.quantile) / gaussian_abs_quantile(no.quantile);
    if (pass == 3) break;  // the last fit's samples are those its spread and uncertainty describe
    const double bound = lo.fit_outlier_noise * std::max(spread, 0.5 * pixel_size);
    // A run whose own RMS about its line exceeds the bound steps along its wall (row houses, a
    // step of a few pixels the smoothed normals did not turn at): it leaves the fit whole.
    std::vector<double> square(runs, 0.0), total(runs, 0.0);
    for (std::size_t k = 0; k < samples.size(); ++k) {
      square[samples[k].run] += samples[k].w * residuals[k].first * residuals[k].first;
      total[samples[k].run] += samples[k].w;
    }
    std::vector<std::pair<double, double>> run_rms;  // RMS, length
    for (int j = 0; j < runs; ++j) if (total[j] > 0) run_rms.push_back({std::sqrt(square[j] / total[j]), total[j]});
    const double run_bound = lo.fit_outlier_noise * std::max(weighted_quantile(std::move(run_rms), 0.5), 0.3 * pixel_size);
    for (std::size_t k = 0; k < samples.size(); ++k) {
      const int j = samples[k].run;
      keep[k] = residuals[k].first <= bound && square[j] <= run_bound * run_bound * total[j] ? 1.0 : 0.0;
    }
  }
  if (std::acos(std::clamp(normal.dot(start), -1.0, 1.0)) * 180.0 / M_PI > lo.fit_max_turn_deg) return std::nullopt;
  if (spread_out) *spread_out = spread;
  if (uncertainty) {
    // A line's direction fitted over a length L of noise sigma correlated over c: its standard
    // error is sigma sqrt(12 c / L^3) = sigma sqrt(c / sum of t^2), summed over every run.
    const Vec2 tangent(-normal.y(), normal.x());
    double moment = 0;
    for (std::size_t k = 0; k < samples.size(); ++k) {
      const double t = tangent.dot(samples[k].q - mean[samples[k].run]);
      moment += keep[k] * samples[k].w * t * t;
    }
    if (moment > 0) *uncertainty = spread * std::sqrt(std::max(correlation_m, pixel_size) / moment);
  }
  return normal;
}

}  // namespace lodforge
