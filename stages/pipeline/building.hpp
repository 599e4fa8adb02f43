// The per-building chain: contour rings in, LOD0 polygon with a status out. Pure computation:
// no I/O, no threads. Every failure is caught here and becomes a status with the fallback.
#pragma once
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "geometry/types.hpp"
#include "directions/lattice.hpp"
#include "labeling/mrf.hpp"
#include "pipeline/core_options.hpp"

namespace lodforge {

struct BuildingResult {
  PolygonWithHoles footprint;  // the LOD0 polygon (always valid)
  bool ok = true;              // false: footprint is the fallback
  std::string failed_stage;    // when !ok: which stage failed
  std::string reason;          // when !ok: why
  // Diagnostics.
  std::vector<Vec2> directions;  // final dominant directions (unit normals)
  EdgeLabels labels;             // per ring, per contour edge
  double alignment_rms_deg = -1, alignment_max_deg = -1;  // after deformation, if run
  int deformation_iterations = 0;
  int mesh_vertices = 0;         // of the deformation mesh, if one was built
  double noise_m = -1;          // the boundary noise measured on the contour (m), when labeled; at least the floor it was given
  double regularity_noise_m = -1;  // ... and held to noise.regularity_ceiling instead: what its regularity is judged by (m); the same
  double arc_noise_m = -1;      // ... and measured about parabolas along the same runs, which an arc does not inflate (m); the same
  std::string model;            // the outline chosen: "regular" (walls held to the lattice; also after its oblique
                                // walls are redrawn per stretch), "lines" (pixel thresholds), "lattice", "rectangle",
                                // "coarse_lattice" (the lattice outline drawn for a larger noise, models.coarse_scale),
                                // "staircase_lines" (its staircases drawn as oblique walls, models.staircase_corners),
                                // "merged_steps" (the chosen outline with steps merged, models.merge_patience),
                                // "ellipse" (its moments' ellipse, models.ellipse_turn_deg);
                                // empty for the fallback
  bool lattice_lent = false;    // its walls held to its neighbours' lattice (BuildingStart::neighbour_lattice)
  bool lattice_of_support = false;  // its outline drawn on the lattice with the most labeled contour (lattice.support_turn_deg)
  double rounding_m = 0;        // the radius the segmentation rounded its corners by, where its outline's square corners
                                // lie farther off the contour than its noise explains (models.rounding_noise; m), else 0
  int rounding_corners = -1;    // the square corners that rounding was measured on; -1: none measured (an outline off the
                                // lattice, or rounding_noise 0). Three or more: rounding_m is a measure
  bool rounding_pooled = false;  // it measured no rounding of its own and took its mask's (BuildingStart::mask_rounding_m)
  // Where its mask's rounding was not known yet (BuildingStart::mask_rounding_m < 0) and it
  // measured none of its own on an outline that can take one: the outline chosen before its last
  // step squared it, and what that step squared it with (take_mask_rounding); else none.
  struct Unsquared {
    PolygonWithHoles outline;
    CornerContext context;
  };
  std::optional<Unsquared> unsquared;
  // Where its mask's rounding was not known yet and it measured one of its own (so never with
  // unsquared, which is kept where it measured none): the outlines on
  // its lattice that compete with the chosen one under the mask's rounding
  // (chain::simplify_under_rounding, in take_mask_rounding), and its context; else none.
  struct RoundingCandidates {
    std::vector<std::pair<PolygonWithHoles, std::string>> outlines;
    CornerContext context;
  };
  std::optional<RoundingCandidates> rounding_candidates;
  // Where it was drawn as its ellipse and its mask's rounding was not known yet: the outline
  // chosen before the ellipse (its model, whether its lattice was lent), what the chain squared
  // with, and whether on a lattice, for take_mask_rounding to compare the ellipse with the
  // rectangle rounded so (chain::ellipse_under_rounding); else none.
  struct BeforeEllipse {
    PolygonWithHoles outline;
    std::string model;
    bool lattice_lent = false;
    CornerContext context;
    bool on_lattice = false;
  };
  std::optional<BeforeEllipse> before_ellipse;
  // Where its mask's rounding was not known yet and it was read as round (not held to its
  // lattice: its best rectangle, sharp, explains its contour less well than its ellipse; refinement
  // .round_fit_ratio): the lattice and noise that test took, for held_under_rounding to take it
  // again with the rectangle rounded as its mask rounds corners; else none.
  struct ReadRound {
    Vec2 lattice = Vec2::Zero();
    double noise_m = 0;
  };
  std::optional<ReadRound> read_round;
  std::string route;            // the chain's corner route taken: "original" or "deformed"; empty otherwise
  std::string note;             // when ok: why the route taken is not the one asked for (a budget), else empty
  // The holes of its contour that its footprint covers (covered_holes, set by whoever runs the
  // batch: after the raster's edge clips it): a courtyard a model draws filled (a rectangle, an
  // ellipse) or a hole drawn across the outline and left out (holes_that_fit). How many, their area (m^2).
  int holes_covered = 0;
  double holes_covered_m2 = 0;
  // Its holes covered, measured on its contour's rings (those it was regularized from).
  void count_covered_holes(const std::vector<Ring>& rings);
  // What its output's reason says: for the fallback, why; else its note, then the holes it covers.
  std::string remark() const;
  double seconds = 0;
  // ... of which: its start (the normals smoothed, the noise sampled: its share of the mask's
  // noise rounds too), its labeling (directions, noise, lattice), its outline (corner route and
  // model choice), each to its end or to where the chain failed in it; the rest is the
  // fallback's, where one was drawn.
  struct ChainSeconds {
    double start = 0, labeling = 0, outline = 0;
  } chain_seconds;
  // Time spent on its start outside the chain (its share of the mask's noise rounds), in both.
  void add_start_seconds(double s) {
    seconds += s;
    chain_seconds.start += s;
  }
  // Another run's times (the same building's, drawn before) added to this one's.
  void add_seconds(const BuildingResult& earlier) {
    seconds += earlier.seconds;
    chain_seconds.start += earlier.chain_seconds.start;
    chain_seconds.labeling += earlier.chain_seconds.labeling;
    chain_seconds.outline += earlier.chain_seconds.outline;
  }

