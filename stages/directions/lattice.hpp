// The building's lattice (its main wall direction, up to quarter turns) from the chords of its
// contour. An addition to the paper: under a network's wobble (a boundary that swings by a metre
// over a few metres) the smoothed normals spread by tens of degrees and the labeled main direction
// follows a flank; a chord spanning several metres of contour averages the wobble out.
#pragma once
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "common/option.hpp"
#include "geometry/types.hpp"

namespace lodforge {

struct LatticeOptions {
  double chord_m = 16.0;        // chords span this much contour (m) ...
  double chord_share = 0.125;   // ... and at most this share of the ring's perimeter
  double smooth_deg = 6.0;      // the chords' angle histogram is smoothed by this (degrees)
  double window_deg = 15.0;     // chords within this of its peak are averaged
  double min_share = 0.45;      // the chords give a lattice when this share of them is near its peak ...
  double max_gap_deg = 5.0;     // ... and the labeled main direction is kept within this of it ...
  double main_share_ratio = 0.5;  // ... or with this ratio of the peak's share of the chords
  double fit_max_turn_deg = 10;    // the lattice fitted to the contour's runs, turned at most this far
  double fit_hysteresis_deg = 15;  // ... a run keeping its axis until a normal turns this past 45 degrees
  double fit_outlier_noise = 3;    // ... samples this many spreads off their run's line left out
  double fit_keep_uncertainty = 2; // ... and the labeled lattice kept within this many standard errors of it
  double fit_step_noise = 4;       // ... a run stepping by this many noises fitted piece by piece
  double neighbour_radius_m = 30;  // buildings within this (m, centre to centre) lend an undetermined one their lattice
  double neighbour_agreement = 0.8;  // ... where they agree on it this well (mean resultant of 4 x their angles)
  double neighbour_max_extent_m = 100;  // ... lent only by buildings whose box is at most this wide and tall (m)
  double neighbour_noise = 250;  // a building under this many noises is drawn on its neighbours' lattice too
  double undetermined_noise = 60;  // ... and one under this many has no lattice of its own: it takes theirs
  double support_turn_deg = 15;  // a building's outline is drawn again on the lattice with the most labeled contour this far off its own

