// A block split among the cadastral footprints it covers (stages/partition).
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "geometry/polygon.hpp"
#include "partition/partition.hpp"
#include "parts/parts.hpp"
#include "pipeline/core_options.hpp"
#include <opencv2/core.hpp>

namespace lodforge {
namespace {

Ring rotated(Ring r, double degrees) {
  const double a = degrees * M_PI / 180, c = std::cos(a), s = std::sin(a);
  for (Vec2& p : r) p = Vec2(c * p.x() - s * p.y(), s * p.x() + c * p.y());
  return r;
}

Ring box(double x0, double y0, double x1, double y1) { return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}; }

// The directed edges of a polygon's rings, as exact coordinate quadruples.
std::set<std::array<double, 4>> edges(const PolygonWithHoles& p) {
  std::set<std::array<double, 4>> out;
  auto add = [&](const Ring& r) {
    for (std::size_t i = 0; i < r.size(); ++i) {
      const Vec2& a = r[i];
      const Vec2& b = r[(i + 1) % r.size()];
      out.insert({a.x(), a.y(), b.x(), b.y()});
    }
  };
  add(p.outer);
  for (const Ring& h : p.holes) add(h);
  return out;
}

// The length of boundary two polygons share: edges of one that the other runs the other way.
double shared_length(const PolygonWithHoles& a, const PolygonWithHoles& b) {
  const auto eb = edges(b);
  double length = 0;
  for (const auto& e : edges(a))
    if (eb.count({e[2], e[3], e[0], e[1]})) length += std::hypot(e[2] - e[0], e[3] - e[1]);
  return length;
}

// Two houses of a row, 10 m wide, sharing a party wall; the mask reaches 0.5 m past the cadastre
// all round (roof overhangs). Turned by 30° too: nothing depends on the axes.
TEST(Partition, TwoHousesSharingAWallShareItExactlyWithoutGapOrOverlap) {
  for (double angle : {0.0, 30.0}) {
    SCOPED_TRACE(angle);
    const PolygonWithHoles outline{rotated(box(-0.5, -0.5, 20.5, 10.5), angle), {}};
    const std::vector<std::vector<PolygonWithHoles>> footprints{{{rotated(box(0, 0, 10, 10), angle), {}}},
                                                                 {{rotated(box(10, 0, 20, 10), angle), {}}}};
    const Partition p = partition_outlines({outline}, footprints, PartitionOptions{}, 4.0);
    ASSERT_EQ(p.shares.size(), 2u);
    const PolygonWithHoles& a = p.shares[0].polygon;
    const PolygonWithHoles& b = p.shares[1].polygon;
    EXPECT_EQ(polygon_problem(a), "");
    EXPECT_EQ(polygon_problem(b), "");
    EXPECT_TRUE(p.rest.empty());
    EXPECT_EQ(p.dropped_small, 0);
    EXPECT_EQ(p.shares[0].note + p.shares[1].note, "");
    // No gap, no overlap: the two shares make the outline.
    EXPECT_NEAR(area(a) + area(b), area(outline), 1e-6);
    // Each house keeps its half and its overhang, split square to the facade at the party wall:
    // 10.5 m x 11 m, a rectangle.
    EXPECT_NEAR(area(a), 115.5, 1e-6);
    EXPECT_NEAR(area(b), 115.5, 1e-6);
    EXPECT_EQ(vertex_count(a), 4u);
    EXPECT_EQ(vertex_count(b), 4u);
    // The party wall (10 m) and its continuation through the overhangs is one boundary of both,
    // vertex for vertex.
    EXPECT_NEAR(shared_length(a, b), 11.0, 1e-9);
  }
}

// Mask area no footprint covers, farther than extension_m from any: a building of its own.
TEST(Partition, MaskBeyondTheExtensionIsABuildingOfItsOwnAndCadastreModeKeepsThePolygons) {
  const PolygonWithHoles outline{box(0, 0, 30, 10), {}};
  const std::vector<std::vector<PolygonWithHoles>> footprints{{{box(0, 0, 10, 10), {}}}, {{box(10, 0, 20, 10), {}}}};
  PartitionOptions options;
  options.extension_m = 2.0;
  const Partition p = partition_outlines({outline}, footprints, options, 4.0);
  ASSERT_EQ(p.rest.size(), 1u);
  // The second house takes the annex to 2 m from its wall.
  EXPECT_NEAR(area(p.rest[0]), 8.0 * 10, 1e-9);
  EXPECT_EQ(vertex_count(p.rest[0]), 4u);
  EXPECT_NEAR(area(p.shares[1].polygon) + area(p.rest[0]), 200.0, 1e-6);
  EXPECT_NEAR(area(p.shares[0].polygon), 100.0, 1e-9);

  options.lod0 = "cadastre";
  const Partition c = partition_outlines({outline}, footprints, options, 4.0);
  ASSERT_EQ(c.shares.size(), 2u);
  EXPECT_NEAR(area(c.shares[1].polygon), 100.0, 1e-9);  // the cadastre's polygon, not the outline's share
  ASSERT_EQ(c.rest.size(), 1u);  // the annex beyond the extension is found all the same
  EXPECT_NEAR(area(c.rest[0]), area(p.rest[0]), 1e-9);
}

// LoD1.3: two houses of a row, 10 m and 14 m wide, roofs 6 m and 12 m high, one block in the
// mask: two parts, the shared wall identical in both, together the block.
TEST(Parts, TwoHousesOfDifferentHeightsSharingAWallBecomeTwoPartsSharingItExactly) {
  for (double angle : {0.0, 20.0}) {
    SCOPED_TRACE(angle);
    HeightRaster dsm;
    dsm.transform.c = {-10, 0.5, 0, 30, 0, -0.5};
    dsm.values.create(100, 100, CV_32F);
    dsm.valid = cv::Mat::ones(100, 100, CV_8U);
    cv::RNG rng(7);
    const Ring a = rotated(box(0, 0, 10, 10), angle), b = rotated(box(10, 0, 24, 10), angle);
    for (int y = 0; y < 100; ++y)
      for (int x = 0; x < 100; ++x) {
        const Vec2 p = dsm.transform.to_map(x + 0.5, y + 0.5);
        const double h = point_in_ring(p, a) ? 6 : point_in_ring(p, b) ? 12 : 0;
        dsm.values.at<float>(y, x) = float(h + rng.gaussian(0.05));
      }
    const PolygonWithHoles block{rotated(box(0, 0, 24, 10), angle), {}};
    const std::vector<PolygonWithHoles> parts = split_by_roof_steps(block, dsm, 0.5, "deformation", CoreOptions{}, PartOptions{});
    ASSERT_EQ(parts.size(), 2u);
    EXPECT_EQ(polygon_problem(parts[0]), "");
    EXPECT_EQ(polygon_problem(parts[1]), "");
    EXPECT_NEAR(area(parts[0]) + area(parts[1]), 240.0, 1e-6);  // no gap, no overlap
    EXPECT_NEAR(area(parts[0]), 140.0, 3.0);  // the larger first, its wall within a few decimetres
    EXPECT_NEAR(area(parts[1]), 100.0, 3.0);
    EXPECT_NEAR(shared_length(parts[0], parts[1]), 10.0, 0.2);
    // One roof: no parts.
    PartOptions high;
    high.min_step_m = 7;
    EXPECT_TRUE(split_by_roof_steps(block, dsm, 0.5, "deformation", CoreOptions{}, high).empty());
  }
}

}  // namespace
}  // namespace lodforge
