#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

#include "corners/corners.hpp"
#include "geometry/polygon.hpp"
#include "labeling/mrf.hpp"
#include "support/shapes.hpp"

namespace lodforge {
namespace {

// A ring along the boundary of an axis-aligned rectangle with unit edges, labeled by side.
void rectangle_contour(int w, int h, Ring& ring, std::vector<int>& labels) {
  for (int x = 0; x < w; ++x) { ring.emplace_back(x, 0); labels.push_back(0); }
  for (int y = 0; y < h; ++y) { ring.emplace_back(w, y); labels.push_back(1); }
  for (int x = w; x > 0; --x) { ring.emplace_back(x, h); labels.push_back(2); }
  for (int y = h; y > 0; --y) { ring.emplace_back(0, y); labels.push_back(3); }
}

const std::vector<Vec2> axis_normals = {{0, -1}, {1, 0}, {0, 1}, {-1, 0}};

// The right side and top of a w x h box whose bottom wall the test builds (labels 1, 2, 3).
void close_box(int w, int h, Ring& ring, std::vector<int>& labels) {
  for (int y = 0; y < h; ++y) { ring.emplace_back(w, y); labels.push_back(1); }
  for (int x = w; x > 0; --x) { ring.emplace_back(x, h); labels.push_back(2); }
  for (int y = h; y > 0; --y) { ring.emplace_back(0, y); labels.push_back(3); }
}

// A 240 x 80 px box, px metres a pixel, whose bottom wall lies offset_px(x) pixels across at
// column x (traced as a mask's pixels are, each step a vertical edge), all of that wall labeled
// 0 as one run, the other walls 1-3; the ring in metres.
void profile_box(double px, const std::function<int(int)>& offset_px, Ring& ring, std::vector<int>& labels) {
  int y = 0;  // pixels
  const auto step_to = [&](int x, int target) {
    while (y != target) { ring.emplace_back(x * px, y * px); labels.push_back(0); y += target > y ? 1 : -1; }
  };
  for (int x = 0; x < 240; ++x) {
    step_to(x, offset_px(x));
    ring.emplace_back(x * px, y * px);
    labels.push_back(0);
  }
  step_to(240, 0);
  Ring box;
  std::vector<int> box_labels;
  close_box(240, 80, box, box_labels);
  for (const Vec2& p : box) ring.push_back(p * px);
  labels.insert(labels.end(), box_labels.begin(), box_labels.end());
}

// Options for the split tests: no curve test (a step of a few pixels is also a departure it
// would keep as a contour), and corners of a one-line fit (which lie a pixel or two from the
// contour's) not turned into steps.
CornerOptions split_options() {
  CornerOptions o;
  o.curve_px = 0;
  o.max_corner_shift_m = 5;
  return o;
}

// True when a vertex of r lies within 0.6 of p.
bool near(const Ring& r, const Vec2& p) {
  for (const Vec2& v : r) if ((v - p).norm() < 0.6) return true;
  return false;
}

TEST(Corners, RectangleGivesItsFourCorners) {
  Ring ring;
  std::vector<int> labels;
  rectangle_contour(10, 6, ring, labels);
  std::string problem;
  const Ring out = extract_corners(ring, labels, axis_normals, 1.0, CornerOptions{}, &problem);
  ASSERT_EQ(out.size(), 4u) << problem;
  EXPECT_NEAR(signed_area(out), 60.0, 1e-9);
}

// A thin building whose short ends got no direction of their own: its two long walls, each
// labeled over half of each end, still make a polygon, its ends square steps where the labels
// change; two runs that are neither parallel nor curved do not.
TEST(Corners, TwoParallelRunsCloseWithSquareEnds) {
  CornerOptions straight;
  straight.curve_px = 0;  // (a run over a wall and an end would bow like a curve ...
  straight.split_px = 0;  // ... or split into steps)
  Ring ring;
  std::vector<int> labels;
  rectangle_contour(40, 6, ring, labels);
  for (int& l : labels) l = l == 0 || l == 1 ? 0 : 2;  // the bottom wall and the right end: label 0
  std::string problem;
  const Ring out = extract_corners(ring, labels, axis_normals, 1.0, straight, &problem);
  ASSERT_EQ(out.size(), 4u) << problem;
  // The long walls fitted without the end edges their runs took in: within 2 % of the 240 m^2
  // (with them, each wall moves 0.4 m inwards: 209 m^2).
  EXPECT_NEAR(std::abs(signed_area(out)), 6.0 * 40.0, 0.02 * 240.0);
  for (std::size_t i = 0; i < out.size(); ++i) {
    const Vec2 e = edge_vector(out, i);
    EXPECT_LT(std::min(std::abs(e.x()), std::abs(e.y())), 1e-9) << i;  // square to the axes
  }
  for (int& l : labels) l = l == 0 ? 0 : 1;  // labels square to each other
  problem.clear();
  EXPECT_TRUE(extract_corners(ring, labels, axis_normals, 1.0, straight, &problem).empty());
  EXPECT_NE(problem.find("only 2 straight runs"), std::string::npos) << problem;
}

TEST(Corners, ShortRunsAreAbsorbed) {
  Ring ring;
  std::vector<int> labels;
  rectangle_contour(10, 6, ring, labels);
  labels[4] = 1;  // a one-edge outlier in the bottom wall
  absorb_short_runs(ring, labels, 2.0);
  EXPECT_EQ(labels[4], 0);
}

// The absorption as it was first written (label_runs recomputed after each merge), which the
// one-pass version must match choice for choice.
void absorb_short_runs_reference(const Ring& ring, std::vector<int>& labels, double min_length) {
  const auto length = [&](int first, int count) {
    double sum = 0;
    for (int k = 0; k < count; ++k) sum += edge_vector(ring, (first + k) % ring.size()).norm();
    return sum;
  };
  for (std::size_t guard = 0; guard < ring.size(); ++guard) {
    const auto runs = label_runs(labels);
    if (runs.size() <= 4) return;
    int shortest = -1;
    double shortest_length = min_length;
    for (int r = 0; r < int(runs.size()); ++r)
      if (const double l = length(runs[r].first, runs[r].second); l < shortest_length) shortest_length = l, shortest = r;
    if (shortest < 0) return;
    const int n = int(runs.size());
    const auto& prev = runs[(shortest + n - 1) % n];
    const auto& next = runs[(shortest + 1) % n];
    const int label = labels[length(prev.first, prev.second) >= length(next.first, next.second) ? prev.first : next.first];
    for (int k = 0; k < runs[shortest].second; ++k) labels[(runs[shortest].first + k) % labels.size()] = label;
  }
}

// On random rings and labels (edges of one to three units, so that runs of equal length are
// common, and of random lengths), the one-pass absorption gives the reference's labels exactly.
TEST(Corners, ShortRunAbsorptionMatchesTheReference) {
  std::mt19937 rng(7);
  int differing = 0, changed = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int n = 8 + int(rng() % 120);
    const bool integer = trial % 2 == 0;
    Ring ring;
    Vec2 at(0, 0);
    for (int i = 0; i < n; ++i) {  // a walk of axis steps of 1-3 units, or of random steps
      ring.push_back(at);
      const double step = integer ? double(1 + rng() % 3) : std::uniform_real_distribution<double>(0.2, 3)(rng);
      at += rng() % 2 ? Vec2(rng() % 2 ? step : -step, 0) : Vec2(0, rng() % 2 ? step : -step);
    }
    std::vector<int> labels(static_cast<std::size_t>(n));
    int label = 0;
    for (int i = 0; i < n; ++i) {
      if (rng() % 3 == 0) label = int(rng() % 5);
      labels[std::size_t(i)] = label;
    }
    const double min_length = 0.5 + double(rng() % 12);
    std::vector<int> expected = labels, actual = labels;
    absorb_short_runs_reference(ring, expected, min_length);
    absorb_short_runs(ring, actual, min_length);
    differing += expected != actual;
    changed += expected != labels;
  }
  EXPECT_EQ(differing, 0);
  EXPECT_GT(changed, 100);  // (most trials absorbed something)
}

TEST(Corners, ParallelNeighboursGetAStep) {
  // Two bottom walls at y = 0 and y = 1 with different labels of the same direction.
  Ring ring = {{0, 0}, {5, 0}, {5, 1}, {10, 1}, {10, 6}, {0, 6}};
  std::vector<int> labels = {0, 4, 4, 1, 2, 3};
  std::vector<Vec2> normals = axis_normals;
  normals.push_back({0, -1});
  CornerOptions o;
  o.min_run_px = 0;
  std::string problem;
  const Ring out = extract_corners(ring, labels, normals, 1.0, o, &problem);
  ASSERT_FALSE(out.empty()) << problem;
  EXPECT_EQ(ring_problem(out), "");
  // The riser was labeled like the upper wall: the two parallel walls are joined by a step at
  // the junction, keeping the notch (true area 55) instead of bridging it.
  EXPECT_EQ(out.size(), 6u);
  EXPECT_NEAR(signed_area(out), 55.0, 0.5);
}

TEST(Corners, ARunSteppingBetweenTwoParallelOffsetsIsSplit) {
  // A 40 x 20 block whose bottom wall steps 3 px at x = 20 (two row houses out of line), all of
  // it labeled as one run by the labeling (the riser included).
  Ring ring;
  std::vector<int> labels;
  for (int x = 0; x < 20; ++x) { ring.emplace_back(x, 0); labels.push_back(0); }
  for (int y = 0; y < 3; ++y) { ring.emplace_back(20, y); labels.push_back(0); }
  for (int x = 20; x < 40; ++x) { ring.emplace_back(x, 3); labels.push_back(0); }
  for (int y = 3; y < 20; ++y) { ring.emplace_back(40, y); labels.push_back(1); }
  for (int x = 40; x > 0; --x) { ring.emplace_back(x, 20); labels.push_back(2); }
  for (int y = 20; y > 0; --y) { ring.emplace_back(0, y); labels.push_back(3); }
  CornerOptions o = split_options();
  std::string problem;
  const Ring split = extract_corners(ring, labels, axis_normals, 1.0, o, &problem);
  ASSERT_EQ(split.size(), 6u) << problem;
  EXPECT_EQ(ring_problem(split), "");
  EXPECT_TRUE(near(split, {20, 0}) && near(split, {20, 3}) && near(split, {0, 0}) && near(split, {40, 3}));
  // Without it, one line between the two walls.
  CornerOptions off = o;
  off.split_px = 0;
  const Ring one_line = extract_corners(ring, labels, axis_normals, 1.0, off, &problem);
  EXPECT_EQ(one_line.size(), 4u);
  EXPECT_FALSE(near(one_line, {20, 3}));
  // A step smaller than split_px stays one line.
  CornerOptions strict = o;
  strict.split_px = 4;
  EXPECT_EQ(extract_corners(ring, labels, axis_normals, 1.0, strict, &problem).size(), 4u);
}

TEST(Corners, RowOfHousesSteppingBackAndForthGetsOneLinePerHouse) {
  // The bottom wall (one label, as the MRF leaves it: the 2 px risers are too short for their
  // own) steps back and forth: y = 0 over x 0-15, y = 2 over 15-30, y = 0 over 30-45. No single
  // cut explains it, three offsets do.
  Ring ring;
  std::vector<int> labels;
  const auto wall = [&](int x0, int x1, int y) { for (int x = x0; x < x1; ++x) { ring.emplace_back(x, y); labels.push_back(0); } };
  wall(0, 15, 0);
  for (int y = 0; y < 2; ++y) { ring.emplace_back(15, y); labels.push_back(0); }
  wall(15, 30, 2);
  for (int y = 2; y > 0; --y) { ring.emplace_back(30, y); labels.push_back(0); }
  wall(30, 45, 0);
  close_box(45, 20, ring, labels);
  CornerOptions o = split_options();
  std::string problem;
  const Ring steps = extract_corners(ring, labels, axis_normals, 1.0, o, &problem);
  ASSERT_EQ(steps.size(), 8u) << problem;
  EXPECT_EQ(ring_problem(steps), "");
  for (const Vec2& corner : {Vec2(15, 0), Vec2(15, 2), Vec2(30, 2), Vec2(30, 0), Vec2(0, 0), Vec2(45, 0)})
    EXPECT_TRUE(near(steps, corner)) << corner.transpose();
  // Offsets closer than split_m (here in the ring's units, as extract_corners takes them) stay one line.
  CornerOptions coarse = o;
  coarse.split_m = 3;
  EXPECT_EQ(extract_corners(ring, labels, axis_normals, 1.0, coarse, &problem).size(), 4u);
}

// A wall of 60 m at 0.25 m a pixel stepping out by 0.5 m (2 px) over 8 m at each end, as a row of
// houses does, all one run, on a clean mask (its noise pooled over the buildings 0.075 m); but the
// building's noise, measured about one line along each wall, is 0.17 m (the steps themselves put
// it there). One cut explains the run within that noise, its pieces not 5 noises apart; the
// second leaves no more than a pixel's quantization, and the steps, 5 times the mask's noise
// apart, are kept. The mask's noise unknown, the building's stands: one line. A wall wobbling by
// 1 m over 8 m under its noise (0.7 m, its mask's) is not cut into steps.
TEST(Corners, AStepIsJudgedByTheNoiseThePiecesLeave) {
  const double px = 0.25;
  Ring stepped;
  std::vector<int> stepped_labels;
  profile_box(px, [](int x) { return x < 32 || x >= 208 ? -2 : 0; }, stepped, stepped_labels);
  CornerOptions o = split_options();
  CornerContext context;
  context.noise = 0.17;
  context.mask_noise = 0.075;
  std::string problem;
  const Ring steps = extract_corners(stepped, stepped_labels, axis_normals, px, o, &problem, context);
  ASSERT_EQ(steps.size(), 8u) << problem;
  for (const Vec2& corner : {Vec2(8, -0.5), Vec2(8, 0), Vec2(52, 0), Vec2(52, -0.5), Vec2(0, -0.5), Vec2(60, -0.5)})
    EXPECT_TRUE(near(steps, corner)) << corner.transpose();
  CornerContext unknown = context;
  unknown.mask_noise = 0;
  EXPECT_EQ(extract_corners(stepped, stepped_labels, axis_normals, px, o, &problem, unknown).size(), 4u);
  Ring wobbly;
  std::vector<int> wobbly_labels;
  profile_box(px, [&](int x) { return int(std::lround(std::sin(2 * M_PI * (x + 0.5) * px / 8.0) / px)); }, wobbly, wobbly_labels);
  context.noise = context.mask_noise = 0.7;
  EXPECT_EQ(extract_corners(wobbly, wobbly_labels, axis_normals, px, o, &problem, context).size(), 4u) << problem;
}

TEST(Corners, AWobblingWallIsNotSplit) {
  // A wall whose pixels wobble by up to 2 px (a smooth wave over 24 px): a few offsets 1 px apart
  // do not explain it, so it stays one line.
  Ring ring;
  std::vector<int> labels;
  int y = 0;
  for (int x = 0; x < 96; ++x) {
    const int target = int(std::lround(2.0 * std::sin(2 * M_PI * x / 24.0)));
    while (y != target) { ring.emplace_back(x, y); labels.push_back(0); y += target > y ? 1 : -1; }
    ring.emplace_back(x, y); labels.push_back(0);
  }
  while (y != 0) { ring.emplace_back(96, y); labels.push_back(0); y += y < 0 ? 1 : -1; }
  close_box(96, 30, ring, labels);
  CornerOptions o = split_options();
  std::string problem;
  EXPECT_EQ(extract_corners(ring, labels, axis_normals, 1.0, o, &problem).size(), 4u) << problem;
}

// A wall of a 24 x 4 m box whose first 4 m dip 2 m as a V of two 45-degree flanks, each a run of
// its own, square to each other (as the teeth of a staggered row are, which do not join), the
// wall's straight 20 m a third run. The second flank joins the straight wall first (a window of
// those two fits the lattice line within the bounds), and the first flank then joins that wall:
// its neighbour is now on the lattice, and the three runs' edges lie within the bounds about it.
// (The window of the same edges was judged before, as three runs of which two were the teeth: a
// verdict taken again from there is wrong. The first flank and the left wall do not join: their
// chord lies 18 degrees off the lattice, beyond 12.)
TEST(Corners, AFlankJoinsItsWallOnceTheFlankSquareToItHasJoined) {
  const Ring ring = {{0, 0}, {2, -2}, {4, 0}, {24, 0}, {24, 4}, {0, 4}};
  std::vector<std::pair<int, int>> runs;
  std::vector<Vec2> normals;
  for (int k = 0; k < 6; ++k) runs.push_back({k, 1}), normals.push_back(outward_normal(edge_vector(ring, std::size_t(k))));
  const auto merged = zigzags_merged(ring, runs, normals, Vec2(1, 0), 12.0, 0.5, 2.5, 10.0);
  const std::vector<std::pair<int, int>> expected = {{0, 3}, {3, 1}, {4, 1}, {5, 1}};
  EXPECT_EQ(merged, expected);
}

// A bow on a long straight wall, all of it one run (its ends 35 degrees off the wall, which no
// direction of its own took): a wall of 60 m at 0.25 m a pixel, a bow of 16 m chord and 2.5 m
// sagitta from 4 m to 20 m along it. A parabola over the whole run does not explain it (the wall is
// straight), but no window departs to the other side of the wall's line: the bow is drawn as its
// own curve, through its apex, and the wall's two parts stay on one straight line through the
// box's corners. Without that (curve_other_side = 0) one line cuts the bow off. (The building's
// noise 0.4 m, as a segmentation's: the bow is no step between parallel walls, split_noise.)
TEST(Corners, ABowOnAStraightWallIsItsOwnCurve) {
  const double px = 0.25, radius = (8.0 * 8.0 + 2.5 * 2.5) / 5.0;
  const auto bow = [&](double x) { return std::abs(x - 12) < 8 ? -(std::sqrt(radius * radius - (x - 12) * (x - 12)) - (radius - 2.5)) : 0.0; };
  Ring ring;
  std::vector<int> labels;
  profile_box(px, [&](int x) { return int(std::lround(bow((x + 0.5) * px) / px)); }, ring, labels);
  const auto has_vertex_near = [](const Ring& r, const Vec2& p, double within) {
    for (const Vec2& v : r) if ((v - p).norm() < within) return true;
    return false;
  };
  std::string problem;
  CornerContext context;
  context.noise = 0.4;
  const Ring with = extract_corners(ring, labels, axis_normals, px, CornerOptions{}, &problem, context);
  ASSERT_FALSE(with.empty()) << problem;
  EXPECT_TRUE(has_vertex_near(with, {12, -2.5}, 0.5));
  EXPECT_TRUE(has_vertex_near(with, {0, 0}, 0.3));
  EXPECT_TRUE(has_vertex_near(with, {60, 0}, 0.3));
  EXPECT_LE(with.size(), 16u);  // the corners, the bow's ends and a few vertices along it
  for (const Vec2& v : with) EXPECT_GE(v.y(), bow(v.x()) - 0.3) << v.transpose();  // none beyond the bow
  // Without: one line through the whole run, off the wall by a fifth of the bow's depth.
  CornerOptions off;
  off.curve_other_side = 0;
  const Ring without = extract_corners(ring, labels, axis_normals, px, off, &problem, context);
  ASSERT_FALSE(without.empty()) << problem;
  EXPECT_FALSE(has_vertex_near(without, {12, -2.5}, 1.0));
  PolygonWithHoles truth{{{0, 0}}, {}};
  for (int k = 0; k <= 32; ++k) truth.outer.push_back({4 + 0.5 * k, bow(4 + 0.5 * k)});
  for (const Vec2& p : {Vec2(60, 0), Vec2(60, 20), Vec2(0, 20)}) truth.outer.push_back(p);
  const double iou_with = test::iou({with, {}}, truth), iou_without = test::iou({without, {}}, truth);
  EXPECT_GT(iou_with, 0.99);
  EXPECT_GT(iou_with, iou_without + 0.02) << iou_without;
}

// A building with a round end (a stadium: a 30 x 20 m box, then a half disc of 10 m), traced at
// 0.25 m, whose round end the labeling gave, for its first and last 30 degrees, to the walls on
// either side of it. The walls' lines run on past where their contour leaves them; at the curve
// the wall ends at the foot of its last vertex within 2 px of its line, and its contour leads on
// to the curve: every vertex lies within those 2 px of the contour. (The feet of the curve's ends
// on the walls' lines lie 1.1 m off it, beyond the round end.)
TEST(Corners, AWallRunningIntoACurveEndsWhereItsContourLeavesIt) {
  const double px = 0.25, radius = 10;
  const Vec2 centre(30, 10);
  Ring ring;
  std::vector<int> labels;
  for (int k = 0; k < 120; ++k) { ring.emplace_back(k * px, 0); labels.push_back(0); }
  const int arc = int(std::lround(M_PI * radius / px));
  for (int k = 0; k < arc; ++k) {
    const double theta = -M_PI / 2 + M_PI * k / arc;
    ring.push_back(centre + radius * Vec2(std::cos(theta), std::sin(theta)));
    labels.push_back(theta < -M_PI / 3 ? 0 : theta > M_PI / 3 ? 2 : 1);
  }
  for (int k = 120; k > 0; --k) { ring.emplace_back(k * px, 20); labels.push_back(2); }
  for (int k = 80; k > 0; --k) { ring.emplace_back(0, k * px); labels.push_back(3); }
  CornerContext context;
  context.noise = 0.05;
  CornerOptions o;
  o.split_px = 0;  // (the wall's stretch along the curve is not cut off as a step of its own)
  std::string problem;
  const Ring out = extract_corners(ring, labels, axis_normals, px, o, &problem, context);
  ASSERT_FALSE(out.empty()) << problem;
  EXPECT_TRUE(ring_problem(out).empty()) << ring_problem(out);
  for (const Vec2& v : out) {
    double nearest = 1e9;
    for (std::size_t i = 0; i < ring.size(); ++i) nearest = std::min(nearest, distance_to_segment(v, ring[i], ring[(i + 1) % ring.size()]));
    EXPECT_LE(nearest, 2 * px) << v.transpose();
  }
  PolygonWithHoles truth{{{0, 0}, {30, 0}}, {}};
  for (int k = 1; k < 36; ++k) truth.outer.push_back(centre + radius * Vec2(std::sin(M_PI * k / 36), -std::cos(M_PI * k / 36)));
  for (const Vec2& p : {Vec2(30, 20), Vec2(0, 20)}) truth.outer.push_back(p);
  EXPECT_GT(test::iou({out, {}}, truth), 0.99);  // (0.9855 with the feet)
  EXPECT_LE(out.size(), 24u);  // the box's corners and a few vertices along the round end
}

TEST(Corners, TooFewRunsIsAProblem) {
  Ring ring = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  std::string problem;
  EXPECT_TRUE(extract_corners(ring, {0, 0, 0, 0}, axis_normals, 1.0, CornerOptions{}, &problem).empty());
  EXPECT_NE(problem.find("straight runs"), std::string::npos);
}

}  // namespace
}  // namespace lodforge
