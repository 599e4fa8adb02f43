// Re-estimation of the dominant directions after labeling (NOTES.md: the mean of inlier normals
// is biased on a staircase). Each direction is fitted by least squares to the runs labeled with
// it: every run keeps its own offset, all share one orientation (the smallest eigenvector of the
// pooled within-run scatter of the edge midpoints, run ends trimmed where corners are rounded).
// Directions within snap_deg of parallel or perpendicular are fitted jointly and made exactly so
// (an addition to the paper: it measures better, see docs/paper-reading.md); others stay free.
#pragma once
#include <algorithm>
#include <vector>

#include "common/option.hpp"
#include "geometry/types.hpp"

namespace lodforge {

struct RefineOptions {
  double trim_px = 1.5;          // edges this close to a run's end are left out of the fit
  double merge_angle_deg = 5.0;  // directions closer than this are merged into one
  double snap_deg = 5.0;         // near-parallel / near-perpendicular directions are snapped (0 = off)
  double release_px = 1.0;       // a run whose own direction would move its ends more than this keeps it (0 = off)
  double release_noise = 3.0;    // ... and more than this many times the building's boundary noise
  double min_wall_m = 2.5;       // a direction off the building's lattice needs a run this long (0 = off) ...
  double min_wall_noise = 5.0;   // ... reaching across the lattice by this many times the boundary noise
  double lattice_deg = 15.0;     // ... the lattice: the main direction and its quarter turns, within this
  double min_lattice_share = 0.5;  // a building with less of its contour along its lattice ...
  double min_turning = 1.5;        // ... whose outline turns less than this many full turns has no lattice
  double min_round_px = 40;        // ... unless its outline is shorter than this many pixels
  double min_round_m = 20;         // ... or than this (m)
  double min_round_noise = 80;     // ... or than this many times the mask's boundary noise
  double round_fit_ratio = 1;      // ... or whose best rectangle explains its contour as well as this many times its moments' ellipse does
  double round_fit_noise = 2;      // ... and within this many times the building's boundary noise (or pixels)
  double missing_axis_deg = 10;    // a building on a lattice with no direction this near one of its axes and a curve gets it (0 = off)

