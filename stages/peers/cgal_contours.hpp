// A peer regularizer for comparison: CGAL's Shape_regularization closed-contour regularization
// (Contours::regularize_closed_contour with Multiple_directions_2), each ring on its own. CGAL
// expects a polyline, not a pixel staircase, so each ring is first simplified by Douglas–Peucker
// (simplify_m); that is the peer's own preprocessing and part of its settings.
#pragma once
#include <string>
#include <vector>

#include "common/option.hpp"
#include "geometry/types.hpp"

namespace lodforge {

struct CgalContourOptions {
  double simplify_m = 0.5;      // Douglas–Peucker tolerance before CGAL (m)
  double min_length_m = 3.0;    // CGAL minimum_length: shortest edge that can give a direction (m)
  double max_angle_deg = 10.0;  // CGAL maximum_angle: edges this close to a direction are aligned to it
  double max_offset_m = 0.5;    // CGAL maximum_offset: parallel consecutive edges this close merge (m)

  template <class V>
  void visit(V& v) {
    v("simplify_m", simplify_m, "Douglas-Peucker tolerance applied before CGAL's regularization (m)", Check::at_least(0));
    v("min_length_m", min_length_m, "CGAL Multiple_directions_2 minimum_length: shortest edge defining a direction (m)", Check::above(0));
    v("max_angle_deg", max_angle_deg, "CGAL Multiple_directions_2 maximum_angle (degrees)", Check::between(0, 90));
    v("max_offset_m", max_offset_m, "CGAL regularize_closed_contour maximum_offset (m)", Check::at_least(0));
  }
};

// The regularized rings (outer counter-clockwise, holes clockwise), or an empty polygon with
// *problem set when CGAL gives no usable ring.
PolygonWithHoles cgal_regularize_contours(const std::vector<Ring>& rings, const CgalContourOptions& options,
                                          std::string* problem);

}  // namespace lodforge
