// Stage 7: corner extraction into the LOD0 ring (paper §2.5). Each maximal run of edges with one
// target direction becomes a line with that direction, placed by least squares (closed form:
// with the direction fixed, the offset is the length-weighted mean of the edge midpoints'
// projections); corners are the intersections of consecutive lines.
#pragma once
#include <algorithm>
#include <string>
#include <vector>
#include <utility>

#include "common/option.hpp"
#include "geometry/types.hpp"

namespace lodforge {

struct CornerOptions {
  std::string route = "original";  // fit the lines to the original contour, or the deformed one
  double min_run_px = 2.0;         // runs shorter than this (in pixel edges) join a neighbour
  double min_run_noise = 2.0;      // ... and runs shorter than this many times the boundary noise
  double parallel_angle_deg = 10.0;  // consecutive lines closer than this in angle get a step
  double max_corner_shift_m = 1.25;  // an intersection farther than this from the run junction is
                                     // replaced by a step between the two lines
  double square_corner_shift_m = 3.0;  // ... or this, when the lines are within parallel_angle_deg of square
  int repair_attempts = 4;           // an invalid polygon is retried with min_run doubled this often
  double untangle_noise = 2.0;       // a loop where a ring crosses itself is cut off when its mean width is under this many boundary noises (at least a pixel)
  double curve_px = 2.5;             // a run whose contour bows this far from its line is a curved wall (0 = off)
  double curve_noise_factor = 2.5;   // ... and this many times the building's boundary noise
  double curve_window_px = 16.0;     // ... measured as the mean offset over windows of this length
  double curve_window_m = 4.0;       // ... and at least this (m)
  double curve_min_explained = 0.3;  // ... and a parabola explains this share of its spread about a line
  double curve_other_side = 1.0;     // ... or no window departs to the other side by more than this share of the threshold
  double curve_tolerance_noise = 0.5;  // a curve's contour is simplified to a pixel and this many times the noise
  double zigzag_max_deg = 40;   // runs zigzagging about a lattice line within this angle (a window of them may end half a wave up a wobble: 1 m over 4 m) ...
  double zigzag_rms_noise = 2;  // ... and this many times the noise (RMS) ...
  double zigzag_max_noise = 3;  // ... and this (everywhere) become one wall
  double curve_smoothing = 0.5;  // ... after a Gaussian smoothing along it of this many curve windows (sigma)
  double snap_max_deg = 10.0;        // a straight wall within this of the building's lattice ...
  double snap_shift_m = 0.0;         // ... is turned onto it when its ends move by at most this (m) ...
  double snap_noise = 2.0;           // ... or this many times its direction's uncertainty at its ends
  double snap_correlation_m = 1.0;   // ... from the boundary noise, correlated over this length (m)
  double merge_offset_m = 0.1;       // consecutive parallel walls offset by less than this (m) ...
  double merge_noise = 0.5;          // ... or this many times the boundary noise are one wall
  double max_cut_m = 3.0;            // an oblique wall shorter than this between square walls is a rounded corner
  double split_px = 1.0;             // a run whose parts lie this far apart (parallel) becomes lines and steps (0 = off)
  double split_m = 0.0;              // ... and at least this far in metres (0: the pixel and noise terms alone)
  double split_noise = 5.0;          // ... and at least this many times the boundary noise
  double split_max_residual = 0.15;  // ... when the parts leave at most this share of the spread about one line
  double split_max_rms_px = 0.5;     // ... and at most this RMS distance to their own lines
  double split_max_rms_noise = 1.5;  // ... or this many times the boundary noise

