#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "geometry/polygon.hpp"
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

// Eq. 2 edge by edge, each weight computed where it is used: the reference the smoothing's
// shared pair weights must reproduce.
std::vector<Vec2> smooth_reference(const Ring& ring, double pixel_size, const SmoothingOptions& o) {
  const std::size_t n = ring.size();
  std::vector<Vec2> normals = edge_normals(ring);
  std::vector<double> mid(n);
  double total = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double len = edge_vector(ring, i).norm();
    mid[i] = total + 0.5 * len;
    total += len;
  }
  const double scale = std::max(1.0, o.min_neighbourhood_px * pixel_size / o.neighbourhood_m);
  const double threshold = o.neighbourhood_m * scale, sigma_d2 = std::pow(o.sigma_d_m * scale, 2);
  for (int pass = 0; pass < o.passes; ++pass) {
    std::vector<Vec2> next(n);
    for (std::size_t i = 0; i < n; ++i) {
      Vec2 sum = normals[i];
      auto add = [&](std::size_t k) {
        const double d = std::min(std::abs(mid[i] - mid[k]), total - std::abs(mid[i] - mid[k]));
        if (d >= threshold) return false;
        const double angle = std::acos(std::clamp(normals[i].dot(normals[k]), -1.0, 1.0)) * 180.0 / M_PI;
        sum += std::exp(-d / sigma_d2 - angle / (o.sigma_a_deg * o.sigma_a_deg)) * normals[k];
        return true;
      };
      for (std::size_t k = (i + 1) % n, steps = 0; steps < n / 2 && add(k); k = (k + 1) % n) ++steps;
      for (std::size_t k = (i + n - 1) % n, steps = 0; steps < (n - 1) / 2 && add(k); k = (k + n - 1) % n) ++steps;
      next[i] = sum.normalized();
    }
    normals = next;
  }
  return normals;
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

TEST(Smoothing, SharedPairWeightsGiveEquationTwo) {
  // A staircase, a ring of a few uneven edges (the neighbourhood wraps around it, and a long edge
  // makes the arc to later edges shrink again), and a wide neighbourhood over the staircase.
  const PolygonWithHoles rect = test::rotated({{{0, 0}, {20, 0}, {20, 12}, {0, 12}}, {}}, 30.0);
  const Ring stairs = test::rasterize_shape(rect, 0.1, 0, 0, 1).buildings[0].rings[0];
  const Ring few = {{0, 0}, {3, 0}, {3, 0.2}, {2.9, 0.5}, {0.2, 0.4}, {0, 0.3}};
  SmoothingOptions every, wide, whole;  // (every edge smoothed on its own, as eq. 2: no blocks)
  every.block_neighbours = wide.block_neighbours = whole.block_neighbours = 0;
  wide.neighbourhood_m = 3.0;
  wide.sigma_d_m = 1.5;
  whole.neighbourhood_m = 10.0;  // more than half the small ring: every edge is a neighbour
  for (const auto& [ring, options] : {std::pair{stairs, every}, std::pair{stairs, wide}, std::pair{few, wide}, std::pair{few, whole}}) {
    const std::vector<Vec2> got = smooth_normals(ring, 0.1, options), want = smooth_reference(ring, 0.1, options);
    ASSERT_EQ(got.size(), want.size());
    // (The angle weights come from tables within about 1e-9 of eq. 2's exponential: the normals
    // agree to better than 1e-9, not to the last bit.)
    for (std::size_t i = 0; i < got.size(); ++i) EXPECT_LT((got[i] - want[i]).norm(), 1e-9) << "edge " << i << " of " << got.size();
  }
}

