// Re-estimation of the dominant directions after labeling (NOTES.md: the mean of inlier normals
// is biased on a staircase). Each direction is fitted by least squares to the runs labeled with
// it: every run keeps its own offset, all share one orientation (the smallest eigenvector of the
// pooled within-run scatter of the edge midpoints, run ends trimmed where corners are rounded).
// Directions within snap_deg of parallel or perpendicular are fitted jointly and made exactly so
// (an addition to the paper: it measures better, see docs/paper-reading.md); others stay free.
#pragma once
#include <vector>

#include "common/option.hpp"
#include "geometry/types.hpp"

namespace lodforge {

struct RefineOptions {
  double trim_px = 1.5;          // edges this close to a run's end are left out of the fit
  double merge_angle_deg = 5.0;  // directions closer than this are merged into one
  double snap_deg = 5.0;         // near-parallel / near-perpendicular directions are snapped (0 = off)
  double release_px = 1.0;       // a run whose own direction would move its ends more than this keeps it (0 = off)

  template <class V>
  void visit(V& v) {
    v("trim_px", trim_px, "edges this close to a run's end (pixels) are left out of the direction fit", Check::at_least(0));
    v("merge_angle_deg", merge_angle_deg, "re-estimated directions closer than this are merged (degrees)", Check::between(0, 45));
    v("snap_deg", snap_deg, "directions within this of parallel or perpendicular are fitted jointly and snapped exactly (degrees, 0 = off)", Check::between(0, 20));
    v("release_px", release_px, "a long run whose own least-squares direction differs from its label's so much that its ends move by more than this (pixels, and twice its noise) gets its own direction (0 = off)", Check::at_least(0));
  }
};

using EdgeLabels = std::vector<std::vector<int>>;

// Refits every used direction; drops unused ones, merges close ones and renumbers labels.
// pixel_size converts trim_px to map units.
void refine_directions(const std::vector<Ring>& rings, EdgeLabels& labels, std::vector<Vec2>& directions,
                       double pixel_size, const RefineOptions& options);

// Releases long runs from their shared direction: a run whose own least-squares direction
// differs from its label's enough to move the run's ends by more than release_px pixels (and
// more than twice the run's own residual noise) gets a direction of its own, appended to
// `directions`. Shared directions keep short walls regular; a long wall is placed where its
// pixels are (a 100 m wall 1° off its shared direction is 0.9 m off at its ends).
// Returns the number of runs released.
int release_runs(const std::vector<Ring>& rings, EdgeLabels& labels, std::vector<Vec2>& directions, double pixel_size,
                 const RefineOptions& options);

}  // namespace lodforge