  template <class V>
  void visit(V& v) {
    v("route", route, "fit the corner lines to the 'original' contour with the MRF directions, or to the 'deformed' contour (the paper)", Check::one_of({"original", "deformed"}));
    v("min_run_px", min_run_px, "runs of one direction shorter than this (pixel lengths) join their neighbours", Check::at_least(0));
    v("min_run_noise", min_run_noise, "runs shorter than this many times the building's boundary noise join their neighbours (0 = off)", Check::at_least(0));
    v("parallel_angle_deg", parallel_angle_deg, "consecutive lines closer than this in angle are joined by a perpendicular step (degrees)", Check::between(0, 89));
    v("max_corner_shift_m", max_corner_shift_m, "an intersection farther than this from where the runs meet is replaced by a step (m)", Check::above(0));
    v("square_corner_shift_m", square_corner_shift_m, "the same for two lines within parallel_angle_deg of perpendicular, whose intersection is well posed (a rounded corner puts it farther from the runs' junction) (m)", Check::above(0));
    v("untangle_noise", untangle_noise, "where a ring crosses itself, the loop is cut off when its mean width (area over half its perimeter) is under this many times the boundary noise, and at least a pixel (0 = off: the polygon is retried as below)", Check::at_least(0));
    v("repair_attempts", repair_attempts, "retries of an invalid polygon with min_run_px doubled each time (when all fail, they are made again with runs unsplit)", Check::between(0, 20));
    v("curve_px", curve_px, "a run whose contour departs from its fitted line by more than this on average over a window (pixels) is kept as a curve: its contour, simplified, replaces the line (0 = off)", Check::at_least(0));
    v("curve_noise_factor", curve_noise_factor, "... and by more than this many times the building's boundary noise (a wobble's window means stay below, an arc's do not)", Check::at_least(0));
    v("curve_window_px", curve_window_px, "length of the windows over which a run's departure from its line is averaged (pixels)", Check::above(0));
    v("curve_window_m", curve_window_m, "... and their least length (m)", Check::at_least(0));
    v("curve_other_side", curve_other_side, "... or, where it does not (a bay or a bow on a long straight wall, which a parabola over the whole run does not explain), no window of the run departs to the other side of its straight part's line (the median offset of its contour) by more than this share of that threshold: a wobble that departs that far one way does so the other way too, half a wave on. The bay, the stretch departing by more than the noise, is then drawn as a curve and the rest of the run as the wall (0 = off)", Check::at_least(0));
    v("curve_min_explained", curve_min_explained, "... and a parabola along the run explains at least this share of its contour's spread about a straight line: an arc bends one way all along, a wobble of several half-waves along a long wall does not (0 = off)", Check::between(0, 1));
    v("curve_tolerance_noise", curve_tolerance_noise, "a curved wall's contour is simplified by Douglas-Peucker to a pixel or this many times the boundary noise, the larger", Check::at_least(0));
    v("zigzag_max_deg", zigzag_max_deg, "consecutive runs, one off the building's lattice at least, whose contour zigzags about one line of the lattice become one wall on it (a wobbling wall, its flanks labeled with their slopes): the line from their start to their end within this angle of the lattice (degrees, 0 = off) ...", Check::between(0, 45));
    v("zigzag_rms_noise", zigzag_rms_noise, "... their contour within this many times the boundary noise of that line, RMS (at least a pixel) ...", Check::at_least(0));
    v("zigzag_max_noise", zigzag_max_noise, "... and within this many times the noise everywhere (at least two pixels)", Check::at_least(0));
    v("curve_smoothing", curve_smoothing, "... after it is smoothed along its length by a Gaussian whose sigma is this many curve windows (the window of the curve test, curve_window_px and curve_window_m), so that the wobble on a curved wall is not traced, its bend kept; the window narrows towards the run's ends, which stay where they are (0 = off)", Check::between(0, 4));
    v("snap_max_deg", snap_max_deg, "a straight wall within this angle of the building's lattice (its main direction and quarter turns of it) is turned onto the lattice when that moves its ends little (degrees, 0 = off)", Check::between(0, 45));
    v("snap_shift_m", snap_shift_m, "... by at most this (m) ...", Check::at_least(0));
    v("snap_noise", snap_noise, "... or by at most this many times the uncertainty of its fitted direction at its ends (noise * sqrt(3 * snap_correlation_m / length))", Check::at_least(0));
    v("snap_correlation_m", snap_correlation_m, "the length over which the boundary noise is taken to be correlated, for that uncertainty (m, at least a pixel)", Check::above(0));
    v("merge_offset_m", merge_offset_m, "parallel walls offset by less than this (m), consecutive or joined by a riser at most twice that long, become one wall", Check::at_least(0));
    v("merge_noise", merge_noise, "... or by less than this many times the building's boundary noise", Check::at_least(0));
    v("max_cut_m", max_cut_m, "an oblique wall shorter than this (m) between two square walls of the lattice is a corner the segmentation rounded: the two walls meet at their intersection (0 = off)", Check::at_least(0));
    v("split_px", split_px, "a straight run whose contour is explained by parallel lines this far apart or more (pixels, and split_m; each part at least 4 times as long) becomes those lines joined by steps (0 = off)", Check::at_least(0));
    v("split_m", split_m, "the least offset between parallel parts of a run that splits it, in metres (the largest of this, split_px and split_noise applies; 0 = none: a step of a few decimetres is real where the pixels and the noise resolve it, and split_noise keeps a wobble from splitting a wall)", Check::at_least(0));
    v("split_noise", split_noise, "... and at least this many times the building's boundary noise (a step smaller than that is the noise's); where the parts leave no more than split_max_rms_px, the noise they leave where less, but at least the noise pooled over the mask: a clean row of houses stepping by half a metre measures its steps as its noise about one line along each wall", Check::at_least(0));
    v("split_max_residual", split_max_residual, "parts split a run only when they leave at most this share of its contour's spread about one line", Check::between(0, 1));
    v("split_max_rms_px", split_max_rms_px, "... and at most this RMS distance of the contour to the parts' lines (pixels)", Check::above(0));
    v("split_max_rms_noise", split_max_rms_noise, "... or at most this many times the building's boundary noise, which also stands for split_max_residual (a wobbling wall lies about its line by the noise)", Check::at_least(0));
  }
};

// The length over which the boundary noise is taken to be correlated: snap_correlation_m, at
// least a pixel (for the standard error of a mean or a fit along the contour).
inline double noise_correlation_m(const CornerOptions& o, double pixel_size) { return std::max(o.snap_correlation_m, pixel_size); }

// The least run of a regular outline (pixels): min_run_px, and min_run_noise times the noise.
inline double regular_min_run_px(const CornerOptions& o, double noise, double pixel_size) {
  return std::max(o.min_run_px, o.min_run_noise * noise / pixel_size);
}

// Absorbs runs shorter than min_run_px pixel lengths into their longer neighbour, in place.
void absorb_short_runs(const Ring& ring, std::vector<int>& labels, double min_length);

// What the corner extraction knows of the whole building.
struct CornerContext {
  double noise = 0;                // its boundary noise (see boundary_noise)
  double regularity_noise = 0;     // the noise its regularity is judged by (noise.regularity_ceiling; 0 or less: noise): regularity()
  double mask_noise = 0;           // the noise pooled over its mask's buildings (0: unknown)
  double mask_rounding = 0;        // the corner rounding pooled over its mask's buildings (0: none; negative: not known yet)
  Vec2 lattice = Vec2::Zero();     // its main wall direction (unit normal); zero: no lattice snap
  // The noise its snaps, curves and squarings are judged by: the regularity noise, at least the noise.
  double regularity() const { return std::max(noise, regularity_noise); }
};

// The runs (first edge, edge count) of ring left where consecutive runs that zigzag about a line
// of the lattice are merged, as extract_corners merges them (corners.zigzag_*; the bounds in
// metres, square_deg its parallel_angle_deg), each run's line fitted along its given normal.
// (That step of extract_corners alone, for tests.)
std::vector<std::pair<int, int>> zigzags_merged(const Ring& ring, std::vector<std::pair<int, int>> runs, const std::vector<Vec2>& normals,
                                                const Vec2& lattice, double max_deg, double max_rms, double max_dev, double square_deg);

// The corner ring of one contour ring (in metres; pixel_size converts the _px options). A curved
// run (see curve_px) keeps its contour, simplified, between the lines of its neighbours; straight
// walls near the building's lattice are turned onto it and parallel neighbours within the noise
// merged (snap_*, merge_*). labels: per edge; directions: unit outward normals.
// Returns an empty ring and sets *problem when no polygon can be formed. *curved (when given):
// whether a run was kept as a curve.
Ring extract_corners(const Ring& ring, const std::vector<int>& labels, const std::vector<Vec2>& directions,
                     double pixel_size, const CornerOptions& options, std::string* problem,
                     const CornerContext& context = {}, bool* curved = nullptr);

}  // namespace lodforge