// The neighbourhood widens to noise_neighbourhood boundary noises, up to max_neighbourhood_m, and
// never narrows what the pixel size asks for: 0.5 m at 0.1 m a pixel without a noise, 6 x 0.2 m
// under 0.2 m of noise, 2.5 m under a metre; at 2 m a pixel two pixels (4 m) whatever the noise.
TEST(Smoothing, TheNeighbourhoodWidensWithTheNoise) {
  const SmoothingOptions o;
  EXPECT_DOUBLE_EQ(smoothing_neighbourhood_m(0.1, o, 0.0), 0.5);
  EXPECT_DOUBLE_EQ(smoothing_neighbourhood_m(0.1, o, 0.05), 0.5);
  EXPECT_NEAR(smoothing_neighbourhood_m(0.1, o, 0.2), 1.2, 1e-12);
  EXPECT_DOUBLE_EQ(smoothing_neighbourhood_m(0.1, o, 1.0), 2.5);
  EXPECT_DOUBLE_EQ(smoothing_neighbourhood_m(0.25, o, 0.1), 1.25);
  EXPECT_DOUBLE_EQ(smoothing_neighbourhood_m(2.0, o, 1.0), 4.0);
  SmoothingOptions off = o;
  off.noise_neighbourhood = 0;
  EXPECT_DOUBLE_EQ(smoothing_neighbourhood_m(0.1, off, 1.0), 0.5);
  // No bound in metres: six noises, however many; no smoothing at all: none, whatever the noise.
  SmoothingOptions unbounded = o;
  unbounded.max_neighbourhood_m = 0;
  EXPECT_DOUBLE_EQ(smoothing_neighbourhood_m(0.1, unbounded, 0.0), 0.5);
  EXPECT_NEAR(smoothing_neighbourhood_m(0.1, unbounded, 1.0), 6.0, 1e-12);
  EXPECT_DOUBLE_EQ(smoothing_neighbourhood_m(2.0, unbounded, 0.0), 10.0);
  SmoothingOptions none = o;
  none.neighbourhood_m = 0;
  EXPECT_DOUBLE_EQ(smoothing_neighbourhood_m(0.1, none, 0.0), 0.0);
  EXPECT_DOUBLE_EQ(smoothing_neighbourhood_m(0.1, none, 1.0), 0.0);
}

// A wobble of 1 m whose wavelength is 3 m, at 0.1 m a pixel: its flanks stand about 60 degrees
// off the walls. Smoothed over the paper's half metre, the normals lie 26 degrees off the walls'
// directions (median over the edges); smoothed for the wobble's noise (about 0.6 m, as a mask of
// such buildings pools it), 18 degrees (19 edge by edge: below).
TEST(Smoothing, AFastWobbleIsSmoothedOverItsNoise) {
  const PolygonWithHoles rect = test::rotated({{{0, 0}, {25, 0}, {25, 18}, {0, 18}}, {}}, 20.0);
  const Ring ring = test::rasterize_shape_m(rect, 0.1, 1.0, 3.0, 2.0, 1).buildings[0].rings[0];
  const auto median_off_walls = [&](double noise_m) {
    std::vector<double> off;
    for (const Vec2& n : smooth_normals(ring, 0.1, SmoothingOptions{}, noise_m)) off.push_back(angle_to_nearest_deg(n, 20.0));
    return median(off);
  };
  const double paper = median_off_walls(0.0), noisy = median_off_walls(0.6);
  std::cout << "median degrees off the walls: " << paper << " -> " << noisy << '\n';
  EXPECT_GT(paper, 22.0);
  EXPECT_LT(noisy, paper - 5.0);
}

