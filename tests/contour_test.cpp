#include <gtest/gtest.h>

#include <map>
#include <opencv2/imgproc.hpp>
#include <random>

#include "contour/contour.hpp"
#include "geometry/polygon.hpp"

namespace lodforge {
namespace {

cv::Mat mask_from(const std::vector<std::string>& rows) {
  cv::Mat m = cv::Mat::zeros(int(rows.size()), int(rows[0].size()), CV_8U);
  for (int r = 0; r < m.rows; ++r)
    for (int c = 0; c < m.cols; ++c) m.at<uint8_t>(r, c) = rows[r][c] == '#';
  return m;
}

ContourOptions no_minimum(int connectivity = 8) {
  ContourOptions o;
  o.connectivity = connectivity;
  o.min_area_m2 = 0;
  o.min_hole_area_m2 = 0;
  o.min_pixels = 0;
  return o;
}

GeoTransform transform(double x0 = 100, double y0 = 200, double pixel = 0.5) {
  GeoTransform t;
  t.c = {x0, pixel, 0, y0, 0, -pixel};
  return t;
}

TEST(Contour, SinglePixelIsOneCounterClockwiseSquareInMapCoordinates) {
  const auto result = extract_contours(mask_from({"...", ".#.", "..."}), transform(), no_minimum());
  ASSERT_EQ(result.buildings.size(), 1u);
  const Ring& ring = result.buildings[0].rings[0];
  ASSERT_EQ(ring.size(), 4u);
  EXPECT_DOUBLE_EQ(signed_area(ring), 0.25);
  for (const Vec2& p : ring) {
    EXPECT_TRUE(p.x() == 100.5 || p.x() == 101.0) << p.transpose();
    EXPECT_TRUE(p.y() == 199.5 || p.y() == 199.0) << p.transpose();
  }
}

TEST(Contour, CourtyardBecomesClockwiseHole) {
  const auto result = extract_contours(mask_from({"#####", "#...#", "#...#", "#####"}), transform(0, 0, 1), no_minimum());
  ASSERT_EQ(result.buildings.size(), 1u);
  const auto& rings = result.buildings[0].rings;
  ASSERT_EQ(rings.size(), 2u);
  EXPECT_DOUBLE_EQ(signed_area(rings[0]), 20.0);
  EXPECT_DOUBLE_EQ(signed_area(rings[1]), -6.0);
  EXPECT_EQ(polygon_problem({rings[0], {rings[1]}}), "");
}

TEST(Contour, SmallHolesAreFilledAndSmallComponentsDropped) {
  ContourOptions o = no_minimum(4);
  o.min_hole_area_m2 = 7;
  o.min_area_m2 = 2;
  const auto result = extract_contours(mask_from({"#####.", "#...#.", "#...#.", "#####.", ".....#"}), transform(0, 0, 1), o);
  ASSERT_EQ(result.buildings.size(), 1u);
  EXPECT_EQ(result.buildings[0].rings.size(), 1u);
  EXPECT_EQ(result.dropped_small, 1);
}

// At 2 m a pixel is 4 m^2, as large as the area filters: a lone pixel, a component or a hole,
// is dropped or filled by min_pixels; two pixels stay.
TEST(Contour, ALonePixelIsNoBuildingAndNoCourtyardAtCoarsePixels) {
  ContourOptions o;  // min_area_m2 = min_hole_area_m2 = 4, min_pixels = 2
  const cv::Mat m = mask_from({"#######..#.", "#.#####....", "#######..##", "#...###....", "#######...."});
  const auto result = extract_contours(m, transform(0, 0, 2), o);
  ASSERT_EQ(result.buildings.size(), 2u);        // the block and the pair; the lone pixel dropped
  EXPECT_EQ(result.dropped_small, 1);
  EXPECT_EQ(result.buildings[0].rings.size(), 2u);  // the 3-pixel courtyard stays, the 1-pixel one is filled
  EXPECT_NEAR(std::abs(signed_area(result.buildings[0].rings[1])), 3 * 4.0, 1e-9);
  o.min_pixels = 0;
  const auto all = extract_contours(m, transform(0, 0, 2), o);
  EXPECT_EQ(all.buildings.size(), 3u);
  EXPECT_EQ(all.buildings[0].rings.size(), 3u);
}

TEST(Contour, DiagonalContactsGiveSimpleRings) {
  const cv::Mat m = mask_from({"#..#", ".##.", ".##.", "#..#"});
  const auto eight = extract_contours(m, transform(), no_minimum(8));
  ASSERT_EQ(eight.buildings.size(), 1u);
  for (const Ring& r : eight.buildings[0].rings) EXPECT_EQ(ring_problem(r), "");
  EXPECT_EQ(extract_contours(m, transform(), no_minimum(4)).buildings.size(), 5u);
  // A ring that would touch itself: a U whose tips meet diagonally.
  const auto touch = extract_contours(mask_from({"###.", "#..#", "####"}), transform(), no_minimum(8));
  ASSERT_EQ(touch.buildings.size(), 1u);
  PolygonWithHoles p{touch.buildings[0].rings[0], {}};
  for (std::size_t i = 1; i < touch.buildings[0].rings.size(); ++i) p.holes.push_back(touch.buildings[0].rings[i]);
  EXPECT_EQ(polygon_problem(p), "");
}

TEST(Contour, CheckerboardStaysValid) {
  cv::Mat m = cv::Mat::zeros(12, 12, CV_8U);
  for (int r = 1; r < 11; ++r)
    for (int c = 1; c < 11; ++c) m.at<uint8_t>(r, c) = (r + c) % 2;
  const auto result = extract_contours(m, transform(), no_minimum(8));
  ASSERT_EQ(result.buildings.size(), 1u);
  PolygonWithHoles p{result.buildings[0].rings[0], {}};
  for (std::size_t i = 1; i < result.buildings[0].rings.size(); ++i) p.holes.push_back(result.buildings[0].rings[i]);
  EXPECT_EQ(polygon_problem(p), "");
}

TEST(Contour, BuildingsAreOrderedByFirstPixelInRasterOrder) {
  const auto result = extract_contours(mask_from({"....##", "##..##", "##....", "....#."}), transform(), no_minimum(4));
  ASSERT_EQ(result.buildings.size(), 3u);
  EXPECT_EQ(result.buildings[0].first_row, 0);
  EXPECT_EQ(result.buildings[0].first_col, 4);
  EXPECT_EQ(result.buildings[1].first_row, 1);
  EXPECT_EQ(result.buildings[1].first_col, 0);
  EXPECT_EQ(result.buildings[2].first_row, 3);
  EXPECT_EQ(result.buildings[2].pixel_count, 1);
}

TEST(Contour, AnyNonZeroValueIsBuildingAndTheFirstPixelIsTheLeftmostOfTheTopRow) {
  // A component whose top row starts right of where lower rows start, in a 0/255 mask.
  const std::vector<std::string> rows = {".....", "...##", ".####", "##..."};
  const cv::Mat ones = mask_from(rows);
  const cv::Mat full = ones * 255;
  const auto a = extract_contours(ones, transform(), no_minimum()), b = extract_contours(full, transform(), no_minimum());
  ASSERT_EQ(a.buildings.size(), 1u);
  ASSERT_EQ(b.buildings.size(), 1u);
  EXPECT_EQ(a.buildings[0].rings, b.buildings[0].rings);
  EXPECT_EQ(b.buildings[0].first_row, 1);
  EXPECT_EQ(b.buildings[0].first_col, 3);
  EXPECT_EQ(b.buildings[0].pixel_count, 8);
}


// Random masks of blobs and speckles (a segmentation's), some touching only at a corner.
cv::Mat random_mask(std::mt19937& rng, int rows, int cols, double density, int max_size = 6) {
  cv::Mat m = cv::Mat::zeros(rows, cols, CV_8U);
  std::uniform_int_distribution<int> x(0, cols - 1), y(0, rows - 1), size(1, max_size);
  const int blobs = int(density * rows * cols / 9);
  for (int i = 0; i < blobs; ++i) {
    const cv::Rect r(x(rng), y(rng), size(rng), size(rng));
    m(r & cv::Rect(0, 0, cols, rows)).setTo(i % 7 == 0 ? 0 : 200);  // some bites out of earlier blobs
  }
  return m;
}

TEST(Contour, TheComponentsAreOpenCvsComponentsAsRuns) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 40; ++trial) {
    const int connectivity = trial % 2 ? 4 : 8;
    const cv::Mat mask = random_mask(rng, 20 + trial, 31 + 2 * trial, 0.1 + 0.02 * (trial % 10));
    const Components c = label_components(mask, connectivity);
    cv::Mat labels, stats, centroids;
    const int count = cv::connectedComponentsWithStats(mask, labels, stats, centroids, connectivity, CV_32S);
    ASSERT_EQ(c.count, count) << "trial " << trial;
    // The same partition of the pixels (labels may be numbered otherwise), and per component
    // its box and pixel count.
    std::map<int, int> ours_of;
    for (int yy = 0; yy < mask.rows; ++yy)
      for (int xx = 0; xx < mask.cols; ++xx) {
        const int theirs = labels.at<int>(yy, xx), ours = c.label_at({xx, yy});
        ASSERT_EQ(theirs == 0, ours == 0) << "trial " << trial << " pixel " << xx << ", " << yy;
        if (theirs == 0) continue;
        const auto [it, added] = ours_of.try_emplace(theirs, ours);
        ASSERT_EQ(it->second, ours) << "trial " << trial << " pixel " << xx << ", " << yy;
        if (added) {
          // Its first pixel in raster order is the component's first.
          EXPECT_EQ(c.firsts[std::size_t(ours)], cv::Point(xx, yy));
          EXPECT_EQ(c.areas[std::size_t(ours)], stats.at<int>(theirs, cv::CC_STAT_AREA));
          EXPECT_EQ(component_box(c, ours), cv::Rect(stats.at<int>(theirs, cv::CC_STAT_LEFT), stats.at<int>(theirs, cv::CC_STAT_TOP),
                                                     stats.at<int>(theirs, cv::CC_STAT_WIDTH), stats.at<int>(theirs, cv::CC_STAT_HEIGHT)));
        }
      }
    ASSERT_EQ(int(ours_of.size()), count - 1);
    // Numbered by first pixel in raster order.
    for (int k = 2; k < c.count; ++k)
      EXPECT_LT(std::make_pair(c.firsts[std::size_t(k - 1)].y, c.firsts[std::size_t(k - 1)].x),
                std::make_pair(c.firsts[std::size_t(k)].y, c.firsts[std::size_t(k)].x));
  }
}

