// Steps merged one at a time: the path of ever simpler outlines a model choice walks along.
#pragma once
#include <cstddef>
#include <optional>
#include <utility>
#include <cstdint>
#include <vector>

#include "geometry/types.hpp"

namespace lodforge {

// The outline with its cheapest step merged: of every three consecutive walls whose first and
// last are parallel (within parallel_deg) and face the same way (a step, or half of a notch), the
// one whose merge moves the least area (2 a c / (a + c) times their offset, a and c their
// lengths); the two walls become one at their length-weighted mean offset (which keeps the area
// where the walls before and after are square to it), met by those walls, two vertices fewer. A
// step whose merged wall would meet them within 10 degrees of parallel is passed over. None when
// no ring has a step to merge (a ring keeps at least four vertices: one of six vertices or more).
std::optional<PolygonWithHoles> merge_cheapest_step(const PolygonWithHoles& polygon, double parallel_deg);

// The outline with every staircase drawn as one oblique wall: a run of at least min_corners
// (fewer than 3 count as 3) vertices in a row that turn square (within square_deg of 90 degrees)
// and alternately left and right (a wall at an angle to the lattice, drawn as steps along it) is
// replaced by the line through the middles of its steps' walls (weighted by their lengths), from
// where it meets the wall before the run to where it meets the wall after; a run whose line meets
// those walls within 10 degrees of parallel, or farther from the run than its length, stays.
// None when no run is replaced.
std::optional<PolygonWithHoles> staircases_as_lines(const PolygonWithHoles& polygon, int min_corners, double square_deg);

// The outline with its short oblique walls squared: a wall off the lattice (farther than on_deg
// from its main direction and quarter turns) between two walls on it is drawn as a step along
// the lattice at its middle where those two lie along the same axis and face the same way (the
// area kept), or dropped for the corner where they meet where they lie along square axes, when
// its direction is not told apart from the lattice's under the boundary noise: turning it about
// its middle onto the nearest axis moves its ends by at most k times the uncertainty a noise of
// standard deviation `noise`, correlated over `correlation`, leaves at the ends of a fitted line
// of its length L, noise sqrt(3 correlation / max(L, correlation)) (the rule corners.snap_*
// applies to the runs; k = 0: no such test). (A corner moves the outline farther than that turn,
// up to L sin cos of the wall's angle off the lattice.) Also, whatever the noise, a chain of one
// to twelve walls shorter than max_chain together, one off the lattice at least, between two walls
// on it at least min_wall long (where the segmentation rounded a step's or a corner's corners;
// short walls on the lattice within the chain are its steps): a step where it keeps the area
// between the chain and the two walls' lines, or the corner; none between walls on one line (a
// notch or a knob); the area a corner moves is at most a rounding's of radius max_chain / 2
// between its tangent points. Ring by ring, each kept where the polygon stays valid with it; none
// when no wall is squared.
std::optional<PolygonWithHoles> square_connectors(const PolygonWithHoles& polygon, const Vec2& lattice, double on_deg,
                                                  double noise, double correlation, double k, double max_chain, double min_wall);

// The treads of the steps a segmentation rounded by `radius` R, turned onto the lattice: a wall at
// least 2 R long whose corners turn opposite ways (a step's, or a staircase's tread: the rounding
// cuts its convex corner and fills its concave one, up to R (sqrt 2 - 1) each, and its fitted line
// tilts by up to that at each end), more than on_deg off the lattice and not square (within
// on_deg) to both its neighbours, turned about its middle onto the nearest axis where that moves
// its ends by at most shift_ratio R (sqrt 2 - 1: the rounding's offset). A wall between two
// treads turned onto parallel axes is drawn square to them through its middle (a staircase's
// riser). The corners where the walls' lines then meet, each within 2 (shift_ratio + 1) R of the
// old one, every wall keeping its sense; all the ring's treads at once, else one by one, each
// kept where the ring stays valid. A wall whose corners turn alike (a side of a rectangle) is
// rounded alike at both ends and keeps its direction. The oblique risers left between a tread and
// a wall on the lattice are then square_connectors' (a chain shorter than 2 R). Only where the
// outer ring's longest wall lies on the lattice (within on_deg); ring by ring, each kept where
// the polygon stays valid with it; none when no wall is turned.
std::optional<PolygonWithHoles> level_rounded_treads(const PolygonWithHoles& polygon, const Vec2& lattice, double on_deg,
                                                     double radius, double shift_ratio);

// How far the outline's square corners lie from the contour, at the median, where that is
// farther than least_gap (else 0): its corners where two walls at least min_wall long meet within
// square_deg of a right angle, directly or through walls shorter than max_cut together that lie
// inside the corner (as sharpen_rounded_corners finds them, there with walls at least max_cut
// long), each the point where the two walls' lines meet. A segmentation that rounds corners by a radius R leaves them R (sqrt 2 - 1) off the
// contour; a sharp corner lies within the boundary noise of it. 0 with fewer than three such
// corners. *corners (when given): how many there are.
double corner_rounding_gap(const PolygonWithHoles& outline, const std::vector<Ring>& contour, double min_wall, double max_cut,
                           double square_deg, double least_gap, std::size_t* corners = nullptr);

// The corners the segmentation rounded made sharp, on rings where most square corners are: a
// square corner is two walls at least max_cut long meeting within square_deg of a right angle,
// directly or through one to twelve shorter walls, together shorter than max_cut, whose vertices all
// lie inside the corner the two walls make (on the inner side of both walls' lines, no farther
// from where they meet than the shorter walls are long together; a step or a wing beside the
// corner lies outside one of the lines); it is rounded when it meets through such walls (an arc drawn as a cut or as
// a few walls along it; a small notch cut out of the corner looks the same). Where at least
// min_share of a ring's square corners are rounded, and two or more, every rounded one becomes
// the point where its two walls meet: a segmentation network rounds every corner of a building
// alike, where a building's own cut, rounded or notched corners are a few of its corners
// (models.rounded_share). Under a rounding of the segmentation's measured (radius > 0: its radius,
// corner_rounding_gap), the shorter walls may be up to 2.5 radii long together (a rounding drawn
// as a staircase along its arc is two radii long), where beyond max_cut their corner moves no
// more area than radius^2 / 2 (the triangle between a rounding's tangent points). Ring by ring,
// each kept where the polygon stays valid; none when no corner is sharpened.
std::optional<PolygonWithHoles> sharpen_rounded_corners(const PolygonWithHoles& polygon, double max_cut, double square_deg,
                                                        double min_share, double radius = 0);

// The same merges one after another, with the contour's mean distance to the outline (each
// contour edge's midpoint to the nearest wall, weighted by the edge's length: contour_fit) kept
// up to date: a merge changes five walls, so only the midpoints nearest them are measured again,
// the others against the three new walls alone, and of those only the ones in a cell of a grid
// over the midpoints that may lie nearer a new wall than the farthest of the cell's distances.
class StepPath {
 public:
  StepPath(const std::vector<Ring>& contour, PolygonWithHoles outline, double parallel_deg);
  // Merges the cheapest step; false (and the outline unchanged) when none is left.
  bool merge_next();
  const PolygonWithHoles& outline() const { return outline_; }
  double fit() const;

