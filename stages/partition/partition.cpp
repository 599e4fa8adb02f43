#include "partition/partition.hpp"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Polygon_set_2.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "geometry/polygon.hpp"

namespace lodforge {

namespace {

using K = CGAL::Exact_predicates_exact_constructions_kernel;
using CPolygon = CGAL::Polygon_2<K>;
using CPolygonWithHoles = CGAL::Polygon_with_holes_2<K>;
using CSet = CGAL::Polygon_set_2<K>;

CPolygon to_cgal(const Ring& ring, bool counter_clockwise) {
  CPolygon p;
  for (const Vec2& v : ring) p.push_back(K::Point_2(v.x(), v.y()));
  if (p.is_counterclockwise_oriented() != counter_clockwise) p.reverse_orientation();
  return p;
}

CPolygonWithHoles to_cgal(const PolygonWithHoles& polygon) {
  CPolygonWithHoles out(to_cgal(polygon.outer, true));
  for (const Ring& h : polygon.holes) out.add_hole(to_cgal(h, false));
  return out;
}

// Exact coordinates rounded the same way wherever they were computed: a vertex two results share
// (a shared wall's end) becomes the same double in both.
// (A coordinate whose interval is one double is that double: exact without computing it again.)
double rounded(const K::FT& x) {
  const std::pair<double, double> i = CGAL::to_interval(x);
  return i.first == i.second ? i.first : CGAL::to_double(CGAL::exact(x));
}

Ring to_ring(const CPolygon& p) {
  Ring r;
  for (auto v = p.vertices_begin(); v != p.vertices_end(); ++v) r.emplace_back(rounded(v->x()), rounded(v->y()));
  return remove_degenerate_vertices(r, 1e-9);
}

// The polygons of a set as ours, valid ones only (a polygon pinched at a vertex is not valid
// as we write polygons): (valid, the area of the invalid ones).
std::pair<std::vector<PolygonWithHoles>, double> polygons_of(const CSet& set) {
  std::vector<CPolygonWithHoles> parts;
  set.polygons_with_holes(std::back_inserter(parts));
  std::vector<PolygonWithHoles> out;
  double invalid = 0;
  for (const CPolygonWithHoles& part : parts) {
    if (part.is_unbounded()) continue;
    PolygonWithHoles p;
    p.outer = to_ring(part.outer_boundary());
    if (signed_area(p.outer) < 0) std::reverse(p.outer.begin(), p.outer.end());
    for (auto h = part.holes_begin(); h != part.holes_end(); ++h) {
      Ring ring = to_ring(*h);
      if (signed_area(ring) > 0) std::reverse(ring.begin(), ring.end());
      p.holes.push_back(std::move(ring));
    }
    if (p.outer.size() >= 3 && polygon_problem(p).empty()) out.push_back(std::move(p));
    else invalid += std::abs(CGAL::to_double(part.outer_boundary().area()));
  }
  std::sort(out.begin(), out.end(), [](const PolygonWithHoles& a, const PolygonWithHoles& b) {
    const double x = area(a), y = area(b);
    if (x != y) return x > y;
    return std::lexicographical_compare(a.outer.begin(), a.outer.end(), b.outer.begin(), b.outer.end(),
                                        [](const Vec2& p, const Vec2& q) { return p.x() != q.x() ? p.x() < q.x() : p.y() < q.y(); });
  });
  return {out, invalid};
}

// (Only valid polygons enter a polygon set: CGAL takes no other. The callers' are valid; an
// invalid one would be left out, not crash.)
CSet set_of(const std::vector<PolygonWithHoles>& polygons) {
  CSet s;
  for (const PolygonWithHoles& p : polygons)
    if (p.outer.size() >= 3 && polygon_problem(p).empty()) s.join(to_cgal(p));
  return s;
}

// The band within distance d around the footprints' union U, split among the footprints as a
// mitered offset splits it: each boundary edge of U sweeps a quadrilateral outward to the miter
// points of its two vertices (on the bisectors of its neighbours' normals, at most 2 d out), and
// the quadrilateral goes to the footprint the edge bounds. Adjacent quadrilaterals share their
// bisector exactly, so a row's front overhang is split at the party walls' ends, square to the
// facade, by straight lines. Inner vertices are U's own (exact), so the band meets U without a
// sliver. Quadrilaterals that fold over (a short edge between reflex corners) are left out; where
// two overlap, the earlier footprint keeps the overlap (in partition_outlines).
std::vector<CSet> band_cells(const std::vector<CSet>& own, const CSet& covered, double d) {
  std::vector<std::vector<CPolygon>> quads(own.size());
  std::vector<CPolygonWithHoles> parts;
  if (d > 0) covered.polygons_with_holes(std::back_inserter(parts));
  auto sweep = [&](const CPolygon& ring) {
    // (Outer boundaries counter-clockwise, holes clockwise: U on the left of every edge.)
    std::vector<K::Point_2> exact(ring.vertices_begin(), ring.vertices_end());
    const std::size_t n = exact.size();
    if (n < 3) return;
    std::vector<Vec2> v(n), offset(n);
    for (std::size_t k = 0; k < n; ++k) v[k] = Vec2(CGAL::to_double(exact[k].x()), CGAL::to_double(exact[k].y()));
    for (std::size_t k = 0; k < n; ++k) {
      const Vec2 in = v[k] - v[(k + n - 1) % n], out = v[(k + 1) % n] - v[k];
      const Vec2 n1 = outward_normal(in), n2 = outward_normal(out);
      Vec2 m = n1 + n2;
      m = m.norm() < 1e-9 ? n1 : Vec2(m.normalized());
      const double length = d / std::max(0.5, n1.dot(m));  // the miter, at most 2 d
      offset[k] = v[k] + m * length;
    }
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t l = (k + 1) % n;
      CPolygon quad;
      quad.push_back(exact[k]);
      quad.push_back(K::Point_2(offset[k].x(), offset[k].y()));
      quad.push_back(K::Point_2(offset[l].x(), offset[l].y()));
      quad.push_back(exact[l]);
      if (!quad.is_simple() || quad.area() == 0) continue;
      if (!quad.is_counterclockwise_oriented()) quad.reverse_orientation();
      // The footprint the edge bounds: the one holding a point just inside U at its middle.
      const K::Vector_2 edge = exact[l] - exact[k];
      const K::Point_2 probe = CGAL::midpoint(exact[k], exact[l]) + K::Vector_2(-edge.y(), edge.x()) * K::FT(1e-7);
      for (std::size_t i = 0; i < own.size(); ++i)
        if (own[i].oriented_side(probe) == CGAL::ON_POSITIVE_SIDE) {
          quads[i].push_back(std::move(quad));
          break;
        }
    }
  };
  for (const CPolygonWithHoles& part : parts) {
    sweep(part.outer_boundary());
    for (auto h = part.holes_begin(); h != part.holes_end(); ++h) sweep(*h);
  }
  std::vector<CSet> cells(own.size());
  for (std::size_t i = 0; i < own.size(); ++i)
    if (!quads[i].empty()) cells[i].join(quads[i].begin(), quads[i].end());
  return cells;
}

}  // namespace

