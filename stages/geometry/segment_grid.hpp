// Segments bucketed in a uniform grid, for the nearest segment to many points: the models
// measure a contour's thousands of edges against an outline, or an outline's corners against a
// contour, many times a building.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

#include "geometry/polygon.hpp"
#include "geometry/types.hpp"

namespace lodforge {

class SegmentGrid {
 public:
  struct Segment {
    Vec2 a, b, low, high;  // ends and bounding box
  };

  // The ring's edges (vertex k to k + 1, cyclically) appended to segments.
  static void add_ring(const Ring& ring, std::vector<Segment>& segments) {
    for (std::size_t k = 0; k < ring.size(); ++k) {
      const Vec2& a = ring[k];
      const Vec2& b = ring[(k + 1) % ring.size()];
      segments.push_back({a, b, a.cwiseMin(b), a.cwiseMax(b)});
    }
  }

  // Over more than min_bucketed segments with finite ends, a grid over their bounding box of
  // about four cells a segment (at most 512 a side); fewer are looked at one by one.
  explicit SegmentGrid(std::vector<Segment> segments, std::size_t min_bucketed = 24) : segments_(std::move(segments)) {
    if (segments_.empty()) return;
    low_ = segments_[0].low, high_ = segments_[0].high;
    for (const Segment& s : segments_) low_ = low_.cwiseMin(s.low), high_ = high_.cwiseMax(s.high);
    bucketed_ = segments_.size() > min_bucketed && low_.allFinite() && high_.allFinite();
    if (!bucketed_) return;
    const Vec2 extent = (high_ - low_).cwiseMax(1e-9);
    cell_ = std::max({std::sqrt(extent.x() * extent.y() / (4.0 * double(segments_.size()))), extent.x() / 512, extent.y() / 512});
    nx_ = std::max(1L, long(std::ceil(extent.x() / cell_))), ny_ = std::max(1L, long(std::ceil(extent.y() / cell_)));
    start_.assign(std::size_t(nx_ * ny_) + 1, 0);
    for (int pass = 0; pass < 2; ++pass) {
      std::vector<std::size_t> fill(start_.begin(), start_.end() - 1);
      for (std::size_t k = 0; k < segments_.size(); ++k)
        for (long y = cell_of(segments_[k].low.y(), low_.y(), ny_); y <= cell_of(segments_[k].high.y(), low_.y(), ny_); ++y)
          for (long x = cell_of(segments_[k].low.x(), low_.x(), nx_); x <= cell_of(segments_[k].high.x(), low_.x(), nx_); ++x) {
            if (pass == 0) ++start_[std::size_t(y * nx_ + x) + 1];
            else items_[fill[std::size_t(y * nx_ + x)]++] = k;
          }
      if (pass == 0) {
        for (std::size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
        items_.resize(start_.back());
      }
    }
  }

  const std::vector<Segment>& segments() const { return segments_; }
  // The side of a cell (infinity without a grid: every segment is looked at).
  double cell() const { return bucketed_ ? cell_ : std::numeric_limits<double>::infinity(); }

  // consider(k) for every segment k that may lie within `best` of p (a distance the calls may
  // lower as they go): the cells about p's, ring by ring, until a ring lies farther than best; a
  // segment in several cells is offered once per cell. Without a grid (or p not finite), every
  // segment in order.
  template <class Consider>
  void visit(const Vec2& p, const double& best, Consider consider) const {
    if (!bucketed_ || !p.allFinite()) {
      for (std::size_t k = 0; k < segments_.size(); ++k) consider(k);
      return;
    }
    const long cx = long(std::floor((p.x() - low_.x()) / cell_)), cy = long(std::floor((p.y() - low_.y()) / cell_));
    const long last_ring = std::max({std::abs(cx), std::abs(cx - (nx_ - 1)), std::abs(cy), std::abs(cy - (ny_ - 1))});
    // Ring r's cells lie at least (r - 1) cells from p's; rings short of the grid (p outside it)
    // hold no cell.
    const long first_ring = std::max({0L, -cx, cx - (nx_ - 1), -cy, cy - (ny_ - 1)});
    for (long r = first_ring; r <= last_ring && double(r - 1) * cell_ <= best; ++r)
      for (long y = std::max(cy - r, 0L); y <= std::min(cy + r, ny_ - 1); ++y) {
        const auto cell = [&](long x) {
          for (std::size_t c = start_[std::size_t(y * nx_ + x)]; c < start_[std::size_t(y * nx_ + x) + 1]; ++c) consider(items_[c]);
        };
        if (y == cy - r || y == cy + r) {
          for (long x = std::max(cx - r, 0L); x <= std::min(cx + r, nx_ - 1); ++x) cell(x);
        } else {
          if (cx - r >= 0 && cx - r < nx_) cell(cx - r);
          if (cx + r >= 0 && cx + r < nx_) cell(cx + r);
        }
      }
  }

  // The least squared distance from p to a segment (infinity without one).
  double nearest_squared(const Vec2& p) const {
    double best = std::numeric_limits<double>::infinity(), squared_best = best;
    visit(p, best, [&](std::size_t k) {
      const Segment& s = segments_[k];
      const Vec2 gap = (s.low - p).cwiseMax(p - s.high).cwiseMax(0.0);
      if (gap.squaredNorm() > squared_best) return;  // (its box lies farther than the best)
      const double squared = squared_distance_to_segment(p, s.a, s.b);
      if (squared < squared_best) squared_best = squared, best = std::sqrt(squared);
    });
    return squared_best;
  }

 private:
  long cell_of(double v, double origin, long count) const { return std::clamp(long(std::floor((v - origin) / cell_)), 0L, count - 1); }

  std::vector<Segment> segments_;
  bool bucketed_ = false;
  Vec2 low_ = Vec2::Zero(), high_ = Vec2::Zero();
  double cell_ = 1;
  long nx_ = 1, ny_ = 1;
  std::vector<std::size_t> start_, items_;  // per cell its items' range, the segments' indices
};

}  // namespace lodforge
