// LoD1.3: a building split into parts where its roof height steps (a wall between houses of
// different heights), each part regularized and later extruded to its own height, as 3DBAG's
// LoD1.3. The parts tile the building's LOD0 footprint exactly (shared walls identical).
// Pure computation.
#pragma once
#include <string>
#include <vector>

#include "common/option.hpp"
#include "contour/contour.hpp"
#include "geometry/types.hpp"
#include "heights/heights.hpp"
#include "pipeline/core_options.hpp"

namespace lodforge {

struct PartOptions {
  bool enabled = true;
  double min_step_m = 1.5;         // a roof height step at least this high between neighbouring DSM cells separates parts
  double max_slope_deg = 60;       // ... and higher than a roof this steep rises over a cell
  double min_part_area_m2 = 12;    // smaller regions of one height join their neighbour

  template <class V>
  void visit(V& v) {
    v("enabled", enabled, "split buildings into LoD1.3 parts where the roof height steps (CityGML BuildingParts, CityJSON BuildingPart children, GeoPackage layer parts), beside the LoD1.2 block");
    v("min_step_m", min_step_m, "a step of the DSM between neighbouring cells inside a building at least this high separates two parts (m)", Check::above(0));
    v("max_slope_deg", max_slope_deg, "... and higher than the rise of a roof this steep over one cell (so a steep roof on a coarse grid is not cut into strips)", Check::between(0, 89));
    v("min_part_area_m2", min_part_area_m2, "a region of one height smaller than this joins the neighbour it borders longest (chimneys, dormers, trees, mixed cells) (m^2)", Check::at_least(0));
  }
};

// The building's parts where its roof steps, largest first, covering footprint exactly; empty when
// it has one part (or the split fails). dsm: a window holding the footprint. Each part's outline
// is its cells' regularization by `regularizer` (the building's: regularize_with, each part with its
// own noise: the cells are the DSM's, not the segmentation's), then the parts are fitted to the
// footprint.
std::vector<PolygonWithHoles> split_by_roof_steps(const PolygonWithHoles& footprint, const HeightRaster& dsm, double pixel_size,
                                                  const std::string& regularizer, const CoreOptions& core, const PartOptions& options);

}  // namespace lodforge
