#include "heights/heights.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/imgproc.hpp>

#include "geometry/rasterize.hpp"

namespace lodforge {

double percentile(std::vector<float>& v, double p) {
  if (v.empty()) return std::nan("");
  const double rank = std::clamp(p, 0.0, 100.0) / 100.0 * double(v.size() - 1);
  const std::size_t lo = std::size_t(std::floor(rank));
  std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(lo), v.end());
  const double a = v[lo];
  if (lo + 1 >= v.size()) return a;
  const double b = *std::min_element(v.begin() + std::ptrdiff_t(lo) + 1, v.end());
  return a + (rank - double(lo)) * (b - a);
}

namespace {

// The footprint's pixel box, grown by margin pixels, clipped to the raster.
cv::Rect footprint_box(const PolygonWithHoles& f, const GeoTransform& t, cv::Size size, int margin) {
  Vec2 lo = t.to_pixel(f.outer.front()), hi = lo;
  for (const Vec2& p : f.outer) {
    const Vec2 q = t.to_pixel(p);
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  const cv::Rect box(int(std::floor(lo.x())) - margin, int(std::floor(lo.y())) - margin,
                     int(std::ceil(hi.x()) - std::floor(lo.x())) + 2 * margin + 1,
                     int(std::ceil(hi.y()) - std::floor(lo.y())) + 2 * margin + 1);
  return box & cv::Rect(0, 0, size.width, size.height);
}

std::vector<float> samples(const HeightRaster& r, const cv::Rect& box, const cv::Mat& where) {
  std::vector<float> out;
  for (int y = 0; y < box.height; ++y)
    for (int x = 0; x < box.width; ++x)
      if (where.at<uint8_t>(y, x) && r.valid.at<uint8_t>(box.y + y, box.x + x))
        out.push_back(r.values.at<float>(box.y + y, box.x + x));
  return out;
}

}  // namespace

cv::Rect heights_box(const PolygonWithHoles& footprint, const GeoTransform& transform, cv::Size size, const HeightOptions& o) {
  const int margin = int(std::ceil(o.ring_outer_m / transform.pixel_size())) + 1;
  return footprint_box(footprint, transform, size, margin);
}

namespace {

Heights measure_heights(const PolygonWithHoles& footprint, const HeightRaster& dsm, const HeightRaster* dtm,
                        const HeightOptions& o) {
  Heights h;
  const double pixel = dsm.transform.pixel_size();
  const cv::Rect box = heights_box(footprint, dsm.transform, dsm.values.size(), o);
  if (box.empty()) { h.reason = "the footprint lies outside the DSM"; return h; }
  const GeoTransform local = dsm.transform.window(box.x, box.y);
  cv::Mat inside = cv::Mat::zeros(box.size(), CV_8U);
  rasterize(inside, footprint, local);

  std::vector<float> roof = samples(dsm, box, inside);
  h.roof_samples = int(roof.size());
  h.dsm_cells = cv::countNonZero(inside);
  h.dsm_coverage = h.dsm_cells > 0 ? double(h.roof_samples) / h.dsm_cells : 0.0;
  if (roof.empty()) { h.reason = "no valid DSM value inside the footprint"; return h; }
  if (o.roof == "mean") h.roof = std::accumulate(roof.begin(), roof.end(), 0.0) / double(roof.size());
  else h.roof = percentile(roof, o.roof == "median" ? 50.0 : o.roof_percentile);
  h.roof_min = *std::min_element(roof.begin(), roof.end());
  h.roof_max = *std::max_element(roof.begin(), roof.end());
  h.roof_50p = percentile(roof, 50.0);
  h.roof_70p = percentile(roof, 70.0);

  std::vector<float> ground;
  if (dtm) {
    ground = samples(*dtm, box, inside);
  } else {
    cv::Mat outside = inside == 0, distance;
    cv::distanceTransform(outside, distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);
    const cv::Mat ring = (distance >= float(o.ring_inner_m / pixel)) & (distance <= float(o.ring_outer_m / pixel));
    ground = samples(dsm, box, ring);
  }
  h.ground_samples = int(ground.size());
  if (ground.empty()) {
    h.reason = dtm ? "no valid DTM value inside the footprint" : "no valid DSM value in the ground ring around the building";
    return h;
  }
  h.ground = percentile(ground, o.ground_percentile);
  if (!(h.roof > h.ground)) {
    h.reason = "roof height " + std::to_string(h.roof) + " is not above ground " + std::to_string(h.ground);
    return h;
  }
  h.ok = true;
  return h;
}

}  // namespace

Heights building_heights(const PolygonWithHoles& footprint, const HeightRaster& dsm, const HeightRaster* dtm,
                         const HeightOptions& o) {
  try {
    return measure_heights(footprint, dsm, dtm, o);
  } catch (const std::exception& e) {  // one building's failure is its own: it keeps its LOD0, with the reason
    Heights h;
    h.ok = false;
    h.reason = std::string("internal: ") + e.what();
    return h;
  }
}

}  // namespace lodforge