  template <class V>
  void visit(V& v) {
    v("trim_px", trim_px, "edges this close to a run's end (pixels) are left out of the direction fit", Check::at_least(0));
    v("merge_angle_deg", merge_angle_deg, "re-estimated directions closer than this are merged (degrees)", Check::between(0, 45));
    v("snap_deg", snap_deg, "directions within this of parallel or perpendicular are fitted jointly and snapped exactly (degrees, 0 = off)", Check::between(0, 20));
    v("release_noise", release_noise, "... and by more than this many times the building's boundary noise (a noisy wall's own direction is that uncertain)", Check::at_least(0));
    v("min_wall_m", min_wall_m, "a dominant direction that is not within lattice_deg of the building's main direction or a quarter turn of it is dropped unless one of its runs is at least this long (m): a network's wobble makes short walls in every direction (0 = off)", Check::at_least(0));
    v("min_wall_noise", min_wall_noise, "... whose extent across the lattice (its length times the sine of its angle to the nearest lattice direction) is at least this many times the building's boundary noise", Check::at_least(0));
    v("lattice_deg", lattice_deg, "directions within this of the main direction or a quarter turn of it are on the building's lattice (degrees)", Check::between(0, 45));
    v("min_lattice_share", min_lattice_share, "a building with less than this share of its contour (by smoothed normal) within lattice_deg of its lattice ...", Check::between(0, 1));
    v("min_turning", min_turning, "... whose smoothed outline turns by less than this many full turns in all (a convex shape turns once, a wobble back and forth) is round or oblique: its directions are not held to a lattice", Check::at_least(0));
    v("min_round_px", min_round_px, "... unless its outer ring is shorter than this many pixels (too few to tell a round shape from a rectangle)", Check::at_least(0));
    v("min_round_m", min_round_m, "... or than this (m; the traced outline, whose pixel steps make it up to 1.4 times the true one): a shed of 3 x 4 m whose corners a network rounds by a metre shows no more of a wall than of an arc, and is taken as on a lattice (a rectangle when that explains it, models.rectangle_tolerance)", Check::at_least(0));
    v("min_round_noise", min_round_noise, "... or than this many times the boundary noise pooled over the mask's buildings: under a noise that large a small house's walls are no straighter than an arc (0 = off)", Check::at_least(0));
    v("round_fit_ratio", round_fit_ratio, "... or whose contour lies no farther from its best rectangle (mean distance; models' best_rectangle, its angle searched and its sides moved onto the walls) than this many times its distance to the ellipse of its centroid and second moments per unit area (not fitted further: the comparison leans the rectangle's way), and within round_fit_noise noises of it: a rectangle's four corners against a smooth bow. Its shape then does not tell its own lattice: where its neighbours agree on one it takes theirs (lattice.neighbour_*), as one under min_round_noise does. Under a wobble of a metre the smoothed normals of a house of 12 x 9 m, or of 17 x 12 m, spread off its walls and turn back and forth too little to count, and the house read as round was drawn along its wobble's crests; a disc, an oval or a hexagon stays round. Under its mask's corner rounding (models.pooled_rounding_share; in regularize known after every building's first outline, when a building read as round is judged again and, held, drawn again) the rectangle rounded so, its sides where that lies nearer the contour, moved out to the contour's area: a house of 5 x 5 m under a rounding of 2 m is a disc in its mask (a rounding that moves a corner less than a pixel, R (sqrt 2 - 1), is the staircase's and not counted) (0 = off)", Check::at_least(0));
    v("round_fit_noise", round_fit_noise, "... the rectangle's mean distance to the contour at most this many times the building's boundary noise (its mask's, noise.pooled_floor), or than this many pixels where more (a staircase's spread): a wobbling house's is about one noise; a clean triangle's or trapezoid's, whose rectangle leaves a corner out, metres, so that a clean oblique shape keeps its own walls and lattice (0 = no such bound)", Check::at_least(0));
    v("missing_axis_deg", missing_axis_deg, "a building held to its lattice none of whose directions lies within this of one of the lattice's two axes (either way), whose regular outline keeps a curve, gets that axis's two directions, is labeled again and its outline drawn from those labels: a long thin building whose ends a wobble's flanks spread, so that no direction was found for them, has only its long walls' two, its ends join their runs, and those bow round the ends as curves drawn along the wobble (corners.curve_*; degrees, 0 = off)", Check::between(0, 45));
    v("release_px", release_px, "a long run whose own least-squares direction differs from its label's so much that its ends move by more than this (pixels, and twice its noise) gets its own direction (0 = off)", Check::at_least(0));
  }
};

using EdgeLabels = std::vector<std::vector<int>>;

// Refits every used direction; drops unused ones, merges close ones and renumbers labels.
// pixel_size converts trim_px to map units.
void refine_directions(const std::vector<Ring>& rings, EdgeLabels& labels, std::vector<Vec2>& directions,
                       double pixel_size, const RefineOptions& options);

// Where none of the directions lies within missing_axis_deg of one of the lattice's two axes
// (main, a unit normal, or its quarter turn, either way) and some lie near the other, the missing
// axis's two directions are appended (the MRF's label costs leave them unused where no wall faces
// them); none where neither axis has a direction. Returns whether any was.
bool add_missing_axis(std::vector<Vec2>& directions, const Vec2& main, const RefineOptions& o);

// Drops the directions that are off the building's lattice (main, the direction with the most
// labeled length, and its quarter turns, within lattice_deg) and have no run long enough: a real
// oblique wall is a long straight run, a wobble's are short: a run at least min_wall_m long that
// reaches across the lattice by min_wall_noise times the boundary noise. The lattice's four
// directions are added where missing.
// Returns whether any was dropped (the labels then refer to the old numbering: label again).
bool drop_insignificant_directions(const std::vector<Ring>& rings, const EdgeLabels& labels, std::vector<Vec2>& directions,
                                   const Vec2& main, double noise, const RefineOptions& options);

// Whether an outline this long (m) is too few pixels long to show a round shape from a rectangle:
// under min_round_px pixels or min_round_m.
inline bool too_short_in_pixels(double outline_m, double pixel_size, const RefineOptions& o) {
  return outline_m < std::max(o.min_round_px * pixel_size, o.min_round_m);
}

// Whether an outline this long (m) is too short to show a round shape from a rectangle: too few
// pixels long, or under min_round_noise times its mask's boundary noise (noise_floor_m). Such a
// building is taken as on a lattice.
inline bool too_short_to_show_round(double outline_m, double pixel_size, double noise_floor_m, const RefineOptions& o) {
  return outline_m < o.min_round_noise * noise_floor_m || too_short_in_pixels(outline_m, pixel_size, o);
}

// Releases long runs from their shared direction: a run whose own least-squares direction
// differs from its label's enough to move the run's ends by more than release_px pixels (and
// more than twice the run's own residual noise, and than release_noise times the building's
// boundary noise, building_noise, in map units) gets a direction of its own, appended to
// `directions`. Shared directions keep short walls regular; a long wall is placed where its
// pixels are (a 100 m wall 1° off its shared direction is 0.9 m off at its ends).
// Returns the number of runs released.
int release_runs(const std::vector<Ring>& rings, EdgeLabels& labels, std::vector<Vec2>& directions, double pixel_size,
                 double building_noise, const RefineOptions& options);

}  // namespace lodforge
