// Stage 5: constrained Delaunay triangulation with refinement of a polygon with holes
// (paper §2.4, Figure 7: interior vertices are needed; NOTES.md: a plain CDT of a staircase
// locks or collapses under deformation). CGAL stays inside triangulate.cpp.
#pragma once
#include <array>
#include <vector>

#include "common/option.hpp"
#include "geometry/types.hpp"

namespace lodforge {

struct TriangulationOptions {
  double shape_bound = 0.125;  // CGAL Delaunay_mesh_size_criteria_2 shape bound (B = 1/(4 sin^2 a))
  double size_bound_px = 5.0;  // longest triangle edge, in pixels
  int max_vertices = 200000;   // refinement stops here

  template <class V>
  void visit(V& v) {
    v("shape_bound", shape_bound, "CGAL shape bound of the mesh (0.125 = 20.7 degree minimum angle)", Check::between(0.125, 1e9));
    v("size_bound_px", size_bound_px, "longest mesh edge, in pixels", Check::above(0));
    v("max_vertices", max_vertices, "mesh vertices at most (refinement stops there)", Check::at_least(3));
  }
};

struct BoundaryEdge {
  int a, b;       // mesh vertex indices, interior on the left
  int ring, edge; // the input ring edge this (sub-)edge lies on
};

struct TriangleMesh {
  std::vector<Vec2> vertices;
  std::vector<std::array<int, 3>> triangles;  // counter-clockwise
  std::vector<std::vector<int>> ring_vertex;  // mesh vertex of every input ring vertex
  std::vector<BoundaryEdge> boundary;
};

// rings: [0] outer counter-clockwise, then clockwise holes; simple and pairwise disjoint.
// Coordinates in any unit; size_bound is in the same unit (callers pass pixels).
// Throws std::runtime_error when the rings cannot be meshed.
TriangleMesh triangulate(const std::vector<Ring>& rings, double size_bound, const TriangulationOptions& options);

}  // namespace lodforge
