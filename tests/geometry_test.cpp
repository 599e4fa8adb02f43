#include <gtest/gtest.h>

#include <algorithm>

#include "geometry/polygon.hpp"

namespace lodforge {
namespace {

Ring square(double s = 1.0) { return {{0, 0}, {s, 0}, {s, s}, {0, s}}; }

TEST(Geometry, SignedAreaFollowsOrientation) {
  EXPECT_DOUBLE_EQ(signed_area(square(2)), 4.0);
  Ring cw = square(2);
  std::reverse(cw.begin(), cw.end());
  EXPECT_DOUBLE_EQ(signed_area(cw), -4.0);
}

TEST(Geometry, RingProblemFindsSelfIntersection) {
  EXPECT_EQ(ring_problem(square()), "");
  const Ring bowtie = {{0, 0}, {1, 1}, {1, 0}, {0, 1}};
  EXPECT_NE(ring_problem(bowtie).find("crosses itself"), std::string::npos);
  const Ring repeated = {{0, 0}, {1, 0}, {1, 0}, {0, 1}};
  EXPECT_EQ(ring_problem(repeated), "zero-length edge");
  const Ring touching = {{0, 0}, {4, 0}, {4, 4}, {2, 0}, {0, 4}};  // vertex 3 touches edge 0
  EXPECT_NE(ring_problem(touching), "");
}

TEST(Geometry, PolygonProblemChecksHoles) {
  PolygonWithHoles p{square(10), {{{2, 2}, {2, 4}, {4, 4}, {4, 2}}}};
  EXPECT_EQ(polygon_problem(p), "");
  EXPECT_NEAR(area(p), 96.0, 1e-12);
  PolygonWithHoles ccw_hole{square(10), {{{2, 2}, {4, 2}, {4, 4}, {2, 4}}}};
  EXPECT_EQ(polygon_problem(ccw_hole), "hole 0 is not clockwise");
  PolygonWithHoles outside{square(10), {{{12, 2}, {12, 4}, {14, 4}, {14, 2}}}};
  EXPECT_EQ(polygon_problem(outside), "hole 0 lies outside the outer ring");
  PolygonWithHoles crossing{square(10), {{{8, 2}, {8, 4}, {12, 4}, {12, 2}}}};
  EXPECT_NE(polygon_problem(crossing), "");
}

// Two corner lines that overshoot past each other make a thin inverted loop: it is cut off at the
// crossing, and the ring keeps its corner. A loop wider than allowed, or a figure eight, is left.
TEST(Geometry, UntangleCutsOffAThinLoopOnly) {
  const Ring overshoot = {{0, 0}, {10, 0}, {10, 10.5}, {10.5, 10}, {0, 10}};  // loop (10,10)-(10,10.5)-(10.5,10)
  ASSERT_NE(ring_problem(overshoot), "");
  Ring ring = overshoot;
  EXPECT_FALSE(untangle(ring, 0.1));  // the loop's mean width: 2 x 0.125 m^2 / 1.71 m = 0.15 m
  EXPECT_EQ(ring, overshoot);
  ASSERT_TRUE(untangle(ring, 0.2));
  EXPECT_EQ(ring_problem(ring), "");
  EXPECT_NEAR(signed_area(ring), 100.0, 1e-9);
  ASSERT_EQ(ring.size(), 4u);
  EXPECT_EQ(std::count_if(ring.begin(), ring.end(), [](const Vec2& p) { return (p - Vec2(10, 10)).norm() < 1e-9; }), 1);
  // Clockwise (a hole's way), the same.
  Ring hole(overshoot.rbegin(), overshoot.rend());
  ASSERT_TRUE(untangle(hole, 0.2));
  EXPECT_NEAR(signed_area(hole), -100.0, 1e-9);
  // A bow tie: two triangles of 16 m^2, neither thin.
  const Ring bowtie = {{0, 0}, {8, 0}, {0, 8}, {8, 8}};
  ring = bowtie;
  EXPECT_FALSE(untangle(ring, 1.0));
  EXPECT_EQ(ring, bowtie);
}

TEST(Geometry, RemoveDegenerateVertices) {
  const Ring ring = {{0, 0}, {1, 0}, {2, 0}, {2, 0}, {2, 2}, {0, 2}, {0, 1}};
  const Ring clean = remove_degenerate_vertices(ring, 1e-9);
  ASSERT_EQ(clean.size(), 4u);
  EXPECT_DOUBLE_EQ(signed_area(clean), 4.0);
}

TEST(Geometry, DouglasPeuckerKeepsCornersWithinTolerance) {
  Ring ring;
  for (int i = 0; i < 10; ++i) ring.emplace_back(i, (i % 2) * 0.1);
  for (int i = 0; i < 10; ++i) ring.emplace_back(10, i);
  for (int i = 10; i > 0; --i) ring.emplace_back(i, 10);
  for (int i = 10; i > 0; --i) ring.emplace_back(0, i);
  const Ring simple = douglas_peucker(ring, 0.2);
  EXPECT_EQ(simple.size(), 4u);
  EXPECT_GT(signed_area(simple), 0);
  EXPECT_EQ(ring_problem(simple), "");
  EXPECT_GT(douglas_peucker(ring, 0.05).size(), 4u);
}

TEST(Geometry, DouglasPeuckerOpenKeepsTheEndsAndTheBump) {
  const std::vector<Vec2> line = {{0, 0}, {1, 0.1}, {2, 0}, {3, 2}, {4, 0}, {5, -0.1}, {6, 0}};
  const std::vector<char> keep = douglas_peucker_open(line, 0.5);
  EXPECT_EQ(keep, (std::vector<char>{1, 0, 1, 1, 1, 0, 1}));
  EXPECT_EQ(douglas_peucker_open(line, 5.0), (std::vector<char>{1, 0, 0, 0, 0, 0, 1}));
}

}  // namespace
}  // namespace lodforge
