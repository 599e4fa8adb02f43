#include <gtest/gtest.h>

#include "contour/contour.hpp"
#include "geometry/polygon.hpp"

namespace lodforge {
namespace {

cv::Mat mask_from(const std::vector<std::string>& rows) {
  cv::Mat m = cv::Mat::zeros(int(rows.size()), int(rows[0].size()), CV_8U);
  for (int r = 0; r < m.rows; ++r)
    for (int c = 0; c < m.cols; ++c) m.at<uint8_t>(r, c) = rows[r][c] == '#';
  return m;
}

ContourOptions no_minimum(int connectivity = 8) {
  ContourOptions o;
  o.connectivity = connectivity;
  o.min_area_m2 = 0;
  o.min_hole_area_m2 = 0;
  o.min_pixels = 0;
  return o;
}

GeoTransform transform(double x0 = 100, double y0 = 200, double pixel = 0.5) {
  GeoTransform t;
  t.c = {x0, pixel, 0, y0, 0, -pixel};
  return t;
}

TEST(Contour, SinglePixelIsOneCounterClockwiseSquareInMapCoordinates) {
  const auto result = extract_contours(mask_from({"...", ".#.", "..."}), transform(), no_minimum());
  ASSERT_EQ(result.buildings.size(), 1u);
  const Ring& ring = result.buildings[0].rings[0];
  ASSERT_EQ(ring.size(), 4u);
  EXPECT_DOUBLE_EQ(signed_area(ring), 0.25);
  for (const Vec2& p : ring) {
    EXPECT_TRUE(p.x() == 100.5 || p.x() == 101.0) << p.transpose();
    EXPECT_TRUE(p.y() == 199.5 || p.y() == 199.0) << p.transpose();
  }
}

TEST(Contour, CourtyardBecomesClockwiseHole) {
  const auto result = extract_contours(mask_from({"#####", "#...#", "#...#", "#####"}), transform(0, 0, 1), no_minimum());
  ASSERT_EQ(result.buildings.size(), 1u);
  const auto& rings = result.buildings[0].rings;
  ASSERT_EQ(rings.size(), 2u);
  EXPECT_DOUBLE_EQ(signed_area(rings[0]), 20.0);
  EXPECT_DOUBLE_EQ(signed_area(rings[1]), -6.0);
  EXPECT_EQ(polygon_problem({rings[0], {rings[1]}}), "");
}

TEST(Contour, SmallHolesAreFilledAndSmallComponentsDropped) {
  ContourOptions o = no_minimum(4);
  o.min_hole_area_m2 = 7;
  o.min_area_m2 = 2;
  const auto result = extract_contours(mask_from({"#####.", "#...#.", "#...#.", "#####.", ".....#"}), transform(0, 0, 1), o);
  ASSERT_EQ(result.buildings.size(), 1u);
  EXPECT_EQ(result.buildings[0].rings.size(), 1u);
  EXPECT_EQ(result.dropped_small, 1);
}

// At 2 m a pixel is 4 m^2, as large as the area filters: a lone pixel, a component or a hole,
// is dropped or filled by min_pixels; two pixels stay.
TEST(Contour, ALonePixelIsNoBuildingAndNoCourtyardAtCoarsePixels) {
  ContourOptions o;  // min_area_m2 = min_hole_area_m2 = 4, min_pixels = 2
  const cv::Mat m = mask_from({"#######..#.", "#.#####....", "#######..##", "#...###....", "#######...."});
  const auto result = extract_contours(m, transform(0, 0, 2), o);
  ASSERT_EQ(result.buildings.size(), 2u);        // the block and the pair; the lone pixel dropped
  EXPECT_EQ(result.dropped_small, 1);
  EXPECT_EQ(result.buildings[0].rings.size(), 2u);  // the 3-pixel courtyard stays, the 1-pixel one is filled
  EXPECT_NEAR(std::abs(signed_area(result.buildings[0].rings[1])), 3 * 4.0, 1e-9);
  o.min_pixels = 0;
  const auto all = extract_contours(m, transform(0, 0, 2), o);
  EXPECT_EQ(all.buildings.size(), 3u);
  EXPECT_EQ(all.buildings[0].rings.size(), 3u);
}

TEST(Contour, DiagonalContactsGiveSimpleRings) {
  const cv::Mat m = mask_from({"#..#", ".##.", ".##.", "#..#"});
  const auto eight = extract_contours(m, transform(), no_minimum(8));
  ASSERT_EQ(eight.buildings.size(), 1u);
  for (const Ring& r : eight.buildings[0].rings) EXPECT_EQ(ring_problem(r), "");
  EXPECT_EQ(extract_contours(m, transform(), no_minimum(4)).buildings.size(), 5u);
  // A ring that would touch itself: a U whose tips meet diagonally.
  const auto touch = extract_contours(mask_from({"###.", "#..#", "####"}), transform(), no_minimum(8));
  ASSERT_EQ(touch.buildings.size(), 1u);
  PolygonWithHoles p{touch.buildings[0].rings[0], {}};
  for (std::size_t i = 1; i < touch.buildings[0].rings.size(); ++i) p.holes.push_back(touch.buildings[0].rings[i]);
  EXPECT_EQ(polygon_problem(p), "");
}

TEST(Contour, CheckerboardStaysValid) {
  cv::Mat m = cv::Mat::zeros(12, 12, CV_8U);
  for (int r = 1; r < 11; ++r)
    for (int c = 1; c < 11; ++c) m.at<uint8_t>(r, c) = (r + c) % 2;
  const auto result = extract_contours(m, transform(), no_minimum(8));
  ASSERT_EQ(result.buildings.size(), 1u);
  PolygonWithHoles p{result.buildings[0].rings[0], {}};
  for (std::size_t i = 1; i < result.buildings[0].rings.size(); ++i) p.holes.push_back(result.buildings[0].rings[i]);
  EXPECT_EQ(polygon_problem(p), "");
}

TEST(Contour, BuildingsAreOrderedByFirstPixelInRasterOrder) {
  const auto result = extract_contours(mask_from({"....##", "##..##", "##....", "....#."}), transform(), no_minimum(4));
  ASSERT_EQ(result.buildings.size(), 3u);
  EXPECT_EQ(result.buildings[0].first_row, 0);
  EXPECT_EQ(result.buildings[0].first_col, 4);
  EXPECT_EQ(result.buildings[1].first_row, 1);
  EXPECT_EQ(result.buildings[1].first_col, 0);
  EXPECT_EQ(result.buildings[2].first_row, 3);
  EXPECT_EQ(result.buildings[2].pixel_count, 1);
}

TEST(Contour, AnyNonZeroValueIsBuildingAndTheFirstPixelIsTheLeftmostOfTheTopRow) {
  // A component whose top row starts right of where lower rows start, in a 0/255 mask.
  const std::vector<std::string> rows = {".....", "...##", ".####", "##..."};
  const cv::Mat ones = mask_from(rows);
  const cv::Mat full = ones * 255;
  const auto a = extract_contours(ones, transform(), no_minimum()), b = extract_contours(full, transform(), no_minimum());
  ASSERT_EQ(a.buildings.size(), 1u);
  ASSERT_EQ(b.buildings.size(), 1u);
  EXPECT_EQ(a.buildings[0].rings, b.buildings[0].rings);
  EXPECT_EQ(b.buildings[0].first_row, 1);
  EXPECT_EQ(b.buildings[0].first_col, 3);
  EXPECT_EQ(b.buildings[0].pixel_count, 8);
}

}  // namespace
}  // namespace lodforge
