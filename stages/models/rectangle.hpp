// The simplest outline a building can have, as a model to choose against the chain's: an
// oriented rectangle with the contour's area, centroid and second moments along its axes (a
// rasterized rectangle's pixels have nearly the true rectangle's moments, whatever the noise on
// its boundary, so the fit needs no corner and no run: it holds on buildings of a dozen pixels),
// each side then moved onto the median of the contour nearest to it.
#pragma once
#include <optional>
#include <utility>
#include <vector>

#include "common/option.hpp"
#include "geometry/segment_grid.hpp"
#include "geometry/types.hpp"

namespace lodforge {

struct ModelOptions {
  double outline_tolerance = 0.5;    // in boundary-noise units: how much worse the regular outline may explain the contour
  double regular_fit_noise = 1.0;    // ... or when it explains the contour within this many times the noise
  double arc_noise_ratio = 3.0;      // the noise for the model choice: at most this many times the spread about parabolas along the runs
  double lattice_tolerance = 2.0;    // the lattice outline may explain the contour worse by this many standard errors
  double rescue_fit_noise = 1.0;     // ... and stands in for a failed chain within this many times the noise
  double lattice_fit_noise = 1.1;    // ... and, its lattice from the chords, is taken when it explains the contour within this many times the noise
  double lattice_fit_gap_noise = 1.0;  // ... and no worse than the chosen outline plus this many times the noise
  double noise_fit = 0.8;            // after the rectangle, the lattice outline against an outline that follows the contour closer than the noise's own mean distance, this many noises
  double noise_fit_reach_noise = 2.0;  // ... where it reaches no farther from the contour than that outline plus this many noises
  double noise_fit_min_px = 1.0;     // ... where the noise is at least this many pixels
  double stretch_fit_noise = 1.0;  // a wall off the lattice takes the lattice outline's walls where they explain its contour within this many noises of the regular outline
  double rectangle_tolerance = 1.0;  // ... and a rectangle, by a high percentile of the distances ...
  double rectangle_quantile = 0.95;  // ... this one
  double rectangle_stretch_noise = 6.0;  // ... and leaving no stretch of contour farther than the outline by this many standard errors
  double ellipse_turn_deg = 4.5;     // then a building becomes its moments' ellipse, a vertex every this many degrees of turn, where that explains its contour better
  double ellipse_rectangle_ratio = 3.0;  // ... and lies this many times as near it as its best rectangle
  double coarse_scale = 2.0;         // the lattice outline, as drawn and as if the noise were this many times (and its square) larger, competes
  double coarse_correlation_noise = 2.0;  // ... by an information criterion counting one sample per this many noises of contour
  bool lattice_more_vertices = true;  // ... whatever their vertices (off: only with fewer than the chosen outline)
  int staircase_corners = 4;         // then a staircase of this many square corners turning left and right in turn drawn as one oblique wall competes
  double staircase_square_deg = 10.0;  // ... a corner within this of 90 degrees counting as square
  int merge_patience = 8;            // then the chosen outline's steps merged one at a time, the walk going this many merges past its least criterion
  double merge_parallel_deg = 2.0;   // ... a step's two walls parallel within this (degrees)
  double criterion_stretch_noise = 20.0;  // ... none of those outlines taken that leaves a stretch of contour farther than the chosen outline by this many standard errors
  double square_noise = 3.0;         // last, a short oblique wall between two lattice walls becomes a square step or corner when its turn onto the lattice moves its ends by at most this many uncertainties
  double rounded_share = 0.5;        // then a building's rounded corners made sharp where at least this share of its square corners are rounded
  double rounding_noise = 2.0;       // then chains of oblique walls shorter than twice the segmentation's rounding radius squared, where the building's square corners lie farther than this many noises off its contour
  double tread_rounding = 0.41421356;  // ... and under that rounding R, a step's tread (its corners turning opposite ways) turned onto the lattice where that moves its ends by at most this many R
  double pooled_rounding_share = 0.5;  // ... and a building that measures no rounding of its own takes its mask's, where at least this share of its buildings measured one
  double rounded_criterion = 1.5707963;  // then, under the mask's rounding R, where the building measures one, the lattice outlines compete with the chosen one, all rounded by R, one sample of contour per this many R
  double rounded_stretch_noise = 6.0;  // ... none taken that leaves a stretch of contour farther than the chosen outline by this many standard errors
  double rounded_chain_scale = 2.0;  // ... and the chosen outline, its chains off the lattice squared as if the rounding were this many times as large, competes too
  double spike_deg = 20.0;           // last of all, a needle (a corner sharper than this) is taken away ...
  double spike_noise = 2.0;          // ... where that changes the area by no more than a square of this many noises (at least a pixel)
  double min_noise_px = 0.3;         // the noise assumed at least (a staircase's quantization)
  double fallback_fit_px = 0.5;      // a rectangle replaces a failed building's fallback when it fits within this ...
  double fallback_fit_ratio = 2.0;   // ... or this many times as far as the fallback (mean distances)

