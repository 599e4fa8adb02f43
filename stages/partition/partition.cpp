#include "partition/partition.hpp"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Polygon_set_2.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "geometry/polygon.hpp"
#include "geometry/rasterize.hpp"

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
Ring to_ring(const CPolygon& p) {
  Ring r;
  for (auto v = p.vertices_begin(); v != p.vertices_end(); ++v)
    r.emplace_back(CGAL::to_double(CGAL::exact(v->x())), CGAL::to_double(CGAL::exact(v->y())));
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

CSet set_of(const std::vector<PolygonWithHoles>& polygons) {
  CSet s;
  for (const PolygonWithHoles& p : polygons) s.join(to_cgal(p));
  return s;
}

// The pixels of the grid around box assigned to each footprint: those whose centre lies in it
// (the earlier footprint where two overlap), and those outside every footprint whose nearest
// footprint pixel is within extension_px. Returned as per-footprint sets of row runs (pixel
// rectangles), leaving out the pixels inside the footprint whole (nothing to add to it).
std::vector<CSet> extension_cells(const std::vector<std::vector<PolygonWithHoles>>& footprints, const GeoTransform& grid,
                                  const cv::Rect& box, double extension_px) {
  const int margin = int(std::ceil(extension_px)) + 2;
  const cv::Rect area(box.x - margin, box.y - margin, box.width + 2 * margin, box.height + 2 * margin);
  GeoTransform local = grid;
  const Vec2 origin = grid.to_map(area.x, area.y);
  local.c[0] = origin.x();
  local.c[3] = origin.y();
  cv::Mat labels = cv::Mat::zeros(area.size(), CV_32S), scratch(area.size(), CV_8U);
  for (std::size_t i = footprints.size(); i-- > 0;) {  // the earlier footprint last: it wins an overlap
    scratch.setTo(0);
    for (const PolygonWithHoles& p : footprints[i]) rasterize(scratch, p, local, 1, 0);
    labels.setTo(int(i) + 1, scratch);
  }
  const cv::Mat own = labels.clone();  // (before the extension: the pixels whose centre lies in a footprint)
  if (extension_px > 0) {
    cv::Mat unlabeled = labels == 0, distance, nearest;
    cv::distanceTransform(unlabeled, distance, nearest, cv::DIST_L2, cv::DIST_MASK_5, cv::DIST_LABEL_PIXEL);
    // The footprint of each labeled pixel, by the index distanceTransform gave it.
    std::vector<int> footprint_of_seed(std::size_t(area.area()) + 1, 0);
    for (int y = 0; y < area.height; ++y)
      for (int x = 0; x < area.width; ++x)
        if (const int l = labels.at<int>(y, x)) footprint_of_seed[std::size_t(nearest.at<int>(y, x))] = l;
    for (int y = 0; y < area.height; ++y)
      for (int x = 0; x < area.width; ++x)
        if (!labels.at<int>(y, x) && distance.at<float>(y, x) <= extension_px)
          labels.at<int>(y, x) = footprint_of_seed[std::size_t(nearest.at<int>(y, x))];
  }
  std::vector<CSet> cells(footprints.size());
  std::vector<std::vector<CPolygon>> runs(footprints.size());
  for (int y = 0; y < area.height; ++y) {
    for (int x = 0; x < area.width;) {
      const int l = labels.at<int>(y, x);
      int end = x + 1;
      while (end < area.width && labels.at<int>(y, end) == l) ++end;
      if (l > 0) {
        // Within the run, the pixels inside the footprint whole are skipped: those whose own centre
        // and their 8 neighbours' lie in it.
        auto inner = [&](int c) {
          if (y == 0 || y + 1 == area.height || c == 0 || c + 1 == area.width) return false;
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx)
              if (own.at<int>(y + dy, c + dx) != l) return false;
          return true;
        };
        for (int c = x; c < end;) {
          if (inner(c)) { ++c; continue; }
          int e = c + 1;
          while (e < end && !inner(e)) ++e;
          Ring r{local.to_map(c, y), local.to_map(e, y), local.to_map(e, y + 1), local.to_map(c, y + 1)};
          runs[std::size_t(l - 1)].push_back(to_cgal(r, true));
          c = e;
        }
      }
      x = end;
    }
  }
  for (std::size_t i = 0; i < footprints.size(); ++i)
    if (!runs[i].empty()) cells[i].join(runs[i].begin(), runs[i].end());
  return cells;
}

}  // namespace

Partition partition_outlines(const std::vector<PolygonWithHoles>& outlines,
                             const std::vector<std::vector<PolygonWithHoles>>& footprints, const GeoTransform& grid,
                             const cv::Rect& box, const PartitionOptions& options, double min_area_m2) {
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
  const std::vector<CSet> extensions = extension_cells(footprints, grid, box, options.extension_m / grid.pixel_size());
  CSet cells = covered;
  for (std::size_t i = 0; i < footprints.size(); ++i) {
    FootprintShare& share = out.shares[i];
    CSet cell = extensions[i];
    cell.difference(covered);
    cells.join(cell);
    cell.join(own[i]);
    if (options.lod0 == "cadastre") {
      auto [parts, invalid] = polygons_of(own[i]);
      if (!parts.empty()) share.polygon = parts.front();
      if (parts.size() > 1) share.note = std::to_string(parts.size() - 1) + " smaller part(s) of the footprint left out";
      continue;
    }
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
    if (area(p) >= min_area_m2) out.rest.push_back(std::move(p));
    else ++out.dropped_small;
  }
  return out;
}

}  // namespace lodforge
