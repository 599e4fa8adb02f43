// Small statistics the models share.
#pragma once
#include <algorithm>
#include <utility>
#include <vector>

namespace lodforge {

// The weighted q-quantile of (value, weight) pairs: the least value whose weight and the weights
// of all smaller values reach q of the total. 0 for no values. (A selection, not a sort: each
// round splits the values about a pivot and keeps the side the quantile lies on; a few dozen
// left are sorted. The models take a quantile of every contour edge several times a building.
// The weights are summed in another order than a sort's, so where q of the total falls exactly
// on a sum of weights, rounding may pick the neighbouring value.)
inline double weighted_quantile(std::vector<std::pair<double, double>> values, double q) {
  if (values.empty()) return 0.0;
  double total = 0;
  for (const auto& v : values) total += v.second;
  const double target = q * total;
  std::size_t lo = 0, hi = values.size();
  double below = 0;  // the weight of the values left of lo, all less than those in [lo, hi)
  while (hi - lo > 32) {
    // The median of three as pivot; [lo, hi) split into less than, equal to and more than it.
    const double a = values[lo].first, b = values[lo + (hi - lo) / 2].first, c = values[hi - 1].first;
    const double pivot = std::max(std::min(a, b), std::min(std::max(a, b), c));
    if (!(pivot == pivot)) break;  // (a NaN, which no caller gives: left to the sort, as before)
    std::size_t less = lo, more = hi;
    for (std::size_t k = lo; k < more;) {
      if (values[k].first < pivot) std::swap(values[k++], values[less++]);
      else if (values[k].first > pivot) std::swap(values[k], values[--more]);
      else ++k;
    }
    double w_less = 0, w_equal = 0;
    for (std::size_t k = lo; k < less; ++k) w_less += values[k].second;
    for (std::size_t k = less; k < more; ++k) w_equal += values[k].second;
    if (below + w_less >= target && less > lo) {
      hi = less;
    } else if (below + w_less + w_equal >= target || more == hi) {
      return pivot;
    } else {
      below += w_less + w_equal;
      lo = more;
    }
  }
  std::sort(values.begin() + long(lo), values.begin() + long(hi));
  double acc = below;
  for (std::size_t k = lo; k < hi; ++k) {
    acc += values[k].second;
    if (acc >= target) return values[k].first;
  }
  return values[hi - 1].first;
}

// Weighted sums of points (t along a line, y across it) and their centred second moments, which
// add and subtract: prefix sums of them give any stretch's in constant time. The cuts of a run
// into parallel pieces (corners' split_parallel, fit_lattice's steps) are chosen by them.
struct LineMoments {
  double w = 0, t = 0, y = 0, tt = 0, ty = 0, yy = 0;
  static LineMoments of(double weight, double t, double y) { return {weight, weight * t, weight * y, weight * t * t, weight * t * y, weight * y * y}; }
  LineMoments operator-(const LineMoments& o) const { return {w - o.w, t - o.t, y - o.y, tt - o.tt, ty - o.ty, yy - o.yy}; }
  LineMoments operator+(const LineMoments& o) const { return {w + o.w, t + o.t, y + o.y, tt + o.tt, ty + o.ty, yy + o.yy}; }
  // The centred second moments: spread of t, covariance, spread of y.
  double stt() const { return w > 0 ? tt - t * t / w : 0.0; }
  double sty() const { return w > 0 ? ty - t * y / w : 0.0; }
  double syy() const { return w > 0 ? yy - y * y / w : 0.0; }
  // The spread left about lines of one slope, from summed centred moments (of one or more pieces,
  // each about its own mean: one offset a piece).
  static double spread(double stt, double sty, double syy) { return stt > 1e-12 ? syy - sty * sty / stt : syy; }
};

// A run's samples cut greedily into pieces at parallel offsets, one slope shared, one offset a
// piece (corners' split_parallel, fit_lattice's steps): over the prefix sums of the samples'
// moments (sums[0] zero, sums[k] those of the first k), the cuts made so far (piece p is
// [cuts()[p], cuts()[p + 1])) and the pieces' centred moments summed.
class ParallelPieces {
 public:
  explicit ParallelPieces(const std::vector<LineMoments>& sums) : sums_(&sums), cuts_{0, sums.size() - 1} {
    const LineMoments all = piece(0, cuts_.back());
    stt_ = all.stt(), sty_ = all.sty(), syy_ = all.syy();
  }
  const std::vector<std::size_t>& cuts() const { return cuts_; }
  LineMoments piece(std::size_t a, std::size_t b) const { return (*sums_)[b] - (*sums_)[a]; }
  // The spread left about the pieces' lines.
  double spread() const { return LineMoments::spread(stt_, sty_, syy_); }
  // The shared slope, and a piece's offset across the run about it.
  double slope() const { return stt_ > 1e-12 ? sty_ / stt_ : 0.0; }
  double offset(std::size_t a, std::size_t b) const {
    const LineMoments q = piece(a, b);
    return (q.y - slope() * q.t) / q.w;
  }
  // The cut that leaves the least spread, its two pieces each at least min_weight; 0 where none
  // leaves less than now.
  std::size_t best_cut(double min_weight) const {
    std::size_t best = 0;
    double least = spread();
    for (std::size_t p = 0; p + 1 < cuts_.size(); ++p) {
      const std::size_t a = cuts_[p], b = cuts_[p + 1];
      const LineMoments own = piece(a, b);
      for (std::size_t k = a + 1; k < b; ++k) {
        if ((*sums_)[k].w - (*sums_)[a].w < min_weight || (*sums_)[b].w - (*sums_)[k].w < min_weight) continue;
        const LineMoments left = piece(a, k), right = piece(k, b);
        const double total = LineMoments::spread(stt_ - own.stt() + left.stt() + right.stt(), sty_ - own.sty() + left.sty() + right.sty(),
                                                 syy_ - own.syy() + left.syy() + right.syy());
        if (total < least) least = total, best = k;
      }
    }
    return best;
  }
  void cut(std::size_t k) {
    const auto at = std::upper_bound(cuts_.begin(), cuts_.end(), k);
    const LineMoments own = piece(*(at - 1), *at), left = piece(*(at - 1), k), right = piece(k, *at);
    stt_ += left.stt() + right.stt() - own.stt();
    sty_ += left.sty() + right.sty() - own.sty();
    syy_ += left.syy() + right.syy() - own.syy();
    cuts_.insert(at, k);
  }

 private:
  const std::vector<LineMoments>* sums_;
  std::vector<std::size_t> cuts_;
  double stt_ = 0, sty_ = 0, syy_ = 0;
};

}  // namespace lodforge
