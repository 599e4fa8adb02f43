#include <gtest/gtest.h>

#include "geometry/polygon.hpp"
#include "triangulation/triangulate.hpp"

namespace lodforge {
namespace {

double triangle_area(const TriangleMesh& m, const std::array<int, 3>& t) {
  return 0.5 * cross(m.vertices[t[1]] - m.vertices[t[0]], m.vertices[t[2]] - m.vertices[t[0]]);
}

TEST(Triangulation, CoversThePolygonWithHoleWithPositiveTriangles) {
  const std::vector<Ring> rings = {{{0, 0}, {10, 0}, {10, 10}, {0, 10}}, {{3, 3}, {3, 6}, {6, 6}, {6, 3}}};
  const TriangleMesh mesh = triangulate(rings, 2.0, TriangulationOptions{});
  double total = 0;
  for (const auto& t : mesh.triangles) {
    const double a = triangle_area(mesh, t);
    EXPECT_GT(a, 0);
    total += a;
  }
  EXPECT_NEAR(total, 100.0 - 9.0, 1e-9);
  EXPECT_GT(mesh.vertices.size(), 8u);  // refined: interior vertices exist
  // Input vertices keep their coordinates and their order.
  for (std::size_t r = 0; r < rings.size(); ++r)
    for (std::size_t i = 0; i < rings[r].size(); ++i) EXPECT_EQ(mesh.vertices[mesh.ring_vertex[r][i]], rings[r][i]);
}

TEST(Triangulation, BoundarySubEdgesLieOnTheirInputEdges) {
  const std::vector<Ring> rings = {{{0, 0}, {20, 0}, {20, 1}, {0, 1}}};  // long thin: edges get split
  const TriangleMesh mesh = triangulate(rings, 1.0, TriangulationOptions{});
  double length = 0;
  for (const BoundaryEdge& b : mesh.boundary) {
    const Vec2 a = rings[b.ring][b.edge], c = rings[b.ring][(b.edge + 1) % rings[b.ring].size()];
    const Vec2 dir = (c - a).normalized();
    for (int v : {b.a, b.b}) EXPECT_NEAR(cross(dir, mesh.vertices[v] - a), 0.0, 1e-9);
    EXPECT_GT((mesh.vertices[b.b] - mesh.vertices[b.a]).dot(dir), 0);  // same orientation
    length += (mesh.vertices[b.b] - mesh.vertices[b.a]).norm();
  }
  EXPECT_NEAR(length, perimeter(rings[0]), 1e-9);
  EXPECT_GT(mesh.boundary.size(), 4u);
}

TEST(Triangulation, VertexBudgetStopsRefinement) {
  TriangulationOptions o;
  o.max_vertices = 50;
  const TriangleMesh mesh = triangulate({{{0, 0}, {100, 0}, {100, 100}, {0, 100}}}, 1.0, o);
  EXPECT_LE(mesh.vertices.size(), 51u);
}

}  // namespace
}  // namespace lodforge
