#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

#include "directions/refine.hpp"
#include "labeling/mrf.hpp"

namespace lodforge {
namespace {

Vec2 unit(double deg) { return {std::cos(deg * M_PI / 180), std::sin(deg * M_PI / 180)}; }

LabelingInput one_ring(const std::vector<double>& normal_deg, const std::vector<double>& direction_deg,
                       const std::vector<double>& support) {
  LabelingInput in;
  in.normals.emplace_back();
  for (double a : normal_deg) in.normals[0].push_back(unit(a));
  in.lengths.emplace_back(normal_deg.size(), 0.1);
  for (double a : direction_deg) in.directions.push_back(unit(a));
  in.support = support;
  return in;
}

double exhaustive_minimum(const LabelingInput& in, const MrfOptions& o) {
  const int n = int(in.normals[0].size()), l = int(in.directions.size());
  EdgeLabels labels{std::vector<int>(n, 0)};
  double best = 1e300;
  std::function<void(int)> recurse = [&](int i) {
    if (i == n) { best = std::min(best, labeling_energy(in, labels, o)); return; }
    for (int k = 0; k < l; ++k) { labels[0][i] = k; recurse(i + 1); }
  };
  recurse(0);
  return best;
}

TEST(Mrf, ExpansionReachesTheExhaustiveMinimumOnSmallProblems) {
  MrfOptions o;
  const std::vector<std::vector<double>> cases = {
      {0, 5, 40, 85, 90, 95, 180, 185, 270},
      {0, 0, 45, 90, 90, 135, 180, 225},
      {10, 20, 80, 100, 170, 190, 260, 280, 350},
  };
  for (const auto& normals : cases) {
    const LabelingInput in = one_ring(normals, {0, 90, 180, 270, 45}, {30, 30, 30, 30, 2});
    const EdgeLabels labels = label_edges(in, o);
    const double found = labeling_energy(in, labels, o);
    const double minimum = exhaustive_minimum(in, o);
    EXPECT_LE(found, minimum * 1.02 + 1e-9);
    EXPECT_GE(found, minimum - 1e-9);
  }
}

TEST(Mrf, LabelCostRemovesARareDirection) {
  // 40 edges facing 0°, one facing 30° with its own weak label.
  std::vector<double> normals(40, 0.0);
  normals[20] = 30.0;
  LabelingInput in = one_ring(normals, {0, 30, 180}, {40, 1, 1});
  MrfOptions o;
  o.kappa1 = 0;  // isolate the label term
  EdgeLabels labels = label_edges(in, o);
  for (int x : labels[0]) EXPECT_EQ(x, 0);
  o.kappa2 = 0;
  labels = label_edges(in, o);
  EXPECT_EQ(labels[0][20], 1);
}

TEST(Mrf, SmoothnessRelabelsAnIsolatedOutlier) {
  std::vector<double> normals(30, 90.0);
  normals[15] = 20.0;  // one noisy edge inside a wall, nearer to the 0° label
  LabelingInput in = one_ring(normals, {90, 0}, {29, 29});
  MrfOptions o;
  o.kappa2 = 0;
  o.kappa1 = 5;
  const EdgeLabels labels = label_edges(in, o);
  EXPECT_EQ(labels[0][15], 0);
}

TEST(Mrf, EdgesFacingAlikeAreLabeledAsOneAtTheSameEnergy) {
  // A ring turning in half-degree steps through a quarter turn and back, labeled among its two
  // end directions. Grouped by 1.75 degrees (off the half-degree grid, so no normal lies at the
  // tolerance itself), every four consecutive edges from the first are one group, whose edges
  // share a label; the energy stays within a hair of the edge-by-edge one.
  std::vector<double> normals;
  for (int k = 0; k < 180; ++k) normals.push_back(0.5 * k);
  for (int k = 0; k < 180; ++k) normals.push_back(90.0 - 0.5 * k);
  const LabelingInput in = one_ring(normals, {0, 90}, {1, 1});
  MrfOptions each_edge, grouped;
  each_edge.group_deg = 0;
  grouped.group_deg = 1.75;
  const EdgeLabels alone = label_edges(in, each_edge), together = label_edges(in, grouped);
  for (std::size_t k = 0; k < 360; k += 4)
    for (std::size_t i = k + 1; i < k + 4; ++i) EXPECT_EQ(together[0][i], together[0][k]) << "edge " << i;
  const double e_alone = labeling_energy(in, alone, each_edge), e_together = labeling_energy(in, together, grouped);
  EXPECT_GE(e_together, e_alone - 1e-9);
  EXPECT_LE(e_together, e_alone * 1.01);
  // Both label changes are there, within a group of where the normals pass 45 degrees.
  const auto runs = label_runs(together[0]);
  ASSERT_EQ(runs.size(), 2u);
  for (const auto& [first, count] : runs) EXPECT_NEAR(normals[std::size_t(first)], 45.0, 2.5) << first;
}

// Alpha-expansion stops where no expansion move lowers the energy: on small problems of two or
// three rings (every move tried by brute force), none does. The moves are solved on a cut that leaves out the
// edges whose move a bound settles; a bound that settled one wrongly would leave a lower move.
// The normals lie near the directions (so that the bound settles most edges) or anywhere, the
// smoothness and label costs weak or strong.
TEST(Mrf, NoExpansionMoveLowersTheReturnedLabeling) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit_interval(0.0, 1.0);
  for (int trial = 0; trial < 60; ++trial) {
    LabelingInput in;
    const std::vector<double> directions = {0, 90, 180, 270, 45 + 10 * unit_interval(rng)};
    for (double a : directions) in.directions.push_back(unit(a));
    for (std::size_t l = 0; l < directions.size(); ++l) in.support.push_back(1 + 20 * unit_interval(rng));
    const double spread = trial % 2 ? 25.0 : 360.0;  // near the directions, or anywhere
    // Two rings of several edges, or rings of one and two edges (no smoothness term; both terms
    // between the same two edges) beside one of six.
    for (int ring_size : trial % 5 == 4 ? std::vector<int>{1, 2, 6} : std::vector<int>{7, 4}) {
      in.normals.emplace_back();
      in.lengths.emplace_back();
      for (int i = 0; i < ring_size; ++i) {
        const double near = directions[std::size_t(unit_interval(rng) * 4.0)];
        in.normals.back().push_back(unit(near + spread * (unit_interval(rng) - 0.5)));
        in.lengths.back().push_back(0.05 + 0.5 * unit_interval(rng));
      }
    }
    MrfOptions o;
    o.group_deg = 0;
    o.kappa1 = trial % 3 == 0 ? 0.2 : trial % 3 == 1 ? 1.0 : 6.0;
    o.kappa2 = trial % 4 < 2 ? 10.0 : 1.0;
    const EdgeLabels labels = label_edges(in, o);
    const double found = labeling_energy(in, labels, o);
    std::vector<std::pair<std::size_t, std::size_t>> edges;  // (ring, edge)
    for (std::size_t r = 0; r < labels.size(); ++r)
      for (std::size_t i = 0; i < labels[r].size(); ++i) edges.emplace_back(r, i);
    const std::size_t n = edges.size();
    for (int alpha = 0; alpha < int(directions.size()); ++alpha)
      for (unsigned move = 1; move < (1u << n); ++move) {
        EdgeLabels moved = labels;
        for (std::size_t k = 0; k < n; ++k)
          if (move >> k & 1u) moved[edges[k].first][edges[k].second] = alpha;
        if (moved == labels) continue;
        EXPECT_GE(labeling_energy(in, moved, o), found - 1e-9 * std::max(1.0, found)) << "trial " << trial << " alpha " << alpha << " move " << move;
      }
  }
}

TEST(Mrf, RunsAreCyclic) {
  const auto runs = label_runs({1, 1, 0, 0, 0, 1});
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_EQ(runs[0], std::make_pair(2, 3));
  EXPECT_EQ(runs[1], std::make_pair(5, 3));
  EXPECT_EQ(label_runs({2, 2, 2}).size(), 1u);
}

// A staircase rising 1 in 2 from (0,0), closed by three long axis-aligned edges.
void staircase(Ring& ring, std::vector<int>& labels) {
  Vec2 p(0, 0);
  for (int k = 0; k < 60; ++k) {
    ring.push_back(p);
    p += (k % 3 == 2) ? Vec2(0, 1) : Vec2(1, 0);
    labels.push_back(0);
  }
  ring.push_back(p);
  labels.push_back(1);
  ring.push_back(Vec2(p.x(), 60));
  labels.push_back(2);
  ring.push_back(Vec2(0, 60));
  labels.push_back(3);
}

TEST(Refine, StaircaseDirectionIsFittedExactly) {
  Ring ring;
  std::vector<int> labels;
  staircase(ring, labels);
  EdgeLabels all{labels};
  std::vector<Vec2> directions = {unit(-90), unit(0), unit(90), unit(180)};
  RefineOptions o;
  o.snap_deg = 0;
  refine_directions({ring}, all, directions, 1.0, o);
  ASSERT_EQ(directions.size(), 4u);
  const double expected = std::atan2(1.0, 2.0) * 180 / M_PI - 90;  // the wall's outward normal
  EXPECT_NEAR(std::atan2(directions[0].y(), directions[0].x()) * 180 / M_PI, expected, 0.5);
}

TEST(Refine, NearPerpendicularDirectionsAreSnappedOthersStayFree) {
  // A rectangle rotated 10° whose right wall leans 3° more, plus a 45° cut direction.
  const double a = 10;
  Ring ring;
  std::vector<int> labels;
  auto wall = [&](Vec2 from, double deg, int n, int label) -> Vec2 {
    for (int k = 0; k < n; ++k) { ring.push_back(from + k * unit(deg)); labels.push_back(label); }
    return from + n * unit(deg);
  };
  Vec2 p(0, 0);
  p = wall(p, a, 40, 0);
  p = wall(p, a + 93, 20, 1);
  p = wall(p, a + 135, 10, 2);
  p = wall(p, a + 180, 32, 3);
  p = wall(p, a + 270, 27, 4);
  EdgeLabels all{labels};
  std::vector<Vec2> directions = {unit(a - 90), unit(a), unit(a + 45), unit(a + 90), unit(a + 180)};
  refine_directions({ring}, all, directions, 1.0, RefineOptions{});
  ASSERT_EQ(directions.size(), 5u);
  EXPECT_NEAR(directions[0].dot(directions[1]), 0.0, 1e-12);   // exactly perpendicular
  EXPECT_NEAR(directions[0].dot(directions[3]), -1.0, 1e-12);  // exactly parallel
  const double cut = std::atan2(directions[2].y(), directions[2].x()) * 180 / M_PI;
  EXPECT_NEAR(cut, a + 45, 0.5);  // the cut is not snapped
}

// The lattice's missing axis: added (both ways) where the directions lie along the other one,
// not where each axis has a direction near it, nor where neither has, nor when switched off.
TEST(Refine, TheLatticesMissingAxisIsAddedBothWays) {
  const Vec2 main = unit(20);
  RefineOptions o;
  std::vector<Vec2> directions{unit(20), unit(-160), unit(25)};
  ASSERT_TRUE(add_missing_axis(directions, main, o));
  ASSERT_EQ(directions.size(), 5u);
  EXPECT_NEAR(directions[3].dot(unit(110)), 1.0, 1e-12);
  EXPECT_NEAR(directions[4].dot(unit(-70)), 1.0, 1e-12);
  std::vector<Vec2> square{unit(20), unit(112)};  // the quarter turn within 10 degrees: no axis missing
  EXPECT_FALSE(add_missing_axis(square, main, o));
  EXPECT_EQ(square.size(), 2u);
  std::vector<Vec2> across{unit(-70)};  // the main axis missing
  ASSERT_TRUE(add_missing_axis(across, main, o));
  ASSERT_EQ(across.size(), 3u);
  EXPECT_NEAR(across[1].dot(unit(20)), 1.0, 1e-12);
  EXPECT_NEAR(across[2].dot(unit(-160)), 1.0, 1e-12);
  std::vector<Vec2> oblique{unit(65), unit(-25)};  // 45 degrees off both axes
  EXPECT_FALSE(add_missing_axis(oblique, main, o));
  EXPECT_EQ(oblique.size(), 2u);
  o.missing_axis_deg = 0;
  std::vector<Vec2> off{unit(20), unit(-160)};
  EXPECT_FALSE(add_missing_axis(off, main, o));
  EXPECT_EQ(off.size(), 2u);
}

}  // namespace
}  // namespace lodforge