// Where the neighbourhood spans many edges (2.5 m over edges of 0.1 m), they are smoothed in
// blocks of at least 2.5 m / 8 and interpolated: on the fast wobble above, the edges' normals a
// median of under 3 degrees from eq. 2's edge by edge, as near the walls' directions (17.9 against
// 19.1 degrees, median), and the edges within a metre of a corner within 5 degrees as near. The
// ring started elsewhere (its blocks cut elsewhere, the first and last joined across its start)
// gives each edge about the same normal, the edges at either start too. Where it spans few (the paper's
// half metre), the blocks are not used: the normals are eq. 2's.
TEST(Smoothing, ManyEdgesANeighbourhoodAreSmoothedInBlocks) {
  const PolygonWithHoles rect = test::rotated({{{0, 0}, {25, 0}, {25, 18}, {0, 18}}, {}}, 20.0);
  const Ring ring = test::rasterize_shape_m(rect, 0.1, 1.0, 3.0, 2.0, 1).buildings[0].rings[0];
  SmoothingOptions every;
  every.block_neighbours = 0;
  const SmoothingOptions blocks;
  ASSERT_GT(smoothing_neighbourhood_m(0.1, blocks, 0.6), 2.0 * blocks.block_neighbours * perimeter(ring) / double(ring.size()));
  const std::vector<Vec2> exact = smooth_normals(ring, 0.1, every, 0.6), fast = smooth_normals(ring, 0.1, blocks, 0.6);
  ASSERT_EQ(exact.size(), fast.size());
  std::vector<double> apart, off_exact, off_fast;
  for (std::size_t i = 0; i < exact.size(); ++i) {
    apart.push_back(std::acos(std::clamp(exact[i].dot(fast[i]), -1.0, 1.0)) * 180.0 / M_PI);
    off_exact.push_back(angle_to_nearest_deg(exact[i], 20.0));
    off_fast.push_back(angle_to_nearest_deg(fast[i], 20.0));
  }
  std::cout << "blocks against every edge: median " << median(apart) << " deg apart; off the walls " << median(off_exact) << " -> "
            << median(off_fast) << " deg\n";
  EXPECT_LT(median(apart), 3.0);
  EXPECT_NEAR(median(off_fast), median(off_exact), 2.0);
  // Near the corners.
  std::vector<double> corner_exact, corner_fast;
  std::vector<Vec2> corners;
  for (const Vec2& c : rect.outer) corners.push_back(c);
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const Vec2 m = ring[i] + 0.5 * edge_vector(ring, i);
    double near = 1e9;
    for (const Vec2& c : corners) near = std::min(near, (m - c).norm());
    if (near < 1.0) {
      corner_exact.push_back(off_exact[i]);
      corner_fast.push_back(off_fast[i]);
    }
  }
  ASSERT_FALSE(corner_exact.empty());
  EXPECT_LT(median(corner_fast), median(corner_exact) + 5.0);
  // Started a third of the way round.
  const std::size_t shift = ring.size() / 3;
  Ring turned(ring.begin() + long(shift), ring.end());
  turned.insert(turned.end(), ring.begin(), ring.begin() + long(shift));
  const std::vector<Vec2> again = smooth_normals(turned, 0.1, blocks, 0.6);
  std::vector<double> moved;
  double worst = 0, worst_at_starts = 0;
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const std::size_t k = (i + ring.size() - shift) % ring.size();  // edge i of the ring is edge k of the turned one
    const double a = std::acos(std::clamp(fast[i].dot(again[k]), -1.0, 1.0)) * 180.0 / M_PI;
    moved.push_back(a);
    worst = std::max(worst, a);
    if (std::min({i, ring.size() - i, k, ring.size() - k}) < 20) worst_at_starts = std::max(worst_at_starts, a);
  }
  std::cout << "started elsewhere: median " << median(moved) << ", most " << worst << " deg, at either start " << worst_at_starts << '\n';
  EXPECT_LT(median(moved), 2.0);
  EXPECT_LT(worst_at_starts, 10.0);
  // The paper's neighbourhood at 0.1 m, five edges: eq. 2 itself.
  const std::vector<Vec2> paper = smooth_normals(ring, 0.1, blocks, 0.0), paper_every = smooth_normals(ring, 0.1, every, 0.0);
  for (std::size_t i = 0; i < paper.size(); ++i) ASSERT_EQ(paper[i], paper_every[i]) << "edge " << i;
}

}  // namespace
}  // namespace lodforge
