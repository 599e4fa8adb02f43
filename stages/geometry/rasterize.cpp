#include "geometry/rasterize.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace lodforge {

namespace {

// Even-odd scanline fill of one ring: exactly the pixels whose centre lies inside.
void fill_ring(cv::Mat& image, const Ring& ring, const GeoTransform& t, double value) {
  std::vector<Vec2> px;
  for (const Vec2& p : ring) px.push_back(t.to_pixel(p));
  double top = px[0].y(), bottom = px[0].y();
  for (const Vec2& p : px) { top = std::min(top, p.y()); bottom = std::max(bottom, p.y()); }
  const int first = std::max(0, int(std::floor(top))), last = std::min(image.rows - 1, int(std::ceil(bottom)));
  std::vector<double> crossings;
  for (int row = first; row <= last; ++row) {
    const double y = row + 0.5;
    crossings.clear();
    for (std::size_t i = 0; i < px.size(); ++i) {
      const Vec2& a = px[i];
      const Vec2& b = px[(i + 1) % px.size()];
      if ((a.y() <= y) != (b.y() <= y)) crossings.push_back(a.x() + (y - a.y()) * (b.x() - a.x()) / (b.y() - a.y()));
    }
    std::sort(crossings.begin(), crossings.end());
    for (std::size_t k = 0; k + 1 < crossings.size(); k += 2) {
      // Pixel col is inside when its centre col + 0.5 lies in [x0, x1).
      const int c0 = std::max(0, int(std::ceil(crossings[k] - 0.5)));
      const int c1 = std::min(image.cols - 1, int(std::ceil(crossings[k + 1] - 0.5)) - 1);
      if (c1 >= c0) image.row(row).colRange(c0, c1 + 1).setTo(value);
    }
  }
}

}  // namespace

cv::Rect pixel_box(const PolygonWithHoles& polygon, const GeoTransform& transform) {
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (const Vec2& v : polygon.outer) {
    const Vec2 q = transform.to_pixel(v);
    x0 = std::min(x0, q.x()); y0 = std::min(y0, q.y()); x1 = std::max(x1, q.x()); y1 = std::max(y1, q.y());
  }
  return cv::Rect(cv::Point(int(std::floor(x0)), int(std::floor(y0))), cv::Point(int(std::floor(x1)) + 1, int(std::floor(y1)) + 1));
}

cv::Rect pixel_box(const PolygonWithHoles& polygon, const GeoTransform& transform, int margin, cv::Size raster) {
  return (pixel_box(polygon, transform) + cv::Size(2 * margin, 2 * margin) - cv::Point(margin, margin)) & cv::Rect(cv::Point(0, 0), raster);
}

void rasterize(cv::Mat& image, const PolygonWithHoles& p, const GeoTransform& t, double outer_value, double hole_value) {
  fill_ring(image, p.outer, t, outer_value);
  for (const Ring& h : p.holes) fill_ring(image, h, t, hole_value);
}

}  // namespace lodforge
