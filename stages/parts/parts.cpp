#include "parts/parts.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>

#include "geometry/polygon.hpp"
#include "geometry/rasterize.hpp"
#include "partition/partition.hpp"
#include "pipeline/building.hpp"

namespace lodforge {

namespace {

int find(std::vector<int>& parent, int a) {
  while (parent[std::size_t(a)] != a) a = parent[std::size_t(a)] = parent[std::size_t(parent[std::size_t(a)])];
  return a;
}

}  // namespace

std::vector<PolygonWithHoles> split_by_roof_steps(const PolygonWithHoles& footprint, const HeightRaster& window, double pixel_size,
                                                  const std::string& regularizer, const CoreOptions& core, const PartOptions& options) {
  if (!options.enabled || window.values.empty()) return {};
  // The cells of the footprint's box only (the window holds a ground ring around it too).
  const cv::Rect box = pixel_box(footprint, window.transform, 1, window.values.size());
  if (box.empty()) return {};
  const HeightRaster dsm{window.values(box), window.valid(box), window.transform.window(box.x, box.y)};
  const int rows = dsm.values.rows, cols = dsm.values.cols;
  cv::Mat inside = cv::Mat::zeros(rows, cols, CV_8U);
  rasterize(inside, footprint, dsm.transform);
  auto usable = [&](int y, int x) { return inside.at<uint8_t>(y, x) && dsm.valid.at<uint8_t>(y, x); };
  // Cells of one roof: neighbours whose heights differ less than a step.
  const double step = std::max(options.min_step_m, pixel_size * std::tan(options.max_slope_deg * M_PI / 180));
  std::vector<int> parent(std::size_t(rows) * cols);
  std::iota(parent.begin(), parent.end(), 0);
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols; ++x) {
      if (!usable(y, x)) continue;
      const float h = dsm.values.at<float>(y, x);
      if (x + 1 < cols && usable(y, x + 1) && std::abs(dsm.values.at<float>(y, x + 1) - h) < step)
        parent[std::size_t(find(parent, y * cols + x))] = find(parent, y * cols + x + 1);
      if (y + 1 < rows && usable(y + 1, x) && std::abs(dsm.values.at<float>(y + 1, x) - h) < step)
        parent[std::size_t(find(parent, y * cols + x))] = find(parent, (y + 1) * cols + x);
    }
  std::map<int, std::vector<int>> regions;  // root -> its cells (in raster order: deterministic)
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols; ++x)
      if (usable(y, x)) regions[find(parent, y * cols + x)].push_back(y * cols + x);
  if (regions.size() < 2) return {};
  std::vector<int> label(std::size_t(rows) * cols, -1);
  for (const auto& [root, cells] : regions)
    for (int c : cells) label[std::size_t(c)] = root;
  // Small regions join the neighbour they border longest, smallest first.
  const std::size_t min_cells = std::size_t(std::ceil(options.min_part_area_m2 / (pixel_size * pixel_size)));
  while (regions.size() > 1) {
    auto smallest = regions.end();
    for (auto it = regions.begin(); it != regions.end(); ++it)
      if (it->second.size() < min_cells && (smallest == regions.end() || it->second.size() < smallest->second.size())) smallest = it;
    if (smallest == regions.end()) break;
    std::map<int, int> border;
    for (int c : smallest->second) {
      const int y = c / cols, x = c % cols;
      for (const auto& [dy, dx] : {std::pair{0, 1}, std::pair{1, 0}, std::pair{0, -1}, std::pair{-1, 0}}) {
        const int ny = y + dy, nx = x + dx;
        if (ny < 0 || nx < 0 || ny >= rows || nx >= cols) continue;
        const int l = label[std::size_t(ny * cols + nx)];
        if (l >= 0 && l != smallest->first) ++border[l];
      }
    }
    std::vector<int> cells = std::move(smallest->second);
    regions.erase(smallest);
    if (border.empty()) {  // alone (a cell cut off by nodata): left to the parts around it
      for (int c : cells) label[std::size_t(c)] = -1;
      continue;
    }
    const int to = std::max_element(border.begin(), border.end(), [](const auto& a, const auto& b) { return a.second < b.second; })->first;
    for (int c : cells) label[std::size_t(c)] = to;
    std::vector<int>& target = regions[to];
    target.insert(target.end(), cells.begin(), cells.end());
  }
  if (regions.size() < 2) return {};
  // Each region's outline, regularized as the building's was, largest first.
  std::vector<std::pair<std::size_t, int>> order;
  for (const auto& [root, cells] : regions) order.push_back({cells.size(), root});
  std::sort(order.begin(), order.end(), [](const auto& a, const auto& b) { return a.first != b.first ? a.first > b.first : a.second < b.second; });
  ContourOptions contour;
  contour.connectivity = 4;
  contour.min_area_m2 = 0;
  contour.min_hole_area_m2 = options.min_part_area_m2;
  contour.min_pixels = 0;  // (the parts' own areas decide)
  std::vector<std::vector<PolygonWithHoles>> outlines;
  for (const auto& [size, root] : order) {
    cv::Mat mask = cv::Mat::zeros(rows, cols, CV_8U);
    for (int c : regions[root]) mask.at<uint8_t>(c / cols, c % cols) = 1;
    const ContourResult traced = extract_contours(mask, dsm.transform, contour);
    if (traced.buildings.empty()) return {};
    const auto largest = std::max_element(traced.buildings.begin(), traced.buildings.end(),
                                          [](const BuildingContour& a, const BuildingContour& b) { return a.pixel_count < b.pixel_count; });
    outlines.push_back({regularize_with(regularizer, largest->rings, pixel_size, core).footprint});
  }
  // Fitted to the footprint: its share of each part's cell, the rest to the part it borders longest.
  PartitionOptions fit;
  fit.extension_m = 2 * pixel_size;
  const Partition split = partition_outlines({footprint}, outlines, fit, 0.0, true);
  std::vector<PolygonWithHoles> parts;
  for (const FootprintShare& share : split.shares) {
    // (A part left in pieces, or smaller than a region may be: not a clean split.)
    if (share.polygon.outer.empty() || !share.note.empty() || area(share.polygon) < 0.5 * options.min_part_area_m2) return {};
    parts.push_back(share.polygon);
  }
  if (!split.rest.empty() || split.dropped_small > 0) return {};  // (a piece no part borders: the parts would not tile the footprint)
  return parts;
}

}  // namespace lodforge
