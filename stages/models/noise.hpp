// How noisy a building's contour is. The contour is cut into runs along the building's lattice
// (each edge takes the nearest of its main direction and quarter turns, by its smoothed normal;
// runs shorter than a wall are absorbed), each run is fitted by a line of its own direction held
// near its lattice direction, and the noise is the spread of the contour about those lines. A wall traced exactly by pixels
// leaves its staircase (~0.3 px); a segmentation network's wobble its own amplitude, since a line
// held near the lattice cannot tilt to follow it; oblique walls, arcs and corners, which a lattice
// line does not fit, are left out by taking a low quantile of the distances.
#pragma once
#include <optional>
#include <vector>

#include "common/option.hpp"
#include "directions/lattice.hpp"
#include "geometry/types.hpp"

namespace lodforge {

struct NoiseOptions {
  double min_run_m = 2.0;  // lattice runs shorter than this join their neighbours (m)
  double trim_m = 1.0;     // edges this close to a run's end are left out (rounded corners) (m)
  double quantile = 0.3;   // the distances' quantile (by length) read as that of a Gaussian's
  double max_tilt_deg = 5; // a run's line turns at most this far from its lattice direction
  double pooled_floor = 1; // a building's noise is at least this many times that pooled over its mask
  double pooled_ceiling = 1;  // ... and at most this many times (0 = no ceiling)
  int pooled_whole = 10;      // the buildings the raster's edge cuts are left out of the pool where this many others measure
  double regularity_ceiling = 2;  // the noise a building's regularity is judged by: its own, up to this many times the pooled one
  double ceiling_staircase_px = 0.3;  // ... each ceiling at least the pooled noise and this staircase in quadrature (pixels)
  double coarse_resolved_px = 5;  // the mask's noise measured on it averaged to twice the pixel, taken where this many pixels
  double coarse_max_m = 1;        // ... tried where that many pixels are at most this (m)

