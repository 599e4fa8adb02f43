#include "triangulation/triangulate.hpp"

#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Delaunay_mesh_face_base_2.h>
#include <CGAL/Delaunay_mesh_size_criteria_2.h>
#include <CGAL/Delaunay_mesh_vertex_base_2.h>
#include <CGAL/Delaunay_mesher_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <map>
#include <stdexcept>
#include <string>

#include "geometry/polygon.hpp"

namespace lodforge {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Delaunay_mesh_vertex_base_2<K>;
using Fb = CGAL::Delaunay_mesh_face_base_2<K>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using Cdt = CGAL::Constrained_Delaunay_triangulation_2<K, Tds, CGAL::Exact_predicates_tag>;
using Criteria = CGAL::Delaunay_mesh_size_criteria_2<Cdt>;
using Mesher = CGAL::Delaunay_mesher_2<Cdt, Criteria>;
using Point = K::Point_2;

// A point strictly inside a clockwise hole: just right of one of its edges, checked.
Point point_inside_hole(const Ring& hole) {
  for (std::size_t i = 0; i < hole.size(); ++i) {
    const Vec2 t = edge_vector(hole, i);
    const Vec2 p = hole[i] + 0.5 * t + 1e-3 * t.norm() * outward_normal(t);
    if (point_in_ring(p, hole)) return {p.x(), p.y()};
  }
  throw std::runtime_error("no interior point found in a hole");
}

}  // namespace

TriangleMesh triangulate(const std::vector<Ring>& rings, double size_bound, const TriangulationOptions& o) {
  Cdt cdt;
  std::vector<std::vector<Cdt::Vertex_handle>> handles(rings.size());
  for (std::size_t r = 0; r < rings.size(); ++r) {
    for (const Vec2& p : rings[r]) handles[r].push_back(cdt.insert(Point(p.x(), p.y())));
    for (std::size_t i = 0; i < rings[r].size(); ++i)
      cdt.insert_constraint(handles[r][i], handles[r][(i + 1) % rings[r].size()]);
  }
  if (cdt.number_of_vertices() != [&] { std::size_t n = 0; for (auto& r : rings) n += r.size(); return n; }())
    throw std::runtime_error("rings share vertices");
  std::vector<Point> seeds;
  for (std::size_t r = 1; r < rings.size(); ++r) seeds.push_back(point_inside_hole(rings[r]));
  Mesher mesher(cdt, Criteria(o.shape_bound, size_bound));
  mesher.set_seeds(seeds.begin(), seeds.end(), false);
  mesher.init();
  while (!mesher.is_refinement_done() && int(cdt.number_of_vertices()) < o.max_vertices) mesher.step_by_step_refine_mesh();

  TriangleMesh mesh;
  std::map<Cdt::Vertex_handle, int> index;
  auto vertex_index = [&](Cdt::Vertex_handle v) {
    auto [it, inserted] = index.try_emplace(v, int(mesh.vertices.size()));
    if (inserted) mesh.vertices.emplace_back(v->point().x(), v->point().y());
    return it->second;
  };
  // Keep the input vertices first, in ring order, so indices are stable.
  for (std::size_t r = 0; r < rings.size(); ++r) {
    mesh.ring_vertex.emplace_back();
    for (auto h : handles[r]) mesh.ring_vertex.back().push_back(vertex_index(h));
  }
  std::map<int, int> next_on_boundary;
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
    if (!f->is_in_domain()) continue;
    mesh.triangles.push_back({vertex_index(f->vertex(0)), vertex_index(f->vertex(1)), vertex_index(f->vertex(2))});
    for (int i = 0; i < 3; ++i) {
      auto neighbour = f->neighbor(i);
      if (!cdt.is_infinite(neighbour) && neighbour->is_in_domain()) continue;
      next_on_boundary[vertex_index(f->vertex(Cdt::ccw(i)))] = vertex_index(f->vertex(Cdt::cw(i)));
    }
  }
  // Walk each ring's boundary loop to tell which input edge every sub-edge lies on.
  std::vector<std::pair<int, int>> input_of(mesh.vertices.size(), {-1, -1});
  for (std::size_t r = 0; r < rings.size(); ++r)
    for (std::size_t i = 0; i < rings[r].size(); ++i) input_of[mesh.ring_vertex[r][i]] = {int(r), int(i)};
  for (std::size_t r = 0; r < rings.size(); ++r) {
    const int start = mesh.ring_vertex[r][0];
    int current = start, edge = 0;
    std::size_t guard = 0;
    do {
      auto it = next_on_boundary.find(current);
      if (it == next_on_boundary.end() || ++guard > mesh.vertices.size())
        throw std::runtime_error("mesh boundary of ring " + std::to_string(r) + " is broken");
      if (input_of[current].first == int(r)) edge = input_of[current].second;
      mesh.boundary.push_back({current, it->second, int(r), edge});
      current = it->second;
    } while (current != start);
  }
  return mesh;
}

}  // namespace lodforge
