// Exact polygon rasterization: a pixel belongs to a polygon when its centre lies inside.
#pragma once
#include <opencv2/core/mat.hpp>

#include "geometry/geotransform.hpp"
#include "geometry/types.hpp"

namespace lodforge {

// The pixels (columns, rows) of the grid that the box of the polygon's outer ring touches, not clipped.
cv::Rect pixel_box(const PolygonWithHoles& polygon, const GeoTransform& transform);
// The same grown by margin pixels on every side and clipped to a raster of that size.
cv::Rect pixel_box(const PolygonWithHoles& polygon, const GeoTransform& transform, int margin, cv::Size raster);

// Sets the pixels of image (any type) whose centres lie inside the outer ring to outer_value,
// then those inside a hole to hole_value.
void rasterize(cv::Mat& image, const PolygonWithHoles& polygon, const GeoTransform& transform, double outer_value = 1,
               double hole_value = 0);

}  // namespace lodforge