bool inside(const std::vector<Ring>& rings, const Vec2& p) {  // even-odd
  bool in = false;
  for (const Ring& r : rings)
    for (std::size_t i = 0, j = r.size() - 1; i < r.size(); j = i++)
      if ((r[i].y() > p.y()) != (r[j].y() > p.y()) &&
          p.x() < (r[j].x() - r[i].x()) * (p.y() - r[i].y()) / (r[j].y() - r[i].y()) + r[i].x())
        in = !in;
  return in;
}

// Every pixel of m lies inside the rings (even-odd); every other pixel inside is a fill between
// two pixels inside that touch at a corner, and no two pixels inside touch at a corner alone.
// Returns the number of fills.
long check_rings_cover(const cv::Mat& m, const std::vector<Ring>& rings, const std::string& what) {
  cv::Mat in = cv::Mat::zeros(m.size(), CV_8U);
  for (int yy = 0; yy < m.rows; ++yy)
    for (int xx = 0; xx < m.cols; ++xx) in.at<uint8_t>(yy, xx) = inside(rings, Vec2(xx + 0.5, yy + 0.5));
  auto at = [&in](int x, int y) { return x >= 0 && y >= 0 && x < in.cols && y < in.rows && in.at<uint8_t>(y, x); };
  long filled = 0;
  for (int yy = 0; yy < m.rows; ++yy)
    for (int xx = 0; xx < m.cols; ++xx) {
      if (m.at<uint8_t>(yy, xx)) {
        EXPECT_TRUE(at(xx, yy)) << what << " pixel " << xx << ", " << yy;
        continue;
      }
      if (at(xx, yy)) {
        ++filled;
        bool between = false;
        for (int dy : {-1, 1})
          for (int dx : {-1, 1}) between |= at(xx + dx, yy) && at(xx, yy + dy);
        EXPECT_TRUE(between) << what << " pixel " << xx << ", " << yy;
      }
    }
  for (int yy = -1; yy < m.rows; ++yy)
    for (int xx = -1; xx < m.cols; ++xx) {
      const bool a = at(xx, yy), b = at(xx + 1, yy), c = at(xx, yy + 1), d = at(xx + 1, yy + 1);
      EXPECT_FALSE((a && d && !b && !c) || (b && c && !a && !d)) << what << " diagonal block at " << xx << ", " << yy;
    }
  return filled;
}