  std::string status() const { return ok ? "ok" : "fallback"; }
};

// What one building's contour tells of the boundary noise of the mask it was traced from: its
// noise about the lattice of its contour's chords (lattice_noise; at most models.arc_noise_ratio
// times the spread about parabolas, as the model choice takes it), and the weight of that
// measure, the length of its contour (m; 0 when nothing was measured: a contour the chain does not
// take, or no run along the lattice long enough to measure on).
struct NoiseSample {
  double noise_m = 0;
  double weight_m = 0;
};

// The chain's first steps, which measure that sample on the way (when measure_noise): the
// buildings of a mask are started first, their samples pooled (pooled_noise_floor), and each then
// regularized from its start. (A run pools over a survey of its raster, and starts none.)
struct BuildingStart {
  std::vector<std::vector<Vec2>> normals;  // per ring, per edge: the smoothed outward normals (empty: not started)
  ChordLattice chord;                      // the lattice of the contour's chords
  NoiseSample sample;
  // The noise about the chords' lattice as lattice_noise measures it for the sample, and its arc
  // noise (the chain's own, where it follows the chords: not measured again); negative: unknown.
  double chord_noise_m = -1, chord_arc_noise_m = 0;
  double smoothing_noise_m = 0;  // the noise its normals are smoothed for; of an empty start, the noise the chain smooths for
  NeighbourLattice neighbour_lattice;  // the lattice of the buildings around it (neighbour_lattices)
  Ring cut;  // where the raster's edge cuts the building: the raster's extent (BuildingContour::cut), inside which alone its noise is measured
  double mask_rounding_m = 0;  // the corner rounding pooled over its mask (pooled_rounding), which it takes where it
                               // measures none of its own (models.pooled_rounding_share; 0: none; negative: not known
                               // yet, BuildingResult::unsquared kept for take_mask_rounding)
};
// smoothing_noise_m: the boundary noise pooled over the mask that the normals are smoothed for
// (smoothing.noise_neighbourhood; 0: none known). cut: BuildingStart::cut.
BuildingStart start_building(const std::vector<Ring>& rings, double pixel_size, const CoreOptions& options,
                             bool measure_noise = true, double smoothing_noise_m = 0, const Ring& cut = {});
// The same start with its normals smoothed again, for smoothing_noise_m, and its sample measured
// again (the chords' lattice does not depend on the normals). An empty start stays empty.
BuildingStart restart_building(const std::vector<Ring>& rings, double pixel_size, const CoreOptions& options, BuildingStart start,
                               double smoothing_noise_m);

// rings: [0] outer counter-clockwise, then clockwise holes, in map metres (from
// extract_contours). pixel_size: the raster's ground sampling distance in metres.
// noise_floor_m: the boundary noise the building is taken to have at least, pooled over its
// mask's buildings (0: its own, as measured). start: from start_building on the same rings and
// options, or empty (the chain starts itself, its normals smoothed for the start's
// smoothing_noise_m); the result is the same either way.
BuildingResult regularize_building(const std::vector<Ring>& rings, double pixel_size, const CoreOptions& options,
                                   double noise_floor_m = 0, BuildingStart start = {});

// The noise floor of buildings regularized together: noise.pooled_floor times the weighted
// median of their samples (0 when there are none, or noise.pooled_floor is 0).
double pooled_noise_floor(const std::vector<NoiseSample>& samples, const CoreOptions& options);

// Whether the building's result measured its corner rounding (models.rounding_noise on at least
// three square corners of its outline): a sample of pooled_rounding, rounding_m (0: its corners
// sharp within its noise; its own, whether it took its mask's or not).
bool measured_rounding(const BuildingResult& result);

// The corner rounding of buildings regularized together, from the roundings they measured
// (measured_rounding; 0 for sharp corners): the median of those above 0 where at least
// models.pooled_rounding_share of them are, and three; else 0 (or pooled_rounding_share 0).
double pooled_rounding(const std::vector<double>& measured_m, const CoreOptions& options);

// The building's outline squared again under its mask's rounding, pooled after the chain
// (pooled_rounding; BuildingStart::mask_rounding_m was negative), where it measured none of its
// own and kept its outline for it (result.unsquared, then cleared; rounding_pooled set where
// mask_rounding_m is above 0), and a building drawn as its ellipse compared with its rectangle
// rounded so (result.before_ellipse, then cleared; result.read_round cleared too, for
// held_under_rounding, which is asked first). The same outline as the chain given that rounding
// draws; its time added to the result's. Never throws: a failure leaves the outline the chain drew.
void take_mask_rounding(const std::vector<Ring>& rings, double pixel_size, const CoreOptions& options, double mask_rounding_m,
                        BuildingResult& result);

// Whether a building read as round while its mask's rounding was not known (result.read_round) is
// held to its lattice under that rounding, mask_rounding_m: its best rectangle rounded so explains
// its contour as well as its ellipse does (refinement.round_fit_ratio, round_fit_noise): a house
// of 5 x 5 m under a rounding of 2 m is a disc in its mask. Then its chain, run again with the
// rounding known (BuildingStart::mask_rounding_m), draws it on its lattice.
bool held_under_rounding(const std::vector<Ring>& rings, double pixel_size, const CoreOptions& options, const BuildingResult& result,
                         double mask_rounding_m);

// The regularizers the core offers, by name: "deformation" (the chain above, corner route in
// options.corners.route), "cgal" (CGAL Shape_regularization, options.cgal; the fallback when it
// fails), "douglas_peucker" (tolerance options.fallback.tolerance_m) and "none" (the raw
// contour, collinear vertices removed). The last two always succeed.
const std::vector<std::string>& regularizer_names();

// The same rings through a named regularizer (one of regularizer_names()). A failure inside is
// the building's status (ok false, stage, reason, the fallback footprint), never an exception.
// noise_floor_m, start: as for regularize_building (the chain alone uses them).
BuildingResult regularize_with(const std::string& regularizer, const std::vector<Ring>& rings, double pixel_size,
                               const CoreOptions& options, double noise_floor_m = 0, BuildingStart start = {});

// The fallback footprint: Douglas–Peucker of the raw rings, or the raw rings if that is invalid.
PolygonWithHoles fallback_footprint(const std::vector<Ring>& rings, double tolerance);

}  // namespace lodforge
