#include <gtest/gtest.h>

#include <cmath>

#include "normals/smoothing.hpp"
#include "support/shapes.hpp"

namespace lodforge {
namespace {

double angle_to_nearest_deg(const Vec2& n, double base_deg) {
  double best = 180;
  for (int k = 0; k < 4; ++k) {
    const double a = (base_deg + 90.0 * k) * M_PI / 180.0;
    best = std::min(best, std::acos(std::clamp(n.dot(Vec2(std::cos(a), std::sin(a))), -1.0, 1.0)) * 180.0 / M_PI);
  }
  return best;
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

TEST(Smoothing, StaircaseNormalsRecoverTheWallDirection) {
  const PolygonWithHoles rect = test::rotated({{{0, 0}, {20, 0}, {20, 12}, {0, 12}}, {}}, 30.0);
  const auto shape = test::rasterize_shape(rect, 0.1, 0, 0, 1);
  ASSERT_EQ(shape.buildings.size(), 1u);
  const Ring& ring = shape.buildings[0].rings[0];
  std::vector<double> raw, smooth;
  for (const Vec2& n : edge_normals(ring)) raw.push_back(angle_to_nearest_deg(n, 30.0));
  for (const Vec2& n : smooth_normals(ring, 0.1, SmoothingOptions{})) smooth.push_back(angle_to_nearest_deg(n, 30.0));
  EXPECT_GT(median(raw), 25.0);     // pixel edges are 30° or 60° off the walls
  EXPECT_LT(median(smooth), 5.0);   // the bilateral filter brings them back
}

TEST(Smoothing, OnePassLeavesTwoClustersThreePassesMergeThem) {
  const PolygonWithHoles rect = test::rotated({{{0, 0}, {20, 0}, {20, 12}, {0, 12}}, {}}, 30.0);
  const auto shape = test::rasterize_shape(rect, 0.1, 0, 0, 1);
  const Ring& ring = shape.buildings[0].rings[0];
  SmoothingOptions one;
  one.passes = 1;
  std::vector<double> a1, a3;
  for (const Vec2& n : smooth_normals(ring, 0.1, one)) a1.push_back(angle_to_nearest_deg(n, 30.0));
  for (const Vec2& n : smooth_normals(ring, 0.1, SmoothingOptions{})) a3.push_back(angle_to_nearest_deg(n, 30.0));
  EXPECT_GT(median(a1), median(a3));
}

}  // namespace
}  // namespace lodforge
