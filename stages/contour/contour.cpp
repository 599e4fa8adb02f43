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

namespace {

// The raster's edges a component's box touches.
struct CutSides {
  bool left = false, top = false, right = false, bottom = false;
  bool any() const { return left || top || right || bottom; }
};
CutSides cut_sides(const cv::Rect& box, const cv::Rect& raster) {
  return {box.x == raster.x, box.y == raster.y, box.x + box.width == raster.x + raster.width,
          box.y + box.height == raster.y + raster.height};
}

// The chords a cut building's wall direction is read off (wall_direction), in metres: long enough
// to average a wobble of a few metres' wavelength out (2 m chords tilted the sweep by several
// degrees under half a metre of it; 16 m, the chain's lattice.chord_m, fit small pieces less).
constexpr double kWallChordM = 8.0;

// The main wall direction of a ring traced in its box's pixel corners (radians, modulo a quarter
// turn): the peak of the length-weighted histogram, in degrees, of the directions of chords of
// chord_px about each edge, leaving out the chords that reach a vertex on a cut side (the raster's
// edge, not a wall), refined by their mean within 5 degrees of it. 0 where no chord is left.
double wall_direction(const Ring& ring, const cv::Size& box, const CutSides& cut, double chord_px) {
  const std::size_t n = ring.size();
  if (n < 4) return 0.0;
  std::vector<double> position(n + 1, 0.0);  // arc length at each vertex
  std::vector<int> on_edge(3 * n + 1, 0);    // vertices on a cut side before each index, three times round
  for (std::size_t i = 0; i < n; ++i) position[i + 1] = position[i] + (ring[(i + 1) % n] - ring[i]).norm();
  for (std::size_t i = 0; i < 3 * n; ++i) {
    const Vec2& v = ring[i % n];
    const bool edge = (cut.left && v.x() <= 0) || (cut.top && v.y() <= 0) || (cut.right && v.x() >= box.width) ||
                      (cut.bottom && v.y() >= box.height);
    on_edge[i + 1] = on_edge[i] + (edge ? 1 : 0);
  }
  const double perimeter = position[n], half = 0.5 * std::min(chord_px, 0.25 * perimeter);
  // The point at arc length s (any, taken modulo the perimeter) and the index of the vertex after it, unwrapped.
  const auto at = [&](double s, std::size_t* after) {
    const double turns = std::floor(s / perimeter), r = s - turns * perimeter;
    std::size_t i = std::size_t(std::upper_bound(position.begin(), position.end(), r) - position.begin());
    i = std::min(std::max<std::size_t>(i, 1), n);
    const double t = (r - position[i - 1]) / std::max(position[i] - position[i - 1], 1e-12);
    *after = i + std::size_t(std::max(0.0, turns + 1)) * n;  // (shifted by a turn: indices stay positive, below 3n)
    return Vec2(ring[i - 1] + t * (ring[i % n] - ring[i - 1]));
  };
  std::vector<double> histogram(90, 0.0);
  std::vector<std::pair<double, double>> chords;  // direction (radians, modulo a quarter turn), weight
  for (std::size_t i = 0; i < n; ++i) {
    const double mid = 0.5 * (position[i] + position[i + 1]);
    std::size_t a = 0, b = 0;
    const Vec2 pa = at(mid - half, &a), pb = at(mid + half, &b);
    if (b < a || b - a >= n || b > 3 * n || on_edge[b] - on_edge[a] > 0) continue;
    const Vec2 d = pb - pa;
    if (d.squaredNorm() <= 0) continue;
    double angle = std::fmod(std::atan2(d.y(), d.x()), M_PI / 2);
    if (angle < 0) angle += M_PI / 2;
    const double w = position[i + 1] - position[i];
    histogram[std::size_t(std::min(89.0, std::floor(angle * 180 / M_PI)))] += w;
    chords.emplace_back(angle, w);
  }
  if (chords.empty()) return 0.0;
  int peak = 0;
  double best = -1;
  for (int k = 0; k < 90; ++k) {
    double sum = 0;
    for (int j = -3; j <= 3; ++j) sum += histogram[std::size_t((k + j + 90) % 90)];
    if (sum > best) best = sum, peak = k;
  }
  const double centre = (peak + 0.5) * M_PI / 180;
  double c = 0, s = 0;
  for (const auto& [angle, w] : chords) {
    const double gap = std::remainder(angle - centre, M_PI / 2);
    if (std::abs(gap) > 5 * M_PI / 180) continue;
    c += w * std::cos(4 * angle), s += w * std::sin(4 * angle);
  }
  return c == 0 && s == 0 ? centre : std::atan2(s, c) / 4;
}

// The component (0/1, its box) swept out across each cut side by band_px, along the one of its
// wall direction's four axes nearest that side's outward normal: the walls along that axis go
// on straight past the raster's edge, the others turn onto it there. Returns the image, with
// band_px (rounded up) more on every side and one of padding beyond that.
cv::Mat swept_across_cut(const cv::Mat& component, const CutSides& cut, double direction, int band, int connectivity) {
  const int w = component.cols, h = component.rows, o = band + 1;
  cv::Mat out = cv::Mat::zeros(h + 2 * o, w + 2 * o, CV_8U);
  component.copyTo(out(cv::Rect(o, o, w, h)));
  // The axis nearest a side's outward normal: how far it moves along the side (the way j, the
  // pixel's index along it, grows) a pixel across it (at most one: it is within 45 degrees).
  const auto slope = [&](const Vec2& normal, const Vec2& along_j) {
    double best = -2, along = 0;
    for (int k = 0; k < 4; ++k) {
      const Vec2 axis(std::cos(direction + k * M_PI / 2), std::sin(direction + k * M_PI / 2));
      const double across = axis.dot(normal);
      if (across > best) best = across, along = axis.dot(along_j) / std::max(across, 1e-9);
    }
    return along;
  };
  const auto put = [&](int x, int y) {
    if (x >= 0 && y >= 0 && x < out.cols && y < out.rows) out.at<uint8_t>(y, x) = 1;
  };
  const auto pixel = [&](int x, int y) { return x >= 0 && y >= 0 && x < w && y < h && component.at<uint8_t>(y, x) != 0; };
  // A side's pixels, j along it and i inward from it, swept out by k along the axis: what is swept
  // at j is what the axis's line through j crosses over the band inside, by the majority of its
  // pixels (a wall along the axis goes on at its line over the band, not at where its wobble
  // crosses the edge).
  const auto sweep = [&](bool on, const Vec2& normal, const Vec2& along_j, auto&& inside, auto&& target) {
    if (!on) return;
    const double s = slope(normal, along_j);
    const int length = normal.x() != 0 ? h : w, depth = std::min(band, normal.x() != 0 ? w : h);
    // Not where the building is less than half as wide at the edge as a band inside: it ends
    // there (a corner, or an end wall its wobble pushes across the edge), it does not go on.
    int at_edge = 0, at_depth = 0, first = length, last = -1;
    for (int j = 0; j < length; ++j) {
      if (inside(0, j)) ++at_edge, first = std::min(first, j), last = j;
      at_depth += inside(depth - 1, j) ? 1 : 0;
    }
    if (2 * at_edge < at_depth) return;
    // (Between its first and last pixels on the edge: past them, a wall across the axis meets the
    // edge, and the band's majority would carry it on beyond where it does.)
    for (int j = first; j <= last; ++j) {
      int set = 0;
      for (int i = 0; i < depth; ++i) set += inside(i, j - int(std::lround(s * i))) ? 1 : 0;
      if (2 * set < depth) continue;
      for (int k = 1; k <= band; ++k) target(k, j + int(std::lround(s * k)));
    }
  };
  sweep(cut.left, Vec2(-1, 0), Vec2(0, 1), [&](int i, int j) { return pixel(i, j); }, [&](int k, int j) { put(o - k, o + j); });
  sweep(cut.right, Vec2(1, 0), Vec2(0, 1), [&](int i, int j) { return pixel(w - 1 - i, j); },
        [&](int k, int j) { put(o + w - 1 + k, o + j); });
  sweep(cut.top, Vec2(0, -1), Vec2(1, 0), [&](int i, int j) { return pixel(j, i); }, [&](int k, int j) { put(o + j, o - k); });
  sweep(cut.bottom, Vec2(0, 1), Vec2(1, 0), [&](int i, int j) { return pixel(j, h - 1 - i); },
        [&](int k, int j) { put(o + j, o + h - 1 + k); });
  // The swept pixels that do not join the component (a band's majority across the edge where
  // the edge's own pixels are not the building's) are left out, and of the holes the sweep closed
  // (a shallow bay's mouth) the part outside the raster is filled: the bay inside stays a hole,
  // which the clip opens again, and the sweep adds no pixel inside the raster.
  cv::Mat labels;
  cv::connectedComponents(out, labels, connectivity, CV_32S);
  cv::Point any;
  for (int y = 0; y < h && any == cv::Point(); ++y)
    for (int x = 0; x < w; ++x)
      if (component.at<uint8_t>(y, x)) { any = cv::Point(o + x, o + y); break; }
  cv::Mat kept = labels == labels.at<int>(any);
  kept &= 1;
  const auto holes = [](const cv::Mat& m) {  // (a zero border round m: the background is what a flood from a corner reaches)
    cv::Mat flooded = m.clone();
    cv::floodFill(flooded, cv::Point(0, 0), cv::Scalar(2), nullptr, 0, 0, 4);
    return cv::Mat(flooded == 0);
  };
  cv::Mat before = cv::Mat::zeros(out.size(), CV_8U);
  component.copyTo(before(cv::Rect(o, o, w, h)));
  cv::Mat outside = cv::Mat::ones(out.size(), CV_8U) * 255;
  outside(cv::Rect(o, o, w, h)).setTo(0);
  kept.setTo(1, holes(kept) & ~holes(before) & outside);
  return kept;
}

}  // namespace