// The tracing as it was before session 19, kept as the reference the faster one must equal ring
// for ring, vertex for vertex: diagonal contacts filled pass by pass over every pixel, every
// boundary edge listed and sorted by its first corner, rings followed from the first unused edge.
std::vector<Ring> reference_trace(cv::Mat m) {
  cv::copyMakeBorder(m, m, 1, 1, 1, 1, cv::BORDER_CONSTANT, 0);
  for (bool changed = true; changed;) {
    changed = false;
    for (int y = 0; y + 1 < m.rows; ++y)
      for (int x = 0; x + 1 < m.cols; ++x) {
        uint8_t *r0 = m.ptr<uint8_t>(y), *r1 = m.ptr<uint8_t>(y + 1);
        const bool a = r0[x], b = r0[x + 1], c = r1[x], d = r1[x + 1];
        if (a && d && !b && !c) { r0[x + 1] = 1; changed = true; }
        else if (b && c && !a && !d) { r0[x] = 1; changed = true; }
      }
  }
  const int64_t stride = m.cols + 1;
  auto id = [stride](int64_t x, int64_t y) { return y * stride + x; };
  std::vector<std::pair<int64_t, int64_t>> edges;  // (from, to)
  for (int y = 1; y + 1 < m.rows; ++y)
    for (int x = 1; x + 1 < m.cols; ++x) {
      if (!m.at<uint8_t>(y, x)) continue;
      if (!m.at<uint8_t>(y - 1, x)) edges.push_back({id(x + 1, y), id(x, y)});
      if (!m.at<uint8_t>(y + 1, x)) edges.push_back({id(x, y + 1), id(x + 1, y + 1)});
      if (!m.at<uint8_t>(y, x + 1)) edges.push_back({id(x + 1, y + 1), id(x + 1, y)});
      if (!m.at<uint8_t>(y, x - 1)) edges.push_back({id(x, y), id(x, y + 1)});
    }
  std::sort(edges.begin(), edges.end());
  std::vector<char> used(edges.size(), 0);
  std::vector<Ring> rings;
  for (std::size_t start = 0; start < edges.size(); ++start) {
    if (used[start]) continue;
    Ring ring;
    for (std::size_t e = start; !used[e];) {
      used[e] = 1;
      ring.emplace_back(double(edges[e].first % stride) - 1.0, double(edges[e].first / stride) - 1.0);
      e = std::size_t(std::lower_bound(edges.begin(), edges.end(), std::make_pair(edges[e].second, int64_t(-1))) - edges.begin());
    }
    rings.push_back(std::move(ring));
  }
  std::stable_sort(rings.begin(), rings.end(), [](const Ring& a, const Ring& b) { return std::abs(signed_area(a)) > std::abs(signed_area(b)); });
  return rings;
}

