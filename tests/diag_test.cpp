#include <gtest/gtest.h>
#include <cstdlib>
#include <sstream>
#include "commands/stage_options.hpp"
#include "geometry/polygon.hpp"
#include "pipeline/building.hpp"
#include "labeling/mrf.hpp"
#include "support/shapes.hpp"
using namespace lodforge;
TEST(Diag, Sweep) {
  StageOptions so;
  std::vector<std::string> sets;
  if (const char* e = std::getenv("LF_SET")) { std::stringstream ss(e); std::string item; while (std::getline(ss, item, ';')) if (!item.empty()) sets.push_back(item); }
  apply_overrides(so, sets);
  double noise = std::getenv("LF_NOISE") ? atof(std::getenv("LF_NOISE")) : 0.8;
  double px = std::getenv("LF_PX") ? atof(std::getenv("LF_PX")) : 0.25;
  struct S { const char* name; PolygonWithHoles p; size_t n; double angle; };
  std::vector<S> shapes = {
    {"L", {{{0, 0}, {16, 0}, {16, 6}, {6, 6}, {6, 14}, {0, 14}}, {}}, 6, 30},
    {"court", {{{0, 0}, {30, 0}, {30, 24}, {0, 24}}, {{{8, 7}, {8, 17}, {22, 17}, {22, 7}}}}, 8, 17},
    {"cut", {{{0, 0}, {24, 0}, {24, 9}, {17, 16}, {0, 16}}, {}}, 5, 12},
    {"rect", {{{0, 0}, {24, 0}, {24, 14}, {0, 14}}, {}}, 4, 30},
    {"T", {{{6,0},{12,0},{12,10},{18,10},{18,16},{0,16},{0,10},{6,10}}, {}}, 8, 40},
  };
  for (auto& sh : shapes) {
    double sum = 0, raw = 0, ar = 0, arr = 0, mn = 1; int right = 0, fails = 0, N = 20;
    for (int seed = 1; seed <= N; ++seed) {
      const auto truth = test::rotated(sh.p, sh.angle);
      const auto s = test::rasterize_shape(truth, px, noise, 2.0, seed);
      PolygonWithHoles rp{s.buildings[0].rings[0], {}};
      for (size_t k = 1; k < s.buildings[0].rings.size(); ++k) rp.holes.push_back(s.buildings[0].rings[k]);
      const auto r = regularize_building(s.buildings[0].rings, px, so.core);
      size_t n = r.footprint.outer.size(); for (auto& h : r.footprint.holes) n += h.size();
      sum += test::iou(r.footprint, truth); mn = std::min(mn, test::iou(r.footprint, truth)); ar += area(r.footprint)/area(truth)/N; arr += area(rp)/area(truth)/N; raw += test::iou(rp, truth); right += (n == sh.n); fails += !r.ok;
    }
    printf("%-6s IoU %.4f (raw %.4f) right-count %2d/%d fails %d area ratio %.4f raw %.4f min %.4f\n", sh.name, sum / N, raw / N, right, N, fails, ar, arr, mn);
  }
}
TEST(Diag, One) {
  StageOptions so; apply_overrides(so, {"smoothing.min_neighbourhood_px=5"});
  const PolygonWithHoles l = {{{0, 0}, {16, 0}, {16, 6}, {6, 6}, {6, 14}, {0, 14}}, {}};
  const auto truth = test::rotated(l, 30.0);
  const auto s = test::rasterize_shape(truth, 0.25, 0.0, 2.0, 1);
  const auto r = regularize_building(s.buildings[0].rings, 0.25, so.core);
  for (auto& d : r.directions) printf("dir %.3f\n", atan2(d.y(), d.x())*180/M_PI);
  for (auto& p : truth.outer) printf("T %.3f %.3f\n", p.x()-500000, p.y()-5000000);
  for (auto& p : r.footprint.outer) printf("R %.3f %.3f\n", p.x()-500000, p.y()-5000000);
}
#include "deformation/deform.hpp"
#include "triangulation/triangulate.hpp"
TEST(Diag, Align) {
  const PolygonWithHoles l = {{{0, 0}, {16, 0}, {16, 6}, {6, 6}, {6, 14}, {0, 14}}, {}};
  for (int seed : {1, 2, 3}) {
  const auto s = test::rasterize_shape(test::rotated(l, 30.0), 0.25, 0.8, 2.0, seed);
  const auto lab = regularize_building(s.buildings[0].rings, 0.25, CoreOptions{});
  std::vector<Ring> px = s.buildings[0].rings; Vec2 o = px[0][0]; for (auto& r : px) for (auto& p : r) p = (p - o) / 0.25;
  auto mesh = triangulate(px, 5.0, TriangulationOptions{});
  std::vector<Vec2> t; for (auto& b : mesh.boundary) t.push_back(lab.directions[lab.labels[b.ring][b.edge]]);
  auto d = deform(mesh, t, DeformationOptions{});
  printf("seed %d rounds %d iters %d rms %.2f max %.2f\n", seed, d.rounds, d.iterations, d.rms_deg, d.max_deg);
  for (size_t k = 0; k < mesh.boundary.size(); ++k) { Vec2 e = d.vertices[mesh.boundary[k].b] - d.vertices[mesh.boundary[k].a]; double a = asin(std::min(1.0, std::abs(e.dot(t[k]))/e.norm()))*180/M_PI; if (a > 3) printf("  edge %zu (ring edge %d) len %.4f (orig %.3f) angle %.1f labels prev %d this %d next %d\n", k, mesh.boundary[k].edge, e.norm(), (mesh.vertices[mesh.boundary[k].b]-mesh.vertices[mesh.boundary[k].a]).norm(), a, lab.labels[0][(mesh.boundary[k].edge+lab.labels[0].size()-1)%lab.labels[0].size()], lab.labels[0][mesh.boundary[k].edge], lab.labels[0][(mesh.boundary[k].edge+1)%lab.labels[0].size()]); }
  }
}
TEST(Diag, Cross) {
  const PolygonWithHoles l = {{{0, 0}, {16, 0}, {16, 6}, {6, 6}, {6, 14}, {0, 14}}, {}};
  for (int seed : {1, 2, 3}) {
  const auto s = test::rasterize_shape(test::rotated(l, 30.0), 0.25, 0.8, 2.0, seed);
  const auto lab = regularize_building(s.buildings[0].rings, 0.25, CoreOptions{});
  std::vector<Ring> px = s.buildings[0].rings; Vec2 o = px[0][0]; for (auto& r : px) for (auto& p : r) p = (p - o) / 0.25;
  auto mesh = triangulate(px, 5.0, TriangulationOptions{});
  std::vector<Vec2> t; for (auto& b : mesh.boundary) t.push_back(lab.directions[lab.labels[b.ring][b.edge]]);
  auto d = deform(mesh, t, DeformationOptions{});
  Ring ring; for (int v : mesh.ring_vertex[0]) ring.push_back(d.vertices[v]);
  ring = remove_degenerate_vertices(ring, 0.1);
  printf("seed %d: %s\n", seed, ring_problem(ring).c_str());
  size_t n = ring.size();
  for (size_t i = 0; i < n; ++i) for (size_t j = i + 2; j < n; ++j) { if (i == 0 && j == n - 1) continue;
    if (segments_intersect(ring[i], ring[(i+1)%n], ring[j], ring[(j+1)%n])) printf("  edges %zu and %zu: (%.4f %.4f)-(%.4f %.4f) vs (%.4f %.4f)-(%.4f %.4f); orig (%.1f %.1f) (%.1f %.1f)\n", i, j, ring[i].x(), ring[i].y(), ring[(i+1)%n].x(), ring[(i+1)%n].y(), ring[j].x(), ring[j].y(), ring[(j+1)%n].x(), ring[(j+1)%n].y(), px[0][i].x(), px[0][i].y(), px[0][j].x(), px[0][j].y()); }
  }
}
