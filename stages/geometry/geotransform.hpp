// GDAL's affine geotransform between pixel (column, row) and map coordinates.
#pragma once
#include <array>
#include <cmath>

#include "geometry/types.hpp"

namespace lodforge {

// GDAL's affine geotransform: x = c0 + col*c1 + row*c2, y = c3 + col*c4 + row*c5.
struct GeoTransform {
  std::array<double, 6> c{0, 1, 0, 0, 0, -1};
  Vec2 to_map(double col, double row) const {
    return {c[0] + col * c[1] + row * c[2], c[3] + col * c[4] + row * c[5]};
  }
  // The transform of a window whose first pixel is (col, row) of this grid.
  GeoTransform window(double col, double row) const {
    GeoTransform w = *this;
    const Vec2 origin = to_map(col, row);
    w.c[0] = origin.x();
    w.c[3] = origin.y();
    return w;
  }
  // The grid of blocks of f x f of its pixels, from its first pixel: the same origin, pixels f times as large.
  GeoTransform coarsened(int f) const {
    GeoTransform g = *this;
    for (std::size_t k : {1, 2, 4, 5}) g.c[k] *= f;
    return g;
  }
  // sqrt of the pixel's area, the ground sampling distance
  double pixel_size() const { return std::sqrt(std::abs(c[1] * c[5] - c[2] * c[4])); }
  // Map (x, y) to fractional (column, row).
  Vec2 to_pixel(const Vec2& p) const {
    const double det = c[1] * c[5] - c[2] * c[4];
    const double dx = p.x() - c[0], dy = p.y() - c[3];
    return {(c[5] * dx - c[2] * dy) / det, (-c[4] * dx + c[1] * dy) / det};
  }
};

}  // namespace lodforge
