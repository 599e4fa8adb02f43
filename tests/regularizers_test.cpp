// The additions to the paper's chain (long runs released from a shared direction, curved walls)
// and the CGAL peer regularizer, on shapes whose truth is known.
#include <gtest/gtest.h>

#include <cmath>

#include "geometry/polygon.hpp"
#include "pipeline/building.hpp"
#include "support/shapes.hpp"

namespace lodforge {
namespace {

BuildingResult run(const PolygonWithHoles& truth, double noise_px, std::uint64_t seed, const std::string& regularizer,
                   const CoreOptions& options) {
  const auto shape = test::rasterize_shape(truth, 0.25, noise_px, noise_px > 0 ? 2.0 : 0.0, seed);
  EXPECT_EQ(shape.buildings.size(), 1u);
  return regularize_with(regularizer, shape.buildings[0].rings, 0.25, options);
}

// A long building whose long walls are 1.2° apart (a slight taper): one shared direction would
// put each long wall's ends 0.5 m off; released, each wall keeps its own direction.
TEST(Regularizers, LongWallsOffTheSharedDirectionAreReleased) {
  const PolygonWithHoles truth = test::rotated({{{0, 0}, {100, 0}, {100, 10}, {0, 10 + 100 * std::tan(1.2 * M_PI / 180)}}, {}}, 20.0);
  CoreOptions released, shared;
  shared.refinement.release_px = 0;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const BuildingResult with = run(truth, 0.5, seed, "deformation", released);
    const BuildingResult without = run(truth, 0.5, seed, "deformation", shared);
    ASSERT_TRUE(with.ok && without.ok) << with.reason << without.reason;
    EXPECT_EQ(with.footprint.outer.size(), 4u) << "seed " << seed;
    EXPECT_GE(test::iou(with.footprint, truth), 0.985) << "seed " << seed;
    EXPECT_GT(test::iou(with.footprint, truth), test::iou(without.footprint, truth) + 0.003) << "seed " << seed;
  }
}

// Short walls a little off stay on the shared directions (their ends would move < 1 px).
TEST(Regularizers, ShortWallsStayOnTheSharedDirections) {
  const PolygonWithHoles truth = test::rotated({{{0, 0}, {12, 0}, {12, 8}, {0, 8.1}}, {}}, 35.0);
  const BuildingResult r = run(truth, 0.0, 1, "deformation", CoreOptions{});
  ASSERT_TRUE(r.ok) << r.reason;
  ASSERT_EQ(r.footprint.outer.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {  // a rectangle: every corner square
    const Vec2 a = edge_vector(r.footprint.outer, i).normalized(), b = edge_vector(r.footprint.outer, (i + 1) % 4).normalized();
    EXPECT_NEAR(a.dot(b), 0.0, 1e-9) << "corner " << i;
  }
}

// A stadium: two straight walls and two half circles of 8 m radius. The arcs are kept as
// simplified contour; without it they become a few long lines cutting and overshooting the arc.
TEST(Regularizers, CurvedWallsFollowTheContour) {
  PolygonWithHoles stadium;
  for (int k = 0; k <= 36; ++k) stadium.outer.push_back({40 + 8 * std::sin(k * M_PI / 36), 8 - 8 * std::cos(k * M_PI / 36)});
  for (int k = 0; k <= 36; ++k) stadium.outer.push_back({-8 * std::sin(k * M_PI / 36), 8 + 8 * std::cos(k * M_PI / 36)});
  const PolygonWithHoles truth = test::rotated(stadium, 10.0);
  CoreOptions curved, straight;
  straight.corners.curve_px = 0;
  const BuildingResult with = run(truth, 0.0, 1, "deformation", curved);
  const BuildingResult without = run(truth, 0.0, 1, "deformation", straight);
  ASSERT_TRUE(with.ok) << with.failed_stage << ": " << with.reason;
  EXPECT_GE(test::iou(with.footprint, truth), 0.99);
  if (without.ok) {
    EXPECT_GT(test::iou(with.footprint, truth), test::iou(without.footprint, truth) + 0.005);
  }
  // Simplified to a pixel: far fewer vertices than the contour, more than a polygon of lines.
  EXPECT_LT(with.footprint.outer.size(), 80u);
  EXPECT_GT(with.footprint.outer.size(), 12u);
}

// A noisy straight-walled L does not become "curved": the wobble averages out over a window.
TEST(Regularizers, NoiseIsNotACurve) {
  const PolygonWithHoles truth = test::rotated({{{0, 0}, {40, 0}, {40, 12}, {12, 12}, {12, 30}, {0, 30}}, {}}, 25.0);
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const BuildingResult r = run(truth, 0.8, seed, "deformation", CoreOptions{});
    ASSERT_TRUE(r.ok) << r.reason;
    EXPECT_EQ(r.footprint.outer.size(), 6u) << "seed " << seed;
  }
}

// The deformed route on a coarse mesh (each labeled run simplified to 1 px before meshing, mesh
// edges up to 20 px): the same footprints as on the full staircase, within a few hundredths.
TEST(Regularizers, DeformedRouteOnACoarseMeshMatchesTheFullMesh) {
  const PolygonWithHoles truth = test::rotated({{{0, 0}, {16, 0}, {16, 6}, {6, 6}, {6, 14}, {0, 14}}, {}}, 30.0);
  CoreOptions full, coarse;
  full.corners.route = coarse.corners.route = "deformed";
  coarse.deformation.simplify_px = 1.0;
  coarse.triangulation.size_bound_px = 20.0;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const BuildingResult a = run(truth, 0.5, seed, "deformation", full), b = run(truth, 0.5, seed, "deformation", coarse);
    ASSERT_TRUE(a.ok && b.ok) << a.reason << b.reason;
    EXPECT_EQ(b.footprint.outer.size(), 6u) << "seed " << seed;
    EXPECT_GE(test::iou(b.footprint, truth), 0.95) << "seed " << seed;
    EXPECT_NEAR(test::iou(b.footprint, truth), test::iou(a.footprint, truth), 0.02) << "seed " << seed;
    EXPECT_LE(b.alignment_max_deg, 5.0) << "seed " << seed;
    EXPECT_LT(b.deformation_iterations, a.deformation_iterations + 50) << "seed " << seed;
  }
}

