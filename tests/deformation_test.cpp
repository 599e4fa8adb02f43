#include <gtest/gtest.h>

#include <ceres/ceres.h>
#include <random>

#include "deformation/amips.hpp"
#include "deformation/deform.hpp"
#include "geometry/polygon.hpp"
#include "pipeline/building.hpp"
#include "support/shapes.hpp"

namespace lodforge {
namespace {

TEST(Amips, RestShapeEnergyIsExpTwo) {
  EXPECT_NEAR(amips::energy(amips::Vec4(1, 0, 0, 1), 0.5), std::exp(2.0), 1e-12);
  EXPECT_TRUE(std::isinf(amips::energy(amips::Vec4(1, 0, 0, -1), 0.5)));
}

TEST(Amips, GradientAndHessianMatchFiniteDifferences) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (int trial = 0; trial < 20; ++trial) {
    const amips::Vec4 j(1 + u(rng), u(rng), u(rng), 1 + u(rng));
    for (double alpha : {0.0, 0.5, 1.0}) {
      amips::Vec4 g;
      amips::Mat4 h;
      amips::energy(j, alpha, &g, &h);
      const double step = 1e-6;
      for (int k = 0; k < 4; ++k) {
        amips::Vec4 e = amips::Vec4::Zero();
        e[k] = step;
        const double fd = (amips::energy(j + e, alpha) - amips::energy(j - e, alpha)) / (2 * step);
        EXPECT_NEAR(g[k], fd, 1e-5 * (1 + std::abs(fd)));
        amips::Vec4 gp = amips::Vec4::Zero(), gm = amips::Vec4::Zero();
        amips::energy(j + e, alpha, &gp);
        amips::energy(j - e, alpha, &gm);
        const amips::Vec4 column = (gp - gm) / (2 * step);
        for (int l = 0; l < 4; ++l) EXPECT_NEAR(h(l, k), column[l], 1e-4 * (1 + std::abs(column[l])));
      }
    }
  }
}

// A rasterized noisy L with its MRF targets, in pixel units, as the pipeline builds it.
struct Problem {
  TriangleMesh mesh;
  std::vector<Vec2> targets;
};

Problem l_shape_problem(std::uint64_t seed) {
  const PolygonWithHoles l = test::rotated({{{0, 0}, {16, 0}, {16, 6}, {6, 6}, {6, 14}, {0, 14}}, {}}, 30.0);
  const double pixel = 0.25;
  const auto shape = test::rasterize_shape(l, pixel, 0.8, 2.0, seed);
  const BuildingResult labeled = regularize_building(shape.buildings[0].rings, pixel, CoreOptions{});
  EXPECT_TRUE(labeled.ok);
  std::vector<Ring> rings_px = shape.buildings[0].rings;
  const Vec2 origin = rings_px[0][0];
  for (Ring& r : rings_px) for (Vec2& p : r) p = (p - origin) / pixel;
  Problem problem;
  problem.mesh = triangulate(rings_px, 5.0, TriangulationOptions{});
  for (const BoundaryEdge& b : problem.mesh.boundary) problem.targets.push_back(labeled.directions[labeled.labels[b.ring][b.edge]]);
  return problem;
}

// Ceres' LBFGS on the same energy, for comparison.
class CeresEnergy : public ceres::FirstOrderFunction {
 public:
  explicit CeresEnergy(const DeformationEnergy& e) : energy_(e) {}
  bool Evaluate(const double* parameters, double* cost, double* gradient) const override {
    const Eigen::Map<const Eigen::VectorXd> x(parameters, energy_.size());
    Eigen::VectorXd g;
    *cost = energy_.value(x, gradient ? &g : nullptr);
    if (!std::isfinite(*cost)) return false;  // a flipped triangle: reject the step
    if (gradient) Eigen::Map<Eigen::VectorXd>(gradient, energy_.size()) = g;
    return true;
  }
  int NumParameters() const override { return energy_.size(); }