 private:
  void measure(std::size_t point, const int (&first)[3]);  // against every wall, these first
  // Midpoint p's distance again after a merge: against the three new walls, or (moved: its
  // nearest wall changed) every wall where those are farther than it was.
  void update(std::size_t p, bool moved, const int (&changed)[3]);
  void index_midpoints();

  // The grid: cells of cell_ metres from low_, nx_ a row; per cell its midpoints
  // (cell_items_[cell_start_[c] .. cell_start_[c + 1])), their box, and a bound on their distances
  // (at least the largest; infinite for one not a number). Empty (no grid) where a midpoint is
  // not finite.
  double cell_ = 0;
  Vec2 low_ = Vec2::Zero();
  long nx_ = 0, ny_ = 0;
  std::vector<std::size_t> cell_start_, cell_items_, cell_of_;
  std::vector<Vec2> cell_low_, cell_high_;
  std::vector<double> cell_bound_;
  double bound_ = 0;                           // at least every cell's bound
  std::vector<std::vector<std::size_t>> members_;  // by wall id: midpoints that had it nearest (those still do among them)
  std::vector<std::uint32_t> seen_;            // per midpoint: the merge that updated it last
  std::uint32_t merges_ = 0;

  double cos_parallel_;
  PolygonWithHoles outline_;
  std::vector<std::vector<int>> wall_ids_;      // per ring, per vertex: the wall from it to the next
  std::vector<std::pair<Vec2, Vec2>> walls_;    // by id
  std::vector<char> alive_;                     // by id
  std::vector<Vec2> midpoints_;                 // of the contour's edges
  std::vector<double> weights_, distances_;     // their lengths, their distances to the outline
  std::vector<int> nearest_;                    // their nearest wall's id
  std::vector<std::size_t> ring_starts_;        // the first midpoint of each contour ring, and their count last
  std::vector<double> perimeters_;              // of each contour ring
};

}  // namespace lodforge
