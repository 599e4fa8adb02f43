#include "contour/contour.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <opencv2/imgproc.hpp>

#include "geometry/polygon.hpp"

namespace lodforge {

namespace {

// Eight pixels from p on, as one word (to skip stretches of a row eight at a time).
uint64_t word_at(const uint8_t* p) {
  uint64_t w;
  std::memcpy(&w, p, sizeof w);
  return w;
}

bool no_zero_byte(uint64_t w) {
  constexpr uint64_t low = 0x0101010101010101ULL, high = low << 7;
  return ((w - low) & ~w & high) == 0;
}

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
        // Where the two rows agree on eight pixels, none of the eight blocks starting on them is
        // diagonal (a diagonal block's rows differ in both its columns).
        while (x + 8 <= m.cols && word_at(r0 + x) == word_at(r1 + x)) x += 8;
        if (x + 1 >= m.cols) break;
        const bool a = r0[x], b = r0[x + 1], c = r1[x], d = r1[x + 1];
        if (a && d && !b && !c) { r0[x + 1] = 1; changed = true; }
        else if (b && c && !a && !d) { r0[x] = 1; changed = true; }
      }
    }
  }
}

// Traces every ring of a 0/1 image whose border rows and columns are 0, after filling its
// diagonal contacts (resolve_diagonal_contacts). A pixel corner (x, y) has an edge out of it for each side of a building pixel
// that borders the background there (interior on the left in map coordinates, rows growing
// southwards): with no diagonal contact, at most one. Rings start at their first corner in raster
// order and are found in that order; the outer ring is then put first.
std::vector<Ring> trace_padded(cv::Mat& m) {
  resolve_diagonal_contacts(m);
  enum : uint8_t { kNone, kLeft, kRight, kUp, kDown };
  // The edge out of corner (x, y), from the four pixels around it.
  auto out_of = [&m](int x, int y) -> uint8_t {
    if (x < 1 || y < 1 || x >= m.cols || y >= m.rows) return kNone;
    const uint8_t* above = m.ptr<uint8_t>(y - 1);
    const uint8_t* below = m.ptr<uint8_t>(y);
    const bool tl = above[x - 1], tr = above[x], bl = below[x - 1], br = below[x];
    if (bl && !tl) return kLeft;
    if (tr && !br) return kRight;
    if (tl && !tr) return kUp;
    if (br && !bl) return kDown;
    return kNone;
  };
  const int width = m.cols + 1;
  std::vector<char> visited(std::size_t(width) * std::size_t(m.rows + 1), 0);
  std::vector<Ring> rings;
  for (int y = 1; y < m.rows; ++y) {
    const uint8_t* above = m.ptr<uint8_t>(y - 1);
    const uint8_t* below = m.ptr<uint8_t>(y);
    for (int x = 1; x < m.cols; ++x) {
      // A ring's first corner has a horizontal edge out of it or into it: the pixels above and
      // below that edge differ. Where the two rows agree on eight pixels, none of their seven
      // corners starts a ring.
      if (x + 7 <= m.cols && word_at(above + x - 1) == word_at(below + x - 1)) {
        x += 6;
        continue;
      }
      if (visited[std::size_t(y) * width + x] || out_of(x, y) == kNone) continue;
      Ring ring;
      int cx = x, cy = y;
      while (!visited[std::size_t(cy) * width + cx]) {
        visited[std::size_t(cy) * width + cx] = 1;
        // Pixel-corner coordinates without the padding.
        ring.emplace_back(double(cx) - 1.0, double(cy) - 1.0);
        switch (out_of(cx, cy)) {
          case kLeft: --cx; break;
          case kRight: ++cx; break;
          case kUp: --cy; break;
          case kDown: ++cy; break;
          default: break;
        }
      }
      rings.push_back(std::move(ring));
    }
  }
  // In pixel coordinates (y down) the outer ring has negative shoelace area; the largest
  // |area| ring is the outer one. Put it first.
  std::stable_sort(rings.begin(), rings.end(), [](const Ring& a, const Ring& b) {
    return std::abs(signed_area(a)) > std::abs(signed_area(b));
  });
  return rings;
}

}  // namespace

std::vector<Ring> trace_component(cv::Mat m) {
  // Pad by one pixel so that neighbours never fall outside.
  cv::copyMakeBorder(m, m, 1, 1, 1, 1, cv::BORDER_CONSTANT, 0);
  return trace_padded(m);
}

int Components::label_at(cv::Point p) const {
  if (p.y < 0 || p.y >= rows || p.x < 0 || p.x >= cols) return 0;
  const auto first = runs.begin() + std::ptrdiff_t(row_begin[std::size_t(p.y)]),
             last = runs.begin() + std::ptrdiff_t(row_begin[std::size_t(p.y) + 1]);
  auto it = std::upper_bound(first, last, p.x, [](int x, const Run& r) { return x < r.x0; });
  if (it == first) return 0;
  --it;
  return p.x < it->x1 ? it->label : 0;
}

