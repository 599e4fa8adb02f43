// Per-stage micro-benchmarks on rasterized noisy buildings of growing size, so the growth of each
// stage's cost with the contour's edge count is visible. Run: build/bench/stages_bench
#include <benchmark/benchmark.h>

#include "corners/corners.hpp"
#include "deformation/deform.hpp"
#include "directions/ransac.hpp"
#include "directions/refine.hpp"
#include "labeling/mrf.hpp"
#include "normals/smoothing.hpp"
#include "pipeline/building.hpp"
#include "synth/city.hpp"
#include "triangulation/triangulate.hpp"

#include <Eigen/Geometry>

namespace lodforge {
namespace {

// An L-shaped building, 30° rotated, scaled so that its contour has about `edges` pixel edges
// at 0.25 m, degraded like a segmentation.
std::vector<Ring> building(int edges) {
  const double pixel = 0.25;
  // The unit L (16 x 14 m) has ~330 staircase edges at 0.25 m when rotated 30°.
  const double scale = edges / 330.0;
  PolygonWithHoles l{{{0, 0}, {16, 0}, {16, 6}, {6, 6}, {6, 14}, {0, 14}}, {}};
  Vec2 lo(1e18, 1e18), hi(-1e18, -1e18);
  for (Vec2& p : l.outer) {
    p = Vec2(1000, 1000) + Eigen::Rotation2Dd(M_PI / 6) * (p * scale);
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  GeoTransform t;
  t.c = {std::floor(lo.x() - 5), pixel, 0, std::ceil(hi.y() + 5), 0, -pixel};
  cv::Mat mask = cv::Mat::zeros(int((hi.y() - lo.y() + 10) / pixel) + 2, int((hi.x() - lo.x() + 10) / pixel) + 2, CV_8U);
  rasterize(mask, l, t);
  mask = degrade_mask(mask, 0.5, 2.0, 7);
  return extract_contours(mask, t, ContourOptions{}).buildings.at(0).rings;
}

void set_edges(benchmark::State& state, const std::vector<Ring>& rings) {
  std::size_t n = 0;
  for (const Ring& r : rings) n += r.size();
  state.counters["edges"] = double(n);
}

void BM_Smoothing(benchmark::State& state) {
  const auto rings = building(int(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(smooth_normals(rings[0], 0.25, SmoothingOptions{}));
  set_edges(state, rings);
}

void BM_WholeChainOriginalRoute(benchmark::State& state) {
  const auto rings = building(int(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(regularize_building(rings, 0.25, CoreOptions{}));
  set_edges(state, rings);
}

void BM_WholeChainDeformedRoute(benchmark::State& state) {
  const auto rings = building(int(state.range(0)));
  CoreOptions o;
  o.corners.route = "deformed";
  for (auto _ : state) benchmark::DoNotOptimize(regularize_building(rings, 0.25, o));
  set_edges(state, rings);
}

void BM_Triangulation(benchmark::State& state) {
  auto rings = building(int(state.range(0)));
  const Vec2 origin = rings[0][0];
  for (Ring& r : rings) for (Vec2& p : r) p = (p - origin) / 0.25;
  for (auto _ : state) benchmark::DoNotOptimize(triangulate(rings, 5.0, TriangulationOptions{}));
  set_edges(state, rings);
}

BENCHMARK(BM_Smoothing)->Arg(100)->Arg(500)->Arg(2000)->Arg(10000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_WholeChainOriginalRoute)->Arg(100)->Arg(500)->Arg(2000)->Arg(10000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Triangulation)->Arg(100)->Arg(500)->Arg(2000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_WholeChainDeformedRoute)->Arg(100)->Arg(500)->Arg(2000)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace lodforge

BENCHMARK_MAIN();