  template <class V>
  void visit(V& v) {
    v("chord_m", chord_m, "the building's lattice is also read off chords of the contour spanning this much of it (m), which average a wobble out (0 = off: the labeled main direction alone)", Check::at_least(0));
    v("chord_share", chord_share, "... and at most this share of the ring's perimeter (a small building's chords stay on its walls)", Check::between(0, 0.5));
    v("smooth_deg", smooth_deg, "... their directions, modulo quarter turns, gathered in a histogram smoothed by this (degrees) ...", Check::between(0.1, 20));
    v("window_deg", window_deg, "... and averaged within this of its peak (degrees)", Check::between(0.1, 45));
    v("min_share", min_share, "the chords give the building a lattice when at least this share of them (by length) lies within window_deg of its peak (chords of a round building spread evenly: 2 window_deg / 90)", Check::between(0, 1));
    v("max_gap_deg", max_gap_deg, "the labeled main direction (the direction with the most labeled contour) stays the lattice when within this of the chords' (degrees) ...", Check::between(0, 45));
    v("main_share_ratio", main_share_ratio, "... or when its own share of the chords (within window_deg) is at least this ratio of the chords' peak's; less, it follows a wobble's flank and the chords' direction is taken", Check::between(0, 1));
    v("fit_max_turn_deg", fit_max_turn_deg, "the lattice the outline's walls are held to is fitted to the contour: one direction for every run along its axes (from the chords' direction when they give one, else the labeled main direction), each run with its own offset, which averages a wobble out over whole walls; the fit is taken when it turns at most this far from where it started (degrees; no fit, and the labeled lattice stays, when it turns farther, when fewer than two runs have a middle, or at 0 = off)", Check::between(0, 45));
    v("fit_hysteresis_deg", fit_hysteresis_deg, "... the contour cut into those runs where a smoothed normal turns this far past 45 degrees from its run's axis (a wobble's flank, up to 45 + this, does not cut a wall; a corner does) (degrees)", Check::between(0, 44));
    v("fit_outlier_noise", fit_outlier_noise, "... samples farther than this many spreads (the noise of the runs about their lines) from their run's line, and runs whose own RMS about it is over this many times the runs' median (a run stepping along row houses), left out of the fit (judged first about the direction the fit starts from, then about each fit)", Check::above(0));
    v("fit_step_noise", fit_step_noise, "... a run whose contour steps between parallel offsets (a row of houses set back in turn, under one label) fitted piece by piece, each piece its own offset, one slope: where the run lies more than twice the building's boundary noise (RMS) off a line along its axis (the walls of the lattice the fit starts from), cut where its steps are at least this many noises (and 2 pixels) apart, pieces at least 4 times that step long. A line through the steps tilts toward them (0 = off)", Check::at_least(0));
    v("neighbour_radius_m", neighbour_radius_m, "a building whose own lattice is undetermined (too small to show its walls under its mask's noise, undetermined_noise, or no rounder than its rectangle, refinement.round_fit_ratio; the neighbours' lattice within fit_keep_uncertainty standard errors of its fitted one; without a fit, its chords giving it none) takes the lattice of the buildings around it: those whose centres lie within this distance of its centre (where none does, those whose boxes come within half of it: a shed beside a long block) and whose chords give them a lattice, spanning at least 1 / tan(window_deg) pixels (shorter ones measure the pixel grid), weighted by that share times their perimeter (m, 0 = off). Under a metre of wobble a small house is a blob whose own direction is anyone's; its street's is not", Check::at_least(0));
    v("neighbour_agreement", neighbour_agreement, "... when they agree: the length of the weighted mean of their lattices' directions times four (as unit vectors) at least this (1: all alike)", Check::between(0, 1));
    v("neighbour_max_extent_m", neighbour_max_extent_m, "... and lent only by buildings whose outer ring's box is at most this wide and tall (m): a tiled run then finds every building that may lend to its own within a margin of neighbour_radius_m plus this around them, and lends what the whole mask would (0: no limit, tiles lend nothing)", Check::at_least(0));
    v("neighbour_noise", neighbour_noise, "a building whose outer ring is shorter than this many times the boundary noise pooled over the mask's buildings (noise.pooled_floor), held to a lattice of its own while its neighbours agree on one, is also drawn on theirs, from the same labels, and that outline taken where every wall of it lies on their lattice and it explains the contour no worse by the model choice's information criterion (its own lattice counted as a parameter more): a wobble as long as the building bends its whole blob and turns its walls together, and the lattice fitted to them (a shed of 4 x 2.5 m under half a metre of wobble is a blob whose walls lie up to 35 degrees off its street's), but a clean small house may stand askew to its street. A larger value tries more buildings, at the time of a second model choice each (0 = off)", Check::at_least(0));
    v("undetermined_noise", undetermined_noise, "a building whose outer ring is shorter than this many times the boundary noise pooled over the mask's buildings (noise.pooled_floor) is too small to show its own lattice under that noise: it takes its neighbours' where they agree on one (neighbour_*), without a second model choice. Between this and refinement.min_round_noise it is held to a lattice, its own unless (as a larger building) its walls do not show and its rectangle explains it as well as its ellipse (refinement.round_fit_ratio), its neighbours' otherwise only by neighbour_noise's test (a clean house of 5 x 4 m at 1 m pixels, 18 m round, 64 noises of its staircase's 0.28 m, may stand askew to its street) (0 = off)", Check::at_least(0));
    v("support_turn_deg", support_turn_deg, "the lattice that holds the most of a building's labeled contour (its directions within max_gap_deg of each other, up to quarter turns, one lattice) is also tried where it lies farther than this from the one its outline is held to (the single direction with the most labeled contour, its chords' or its fitted one: a street front of one direction outweighs each of the walls of two at right angles behind it, not both): its outline drawn on that lattice, from the same labels, is taken where it has no more vertices and explains the contour better by the model choice's information criterion (degrees; 0 = off)", Check::between(0, 45));
    v("fit_keep_uncertainty", fit_keep_uncertainty, "... and the labeled lattice (the main direction, or the chords' above) kept where it lies within this many standard errors of the fit (the spread correlated over corners.snap_correlation_m): a clean wall's labeled direction is exact", Check::at_least(0));
  }
};

// The chords' lattice: the peak of the length-weighted histogram, modulo quarter turns, of the
// directions of chords spanning min(chord_m, chord_share * perimeter) of each ring around each
// edge, refined by their mean within window_deg: a unit vector (any of the four), zero when the
// rings give no chord; and the share of the chords near the peak.
struct ChordLattice {
  Vec2 direction = Vec2::Zero();
  double share = 0;  // of the chords' weight, within window_deg of the histogram's peak
  std::vector<std::pair<double, double>> chords;  // each chord's direction times four (radians), weight