  template <class V>
  void visit(V& v) {
    v("outline_tolerance", outline_tolerance, "the regular outline (walls held to the lattice, steps and curves judged against the noise) is kept when it explains the contour (mean distance of the contour to it) no worse than the plain one (pixel thresholds) plus this many times the boundary noise", Check::at_least(0));
    v("regular_fit_noise", regular_fit_noise, "... or when it explains the contour within this many times the boundary noise (mean distance; the noise here taken as the spread of the contour's runs along the fitted lattice where that is more, lattice.fit_max_turn_deg, bounded by arc_noise_ratio), however closer the plain one follows it: at a few centimetres a pixel, the plain outline's thresholds of a few pixels follow a wobble of a metre, vertex by vertex (0 = off)", Check::at_least(0));
    v("lattice_tolerance", lattice_tolerance, "a building on a lattice gets the lattice outline (straight walls labeled among its main direction and quarter turns alone) when that has no more vertices than the chosen outline and explains the contour (mean distance) no worse than it plus this many standard errors of that mean: the boundary noise times sqrt(corners.snap_correlation_m / perimeter); 0 = never", Check::at_least(0));
    v("lattice_fit_noise", lattice_fit_noise, "a building whose lattice was taken from its contour's chords (its main direction followed a wobble's flank, see lattice.main_share_ratio) gets the lattice outline, when that has fewer vertices, if the contour lies within this many times the boundary noise of it (mean distance) however closer a more intricate outline follows it: under a wobble of many pixels, the plain outline follows the wobble (0 = off)", Check::at_least(0));
    v("lattice_fit_gap_noise", lattice_fit_gap_noise, "... and no worse than the chosen outline plus this many times the boundary noise (mean distances): a real wing the lattice outline leaves out costs more than a wobble", Check::at_least(0));
    v("noise_fit", noise_fit, "after the rectangle's test, a building on a lattice (not one from its chords, lattice_fit_noise) whose chosen outline, neither the lattice outline nor a rectangle, has more vertices than its lattice outline gets the lattice outline where that explains the contour (mean distance) no worse than the chosen outline or than the boundary noise alone would, this many noises, whichever is more, plus lattice_tolerance standard errors: a contour drawn closer than its noise (0.8: the mean distance to its line of a Gaussian noise, sqrt(2 / pi) of its standard deviation) is drawn along the noise, and the outline with fewer vertices explains it as well; unless it leaves a stretch of contour that the chosen outline explains (criterion_stretch_noise) or reaches farther (noise_fit_reach_noise), and only where the noise is at least noise_fit_min_px pixels. The noise is the one the building's steps are judged by (noise.pooled_ceiling), the standard errors lattice_tolerance's (of its regularity noise). (0 = off; off too where lattice_tolerance is 0, which draws no lattice outline)", Check::at_least(0));
    v("noise_fit_reach_noise", noise_fit_reach_noise, "... and where the lattice outline reaches no farther from the contour than the chosen outline plus this many boundary noises (the largest distance to the contour of the points a quarter and three quarters along each edge): a lattice outline whose walls meet beyond a corner the mask cuts at an angle", Check::at_least(0));
    v("noise_fit_min_px", noise_fit_min_px, "... and where the boundary noise is at least this many pixels: under a pixel a contour's deviations are its staircase and the steps of one or two pixels of real jogs, which an outline drawn along them does not follow as it follows a noise the pixels resolve (0 = at any noise)", Check::at_least(0));
    v("stretch_fit_noise", stretch_fit_noise, "a wall of the regular outline more than corners.snap_max_deg off the building's lattice is redrawn with the lattice outline's walls (the contour edges nearest to it labeled as the lattice labeling has them) when the lattice outline explains that stretch of contour no worse than the regular outline plus this many times the boundary noise (mean distances; the noise taken as the regular outline's own mean distance where that is less), and draws at most two walls along it (more only where it explains the stretch no worse than the regular outline): an oblique cut across a wobble or a notch becomes square walls, a real oblique wall or an arc, which a staircase would follow, stays (0 = off)", Check::at_least(0));
    v("rescue_fit_noise", rescue_fit_noise, "when the chain fails, the lattice outline stands in for the fallback if the contour lies within this many times the boundary noise of it (mean distance), or as close to it as to the fallback", Check::at_least(0));
    v("rectangle_tolerance", rectangle_tolerance, "a building becomes the oriented rectangle of its contour's moments when that explains the contour no worse than the regularized outline plus this many times the boundary noise (a high percentile of the distances of the contour to each, rectangle_quantile: a rectangle must follow the contour everywhere, not on average; 0 = off)", Check::at_least(0));
    v("rectangle_quantile", rectangle_quantile, "... that percentile, as a share (0.95: the rectangle may leave 5 % of the contour, by length, farther than the outline does plus the tolerance)", Check::between(0.5, 1));
    v("rectangle_stretch_noise", rectangle_stretch_noise, "... and when it leaves no stretch of contour that the outline explains: along no stretch (from corners.snap_correlation_m long, at least a pixel, doubling, to half the ring) may the contour lie farther from the rectangle than from the outline, on average, by more than this many standard errors of such a mean (the boundary noise times the square root of that correlation length over the stretch's length): a wing, a notch or the bow of an arc, metres long, that a percentile passes over (0 = off)", Check::at_least(0));
    v("arc_noise_ratio", arc_noise_ratio, "the boundary noise the model choice allows for (every tolerance in noises above) is at most this many times the contour's spread about parabolas fitted along the same runs of the lattice: a round building's contour lies metres off lattice lines, which is no noise, and a rectangle or a pentagon would explain it 'within the noise'; the floor min_noise_px still applies, and the outlines themselves (runs, steps, curves) are drawn with the noise as measured (0 = no bound)", Check::at_least(0));
    v("ellipse_turn_deg", ellipse_turn_deg, "after the outlines below, a building without holes becomes the ellipse of its contour's centroid, area and second moments, drawn with a vertex wherever its tangent has turned by this many degrees (4.5: 80 vertices, each turning by less than the 5 degrees eval counts as a corner; 8 to 360 vertices), its area pi a b, where that explains the contour better (mean distance, the ellipse's to first order) by an information criterion of the form coarse_scale's outlines compete by (five parameters against two a vertex; one sample of contour per coarse_correlation_noise of the model choice's noise, arc_noise_ratio), or, where the noise is its mask's (pooled), explains it within noise_fit noises or the outline's fit, plus lattice_tolerance standard errors (under noise_fit_min_px pixels of noise, the noise's part beyond the pixels' staircase, a pixel over the square root of 12, in quadrature: the lobes of a wobble under a pixel are still tens of pixels long), as the lattice outline is taken (noise_fit: a wobble of a few metres' wavelength around a disc of 10 m radius has as many lobes as an octagon has sides, which an outline of as many chords follows closer than the noise) and leaves out no stretch of it that the outline explains (rectangle_stretch_noise), unless the outline leaves one the ellipse explains. A building without a lattice (refinement.min_lattice_share) or, on one, long enough to show its shape (refinement.min_round_*: a wobble's flanks turn a round building's normals back and forth, and it reads as on a lattice). A round or oval building, whose runs the labeling cuts into chords of a few metres, each bowing less than the curve test sees at coarse pixels (corners.curve_px), is its curve, not a polygon of 7-11 chords; an octagon's or a pentagon's corners lie farther from their ellipse than the polygon's fewer parameters pay for (0 = off; at most 15, so that the steps after read it as an arc, three vertices in a row turning by under 20 degrees)", Check::between(0, 15));
    v("ellipse_rectangle_ratio", ellipse_rectangle_ratio, "... and where the contour lies at least this many times as near its ellipse as its best rectangle (mean distances; best_rectangle, the same five parameters): a disc's contour lies 0.07 of its radius from its best square, a small house whose corners a segmentation rounded or blurred about as near its rectangle as its ellipse (within twice on the campus's, blurred by 1 m or rounded by 2 m at 0.5 m), and stays a polygon. Under its mask's corner rounding (pooled_rounding_share; known after every building's first outline in regularize, when an ellipse drawn before is judged again), the rectangle rounded so: a house of 5 m under a rounding of 2 m is a disc in its mask. Where the noise is taken as above, each distance beyond the noise's own mean distance (noise_fit noises, in quadrature), the ellipse's at least lattice_tolerance standard errors (at most its distance): under a wobble of a metre a small house's blob lies within the noise of its ellipse and of its rectangle alike", Check::at_least(1));
    v("coarse_scale", coarse_scale, "the chosen outline competes with the lattice outline, as drawn and as if the boundary noise were this many times, and its square, as large (when the building has a lattice outline, the chosen one more than 4 vertices and no arc, three vertices in a row turning by 0.5-20 degrees, and within the time budget); one with a lower Bayesian information criterion replaces it, whatever its vertices (more pay for themselves only where they explain the contour better: a block's rear annexes, steps of a metre or two, drawn as square steps where the chain's outline cut a diagonal across them): n ln(d^2) + 2 ln(n) per vertex, d the contour's mean distance to the outline (at least a tenth of a pixel), n the contour's length over coarse_correlation_noise noises (at least a pixel; n at least 2). A wobble whose wavelength is a few times its amplitude cuts the contour into a run at each flank, measures too little noise and leaves its crests as notches; the criterion weighs the fit against the vertices rather than against that noise (docs/quality.md, a shorter wobble; 1 or less = off)", Check::at_least(0));
    v("coarse_correlation_noise", coarse_correlation_noise, "... the length of contour, in boundary noises, that counts as one independent sample for that criterion, which staircase_corners and merge_patience use too (about a wobble's correlation length)", Check::above(0));
    v("lattice_more_vertices", lattice_more_vertices, "... those lattice outlines competing whatever their vertices: one with more of them than the chosen outline is taken where it explains the contour enough better to pay for them (off: only those with fewer compete, as before session 58)");
    v("staircase_corners", staircase_corners, "after coarse_scale, under the same conditions and criterion: the chosen outline with every staircase (at least this many vertices in a row turning square, left and right in turn: a wall at an angle to the lattice drawn as steps) drawn as the line through the middles of its steps' walls, from the wall before it to the wall after, competes (0 = off; fewer than 3 count as 3)", Check::between(0, 1000));
    v("staircase_square_deg", staircase_square_deg, "... a corner within this of 90 degrees counting as square", Check::between(0, 45));
    v("merge_patience", merge_patience, "after staircase_corners, under the same conditions and criterion: the chosen outline's steps merged one at a time, the cheapest first (of three walls in a row whose first and last are parallel and face the same way, the two become one at their length-weighted mean offset; the cheapest moves the least area), each outline of that path competing; the walk stops once this many merges have passed without a new least criterion (the criterion is not monotone along it), and the least among its valid polygons is kept. What the wobble's crests leave as notches a metre wide the coarse lattice outline may not reach (0 = off)", Check::between(0, 1000));
    v("merge_parallel_deg", merge_parallel_deg, "... a step's two walls count as parallel within this (degrees)", Check::between(0, 45));
    v("criterion_stretch_noise", criterion_stretch_noise, "... and none of those simpler outlines (coarse lattice, staircases as lines, merged steps: of these, the last that passes) taken where it leaves a stretch of contour that the outline chosen before them explains, as rectangle_stretch_noise says, by this many standard errors: the criterion weighs the fit over the whole contour, and a block of row houses whose real setbacks are drawn as one oblique wall, or merged, still fits well on the whole (0 = off)", Check::at_least(0));
    v("square_noise", square_noise, "last, the chosen outline's walls off the building's lattice (farther than merge_parallel_deg) that lie between two walls on it are squared: drawn as a step square to those two at the wall's middle (the two facing the same way) or dropped for the corner where they meet (the two square to each other), when turning the wall onto the lattice moves its ends by at most this many times the uncertainty the boundary noise (its regularity's, noise.regularity_ceiling) leaves at the ends of a fitted line of its length, noise * sqrt(3 * corners.snap_correlation_m / length), as corners.snap_noise judges a run (3: its ends within three standard deviations of a square step's, the short oblique walls a structure drawn with the mask's noise leaves where a wobble blurs a step): a connector a few pixels long drawn across a step of a row of houses or a cut corner, whose direction the noise does not tell from the lattice's, becomes square walls (0 = off)", Check::at_least(0));
    v("rounded_share", rounded_share, "then the corners the segmentation rounded are made sharp, on a building (each of its rings) where at least this share of its square corners are rounded, two or more: a square corner is two walls at least corners.max_cut_m long meeting within corners.parallel_angle_deg of a right angle, directly or through one to twelve shorter walls, together shorter than max_cut_m, that lie inside the corner the two walls make (a step or a wing beside the corner does not; a small notch cut out of the corner does, as a rounding drawn as a step); a rounded one, met through such walls (an arc drawn as a cut or as a few walls), becomes the point where its two walls meet. A network rounds every corner of a building alike; a building's own cut or rounded corners are a few of its corners. Where rounding_noise measures the building's rounding, of radius R, the shorter walls may be up to 2.5 R long together (a rounding drawn as a staircase along its arc is 2 R long) where beyond max_cut_m the corner moves no more area than R^2 / 2 (0 = off; on an outline that draws an arc only under such a rounding, the building's or its mask's)", Check::at_least(0));
    v("rounding_noise", rounding_noise, "then, where the segmentation rounded the building's corners by more than its noise explains (its outline's square corners, as chosen: two walls at least two pixels and corners.snap_correlation_m long meeting within corners.parallel_angle_deg of a right angle, directly or through walls shorter than corners.max_cut_m together that lie inside the corner, each the point where the two walls' lines meet, lie at the median farther than this many times the boundary noise from its contour; a rounding of radius R leaves them R (sqrt 2 - 1) off it), a chain of one to twelve walls, one off the lattice at least, between two walls on the lattice at least as long as those corners' walls, is squared whatever the noise: between parallel walls a step where it keeps the area, where the chain spans less than 2 R along them and less than 3 R and that length across (a rounding spreads a step that far, and a higher one keeps a riser longer than R); between walls on about one line, a bump that leaves the line one way and comes back (spanning less than 4 R and that length along it, reaching less than 2 R and that length off it), a rectangle as deep as it reaches that keeps its area and centre, at least that length wide; between square walls, where the chain is shorter than 2 R together, the corner where that moves no more area than the triangle between a rounding's tangent points, R^2 / 2 (more: a step or a wing the rounding merged into the corner). A rounded step or corner of a metre or two is drawn with oblique walls that square_noise, judging by a noise of a few centimetres, keeps; --stats counts the buildings and their median radius (corner_rounding) (0 = off)", Check::at_least(0));
    v("tread_rounding", tread_rounding, "... and first, under that rounding, of radius R, the treads of the steps it rounded: a wall at least 2 R long whose corners turn opposite ways (a step's, or a staircase's: the rounding cuts its convex corner and fills its concave one, its fitted line tilted by up to R (sqrt 2 - 1) at each end; a wall whose corners turn alike, the side of a rectangle, is rounded alike at both ends and keeps its direction), more than merge_parallel_deg off the lattice, is turned about its middle onto the lattice where that moves its ends by at most this many R, its neighbours' lines meeting it there; the oblique risers left between treads on the lattice are then squared as above. Under a rounding of 1-2 m, the treads of a row of houses stepping by a metre, 5 m long, are fitted 6-11 degrees off the lattice (0 = off; sqrt 2 - 1: a rounding's offset at a corner)", Check::at_least(0));
    v("pooled_rounding_share", pooled_rounding_share, "... and a building that measures no rounding of its own (fewer than three square corners, or their median within rounding_noise noises of its contour) takes the rounding pooled over its mask, as if it had measured it: the median of its buildings' roundings, where at least this share of the buildings that measured one (three square corners or more) measured a rounding, and three did. A network rounds every building of a mask alike; a small or noisy building's own corners do not tell. Pooled over the whole mask in regularize, over the noise survey's windows in run (tiling.noise_survey_windows), so that every tiling and shard agrees; --stats gives it (corner_rounding.pooled_m) (0 = off)", Check::between(0, 1));
    v("rounded_criterion", rounded_criterion, "then, where the segmentation rounded the building's corners by a radius of its own (rounding_noise) and its mask's rounding R is known (pooled over the mask, pooled_rounding_share), the lattice outline and those drawn for a noise coarse_scale and its square times as large, each squared and cleaned as the chosen outline was, compete with it by an information criterion, n ln(d^2) + 2 k ln(n) (k vertices, d the contour's mean distance), every outline compared with the contour as the mask draws it, its corners rounded by R, one independent sample per this many R of contour (pi / 2: a rounding of a square corner departs from the polygon along its quarter circle, pi R / 2 long; where the noise a blur or a rounding leaves is a few centimetres, by which the outline that follows every rounded bump wins): the least taken. A row of houses whose fronts step by a metre, drawn as one oblique wall where a rounding of 2 m smoothed the steps, gets its steps back; staircases drawn along the roundings go (0 = off)", Check::at_least(0));
    v("rounded_stretch_noise", rounded_stretch_noise, "... none taken that leaves a stretch of contour farther than the chosen outline, both rounded so, by this many standard errors (the model noise over the square root of the stretch's samples): a real oblique wall or wing stays (0 = no such test)", Check::at_least(0));
    v("rounded_chain_scale", rounded_chain_scale, "... and so does the chosen outline with its chains off the lattice squared as rounding_noise squares them, as if the rounding were this many times as large (chains up to 2 R times this long, steps spanning 2 R times this along their walls, knobs 4 R times this): a building's own rounding is the median of a few corners, and a recess or a knob a metre deep that the rounding spread wide is drawn with oblique walls reaching past the rounding's arcs, which the rounding as measured leaves; squared, it competes by the same criterion, against the contour as the mask draws it, and stays only where it explains it better for its vertices (1 or less = off)", Check::at_least(0));
    v("spike_deg", spike_deg, "last of all, a needle of the chosen outline (a vertex where it turns back on itself, its corner sharper than this, degrees) is taken away: where one of its arms is a short wall (at most half the other) turning back at the end of a long one, the long wall's line and the line beyond the short one meet at their intersection; else the tip is dropped. Each change only where the outline stays valid and its area changes by no more than a square of spike_noise times the boundary noise (at least a pixel) on a side. Where two walls' lines meet past the end of one, at coarse pixels, a needle a pixel wide, which no building has (0 = off)", Check::between(0, 90));
    v("spike_noise", spike_noise, "... that square's side, in boundary noises", Check::at_least(0));
    v("min_noise_px", min_noise_px, "the boundary noise is taken as at least this (pixels; a staircase's own)", Check::at_least(0));
    v("fallback_fit_px", fallback_fit_px, "when the chain fails, the rectangle replaces the Douglas-Peucker fallback if the contour lies within this (pixels, mean distance) of it ...", Check::at_least(0));
    v("fallback_fit_ratio", fallback_fit_ratio, "... or within this many times the fallback's own mean distance to the contour", Check::at_least(0));
  }
};

// The rectangle with edges along `normal` and its quarter turn whose area, centroid and second
// moments about its axes are those of the ring (counter-clockwise), each side then moved to the
// length-weighted median offset of the ring's edge midpoints nearest to it: a side lies on its
// wall, where the moments alone would move a long wall out by an annex's share, or in by a
// notch's. Empty for a degenerate ring.
Ring moment_rectangle(const Ring& ring, const Vec2& normal);

// The grid over the rings' edges (SegmentGrid(edges, 24)): built into `own` for a polygon of few
// edges (an outline), else one of the last two of many edges (a building's contour, measured
// against again and again) kept on this thread where the rings are the same, bit for bit. Valid
// while `own` lives and until the next call (boundary_distances and corner_rounding_gap call it).
const SegmentGrid& grid_over(const std::vector<const Ring*>& rings, std::optional<SegmentGrid>& own);

// The distance of each of the ring's edge midpoints to the polygon's boundary, with the edge's
// length: (distance, length), per edge; and, when asked, the nearest of the polygon's edges to
// each (numbered along its outer ring, then along each hole; none for a polygon without edges; of
// edges at the same distance, the previous midpoint's nearest, else the first).
std::vector<std::pair<double, double>> boundary_distances(const Ring& ring, const PolygonWithHoles& polygon,
                                                          std::vector<std::size_t>* nearest_segments = nullptr);

// The length-weighted mean distance from the ring's edge midpoints to the polygon's boundary.
double mean_distance_to_boundary(const Ring& ring, const PolygonWithHoles& polygon);
// The same from boundary_distances' (distance, length) list (0 for an empty one).
double mean_distance(const std::vector<std::pair<double, double>>& distances);

// Whether along some stretch of the ring (cyclic; lengths from `correlation`, doubling, up to
// half the ring) the ring's mean distance to a simpler outline (`simple`) exceeds its mean
// distance to a finer one (`fine`) by more than k * noise * sqrt(correlation / length): the two
// per-edge (distance, length) lists of boundary_distances, for the same ring.
bool leaves_a_stretch(const std::vector<std::pair<double, double>>& simple, const std::vector<std::pair<double, double>>& fine,
                      double noise, double correlation, double k);

// The mean distance (mean_distance_to_boundary) of the ring to the ellipse of its centroid and
// second moments per unit area (drawn with 90 vertices); infinity for a degenerate ring or a
// clockwise one. A round building's contour lies near it; a rectangle's corners reach beyond it,
// its sides' middles lie inside it.
double moment_ellipse_fit(const Ring& ring);

// The distance of each of the ring's edge midpoints to that ellipse to first order, with the
// edge's length, as boundary_distances gives them: |f| / |grad f|, f = 0 on the ellipse (its
// error about d^2 / 2r at a distance d where the ellipse bends with radius r). Empty for a
// degenerate or clockwise ring.
std::vector<std::pair<double, double>> moment_ellipse_distances(const Ring& ring);

// That ellipse (the ring's centroid, area and second moments) as a counter-clockwise polygon with a
// vertex wherever its tangent has turned by turn_deg (8 to 360 vertices), its area the ellipse's:
// an arc's chords, each turning alike, not corners. Empty for a degenerate or clockwise ring.
Ring moment_ellipse(const Ring& ring, double turn_deg);

// The best moment rectangle of the ring over the candidate normals, its principal axes and
// every 3 degrees: the one whose boundary lies closest to the ring, its sides then moved onto
// the walls as moment_rectangle's are. *fit: its mean distance (mean_distance_to_boundary).
Ring best_rectangle(const Ring& ring, const std::vector<Vec2>& normals, double* fit);

// A ring as a segmentation that rounds corners by `radius` draws it (an opening and a closing by
// a disc): each corner an arc of that radius (eight chords) tangent to its two walls, the radius
// less where the tangent points would pass the middle of either wall; a polygon's rings so.
Ring rounded_ring(const Ring& ring, double radius);
PolygonWithHoles rounded_polygon(const PolygonWithHoles& polygon, double radius);

// A rectangle (4 vertices) grown, or shrunk, by the same offset on every side so that it has
// `area` once rounded by `radius` (rounded_ring): the rectangle a segmentation that rounds corners
// so drew a contour of that area from. A best rectangle's sides, each at the median of the contour
// nearest to it, lie inside the rounding's arcs: a house of 6 x 6 m under a rounding of 2 m, its
// walls' straight parts 2 m, comes out 5.5 m wide. Unchanged for any other ring, or a radius or
// area not above 0.
Ring grown_for_rounding(const Ring& rectangle, double radius, double area);

// Of the rectangle and the same grown for the rounding (grown_for_rounding, to the ring's area),
// the one whose rounding by `radius` lies nearer the ring (mean distance, *fit when asked): the
// sides at the median of the contour nearest to them, or outside the rounding's arcs. (Where the
// rounding measured is larger than the mask's, the grown one overshoots.)
Ring rectangle_under_rounding(const Ring& ring, const Ring& rectangle, double radius, double* fit = nullptr);

// best_rectangle's mean distance to the ring over the candidate normals; under a rounding (radius
// above 0) that of the rectangle as the mask rounds it (rectangle_under_rounding). Infinity for a
// degenerate ring.
double best_rectangle_fit(const Ring& ring, const std::vector<Vec2>& normals, double radius = 0);

}  // namespace lodforge
