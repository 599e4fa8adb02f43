// Stage 7: corner extraction into the LOD0 ring (paper §2.5). Each maximal run of edges with one
// target direction becomes a line with that direction, placed by least squares (closed form:
// with the direction fixed, the offset is the length-weighted mean of the edge midpoints'
// projections); corners are the intersections of consecutive lines.
#pragma once
#include <string>
#include <vector>

#include "common/option.hpp"
#include "geometry/types.hpp"

namespace lodforge {

struct CornerOptions {
  std::string route = "original";  // fit the lines to the original contour, or the deformed one
  double min_run_px = 2.0;         // runs shorter than this (in pixel edges) join a neighbour
  double parallel_angle_deg = 10.0;  // consecutive lines closer than this in angle get a step
  double max_corner_shift_m = 1.25;  // an intersection farther than this from the run junction is
                                     // replaced by a step between the two lines
  int repair_attempts = 4;           // an invalid polygon is retried with min_run doubled this often
  double curve_px = 2.5;             // a run whose contour bows this far from its line is a curved wall (0 = off)
  double curve_window_px = 16.0;     // ... measured as the mean offset over windows of this length
  double split_px = 1.0;             // a run whose parts lie this far apart (parallel) becomes lines and steps (0 = off)
  double split_m = 0.5;              // ... and at least this far in metres
  double split_max_residual = 0.15;  // ... when the parts leave at most this share of the spread about one line
  double split_max_rms_px = 0.5;     // ... and at most this RMS distance to their own lines

  template <class V>
  void visit(V& v) {
    v("route", route, "fit the corner lines to the 'original' contour with the MRF directions, or to the 'deformed' contour (the paper)", Check::one_of({"original", "deformed"}));
    v("min_run_px", min_run_px, "runs of one direction shorter than this (pixel lengths) join their neighbours", Check::at_least(0));
    v("parallel_angle_deg", parallel_angle_deg, "consecutive lines closer than this in angle are joined by a perpendicular step (degrees)", Check::between(0, 89));
    v("max_corner_shift_m", max_corner_shift_m, "an intersection farther than this from where the runs meet is replaced by a step (m)", Check::above(0));
    v("repair_attempts", repair_attempts, "retries of an invalid polygon with min_run_px doubled each time (when all fail, they are made again with runs unsplit)", Check::between(0, 20));
    v("curve_px", curve_px, "a run whose contour departs from its fitted line by more than this on average over a window (pixels) is kept as a curve: its contour, simplified, replaces the line (0 = off)", Check::at_least(0));
    v("curve_window_px", curve_window_px, "length of the windows over which a run's departure from its line is averaged (pixels)", Check::above(0));
    v("split_px", split_px, "a straight run whose contour is explained by parallel lines this far apart or more (pixels, and split_m; each part at least 4 times as long) becomes those lines joined by steps (0 = off)", Check::at_least(0));
    v("split_m", split_m, "the least offset between parallel parts of a run that splits it, in metres (the larger of this and split_px applies)", Check::at_least(0));
    v("split_max_residual", split_max_residual, "parts split a run only when they leave at most this share of its contour's spread about one line", Check::between(0, 1));
    v("split_max_rms_px", split_max_rms_px, "... and at most this RMS distance of the contour to the parts' lines (pixels)", Check::above(0));
  }
};

// Absorbs runs shorter than min_run_px pixel lengths into their longer neighbour, in place.
void absorb_short_runs(const Ring& ring, std::vector<int>& labels, double min_length);

// The corner ring of one contour ring. A curved run (see curve_px) keeps its contour, simplified
// by Douglas–Peucker to one pixel, between the lines of its neighbours. labels: per edge; directions: unit outward normals.
// Returns an empty ring and sets *problem when no polygon can be formed.
Ring extract_corners(const Ring& ring, const std::vector<int>& labels, const std::vector<Vec2>& directions,
                     double pixel_size, const CornerOptions& options, std::string* problem);

}  // namespace lodforge