ContourResult extract_contours(const cv::Mat& mask, const GeoTransform& transform,
                               const ContourOptions& options, const ComponentFilter& keep, const std::optional<cv::Rect>& raster) {
  return extract_contours(label_components(mask, options.connectivity), transform, options, keep, raster);
}

ContourResult extract_contours(const Components& components, const GeoTransform& transform,
                               const ContourOptions& options, const ComponentFilter& keep, const std::optional<cv::Rect>& raster) {
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
    cv::Point origin = b.bbox.tl();                  // of the traced image's first pixel, past its padding
    const CutSides cut = raster && options.edge_sweep_m > 0 ? cut_sides(b.bbox, *raster) : CutSides{};
    if (cut.any()) {
      // Cut by the raster's edge: swept out across it along its own walls (swept_across_cut).
      const double px = transform.pixel_size();
      const cv::Mat pixels = component(cv::Rect(1, 1, b.bbox.width, b.bbox.height)).clone();  // (tracing alters its image)
      const std::vector<Ring> rings = trace_padded(component);
      const double direction = rings.empty() ? 0.0 : wall_direction(rings[0], b.bbox.size(), cut, std::max(6.0, kWallChordM / px));
      const int band = std::max(4, int(std::ceil(options.edge_sweep_m / px)));
      component = swept_across_cut(pixels, cut, direction, band, options.connectivity);
      origin -= cv::Point(band, band);
      for (const cv::Point& c : {raster->tl(), cv::Point(raster->x, raster->y + raster->height), raster->br(),
                                 cv::Point(raster->x + raster->width, raster->y)})
        b.cut.push_back(transform.to_map(c.x, c.y));
      if (orientation > 0) std::reverse(b.cut.begin(), b.cut.end());
    }
    for (Ring& ring : trace_padded(component)) {
      for (Vec2& p : ring) p = transform.to_map(p.x() + origin.x, p.y() + origin.y);
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
