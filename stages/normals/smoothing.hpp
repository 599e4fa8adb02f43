// Stage 2: bilateral smoothing of edge normals along the contour (paper eq. 1–2).
#pragma once
#include <vector>

#include "common/option.hpp"
#include "geometry/types.hpp"

namespace lodforge {

struct SmoothingOptions {
  double sigma_d_m = 0.5;        // distance width of eq. 2 (m)
  double sigma_a_deg = 10.0;     // angle width of eq. 2 (degrees)
  double neighbourhood_m = 0.5;  // thre_d: neighbours closer than this along the contour (m)
  double min_neighbourhood_px = 5.0;  // on coarse rasters, widen both to this many pixels
                                      // (the paper's 0.5 m at its 9 cm pixels is 5.5 px)
  double max_neighbourhood_m = 2.5;     // ... but at most this (m): walls this short keep their own normals
  double least_neighbourhood_px = 2.0;  // ... the bound never narrowing it below this many pixels
  double noise_neighbourhood = 6.0;     // at least this many boundary noises (up to max_neighbourhood_m)
  int noise_rounds = 3;                 // ... the noise pooled over a mask, smoothed for, in this many rounds at most
  double noise_gain = 0.1;              // ... a wider round kept where it pools this much more noise
  int noise_gain_buildings = 128;       // ... judged on this many of the mask's buildings
  int passes = 3;                // one pass leaves a wall as two clusters (NOTES.md)
  double block_neighbours = 8;   // where the neighbourhood spans more edges, edges smoothed in blocks

  template <class V>
  void visit(V& v) {
    v("sigma_d_m", sigma_d_m, "distance width sigma_d of eq. 2 (m)", Check::above(0));
    v("sigma_a_deg", sigma_a_deg, "angle width sigma_a of eq. 2 (degrees)", Check::above(0));
    v("neighbourhood_m", neighbourhood_m, "thre_d: neighbours along the contour closer than this (m)", Check::at_least(0));
    v("min_neighbourhood_px", min_neighbourhood_px, "lower bound of thre_d and sigma_d in pixels, for coarse rasters", Check::at_least(0));
    v("max_neighbourhood_m", max_neighbourhood_m, "upper bound of that widening in metres: on coarse rasters (pixels over 0.5 m) min_neighbourhood_px pixels would average the normals of walls shorter than this, which then get no direction of their own (0 = no bound)", Check::at_least(0));
    v("least_neighbourhood_px", least_neighbourhood_px, "... the bound never narrowing the widening below this many pixels (a staircase needs two edges to show its wall's direction)", Check::at_least(0));
    v("noise_neighbourhood", noise_neighbourhood, "thre_d and sigma_d widened to at least this many times the boundary noise pooled over the mask (noise.pooled_floor), up to max_neighbourhood_m: a wall's direction read over a shorter stretch of a contour that wobbles by that noise is the wobble's (a flank of a fast wobble, tens of degrees off the wall), and the labeling follows it (docs/quality.md, a shorter wobble; 0 = off)", Check::at_least(0));
    v("noise_rounds", noise_rounds, "... the mask's noise measured on normals smoothed for the noise of the round before, from none, until the neighbourhood it asks for widens by 5 % or less, in this many rounds at most (a contour smoothed too little measures too little noise: a fast wobble's flanks cut its runs short; 1 = the first round alone, smoothed for no noise)", Check::between(1, 10));
    v("noise_gain", noise_gain, "... and a wider round kept only where the noise it pools is more than the narrower round's by this fraction: where the narrower smoothing measured the noise whole (a wobble long against its amplitude), the wider one only averages short walls away", Check::at_least(0));
    v("noise_gain_buildings", noise_gain_buildings, "... that gain judged on this many of the buildings, spread evenly over the mask's (all of a mask of fewer), their noise pooled both ways, and a kept round's noise, which the next round smooths for, pooled over them too: only the last round kept smooths the others (a round judged then costs a mask of thousands little; its time, kept or dropped, is charged to the buildings judged)", Check::at_least(1));
    v("passes", passes, "number of smoothing passes", Check::between(1, 100));
    v("block_neighbours", block_neighbours, "where thre_d spans more than twice this many contour edges (fine pixels, a wide noise), consecutive edges are smoothed as blocks of at least thre_d / block_neighbours metres (closed at the edge that reaches it), their normals summed by length, and each edge takes the normal interpolated between the two blocks about it: the same neighbourhood read at about block_neighbours samples a side (6-7 with the blocks' overshoot), not one an edge, for a fraction of the time (0, or under 1 = every edge)", Check::at_least(0));
  }
};

// Outward unit normals of every edge of a ring.
std::vector<Vec2> edge_normals(const Ring& ring);

// The neighbourhood thre_d along the contour (m) that smooth_normals uses at this pixel size for
// a boundary noise of noise_m (0: none known); sigma_d is widened in the same ratio.
double smoothing_neighbourhood_m(double pixel_size, const SmoothingOptions& options, double noise_m = 0);

// Smoothed normals of every edge of one ring. pixel_size in metres; noise_m: the boundary noise
// pooled over the ring's mask, when known (noise_neighbourhood).
std::vector<Vec2> smooth_normals(const Ring& ring, double pixel_size, const SmoothingOptions& options, double noise_m = 0);

}  // namespace lodforge