TEST(Regularizers, CgalPeerRegularizesARotatedRectangle) {
  const PolygonWithHoles truth = test::rotated({{{0, 0}, {24, 0}, {24, 14}, {0, 14}}, {{{6, 4}, {6, 9}, {12, 9}, {12, 4}}}}, 17.0);
  const BuildingResult r = run(truth, 0.5, 3, "cgal", CoreOptions{});
  ASSERT_TRUE(r.ok) << r.failed_stage << ": " << r.reason;
  EXPECT_EQ(polygon_problem(r.footprint), "");
  ASSERT_EQ(r.footprint.holes.size(), 1u);
  EXPECT_GE(test::iou(r.footprint, truth), 0.95);
  EXPECT_LE(r.footprint.outer.size(), 12u);  // the staircase (hundreds of vertices) is gone
  EXPECT_GT(signed_area(r.footprint.outer), 0);
  EXPECT_LT(signed_area(r.footprint.holes[0]), 0);
}

TEST(Regularizers, CgalPeerFailureGivesTheFallbackWithItsReason) {
  CoreOptions o;
  o.cgal.simplify_m = 100;  // every ring collapses
  const BuildingResult r = run({{{0, 0}, {10, 0}, {10, 6}, {0, 6}}, {}}, 0.0, 1, "cgal", o);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.failed_stage, "cgal");
  EXPECT_NE(r.reason.find("fewer than 3 vertices"), std::string::npos) << r.reason;
  EXPECT_EQ(polygon_problem(r.footprint), "");
}

TEST(Regularizers, EveryNamedRegularizerRunsAndAnUnknownOneIsRefused) {
  const PolygonWithHoles truth = test::rotated({{{0, 0}, {16, 0}, {16, 9}, {0, 9}}, {}}, 5.0);
  for (const std::string& name : regularizer_names()) {
    const BuildingResult r = run(truth, 0.3, 1, name, CoreOptions{});
    EXPECT_TRUE(r.ok) << name << ": " << r.reason;
    EXPECT_GE(test::iou(r.footprint, truth), 0.93) << name;
  }
  EXPECT_THROW(run(truth, 0.3, 1, "bogus", CoreOptions{}), std::invalid_argument);
}

}  // namespace
}  // namespace lodforge