cv::Mat Components::mask_of(int label, int pad) const {
  const cv::Rect box = boxes[std::size_t(label)];
  cv::Mat m = cv::Mat::zeros(box.height + 2 * pad, box.width + 2 * pad, CV_8U);
  for (int y = box.y; y < box.y + box.height; ++y) {
    uint8_t* row = m.ptr<uint8_t>(y - box.y + pad);
    // The row's runs that reach into the box: from the first ending past its left side (a
    // row of a wide mask crosses many buildings) to the first starting past its right side.
    const auto end = runs.begin() + std::ptrdiff_t(row_begin[std::size_t(y) + 1]);
    auto it = std::lower_bound(runs.begin() + std::ptrdiff_t(row_begin[std::size_t(y)]), end, box.x,
                               [](const Run& r, int x) { return r.x1 <= x; });
    for (; it != end && it->x0 < box.x + box.width; ++it)
      if (it->label == label) std::fill(row + it->x0 - box.x + pad, row + it->x1 - box.x + pad, uint8_t(1));
  }
  return m;
}

Components label_components(const cv::Mat& mask, int connectivity) {
  CV_Assert(mask.type() == CV_8U);
  Components c;
  c.rows = mask.rows;
  c.cols = mask.cols;
  c.row_begin.assign(std::size_t(mask.rows) + 1, 0);
  // The runs, and a union-find over them: runs of consecutive rows that touch (share a column,
  // or with 8-connectivity a corner) are one component.
  std::vector<std::size_t> parent;
  auto find = [&parent](std::size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  const int slack = connectivity == 4 ? 0 : 1;
  for (int y = 0; y < mask.rows; ++y) {
    c.row_begin[std::size_t(y)] = c.runs.size();
    const uint8_t* m = mask.ptr<uint8_t>(y);
    for (int x = 0; x < mask.cols;) {
      // (Eight pixels at a time: a word of zeros, a word with no zero byte.)
      while (x + 8 <= mask.cols && word_at(m + x) == 0) x += 8;
      while (x < mask.cols && !m[x]) ++x;
      if (x == mask.cols) break;
      const int start = x;
      while (x + 8 <= mask.cols && no_zero_byte(word_at(m + x))) x += 8;
      while (x < mask.cols && m[x]) ++x;
      c.runs.push_back({start, x, 0});
      parent.push_back(parent.size());
    }
    if (y == 0) continue;
    std::size_t i = c.row_begin[std::size_t(y) - 1], j = c.row_begin[std::size_t(y)];
    const std::size_t above_end = j, end = c.runs.size();
    while (i < above_end && j < end) {
      const Components::Run &a = c.runs[i], &b = c.runs[j];
      if (a.x1 + slack <= b.x0) { ++i; continue; }
      if (b.x1 + slack <= a.x0) { ++j; continue; }
      // Touch: the later root joins the earlier one.
      const std::size_t ra = find(i), rb = find(j);
      if (ra != rb) parent[std::max(ra, rb)] = std::min(ra, rb);
      if (a.x1 < b.x1) ++i; else ++j;
    }
  }
  c.row_begin[std::size_t(mask.rows)] = c.runs.size();
  // Labels by first pixel in raster order: a root is its component's first run.
  std::vector<int> label_of_root(c.runs.size(), 0);
  c.count = 1;
  c.boxes.assign(1, cv::Rect());
  c.areas.assign(1, 0);
  c.firsts.assign(1, cv::Point(-1, -1));
  for (int y = 0; y < mask.rows; ++y) {
    for (std::size_t i = c.row_begin[std::size_t(y)]; i < c.row_begin[std::size_t(y) + 1]; ++i) {
      Components::Run& r = c.runs[i];
      const std::size_t root = find(i);
      if (root == i) {
        label_of_root[i] = c.count++;
        c.boxes.push_back(cv::Rect(r.x0, y, r.x1 - r.x0, 1));
        c.areas.push_back(0);
        c.firsts.push_back(cv::Point(r.x0, y));
      }
      r.label = label_of_root[root];
      const std::size_t k = std::size_t(r.label);
      c.areas[k] += r.x1 - r.x0;
      c.boxes[k] |= cv::Rect(r.x0, y, r.x1 - r.x0, 1);
    }
  }
  return c;
}

ContourResult extract_contours(const cv::Mat& mask, const GeoTransform& transform,
                               const ContourOptions& options, const ComponentFilter& keep) {
  return extract_contours(label_components(mask, options.connectivity), transform, options, keep);
}

ContourResult extract_contours(const Components& components, const GeoTransform& transform,
                               const ContourOptions& options, const ComponentFilter& keep) {
  ContourResult result;
  const int count = components.count;
  // First pixel of each component in raster order, its stable identity: the leftmost in its top row.
  const std::vector<cv::Point>& first = components.firsts;
  const double pixel_area = transform.pixel_size() * transform.pixel_size();
  const double orientation = transform.c[1] * transform.c[5] - transform.c[2] * transform.c[4];
  // (Labels are numbered in that order: the buildings come sorted by first pixel.)
  for (int k = 1; k < count; ++k) {
    if (keep && !keep(component_box(components, k), first[std::size_t(k)])) continue;
    const double pixels = double(components.areas[std::size_t(k)]);
    if (pixels * pixel_area < options.min_area_m2 || pixels < options.min_pixels) {
      ++result.dropped_small;
      continue;
    }
    BuildingContour b;
    b.bbox = component_box(components, k);
    b.pixel_count = components.areas[std::size_t(k)];
    b.first_col = first[std::size_t(k)].x;
    b.first_row = first[std::size_t(k)].y;
    cv::Mat component = components.mask_of(k, 1);  // padded, so that neighbours never fall outside
    for (Ring& ring : trace_padded(component)) {
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
