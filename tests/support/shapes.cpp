#include "support/shapes.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <memory>

#include "eval/metrics.hpp"
#include "synth/city.hpp"

namespace lodforge::test {

PolygonWithHoles rotated(const PolygonWithHoles& p, double angle_deg) {
  Vec2 lo = p.outer.front(), hi = p.outer.front();
  for (const Vec2& q : p.outer) { lo = lo.cwiseMin(q); hi = hi.cwiseMax(q); }
  const Vec2 centre = 0.5 * (lo + hi);
  const Eigen::Rotation2Dd rotation(angle_deg * M_PI / 180.0);
  const Vec2 place(500000.0, 5000000.0);
  auto apply = [&](Ring r) {
    for (Vec2& q : r) q = place + rotation * (q - centre);
    return r;
  };
  PolygonWithHoles out{apply(p.outer), {}};
  for (const Ring& h : p.holes) out.holes.push_back(apply(h));
  return out;
}

namespace {

RasterizedShape rasterize(const PolygonWithHoles& truth, double pixel_size,
                          const std::function<cv::Mat(const cv::Mat&)>& degrade) {
  Vec2 lo = truth.outer.front(), hi = truth.outer.front();
  for (const Vec2& q : truth.outer) { lo = lo.cwiseMin(q); hi = hi.cwiseMax(q); }
  const double margin = 5.0;
  RasterizedShape s;
  // Snap the origin to the pixel grid so results do not depend on sub-pixel placement luck.
  const double x0 = std::floor((lo.x() - margin) / pixel_size) * pixel_size;
  const double y0 = std::ceil((hi.y() + margin) / pixel_size) * pixel_size;
  s.transform.c = {x0, pixel_size, 0, y0, 0, -pixel_size};
  const int cols = int(std::ceil((hi.x() + margin - x0) / pixel_size));
  const int rows = int(std::ceil((y0 - lo.y() + margin) / pixel_size));
  cv::Mat mask = cv::Mat::zeros(rows, cols, CV_8U);
  rasterize(mask, truth, s.transform);
  s.mask = degrade(mask);
  ContourOptions options;
  s.buildings = extract_contours(s.mask, s.transform, options).buildings;
  return s;
}

}  // namespace

RasterizedShape rasterize_shape(const PolygonWithHoles& truth, double pixel_size, double noise_px,
                                double corner_radius_px, std::uint64_t seed) {
  return rasterize(truth, pixel_size, [&](const cv::Mat& mask) {
    return noise_px > 0 || corner_radius_px > 0 ? degrade_mask(mask, noise_px, corner_radius_px, seed) : mask;
  });
}

RasterizedShape rasterize_shape_m(const PolygonWithHoles& truth, double pixel_size, double wobble_m, double wavelength_m,
                                  double radius_m, std::uint64_t seed, double blur_m) {
  return rasterize(truth, pixel_size, [&](const cv::Mat& mask) {
    return degrade_mask(mask, wobble_rms_px(wobble_m, pixel_size), radius_m / pixel_size, seed,
                        wobble_correlation_px(wavelength_m, pixel_size), true, blur_m / pixel_size);
  });
}

double iou(const PolygonWithHoles& a, const PolygonWithHoles& b) { return polygon_iou(a, b); }

std::string test_data() {
  if (const char* env = std::getenv("LODFORGE_TEST_DATA")) return env;
  return std::string(LODFORGE_SOURCE_DIR) + "/tests/data";
}

std::string schemas() {
  const auto has_both = [](const std::string& dir) {
    return std::filesystem::exists(dir + "/citygml2-schemas/citygml/profiles/base/2.0/CityGML.xsd") &&
           std::filesystem::exists(dir + "/cityjson2-schemas/cityjson.min.schema.json");
  };
  if (const char* env = std::getenv("LODFORGE_SCHEMAS")) return has_both(env) ? env : "";
  return has_both(LODFORGE_DEFAULT_SHARED_DATA) ? LODFORGE_DEFAULT_SHARED_DATA : "";
}

}  // namespace lodforge::test
