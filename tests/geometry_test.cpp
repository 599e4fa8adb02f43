#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "geometry/polygon.hpp"
#include "geometry/segment_grid.hpp"

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

// Of a polygon whose holes cross its outer ring or each other, the holes that fit stay, in order.
TEST(Geometry, HolesThatFitKeepsTheValidOnes) {
  const Ring good{{2, 2}, {2, 4}, {4, 4}, {4, 2}}, across{{8, 2}, {8, 4}, {12, 4}, {12, 2}}, over_good{{3, 3}, {3, 5}, {5, 5}, {5, 3}},
      other{{6, 6}, {6, 8}, {8, 8}, {8, 6}};
  const PolygonWithHoles kept = holes_that_fit({square(10), {good, across, over_good, other}});
  ASSERT_EQ(kept.holes.size(), 2u);  // (two of the four left out)
  EXPECT_EQ(kept.holes[0], good);
  EXPECT_EQ(kept.holes[1], other);
  EXPECT_EQ(polygon_problem(kept), "");
  EXPECT_NEAR(area(kept), 92.0, 1e-12);
}

// A point inside a ring whose box's middle lies outside it (a U), and the contour's holes a
// polygon covers: the one it draws filled, not the one it keeps, nor one outside it.
TEST(Geometry, InteriorPointAndCoveredHoles) {
  const Ring u{{0, 0}, {10, 0}, {10, 10}, {8, 10}, {8, 2}, {2, 2}, {2, 10}, {0, 10}};
  const Vec2 p = interior_point(u);
  EXPECT_TRUE(point_in_ring(p, u)) << p.transpose();
  EXPECT_FALSE(point_in_ring(Vec2(5, 5), u));
  const Ring kept{{2, 2}, {2, 4}, {4, 4}, {4, 2}}, filled{{6, 6}, {6, 8}, {7, 8}, {7, 6.5}, {8, 6.5}, {8, 6}}, outside{{12, 2}, {12, 4}, {14, 4}, {14, 2}};
  const std::vector<Ring> contour{square(10), kept, filled, outside};
  EXPECT_EQ(covered_holes(contour, {square(10), {kept}}), (std::vector<std::size_t>{2}));
  EXPECT_EQ(covered_holes(contour, {square(10), {kept, filled}}), (std::vector<std::size_t>{}));
  EXPECT_EQ(covered_holes(contour, {square(10), {}}), (std::vector<std::size_t>{1, 2}));
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

// A needle (a vertex where the ring turns back at 3 degrees, 0.2 m wide at its base, 0.4 m^2) is
// dropped, a short wall turning back at the end of a long one joins the next wall's line; a wedge
// as sharp but large, or a needle with a hole inside it, stays.
TEST(Geometry, RemoveSpikesDropsNeedlesOnly) {
  const Vec2 tip(5.1, 14);
  const PolygonWithHoles needle{{{0, 0}, {10, 0}, {10, 10}, {5.2, 10}, tip, {5.0, 10}, {0, 10}}, {}};
  ASSERT_EQ(polygon_problem(needle), "");
  PolygonWithHoles p = needle;
  EXPECT_EQ(remove_spikes(p, 20, 0.5), 0u);  // more than a square of 0.5 m
  EXPECT_EQ(p.outer, needle.outer);
  EXPECT_EQ(remove_spikes(p, 2, 1.0), 0u);  // sharper than 2 degrees only
  EXPECT_EQ(remove_spikes(p, 20, 1.0), 1u);
  ASSERT_EQ(p.outer.size(), 6u);
  EXPECT_TRUE(std::none_of(p.outer.begin(), p.outer.end(), [&](const Vec2& q) { return (q - tip).norm() < 1e-12; }));
  EXPECT_EQ(polygon_problem(p), "");
  EXPECT_NEAR(signed_area(p.outer), 100.0, 1e-9);
  // A short wall turning back at the end of a long one (1.5 m at 14.7 degrees): the long wall and
  // the roof line beyond the short one meet.
  const Vec2 back(19.62, 10.55);
  PolygonWithHoles hook{{{0, 0}, {20, 0}, {20, 12}, back, {0, 13}}, {}};
  ASSERT_EQ(polygon_problem(hook), "");
  EXPECT_EQ(remove_spikes(hook, 20, 2.0), 1u);
  ASSERT_EQ(hook.outer.size(), 4u);
  const double roof_at_wall = back.y() + (20 - back.x()) * (13 - back.y()) / (0 - back.x());
  EXPECT_NEAR((hook.outer[2] - Vec2(20, roof_at_wall)).norm(), 0, 1e-9);
  EXPECT_EQ(hook.outer[3], Vec2(0, 13));
  // The same hook as a hole (clockwise: the short arm before the tip), the tip its first vertex.
  PolygonWithHoles hooked{{{-10, -10}, {30, -10}, {30, 30}, {-10, 30}}, {{{20, 12}, {20, 0}, {0, 0}, {0, 13}, back}}};
  ASSERT_EQ(polygon_problem(hooked), "");
  EXPECT_EQ(remove_spikes(hooked, 20, 2.0), 1u);
  ASSERT_EQ(hooked.holes.at(0).size(), 4u);
  EXPECT_NEAR((hooked.holes[0][0] - Vec2(20, roof_at_wall)).norm(), 0, 1e-9);
  EXPECT_EQ(polygon_problem(hooked), "");
  // A wedge of 15 degrees with 30 m arms is a building's sharp corner, not a needle.
  PolygonWithHoles wedge{{{0, 0}, {30, 0}, {35, 4}, {30, 30 * std::tan(M_PI / 12)}}, {}};
  ASSERT_EQ(polygon_problem(wedge), "");
  EXPECT_EQ(remove_spikes(wedge, 20, 1.0), 0u);
  // A hole inside the needle keeps it (dropping the tip would leave the hole outside).
  PolygonWithHoles holed = needle;
  holed.holes.push_back({{5.08, 10.5}, {5.1, 11}, {5.12, 10.5}});
  ASSERT_EQ(polygon_problem(holed), "");
  EXPECT_EQ(remove_spikes(holed, 20, 1.0), 0u);
  // A needle of a hole is dropped as the outer ring's.
  PolygonWithHoles in_hole{{{-10, -10}, {30, -10}, {30, 30}, {-10, 30}}, {Ring(needle.outer.rbegin(), needle.outer.rend())}};
  ASSERT_EQ(polygon_problem(in_hole), "");
  EXPECT_EQ(remove_spikes(in_hole, 20, 1.0), 1u);
  EXPECT_EQ(in_hole.holes.at(0).size(), 6u);
  EXPECT_EQ(polygon_problem(in_hole), "");
}

TEST(Geometry, RemoveDegenerateVertices) {
  const Ring ring = {{0, 0}, {1, 0}, {2, 0}, {2, 0}, {2, 2}, {0, 2}, {0, 1}};
  const Ring clean = remove_degenerate_vertices(ring, 1e-9);
  ASSERT_EQ(clean.size(), 4u);
  EXPECT_DOUBLE_EQ(signed_area(clean), 4.0);
}

TEST(Geometry, FlattenAlongLineDropsShallowNotchesAndThoseTheMaskFills) {
  // A 10 x 5 rectangle clipped along y = 0, where the outline dipped 0.3 in and 0.2 out, and
  // bit 2 deep.
  const Ring ring = {{0, 0}, {2, 0}, {2, 0.3}, {3, 0.3}, {3, 0}, {4, 0}, {4.5, -0.2}, {5, 0}, {6, 0}, {6, 2}, {7, 2}, {7, 0},
                     {10, 0}, {10, 5}, {0, 5}};
  const Ring flat = remove_degenerate_vertices(flatten_along_line(ring, {0, 0}, {10, 0}, 0.5), 1e-9);
  // The shallow dips go; the 2 deep bite stays, and so does the rest of the ring.
  const Ring expected = {{0, 0}, {6, 0}, {6, 2}, {7, 2}, {7, 0}, {10, 0}, {10, 5}, {0, 5}};
  EXPECT_EQ(flat, expected);
  // Shallower than they are: nothing goes.
  EXPECT_EQ(flatten_along_line(ring, {0, 0}, {10, 0}, 0.1), ring);
  // Along another line of the ring (x = 10), nothing to flatten: its two vertices there are adjacent.
  EXPECT_EQ(flatten_along_line(ring, {10, 0}, {10, 5}, 0.5), ring);
  // Where the mask fills the 2 deep bite (a dip the outline drew past the raster's edge), it goes
  // too; the rest of the ring, between the same line's vertices the other way round, stays.
  const auto all = [](const Vec2& p) { return p.x() > -1 && p.x() < 11 && p.y() > -1 && p.y() < 6; };  // (the whole ring too)
  const Ring filled = remove_degenerate_vertices(flatten_along_line(ring, {0, 0}, {10, 0}, 0.5, all, 0.1), 1e-9);
  EXPECT_EQ(filled, (Ring{{0, 0}, {10, 0}, {10, 5}, {0, 5}}));
  // Where the mask has the bite too (a yard reaching the edge), it stays; also where it has a
  // narrower yard in a part of it (a third of its width).
  const auto bitten = [&all](const Vec2& p) { return all(p) && !(p.x() > 6 && p.x() < 7 && p.y() < 2); };
  EXPECT_EQ(remove_degenerate_vertices(flatten_along_line(ring, {0, 0}, {10, 0}, 0.5, bitten, 0.1), 1e-9), expected);
  const auto narrow = [&all](const Vec2& p) { return all(p) && !(p.x() > 6.05 && p.x() < 6.4 && p.y() < 1.95); };
  EXPECT_EQ(remove_degenerate_vertices(flatten_along_line(ring, {0, 0}, {10, 0}, 0.5, narrow, 0.1), 1e-9), expected);
  // A hooked dip (a yard whose wall turns back over itself) that the mask has, a little smaller, stays.
  const Ring hooked = {{0, 0}, {6, 0}, {6, 3}, {3, 3}, {3, 4}, {7, 4}, {7, 0}, {10, 0}, {10, 5}, {0, 5}};
  const auto yard = [&all](const Vec2& p) {
    const bool in_yard = (p.x() > 6.05 && p.x() < 6.95 && p.y() < 3.95) || (p.x() > 3.05 && p.x() < 6.95 && p.y() > 3.05 && p.y() < 3.95);
    return all(p) && !in_yard;
  };
  EXPECT_EQ(flatten_along_line(hooked, {0, 0}, {10, 0}, 0.5, yard, 0.1), hooked);
  EXPECT_EQ(remove_degenerate_vertices(flatten_along_line(hooked, {0, 0}, {10, 0}, 0.5, all, 0.1), 1e-9),
            (Ring{{0, 0}, {10, 0}, {10, 5}, {0, 5}}));
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


// The grid's nearest segment is the one a scan over every segment finds, bit for bit: points
// inside, on and outside a ring of a thousand short segments (a contour of pixel edges), and with
// too few segments to bucket.
TEST(Geometry, SegmentGridFindsTheNearestSegmentAsAFullScanDoes) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> jitter(-0.4, 0.4), anywhere(-80.0, 80.0);
  std::vector<SegmentGrid::Segment> segments;
  Ring ring;
  for (int i = 0; i < 1000; ++i) {
    const double t = 2 * M_PI * i / 1000;
    ring.push_back({50 * std::cos(t) + jitter(random), 30 * std::sin(t) + jitter(random)});
  }
  SegmentGrid::add_ring(ring, segments);
  const auto scan = [](const std::vector<SegmentGrid::Segment>& all, const Vec2& p) {
    double best = std::numeric_limits<double>::infinity();
    for (const auto& s : all) best = std::min(best, squared_distance_to_segment(p, s.a, s.b));
    return best;
  };
  const SegmentGrid grid(segments);
  const SegmentGrid few({segments.begin(), segments.begin() + 10});
  std::vector<Vec2> points = {ring[17], 0.5 * (ring[3] + ring[4]), {0, 0}, {200, -150}, {-1e4, 3}};
  for (int i = 0; i < 300; ++i) points.push_back({anywhere(random), anywhere(random)});
  for (const Vec2& p : points) {
    EXPECT_EQ(grid.nearest_squared(p), scan(segments, p)) << p.transpose();
    EXPECT_EQ(few.nearest_squared(p), scan({segments.begin(), segments.begin() + 10}, p)) << p.transpose();
  }
  EXPECT_EQ(grid.nearest_squared(ring[17]), 0.0);
  EXPECT_TRUE(std::isinf(SegmentGrid({}).nearest_squared({1, 2})));
}

}  // namespace
}  // namespace lodforge