// ... and the rings are those of the reference above, in the same order, from the same corners.
TEST(Contour, TracedRingsHoldTheirComponentsPixelsAndOnlyDiagonalFills) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 60; ++trial) {
    // Blobs, and lone pixels that touch at corners anywhere along the rows.
    const cv::Mat mask = trial % 2 ? random_mask(rng, 18 + trial, 25 + trial, 0.15 + 0.02 * (trial % 8))
                                   : random_mask(rng, 12 + trial / 4, 40 + trial, 1.5, 1);
    const Components c = label_components(mask, 8);
    for (int k = 1; k < c.count; ++k) {
      const cv::Mat m = c.mask_of(k, 0);
      const std::vector<Ring> rings = trace_component(m);
      ASSERT_FALSE(rings.empty());
      ASSERT_EQ(rings, reference_trace(m)) << "trial " << trial << " component " << k;
      double area = 0;
      for (const Ring& r : rings) {
        area += signed_area(r);
        for (std::size_t i = 0; i < r.size(); ++i) ASSERT_DOUBLE_EQ((r[(i + 1) % r.size()] - r[i]).norm(), 1.0);  // pixel sides
      }
      // In pixel coordinates (y down) the outer ring turns clockwise: negative area.
      EXPECT_LT(signed_area(rings[0]), 0);
      const long filled = check_rings_cover(m, rings, "trial " + std::to_string(trial) + " component " + std::to_string(k));
      EXPECT_DOUBLE_EQ(-area, double(c.areas[std::size_t(k)] + filled));
    }
    // The whole mask at once: every component's rings.
    cv::Mat ones;
    mask.convertTo(ones, CV_8U, 1.0 / 200);
    const std::vector<Ring> all = trace_component(ones);
    ASSERT_EQ(all, reference_trace(ones)) << "trial " << trial << " whole mask";
    check_rings_cover(ones, all, "trial " + std::to_string(trial) + " whole mask");
  }
}