 private:
  const DeformationEnergy& energy_;
};

TEST(Deformation, NewtonReachesTheMinimumOfThePaperEnergy) {
  const Problem p = l_shape_problem(1);
  DeformationOptions o;
  o.max_rounds = 1;  // the paper's single solve of eq. 15
  o.max_iterations = 500;
  o.keep_boundary_simple = false;  // the paper's energy alone (its minimum may fold the boundary)
  const std::vector<Eigen::Vector2d> rest(p.mesh.vertices.begin(), p.mesh.vertices.end());
  const DeformationEnergy energy(p.mesh, rest, p.targets, o);
  Eigen::VectorXd x0(energy.size()), g0;
  for (std::size_t i = 0; i < rest.size(); ++i) x0.segment<2>(2 * i) = rest[i];
  const double e0 = energy.value(x0, &g0);

  const DeformationResult result = deform(p.mesh, p.targets, o);
  EXPECT_LT(result.energy, e0);
  EXPECT_LT(result.gradient_norm, 1e-6 * g0.norm());
  // No triangle flipped.
  for (const auto& t : p.mesh.triangles)
    EXPECT_GT(cross(result.vertices[t[1]] - result.vertices[t[0]], result.vertices[t[2]] - result.vertices[t[0]]), 0);

  // Ceres LBFGS from the same start does not get lower.
  ceres::GradientProblem problem(new CeresEnergy(energy));
  ceres::GradientProblemSolver::Options options;
  options.max_num_iterations = 3000;
  options.function_tolerance = 1e-14;
  options.gradient_tolerance = 1e-14;
  options.parameter_tolerance = 1e-14;
  ceres::GradientProblemSolver::Summary summary;
  Eigen::VectorXd x = x0;
  ceres::Solve(options, problem, x.data(), &summary);
  EXPECT_LE(result.energy, summary.final_cost * (1 + 1e-9)) << summary.BriefReport();
}

TEST(Deformation, RoundsAlignTheBoundaryWithoutFlips) {
  for (std::uint64_t seed : {1, 2, 3}) {
    const Problem p = l_shape_problem(seed);
    const DeformationResult result = deform(p.mesh, p.targets, DeformationOptions{});
    EXPECT_LE(result.rms_deg, 2.0) << "seed " << seed;
    EXPECT_LE(result.max_deg, 5.0) << "seed " << seed;
    for (const auto& t : p.mesh.triangles)
      EXPECT_GT(cross(result.vertices[t[1]] - result.vertices[t[0]], result.vertices[t[2]] - result.vertices[t[0]]), 0);
    for (std::size_t r = 0; r < p.mesh.ring_vertex.size(); ++r) {
      Ring ring;
      for (int v : p.mesh.ring_vertex[r]) ring.push_back(result.vertices[v]);
      // Risers of the staircase collapse to a point; merged below a tenth of a pixel the ring is simple.
      EXPECT_EQ(ring_problem(remove_degenerate_vertices(ring, 0.1)), "") << "seed " << seed;
    }
  }
}

TEST(Deformation, RoundsStopWhenTheAlignmentStalls) {
  // Targets no closed boundary can meet (every edge asked to face the same way): the rounds stop
  // once one no longer improves the alignment, with the alignment all ten rounds would reach.
  Problem p = l_shape_problem(1);
  for (Vec2& t : p.targets) t = Vec2(0, 1);
  DeformationOptions stalled;
  const DeformationResult early = deform(p.mesh, p.targets, stalled);
  DeformationOptions all = stalled;
  all.min_round_gain = 0;
  const DeformationResult full = deform(p.mesh, p.targets, all);
  EXPECT_EQ(full.rounds, all.max_rounds);
  EXPECT_LT(early.rounds, full.rounds);
  EXPECT_GT(early.rms_deg, 3 * stalled.target_rms_deg);  // it stopped short of the target, stalled
  EXPECT_NEAR(early.rms_deg, full.rms_deg, 0.02 * full.rms_deg);
  for (const auto& t : p.mesh.triangles)
    EXPECT_GT(cross(early.vertices[t[1]] - early.vertices[t[0]], early.vertices[t[2]] - early.vertices[t[0]]), 0);
}

}  // namespace
}  // namespace lodforge
