// Stage 1: building contours from a binary mask (paper §2.2, first paragraph).
// Connected components are buildings; each yields an outer ring and its holes traced on pixel
// corners, mapped to map coordinates through the raster's geotransform.
#pragma once
#include <array>
#include <functional>
#include <optional>
#include <opencv2/core/mat.hpp>
#include <vector>

#include "common/option.hpp"
#include "geometry/geotransform.hpp"
#include "geometry/types.hpp"

namespace lodforge {

struct ContourOptions {
  int connectivity = 8;           // pixels touching at a corner belong to one building (8) or not (4)
  double min_area_m2 = 4.0;       // smaller components are noise, not buildings
  double min_hole_area_m2 = 4.0;  // smaller holes are filled (segmentation speckle)
  int min_pixels = 2;             // components and holes of fewer pixels are dropped / filled too
  double edge_sweep_m = 4.0;      // a building cut by the raster's edge is traced swept this far out across it

  template <class V>
  void visit(V& v) {
    v("connectivity", connectivity, "pixel connectivity of a building: 4 or 8", Check::one_of_numbers({4, 8}));
    v("min_area_m2", min_area_m2, "components smaller than this are dropped (m^2)", Check::at_least(0));
    v("min_hole_area_m2", min_hole_area_m2, "holes smaller than this are filled (m^2)", Check::at_least(0));
    v("edge_sweep_m", edge_sweep_m, "a building the raster's edge cuts is traced swept this far out across the edge (at least 4 pixels) along the one of its walls' directions nearest the edge's normal, and its footprint clipped back to the raster: the regularizer sees its walls go on instead of a wall along the edge that it would square to the building's own (0: traced as cut)", Check::at_least(0));
    v("min_pixels", min_pixels, "components of fewer pixels than this are dropped and holes of fewer filled, whatever their area: a lone pixel is a speckle of the segmentation as likely as a building or a courtyard (at pixels over 1.4 m, where min_area_m2 and min_hole_area_m2 let one through)", Check::at_least(0));
  }
};

struct BuildingContour {
  int first_row = 0, first_col = 0;  // the component's first pixel in raster order
  long pixel_count = 0;
  cv::Rect bbox;                      // pixel bounding box in the mask
  std::vector<Ring> rings;            // [0] outer (counter-clockwise), then holes (clockwise)
  // Where the raster's edge cuts it and it was traced swept out across that edge
  // (ContourOptions::edge_sweep_m): the raster's extent in map coordinates (a convex
  // quadrilateral, counter-clockwise), which its footprint is to be clipped to; else empty.
  Ring cut;
};

struct ContourResult {
  std::vector<BuildingContour> buildings;  // sorted by first pixel in raster order
  int dropped_small = 0;                   // components below min_area_m2
};

// A component's pixel bounding box and first pixel, in mask coordinates.
using ComponentFilter = std::function<bool(const cv::Rect& bbox, const cv::Point& first)>;

// The connected components of a mask (CV_8U, non-zero = building), as the runs of building
// pixels along its rows: a few bytes per run, where a label image takes four a pixel. (While
// labeling, about 24 bytes a run: a speckled mask of lone pixels takes more than a label image.)
struct Components {
  struct Run {
    int x0 = 0, x1 = 0;  // columns [x0, x1)
    int label = 0;
  };
  int rows = 0, cols = 0;
  int count = 0;                       // labels, background (0) included
  std::vector<Run> runs;               // row by row, left to right
  std::vector<std::size_t> row_begin;  // row y's runs: [row_begin[y], row_begin[y + 1])
  std::vector<cv::Rect> boxes;         // per label: its pixels' bounding box
  std::vector<long> areas;             // per label: its pixel count
  std::vector<cv::Point> firsts;       // per label: its first pixel in raster order
  int label_at(cv::Point p) const;     // 0 = background
  // The component's pixels in its box grown by `pad` pixels on every side: CV_8U, 0/1.
  cv::Mat mask_of(int label, int pad) const;
};
// Labels numbered by their first pixel in raster order.
Components label_components(const cv::Mat& mask, int connectivity);
inline cv::Rect component_box(const Components& components, int label) { return components.boxes[std::size_t(label)]; }

// mask: CV_8U, non-zero = building. keep (optional) selects which components to trace; the others
// are skipped and not counted. raster (optional): the whole raster's pixels in the mask's
// coordinates (the mask may be a window of it); a component touching its edge is traced swept out
// across it (ContourOptions::edge_sweep_m, BuildingContour::cut). Not given: none is.
ContourResult extract_contours(const cv::Mat& mask, const GeoTransform& transform,
                               const ContourOptions& options, const ComponentFilter& keep = {},
                               const std::optional<cv::Rect>& raster = std::nullopt);
// The same from the mask's components (label_components with options.connectivity), when the
// caller has them already.
ContourResult extract_contours(const Components& components, const GeoTransform& transform,
                               const ContourOptions& options, const ComponentFilter& keep = {},
                               const std::optional<cv::Rect>& raster = std::nullopt);

// Traces one component given as a CV_8U 0/1 image; returns rings in pixel-corner coordinates
// (x = column, y = row) oriented as map rings of a north-up raster: outer first.
// Diagonal-only pixel contacts are resolved first so that every ring is simple.
std::vector<Ring> trace_component(cv::Mat component);

}  // namespace lodforge