Partition partition_outlines(const std::vector<PolygonWithHoles>& outlines,
                             const std::vector<std::vector<PolygonWithHoles>>& footprints, const PartitionOptions& options,
                             double min_area_m2, bool absorb_rest) {
  Partition out;
  out.shares.resize(footprints.size());
  const CSet outline = set_of(outlines);
  // The cadastre's own cells: each footprint without the earlier ones.
  std::vector<CSet> own(footprints.size());
  CSet covered;
  for (std::size_t i = 0; i < footprints.size(); ++i) {
    own[i] = set_of(footprints[i]);
    own[i].difference(covered);
    covered.join(own[i]);
  }
  const std::vector<CSet> bands = band_cells(own, covered, options.extension_m);
  CSet cells = covered;  // what the cells so far take
  for (std::size_t i = 0; i < footprints.size(); ++i) {
    FootprintShare& share = out.shares[i];
    CSet cell = bands[i];
    cell.difference(cells);
    cells.join(cell);
    if (options.lod0 == "cadastre") {
      auto [parts, invalid] = polygons_of(own[i]);
      if (!parts.empty()) share.polygon = parts.front();
      if (parts.size() > 1) share.note = std::to_string(parts.size() - 1) + " smaller part(s) of the footprint left out";
      continue;
    }
    cell.join(own[i]);
    cell.intersection(outline);
    auto [parts, invalid] = polygons_of(cell);
    if (!parts.empty()) {
      share.polygon = parts.front();
      double left = invalid;
      for (std::size_t k = 1; k < parts.size(); ++k) left += area(parts[k]);
      if (left > 0) {
        char text[112];
        std::snprintf(text, sizeof text, "%.1f m2 of the outline in the footprint's cell left out (apart from its main part)", left);
        share.note = text;
      }
    } else {
      // The outline misses the footprint's cell (or leaves only a pinched part): the cadastre's polygon.
      auto [own_parts, own_invalid] = polygons_of(own[i]);
      if (!own_parts.empty()) share.polygon = own_parts.front();
      share.note = "the regularized outline leaves nothing valid in the footprint's cell; the cadastre's polygon is its LOD0";
    }
  }
  CSet rest = outline;
  rest.difference(cells);
  auto [parts, invalid] = polygons_of(rest);
  out.dropped_small += invalid > 0;
  for (PolygonWithHoles& p : parts) {
    if (absorb_rest) {
      // Into the share it borders longest (half the perimeter the union loses), when the union is one polygon.
      auto perimeter_of = [](const PolygonWithHoles& q) {
        double l = perimeter(q.outer);
        for (const Ring& h : q.holes) l += perimeter(h);
        return l;
      };
      std::size_t best = out.shares.size();
      double best_shared = 0;
      PolygonWithHoles best_union;
      for (std::size_t i = 0; i < out.shares.size(); ++i) {
        if (out.shares[i].polygon.outer.empty()) continue;
        CSet u = set_of({out.shares[i].polygon, p});
        auto [joined, joined_invalid] = polygons_of(u);
        if (joined.size() != 1 || joined_invalid > 0) continue;
        const double shared = (perimeter_of(out.shares[i].polygon) + perimeter_of(p) - perimeter_of(joined.front())) / 2;
        if (shared > best_shared + 1e-9) {
          best = i;
          best_shared = shared;
          best_union = std::move(joined.front());
        }
      }
      if (best < out.shares.size()) {
        out.shares[best].polygon = std::move(best_union);
        continue;
      }
    }
    if (area(p) >= min_area_m2) out.rest.push_back(std::move(p));
    else ++out.dropped_small;
  }
  return out;
}

}  // namespace lodforge
