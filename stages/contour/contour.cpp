#include "contour/contour.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>

#include "geometry/polygon.hpp"

namespace lodforge {

namespace {

// Fills one pixel of every 2x2 block whose pixels touch only diagonally, until none is left,
// so that every corner vertex has at most one incoming and one outgoing boundary edge.
void resolve_diagonal_contacts(cv::Mat& m) {
  bool changed = true;
  while (changed) {
    changed = false;
    for (int y = 0; y + 1 < m.rows; ++y) {
      uint8_t* r0 = m.ptr<uint8_t>(y);
      uint8_t* r1 = m.ptr<uint8_t>(y + 1);
      for (int x = 0; x + 1 < m.cols; ++x) {
        const bool a = r0[x], b = r0[x + 1], c = r1[x], d = r1[x + 1];
        if (a && d && !b && !c) { r0[x + 1] = 1; changed = true; }
        else if (b && c && !a && !d) { r0[x] = 1; changed = true; }
      }
    }
  }
}

struct DirectedEdge {
  int64_t from, to;
};

}  // namespace

std::vector<Ring> trace_component(cv::Mat m) {
  // Pad by one pixel so that neighbours never fall outside.
  cv::copyMakeBorder(m, m, 1, 1, 1, 1, cv::BORDER_CONSTANT, 0);
  resolve_diagonal_contacts(m);
  const int64_t stride = m.cols + 1;
  auto id = [stride](int64_t x, int64_t y) { return y * stride + x; };
  std::vector<DirectedEdge> edges;
  for (int y = 1; y + 1 < m.rows; ++y) {
    for (int x = 1; x + 1 < m.cols; ++x) {
      if (!m.at<uint8_t>(y, x)) continue;
      // Interior on the left in map coordinates (rows grow southwards).
      if (!m.at<uint8_t>(y - 1, x)) edges.push_back({id(x + 1, y), id(x, y)});
      if (!m.at<uint8_t>(y + 1, x)) edges.push_back({id(x, y + 1), id(x + 1, y + 1)});
      if (!m.at<uint8_t>(y, x + 1)) edges.push_back({id(x + 1, y + 1), id(x + 1, y)});
      if (!m.at<uint8_t>(y, x - 1)) edges.push_back({id(x, y), id(x, y + 1)});
    }
  }
  std::sort(edges.begin(), edges.end(),
            [](const DirectedEdge& a, const DirectedEdge& b) { return a.from < b.from; });
  std::vector<char> used(edges.size(), 0);
  auto find_from = [&edges](int64_t v) {
    auto it = std::lower_bound(edges.begin(), edges.end(), v,
                               [](const DirectedEdge& e, int64_t key) { return e.from < key; });
    return static_cast<std::size_t>(it - edges.begin());
  };
  std::vector<Ring> rings;
  for (std::size_t start = 0; start < edges.size(); ++start) {
    if (used[start]) continue;
    Ring ring;
    std::size_t e = start;
    while (!used[e]) {
      used[e] = 1;
      const int64_t v = edges[e].from;
      // Pixel-corner coordinates without the padding.
      ring.emplace_back(double(v % stride) - 1.0, double(v / stride) - 1.0);
      e = find_from(edges[e].to);
    }
    rings.push_back(std::move(ring));
  }
  // In pixel coordinates (y down) the outer ring has negative shoelace area; the largest
  // |area| ring is the outer one. Put it first.
  std::stable_sort(rings.begin(), rings.end(), [](const Ring& a, const Ring& b) {
    return std::abs(signed_area(a)) > std::abs(signed_area(b));
  });
  return rings;
}

cv::Rect component_box(const Components& c, int k) {
  return {c.stats.at<int>(k, cv::CC_STAT_LEFT), c.stats.at<int>(k, cv::CC_STAT_TOP), c.stats.at<int>(k, cv::CC_STAT_WIDTH),
          c.stats.at<int>(k, cv::CC_STAT_HEIGHT)};
}

Components label_components(const cv::Mat& mask, int connectivity) {
  CV_Assert(mask.type() == CV_8U);
  Components c;
  cv::Mat centroids;
  // Any non-zero pixel is foreground to OpenCV's labeling: no 0/1 copy of the mask is needed.
  c.count = cv::connectedComponentsWithStats(mask, c.labels, c.stats, centroids, connectivity == 4 ? 4 : 8, CV_32S);
  return c;
}

ContourResult extract_contours(const cv::Mat& mask, const GeoTransform& transform,
                               const ContourOptions& options, const ComponentFilter& keep) {
  return extract_contours(label_components(mask, options.connectivity), transform, options, keep);
}

ContourResult extract_contours(const Components& components, const GeoTransform& transform,
                               const ContourOptions& options, const ComponentFilter& keep) {
  ContourResult result;
  const cv::Mat& labels = components.labels;
  const cv::Mat& stats = components.stats;
  const int count = components.count;
  // First pixel of each component in raster order, its stable identity: the leftmost in its top row.
  std::vector<cv::Point> first(count, cv::Point(-1, -1));
  for (int k = 1; k < count; ++k) {
    const int top = stats.at<int>(k, cv::CC_STAT_TOP), left = stats.at<int>(k, cv::CC_STAT_LEFT);
    const int* row = labels.ptr<int>(top);
    for (int x = left; x < left + stats.at<int>(k, cv::CC_STAT_WIDTH); ++x)
      if (row[x] == k) {
        first[k] = {x, top};
        break;
      }
  }
  const double pixel_area = transform.pixel_size() * transform.pixel_size();
  std::vector<int> order;
  for (int k = 1; k < count; ++k) {
    if (keep && !keep(component_box(components, k), first[k])) continue;
    const int pixels = stats.at<int>(k, cv::CC_STAT_AREA);
    if (pixels * pixel_area < options.min_area_m2 || pixels < options.min_pixels) {
      ++result.dropped_small;
      continue;
    }
    order.push_back(k);
  }
  std::sort(order.begin(), order.end(), [&first](int a, int b) {
    return std::make_pair(first[a].y, first[a].x) < std::make_pair(first[b].y, first[b].x);
  });
  const double orientation = transform.c[1] * transform.c[5] - transform.c[2] * transform.c[4];
  for (int k : order) {
    BuildingContour b;
    b.bbox = component_box(components, k);
    b.pixel_count = stats.at<int>(k, cv::CC_STAT_AREA);
    b.first_col = first[k].x;
    b.first_row = first[k].y;
    cv::Mat component = labels(b.bbox) == k;
    component /= 255;
    for (Ring& ring : trace_component(component)) {
      for (Vec2& p : ring) p = transform.to_map(p.x() + b.bbox.x, p.y() + b.bbox.y);
      // A north-up raster (negative determinant) maps pixel orientation to map orientation
      // flipped, which is what trace_component assumes; any other transform is fixed here.
      if (orientation > 0) std::reverse(ring.begin(), ring.end());
      const bool is_outer = b.rings.empty();
      // (A hole's area is a whole number of pixels: half a pixel is margin enough.)
      if (!is_outer) {
        const double area = std::abs(signed_area(ring));
        if (area < options.min_hole_area_m2 || area < (options.min_pixels - 0.5) * pixel_area) continue;
      }
      b.rings.push_back(std::move(ring));
    }
    result.buildings.push_back(std::move(b));
  }
  return result;
}

}  // namespace lodforge
