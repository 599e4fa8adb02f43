// The chain's model choice (after its labeling, docs/models.md and docs/paper-reading.md): the
// regular outline (walls held to the building's lattice, steps and curves judged against the
// noise) or the plain one (the paper's corners with pixel thresholds), the lattice outline (every
// wall on the lattice), the moment rectangle, the lattice outline in place of an outline drawn
// closer to the contour than its noise leaves it, the regular outline's oblique stretches redrawn on
// the lattice, simpler outlines by an information criterion (the coarse lattice outline, the
// staircases drawn as lines, the steps merged); last the short connectors squared and the needles
// taken away, and, under its mask's rounding, the lattice outlines against the outline once more.
// Not a public interface: pipeline/building.cpp's chain calls it.
#pragma once
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "corners/corners.hpp"
#include "directions/refine.hpp"
#include "geometry/types.hpp"
#include "labeling/mrf.hpp"
#include "pipeline/building.hpp"

namespace lodforge::chain {

// What the chain's labeling hands the model choice.
struct LabeledBuilding {
  const std::vector<Ring>& rings;      // the contour (map units)
  const std::vector<Ring>& fit_rings;  // the rings the outlines are fitted to: less origin (deformed on that route)
  Vec2 origin;
  double pixel_size;
  const EdgeLabels& labels;  // per ring, per edge, into the chain's directions (input.directions, result.directions; the
                             // model choice may label again, relabel_with_missing_axis, and draw from those labels)
  LabelingInput& input;      // the normals, lengths and directions labeled; the lattice outline's labeling takes it over
  CornerContext context;     // the building's lattice (zero: none) and noise, its mask's noise
  bool on_lattice;           // its walls are held to a lattice (not a round or oblique shape)
  bool follow_chords;        // that lattice is its contour's chords' (a wobble took the labeled one off the walls)
  double fit_spread;         // the runs' spread about the lattice fitted to them (lattice.fit_*; 0: none)
};

// The building's outline and its model into result.footprint and result.model (result.noise_m,
// arc_noise_m, directions and lattice_lent as the chain set them). Throws StageError where no
// outline can be drawn.
void choose_outline(const LabeledBuilding& building, const CoreOptions& o, const std::function<bool()>& over_budget,
                    BuildingResult& result);

// Its last step: the chosen outline's short connectors squared and the corners the segmentation
// rounded made sharp (under the building's rounding, measured here on the outline: rounding_m
// and rounding_corners; or, where it measures none and can take one, its mask's,
// context.mask_rounding above 0: rounding_pooled), then the needles taken away. on_lattice: its
// walls held to context.lattice.
void square_and_clean(const std::vector<Ring>& rings, double pixel_size, bool on_lattice, const CornerContext& context,
                      const CoreOptions& o, BuildingResult& result);

// Under its mask's corner rounding (m), where the building measured one of its own: the
// candidates (outlines on its lattice, with their models' names; and the chosen outline with its
// chains off the lattice squared as if the rounding were models.rounded_chain_scale times as
// large, under its own model's name), each squared and cleaned as above, against the chosen
// outline by an information criterion (n ln(d^2) + 2 k ln(n), k its vertices), every outline compared with the contour as the mask draws it, its corners rounded
// so (d: the contour's mean distance to it), one independent sample of contour per
// models.rounded_criterion roundings (a rounding's departure from a polygon spans its arc, where
// the noise the mask's blur leaves is a few centimetres). The candidate of least criterion, where
// less than the chosen outline's, is taken unless it leaves a stretch of contour the chosen one
// explains (models.rounded_stretch_noise); its model, and its rounding_* as its own squaring
// measured them, with it.
void simplify_under_rounding(const std::vector<Ring>& rings, double pixel_size, const CornerContext& context, const CoreOptions& o,
                             double rounding, std::vector<std::pair<PolygonWithHoles, std::string>> candidates, BuildingResult& result);

// A building drawn as its ellipse before its mask's corner rounding (m, above 0) was known: the
// outline drawn before the ellipse (before), squared and cleaned under that rounding, where the
// contour's rectangle rounded so lies within ellipse_rectangle_ratio of the ellipse's distance (as
// choose_ellipse judges it given the rounding); else the ellipse stands.
void ellipse_under_rounding(const std::vector<Ring>& rings, double pixel_size, const CoreOptions& o, double rounding,
                            BuildingResult::BeforeEllipse before, BuildingResult& result);

// The information criterion the model choice weighs simpler outlines by (n ln(d^2) + 2 k ln(n), d
// the contour's mean distance to the outline, k its vertices, n the contour's length over one
// independent sample of it: models.coarse_correlation_noise times noise_m, at least a pixel):
// the less, the better the outline explains the contour for its vertices. parameters: other
// parameters fitted to the contour, each counted as half a vertex.
double outline_criterion(const std::vector<Ring>& rings, double pixel_size, const CoreOptions& o, double noise_m,
                         const PolygonWithHoles& outline, double parameters = 0);

}  // namespace lodforge::chain
