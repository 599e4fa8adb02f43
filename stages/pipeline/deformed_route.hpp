// The rings a building's outlines are fitted to: its contour in a local frame, or deformed on the
// paper's route (corners.route = deformed: a mesh of the contour deformed by AMIPS towards its
// labeled directions, stages 5-6, triangulation/ and deformation/), bounded in size and work.
// Not a public interface: pipeline/building.cpp's chain calls it.
#pragma once
#include <functional>
#include <vector>

#include "directions/refine.hpp"
#include "geometry/types.hpp"
#include "pipeline/building.hpp"

namespace lodforge::chain {

// The rings the outlines are fitted to: in a local frame (metres from origin) for numerical range,
// deformed on the paper's route (corners.route) unless the contour has more edges than
// budget.max_deformation_edges or the deformation is skipped (result.route and result.note say so).
std::vector<Ring> route_rings(const std::vector<Ring>& rings, const Vec2& origin, double pixel_size, const EdgeLabels& labels,
                              const std::vector<Vec2>& directions, const CoreOptions& o, const std::function<bool()>& over_budget,
                              BuildingResult& result);

}  // namespace lodforge::chain