  // The share of the chords' weight within window_deg of a lattice.
  double share_at(const Vec2& lattice, double window_deg) const;
};
ChordLattice chord_lattice(const std::vector<Ring>& rings, const LatticeOptions& options);

// What a building may lend its neighbours: its chords' lattice, where they give one, and what
// weighs it.
struct LatticeLender {
  std::int64_t id = 0;  // the building's (its first pixel in raster order): a building lends to no one of the same id
  Vec2 centre = Vec2::Zero();  // of its outer ring's vertices
  Vec2 direction = Vec2::Zero();  // its chords' lattice (ChordLattice::direction)
  double share = 0;               // ... and their share near it
  double perimeter = 0;           // of its outer ring
  double extent = 0;              // the larger side of its outer ring's box (m)
  Vec2 low = Vec2::Zero(), high = Vec2::Zero();  // that box's corners
};
LatticeLender lattice_lender(std::int64_t id, const std::vector<Ring>& rings, const ChordLattice& chord);

// The distance from p to a lender's box (0 inside it).
double distance_to_box(const LatticeLender& lender, const Vec2& p);

// Points bucketed in square cells as wide as a radius, for those within the radius of another
// point (at most that far: the 3 x 3 cells around it). Points that are not finite are left out.
class PointsWithinRadius {
 public:
  PointsWithinRadius(std::vector<Vec2> points, double radius);
  // The indices of the points within the radius of p, ascending, into out (cleared first).
  void near(const Vec2& p, std::vector<std::size_t>& out) const;
  bool any_near(const Vec2& p) const;

 private:
  std::pair<long, long> cell_of(const Vec2& p) const;
  std::vector<Vec2> points_;
  double radius_;
  std::map<std::pair<long, long>, std::vector<std::size_t>> cells_;
};

// The lattice a building's neighbours lend it (a unit normal, zero: none), and whether they are
// those whose boxes, not centres, come within the radius.
struct NeighbourLattice {
  Vec2 direction = Vec2::Zero();
  bool from_boxes = false;
};

// Per building (centres and ids), the lattice its neighbours agree on (neighbour_radius_m,
// neighbour_agreement), none where none is within reach, none of them has a lattice of its own, or
// they disagree. The lenders that count: their chords giving them a lattice (min_share) and
// spanning at least 1 / tan(window_deg) pixels of pixel_size (a shorter chord, its ends on pixel
// corners, is turned up to window_deg by the pixel grid: a shed of a few pixels lends the grid's
// axes), their extent at most neighbour_max_extent_m, not the building itself (same id); those
// whose centres lie within the radius of its centre, or, where none does, those whose boxes come
// within half the radius of it, about as near as a near neighbour's walls (a shed beside a long
// block, whose centre is far). Each weighs its share times its perimeter. Deterministic: each sum
// runs over the lenders in order of id, whatever order they are given in.
std::vector<NeighbourLattice> neighbour_lattices(const std::vector<Vec2>& centres, const std::vector<std::int64_t>& ids,
                                                std::vector<LatticeLender> lenders, double pixel_size, const LatticeOptions& options);

}  // namespace lodforge