// A rectangle at 30 degrees on a canvas of 0.5 m pixels, and the raster: the canvas but 40
// pixels on one side (left, right, top or bottom), whose edge there cuts the rectangle.
struct CutRectangle {
  cv::Mat canvas = cv::Mat::zeros(240, 240, CV_8U);
  cv::Rect raster_in_canvas;
  cv::Mat raster;
  CutRectangle(cv::Point2f centre, cv::Size2f size, char side = 'l') {
    cv::Point2f corners[4];
    cv::RotatedRect(centre, size, 30).points(corners);
    std::vector<cv::Point> polygon;
    for (const cv::Point2f& c : corners) polygon.emplace_back(int(std::lround(c.x)), int(std::lround(c.y)));
    cv::fillConvexPoly(canvas, polygon, cv::Scalar(1));
    raster_in_canvas = side == 'l' ? cv::Rect(40, 0, 200, 240) : side == 'r' ? cv::Rect(0, 0, 200, 240)
                     : side == 't' ? cv::Rect(0, 40, 240, 200) : cv::Rect(0, 0, 240, 200);
    raster = canvas(raster_in_canvas).clone();
  }
};

TEST(Contour, ABuildingTheRastersEdgeCutsIsTracedGoingOnAlongItsWalls) {
  // The rectangle 60 pixels from the cut side's edge of the canvas, cut 20 pixels into it.
  for (const char side : {'l', 'r', 't', 'b'}) {
    const cv::Point2f centre = side == 'l' ? cv::Point2f(70, 120) : side == 'r' ? cv::Point2f(170, 120)
                             : side == 't' ? cv::Point2f(120, 70) : cv::Point2f(120, 170);
    const CutRectangle r(centre, side == 'l' || side == 'r' ? cv::Size2f(170, 50) : cv::Size2f(50, 170), side);
    SCOPED_TRACE(std::string("cut side ") + side);
    const ContourOptions o = no_minimum();
    const GeoTransform t = transform(100, 200, 0.5);
    // Not told where the raster's edge is: traced as it is, cut.
    const auto plain = extract_contours(r.raster, t, o);
    ASSERT_EQ(plain.buildings.size(), 1u);
    EXPECT_TRUE(plain.buildings[0].cut.empty());
    // Told: swept out 4 m (8 pixels) across the edge, and the raster's extent kept to clip to
    // (counter-clockwise, as the noise's measure inside it needs).
    const auto swept = extract_contours(r.raster, t, o, {}, cv::Rect(0, 0, r.raster.cols, r.raster.rows));
    ASSERT_EQ(swept.buildings.size(), 1u);
    const BuildingContour& b = swept.buildings[0];
    ASSERT_EQ(b.cut.size(), 4u);
    EXPECT_DOUBLE_EQ(signed_area(b.cut), 0.25 * r.raster.cols * r.raster.rows);
    EXPECT_EQ(b.bbox, plain.buildings[0].bbox);
    EXPECT_EQ(b.pixel_count, plain.buildings[0].pixel_count);
    // Beyond the edge, the swept ring covers what the rectangle itself covers there: its walls go on.
    cv::Mat drawn = cv::Mat::zeros(r.canvas.size(), CV_8U);
    std::vector<cv::Point> pixels;
    for (const Vec2& p : b.rings[0])
      pixels.emplace_back(int(std::lround((p.x() - 100) / 0.5)) + r.raster_in_canvas.x, int(std::lround((200 - p.y()) / 0.5)) + r.raster_in_canvas.y);
    cv::fillPoly(drawn, std::vector<std::vector<cv::Point>>{pixels}, cv::Scalar(1));
    const cv::Rect band = side == 'l' ? cv::Rect(32, 0, 8, 240) : side == 'r' ? cv::Rect(200, 0, 8, 240)
                        : side == 't' ? cv::Rect(0, 32, 240, 8) : cv::Rect(0, 200, 240, 8);
    const double both = cv::countNonZero(drawn(band) & r.canvas(band)), either = cv::countNonZero(drawn(band) | r.canvas(band));
    ASSERT_GT(either, 200);
    EXPECT_GT(both / either, 0.9) << "the sweep beyond the edge is not the rectangle going on";
    // (The ring drawn on its pixel corners covers a pixel more on the right and bottom: a band one wider.)
    const cv::Rect reach = (band + cv::Size(2, 2) - cv::Point(1, 1)) & cv::Rect(0, 0, 240, 240);
    drawn(r.raster_in_canvas).setTo(0);
    drawn(reach).setTo(0);
    EXPECT_EQ(cv::countNonZero(drawn), 0) << "swept farther than 4 m";
  }
}

TEST(Contour, ABuildingThatEndsAtTheRastersEdgeIsNotSwept) {
  // Its corner, pointing at the edge, crosses it by a metre: it is less than half as wide at the
  // edge as 4 m inside, so it ends there. Clipped to the raster (cut kept), not swept.
  const CutRectangle r(cv::Point2f(40 - 2 + 0.5f * (50 * 0.866f + 30 * 0.5f), 120), cv::Size2f(50, 30));
  const auto swept = extract_contours(r.raster, transform(100, 200, 0.5), no_minimum(), {}, cv::Rect(0, 0, r.raster.cols, r.raster.rows));
  ASSERT_EQ(swept.buildings.size(), 1u);
  EXPECT_EQ(swept.buildings[0].cut.size(), 4u);
  double min_x = 1e9;
  for (const Vec2& p : swept.buildings[0].rings[0]) min_x = std::min(min_x, p.x());
  EXPECT_DOUBLE_EQ(min_x, 100.0);
}

}  // namespace
}  // namespace lodforge
