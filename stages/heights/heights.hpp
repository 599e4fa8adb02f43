// Stage 8: a building's roof and ground heights from the DSM (and DTM). Roof: a percentile of the
// DSM heights inside the footprint (3DBAG's LoD1.2: the 70th; 3dfier: the 90th), or their mean
// (the paper) or median; beside it the statistics 3DBAG publishes (minimum, 50th, 70th, maximum).
// Ground: a low percentile of the DTM inside the footprint, or without a DTM of the DSM in a
// ring around the building. Nodata is ignored; too few values is a stated failure.
#pragma once
#include <opencv2/core/mat.hpp>
#include <string>

#include "common/option.hpp"
#include "geometry/geotransform.hpp"
#include "geometry/types.hpp"

namespace lodforge {

struct HeightOptions {
  std::string roof = "percentile";  // mean | median | percentile
  double roof_percentile = 70;     // when roof = percentile (3DBAG's LoD1.2)
  double ground_percentile = 10;
  double ring_inner_m = 1.0, ring_outer_m = 4.0;  // ground ring around the building without a DTM

  template <class V>
  void visit(V& v) {
    v("roof", roof, "LOD1 roof height: a statistic of the DSM inside the footprint: percentile (3DBAG), mean (the paper) or median", Check::one_of({"mean", "median", "percentile"}));
    v("roof_percentile", roof_percentile, "percentile used when roof = percentile (3DBAG's LoD1.2: 70; 3dfier: 90)", Check::between(0, 100));
    v("ground_percentile", ground_percentile, "percentile of the DTM inside the footprint (or of the DSM ring around it) taken as ground", Check::between(0, 100));
    v("ring_inner_m", ring_inner_m, "without a DTM: inner distance of the ground ring around the building (m)", Check::at_least(0));
    v("ring_outer_m", ring_outer_m, "without a DTM: outer distance of the ground ring (m)", Check::above(0));
  }
};

// A window of a height raster on the segmentation's grid.
struct HeightRaster {
  cv::Mat values;  // CV_32F
  cv::Mat valid;   // CV_8U, 1 where values holds data
  GeoTransform transform;
};

struct Heights {
  bool ok = false;
  double roof = 0, ground = 0;  // the LOD1 roof (the `roof` statistic) and the ground
  int roof_samples = 0, ground_samples = 0;  // DSM cells with data inside the footprint; ground cells
  // What 3DBAG publishes besides: the DSM's minimum, 50th, 70th percentile and maximum inside the
  // footprint, and the share of its cells inside the footprint that have data (of dsm_cells).
  double roof_min = 0, roof_50p = 0, roof_70p = 0, roof_max = 0, dsm_coverage = 0;
  int dsm_cells = 0;  // the DSM's cells inside the footprint, with data or not
  std::string reason;  // when !ok
};

// The pixels of a height raster on the grid `transform` (size pixels) that building_heights reads
// for this footprint: its box grown by the ground ring, clipped to the raster. A window of just
// these pixels gives the same heights as any larger one.
cv::Rect heights_box(const PolygonWithHoles& footprint, const GeoTransform& transform, cv::Size size, const HeightOptions& options);

// dtm may be null (ground from a DSM ring). Never throws: a failure is a status with its reason.
Heights building_heights(const PolygonWithHoles& footprint, const HeightRaster& dsm, const HeightRaster* dtm,
                         const HeightOptions& options);

// The p-th percentile (0–100, linear interpolation) of values; values is reordered.
double percentile(std::vector<float>& values, double p);

}  // namespace lodforge
