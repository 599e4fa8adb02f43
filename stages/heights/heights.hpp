// Stage 8: a building's roof and ground heights from the DSM (and DTM). Roof: the mean DSM
// height inside the footprint (the paper), or its median or a percentile (3dfier uses the 90th).
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
  std::string roof = "mean";    // mean | median | percentile
  double roof_percentile = 90;  // when roof = percentile
  double ground_percentile = 10;
  double ring_inner_m = 1.0, ring_outer_m = 4.0;  // ground ring around the building without a DTM

  template <class V>
  void visit(V& v) {
    v("roof", roof, "roof height statistic of the DSM inside the footprint: mean (the paper), median or percentile", Check::one_of({"mean", "median", "percentile"}));
    v("roof_percentile", roof_percentile, "percentile used when roof = percentile (3dfier: 90)", Check::between(0, 100));
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
  double roof = 0, ground = 0;
  int roof_samples = 0, ground_samples = 0;
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
