#include <gtest/gtest.h>

#include <cmath>

#include "contour/contour.hpp"
#include "geometry/polygon.hpp"
#include "pipeline/building.hpp"

namespace lodforge {
namespace {

std::vector<Ring> contour_of(const cv::Mat& mask) {
  GeoTransform t;
  t.c = {1000, 0.5, 0, 2000, 0, -0.5};
  ContourOptions o;
  o.min_area_m2 = 0;
  o.min_hole_area_m2 = 0;
  o.min_pixels = 0;
  auto result = extract_contours(mask, t, o);
  EXPECT_EQ(result.buildings.size(), 1u);
  return result.buildings.at(0).rings;
}

void expect_valid_result(const BuildingResult& r) {
  EXPECT_EQ(polygon_problem(r.footprint), "");
  EXPECT_GT(area(r.footprint), 0);
  if (!r.ok) {
    EXPECT_FALSE(r.failed_stage.empty());
    EXPECT_FALSE(r.reason.empty());
  }
}

TEST(Pathological, OnePixel) {
  cv::Mat m = cv::Mat::zeros(3, 3, CV_8U);
  m.at<uint8_t>(1, 1) = 1;
  const BuildingResult r = regularize_building(contour_of(m), 0.5, CoreOptions{});
  expect_valid_result(r);
  EXPECT_EQ(r.footprint.outer.size(), 4u);
  EXPECT_NEAR(area(r.footprint), 0.25, 1e-9);
}

TEST(Pathological, OnePixelWideLine) {
  cv::Mat m = cv::Mat::zeros(5, 300, CV_8U);
  m.row(2).colRange(10, 290).setTo(1);
  for (const char* route : {"original", "deformed"}) {
    CoreOptions o;
    o.corners.route = route;
    expect_valid_result(regularize_building(contour_of(m), 0.5, o));
  }
}

TEST(Pathological, DiagonalStaircaseOfSinglePixels) {
  cv::Mat m = cv::Mat::zeros(60, 60, CV_8U);
  for (int k = 2; k < 58; ++k) m.at<uint8_t>(k, k) = 1;
  expect_valid_result(regularize_building(contour_of(m), 0.5, CoreOptions{}));
}

TEST(Pathological, RingTouchingItself) {
  cv::Mat m = cv::Mat::zeros(40, 40, CV_8U);
  m(cv::Rect(5, 5, 30, 4)).setTo(1);
  m(cv::Rect(5, 5, 4, 30)).setTo(1);
  m(cv::Rect(31, 5, 4, 20)).setTo(1);
  m(cv::Rect(9, 31, 21, 4)).setTo(1);  // touches the right arm's end only at a corner
  m.at<uint8_t>(25, 31) = 0;
  for (const char* route : {"original", "deformed"}) {
    CoreOptions o;
    o.corners.route = route;
    expect_valid_result(regularize_building(contour_of(m), 0.5, o));
  }
}

TEST(Pathological, HundredThousandEdgeContourFinishes) {
  // A jagged disc: 100,000 unit edges in a sawtooth around a circle.
  Ring ring;
  const int teeth = 25000;
  for (int k = 0; k < teeth; ++k) {
    const double a0 = 2 * M_PI * k / teeth, a1 = 2 * M_PI * (k + 0.5) / teeth;
    const double r = 4000, r2 = 4000.5;
    ring.emplace_back(r * std::cos(a0), r * std::sin(a0));
    ring.emplace_back(r2 * std::cos(a0), r2 * std::sin(a0));
    ring.emplace_back(r2 * std::cos(a1), r2 * std::sin(a1));
    ring.emplace_back(r * std::cos(a1), r * std::sin(a1));
  }
  ASSERT_EQ(ring.size(), 100000u);
  const BuildingResult r = regularize_building({ring}, 0.5, CoreOptions{});
  expect_valid_result(r);

  CoreOptions small;
  small.budget.max_edges = 50000;
  const BuildingResult limited = regularize_building({ring}, 0.5, small);
  expect_valid_result(limited);
  EXPECT_FALSE(limited.ok);
  EXPECT_NE(limited.reason.find("more than budget.max_edges = 50000"), std::string::npos) << limited.reason;
}

TEST(Pathological, TimeBudgetGivesFallbackNotAHang) {
  cv::Mat m = cv::Mat::zeros(200, 200, CV_8U);
  cv::Mat roi = m(cv::Rect(20, 20, 160, 160));
  roi.setTo(1);
  CoreOptions o;
  o.corners.route = "deformed";
  o.budget.max_seconds = 1e-9;
  const BuildingResult r = regularize_building(contour_of(m), 0.5, o);
  expect_valid_result(r);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.reason.find("time budget"), std::string::npos) << r.reason;
}

TEST(Pathological, EmptyInputIsReportedNotCrashing) {
  const BuildingResult r = regularize_building({}, 0.5, CoreOptions{});
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.failed_stage, "input");
}

}  // namespace
}  // namespace lodforge