  template <class V>
  void visit(V& v) {
    v("min_run_m", min_run_m, "when the boundary noise is measured: runs along the building's lattice shorter than this join their neighbours (m)", Check::at_least(0));
    v("trim_m", trim_m, "... and edges this close to a run's end are left out, where corners are rounded (m)", Check::at_least(0));
    v("max_tilt_deg", max_tilt_deg, "... each run fitted by a line of its own direction, turned at most this far from its lattice direction (degrees)", Check::between(0, 45));
    v("pooled_floor", pooled_floor, "every building's boundary noise is taken as at least this many times the noise pooled over its mask's buildings (all of them in regularize; in run, those of the survey, tiling.noise_survey_*): the median, weighted by outline length, of each one's noise about the lattice of its contour's chords. A segmentation's noise is its mask's, not a building's: a small building's walls, shorter than a wobble's wavelength, and runs cut short at fine pixels measure too little of it (0 = off)", Check::at_least(0));
    v("pooled_ceiling", pooled_ceiling, "... and at most this many times the noise pooled over its mask's buildings (and never below the floor, nor below ceiling_staircase_px; 1: every building's noise is its mask's). This noise judges the building's structure: which steps and offsets of its contour are walls of their own (corners.split_*, corners.merge_*, the zigzags, the shortest run) and how closely the model choice's outlines must follow the contour. A building's own measure above its mask's is its structure's more than its noise's: the steps of a row of houses, a sawtooth of bays, arcs, which a noise that large takes for noise and draws as one wall (on masks of one wobble the buildings' own measure reaches 1.4-2.3 times the pooled one at the 95th percentile, bench/sweep.sh's synthetic city; on clean masks 3.5-4.3; a ceiling of 2 drew Delft's stepped rows and sawtooth bays as single walls, docs/quality.md). Its regularity is judged by its own measure still (regularity_ceiling). Only where the floor applies (pooled_floor above 0 and a pooled noise measured; 0 = no ceiling)", Check::at_least(0));
    v("pooled_whole", pooled_whole, "the noise is pooled over the buildings the raster's edge does not cut where at least this many of them measure it: a cut building is measured on its part inside the raster, beside the walls its trace was swept out on across the edge (contour.edge_sweep_m), which the measure leaves out; where a mask holds enough whole buildings they measure the noise alone (on Delft's real mask, 38 whole beside 17 cut: all of them pooled 0.233 m, the whole ones alone 0.252 m). Fewer (a small tile, most of it cut): every building pools (0 = always every building)", Check::at_least(0));
    v("regularity_ceiling", regularity_ceiling, "the noise a building's regularity is judged by: its own measure, at least its boundary noise (pooled_floor, pooled_ceiling) and at most this many times the pooled one (at pooled_ceiling or below: the boundary noise itself; never below ceiling_staircase_px): how far a wall may turn onto the building's lattice (corners.snap_*), which short oblique walls are squared (models.square_noise), whether a run bows as an arc (corners.curve_*), and how much worse the lattice outline and the rectangle may explain the contour (models.lattice_*, models.rectangle_*). Where a building's wobble is larger than its mask's median (a wobble's amplitude varies along a mask), its walls' directions are as much less sure; beyond this it is structure (0 = the boundary noise)", Check::at_least(0));
    v("ceiling_staircase_px", ceiling_staircase_px, "... each of those ceilings at least the pooled noise and a staircase of this many pixels added in quadrature: a wall's pixel staircase depends on its angle to the grid (none along it, about 0.3 px across a diagonal), so at coarse pixels a building's own measure differs from its mask's median by its walls' angles, not its structure (0 = none)", Check::at_least(0));
    v("coarse_resolved_px", coarse_resolved_px, "the noise pooled over the mask is first measured on the mask averaged to twice its pixel (each 2 x 2 block a building where at least half of it is), in the same rounds; where the median it pools comes out at least this many of the mask's own pixels, it is the mask's noise, and the normals are smoothed for what it smoothed for (at least as wide as the averaged mask's narrowest smoothing): at a pixel that fine against a fast wobble the wobble's flanks cut the runs short and the noise measures low (0.27 m at 0.1 m against 0.53 m at 0.2 m on bench/sweep.sh's campus under a metre of wobble at a 2 m wavelength; docs/quality.md). Else it is measured at the pixel (0 = always at the pixel)", Check::at_least(0));
    v("coarse_max_m", coarse_max_m, "... tried only where coarse_resolved_px pixels are at most this (m): a boundary noise of more than a metre is no building's, and the coarser measurement would be time lost (0 = never tried)", Check::at_least(0));
    v("quantile", quantile, "the noise is the distances' quantile of this share (by length), read as that of a Gaussian noise: low, so that oblique walls and arcs, off the lattice lines, do not count", Check::between(0.05, 0.95));
  }
};

// The boundary noise of a building (map units): the standard deviation of the Gaussian noise
// whose |x| has, at `quantile`, the length-weighted quantile of the distances of the contour's
// edge midpoints to their lattice run's line. normals: per ring, per edge, the smoothed outward normals;
// lattice: the building's main wall direction (unit normal). *arc_noise, when asked: the same
// measure about a parabola fitted across each run's line, which an arc's spread does not inflate
// (a round building's contour, far from lattice lines, measures a "noise" of metres about them).
// *measured, when asked: the length of contour the distances were taken on (0: no run to measure
// on, and the noise 0 says nothing). within (optional, a convex ring): only the edges whose
// midpoints lie inside it, a pixel or more from its sides, count (a building the raster's edge
// cuts, traced swept out across it: the sweep's walls hold no noise; BuildingContour::cut).
double lattice_noise(const std::vector<Ring>& rings, const std::vector<std::vector<Vec2>>& normals, const Vec2& lattice,
                     double pixel_size, const NoiseOptions& options, double* arc_noise = nullptr, double* measured = nullptr,
                     const Ring* within = nullptr);

// The building's lattice fitted to its contour: the contour cut into runs along the axes of
// `start` (a run keeps its axis until a smoothed normal turns lattice.fit_hysteresis_deg past 45
// degrees from it: a wobble's flank does not cut a wall, a corner does), their middles (ends
// trimmed by noise.trim_m) turned onto one axis, and one direction fitted to all of them, each
// run with its own offset, by total least squares, three times: samples farther than
// lattice.fit_outlier_noise spreads from their run's line, and runs whose own RMS about it is
// over lattice.fit_outlier_noise times the runs' median (a run stepping along row houses), leave
// the fit; before the first fit they are judged about `start` (a fit with an oblique wall in,
// which a run took in, turns toward it, and its spread keeps it in). A wall's direction averages
// its wobble out over its whole length, where a labeled direction follows a flank. No fit (nullopt) when fewer than two runs have a middle, the runs
// leave fewer than 3 points to spare, or the fit turns more than lattice.fit_max_turn_deg from
// `start`. When fitted: *uncertainty, the standard error of its direction (radians), the spread
// taken as correlated over correlation_m; *spread, the runs' spread about their lines (map
// units, read as lattice_noise reads its distances, at noise.quantile); both 0 otherwise.
// step_noise_m (the building's boundary noise; 0 = not given): a run stepping between parallel
// offsets by lattice.fit_step_noise times that is fitted piece by piece, each its own offset.
std::optional<Vec2> fit_lattice(const std::vector<Ring>& rings, const std::vector<std::vector<Vec2>>& normals,
                                const Vec2& start, double pixel_size, const LatticeOptions& lattice,
                                const NoiseOptions& noise, double correlation_m, double* uncertainty = nullptr,
                                double* spread = nullptr, double step_noise_m = 0);

}  // namespace lodforge
