// The chain's outlines: the corner polygon of a building's labeled contour, validated and retried
// coarser where it is not (stage 7, corners/corners.hpp, over every ring), and how well an outline
// explains the contour. Shared by the chain (pipeline/building.cpp) and its model choice
// (pipeline/model_choice.cpp); not a public interface.
#pragma once
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "corners/corners.hpp"
#include "directions/refine.hpp"
#include "geometry/types.hpp"

namespace lodforge::chain {

// A stage failure: which stage and why.
struct StageError : std::runtime_error {
  StageError(std::string stage_name, const std::string& why) : std::runtime_error(why), stage(std::move(stage_name)) {}
  std::string stage;
};

// A building over its time budget: it gets the fallback, not another model (the budget is a
// safety net for pathological contours).
struct BudgetExceeded : StageError {
  using StageError::StageError;
};

using StageProblem = std::pair<std::string, std::string>;  // stage, problem (empty: none)

// The corner polygon of the rings (metres from origin) at a context, validated: an invalid polygon
// is retried with coarser run absorption (short runs are where crossings come from), then again
// with runs left unsplit (steps are short too), and last, where only its holes are invalid, drawn
// as first asked with the holes that fit (holes_that_fit). *curved (when given): whether the
// polygon drawn keeps a run of a ring as a curve.
StageProblem outline(const std::vector<Ring>& rings, const EdgeLabels& labels, const std::vector<Vec2>& directions,
                     const CornerOptions& o, const Vec2& origin, double pixel_size, const CornerContext& context,
                     double min_run_px, PolygonWithHoles& footprint, bool* curved = nullptr);

// The lattice outline: the contour's edges labeled among the building's lattice directions alone,
// every wall straight (no curve), drawn for the noise in `context`.
StageProblem lattice_outline_of(const std::vector<Ring>& fit_rings, const EdgeLabels& axis_labels, const std::vector<Vec2>& axes,
                                const CornerOptions& o, const Vec2& origin, double pixel_size, const CornerContext& context,
                                PolygonWithHoles& footprint);

// How well a polygon explains the contour: the length-weighted mean distance of every ring's
// edges to the polygon's boundary.
double contour_fit(const std::vector<Ring>& rings, const PolygonWithHoles& polygon);
// The same from each ring's (distance, length) list of boundary_distances against the outline.
double contour_fit(const std::vector<Ring>& rings, const std::vector<std::vector<std::pair<double, double>>>& distances);

// The length of all of a building's rings (m).
double total_perimeter(const std::vector<Ring>& rings);

}  // namespace lodforge::chain
