#include "run/tiles.hpp"

#include <chrono>
#include <map>
#include <optional>
#include <cstdio>
#include <gdal_priv.h>
#include <opencv2/imgproc.hpp>

#include "geometry/polygon.hpp"
#include "geometry/rasterize.hpp"
#include "io/block_cache.hpp"
#include "io/cadastre.hpp"
#include "io/errors.hpp"

namespace lodforge {

TileGrid::TileGrid(cv::Size raster_size, int tile_side_px)
    : raster(raster_size), tile_px(std::max(1, tile_side_px)),
      cols((raster_size.width + tile_px - 1) / tile_px), rows((raster_size.height + tile_px - 1) / tile_px) {}

cv::Rect TileGrid::rect(int tile) const {
  const int c = tile % cols, r = tile / cols;
  return cv::Rect(c * tile_px, r * tile_px, tile_px, tile_px) & cv::Rect(0, 0, raster.width, raster.height);
}

std::string TileGrid::name(int tile) const {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "r%04d_c%04d", tile / cols, tile % cols);  // sorts in tile order
  return buffer;
}

struct MaskWindowReader::Impl {
  GDALDataset* dataset = nullptr;
  BuildingSelector selector;
  std::string path;
  BlockCache* cache = nullptr;
  bool byte_values = true;  // every selected value fits a byte: a byte band is read and compared as bytes
  bool as_double = false;   // a threshold, or a floating-point band's values: read as 64-bit floats
  std::optional<double> nodata;  // the band's, never a building by a threshold
};

MaskWindowReader::MaskWindowReader(const std::string& path, const BuildingSelector& selector, BlockCache* cache) : impl_(new Impl) {
  impl_->selector = selector;
  impl_->cache = cache;
  const auto fits = [](int v) { return v >= 0 && v <= 255; };
  if (selector.rgb) for (int v : *selector.rgb) impl_->byte_values &= fits(v);
  for (int v : selector.values) impl_->byte_values &= fits(v);
  impl_->path = path;
  impl_->dataset = static_cast<GDALDataset*>(GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
  if (!impl_->dataset) {
    delete impl_;
    throw InputError("'" + path + "': not a raster GDAL can read");
  }
  if (selector.rgb && impl_->dataset->GetRasterCount() < 3) {
    GDALClose(impl_->dataset);
    delete impl_;
    throw InputError("'" + path + "': a building colour needs an RGB raster with 3 bands");
  }
  if (!selector.rgb && impl_->dataset->GetRasterCount() > 1) {
    const int bands = impl_->dataset->GetRasterCount();
    GDALClose(impl_->dataset);
    delete impl_;
    throw InputError("'" + path + "': has " + std::to_string(bands) + " bands; building values are read from a one-band class raster " +
                     "(for an RGB label raster give inputs.segmentation.building_rgb, e.g. [0, 0, 255])");
  }
  if (!selector.rgb) {
    impl_->as_double = selector.min || floating_band(*impl_->dataset, 1);
    impl_->nodata = band_nodata(*impl_->dataset, 1);
  }
}

MaskWindowReader::~MaskWindowReader() {
  GDALClose(impl_->dataset);
  delete impl_;
}

cv::Mat MaskWindowReader::read(const cv::Rect& w) const {
  auto band = [&](int b) {
    // A byte band is compared as bytes (a quarter of the memory traffic); a threshold or a
    // floating-point band as 64-bit floats; anything else as Int32.
    const bool bytes = !impl_->as_double && impl_->byte_values && impl_->dataset->GetRasterBand(b)->GetRasterDataType() == GDT_Byte;
    const int depth = bytes ? CV_8U : impl_->as_double ? CV_64F : CV_32S;
    cv::Mat m(w.height, w.width, depth);
    read_window(impl_->cache, *impl_->dataset, impl_->path, b, bytes ? GDT_Byte : impl_->as_double ? GDT_Float64 : GDT_Int32, w, m.data);
    return m;
  };
  // The matches are 0 / 255, combined as such, and taken to 0 / 1 once (a bitwise and: dividing
  // by 255 went through a scaled conversion, half of a window's read).
  cv::Mat mask;
  if (impl_->selector.rgb) {
    for (int b = 0; b < 3; ++b) {
      cv::Mat match;
      cv::compare(band(b + 1), cv::Scalar((*impl_->selector.rgb)[b]), match, cv::CMP_EQ);
      if (b == 0) mask = match;
      else cv::bitwise_and(mask, match, mask);
    }
  } else {
    mask = building_pixels(band(1), impl_->selector, impl_->nodata);  // (as read_building_mask selects them)
  }
  cv::bitwise_and(mask, cv::Scalar(1), mask);
  return mask;
}

std::uint64_t fnv1a(const void* data, std::size_t size, std::uint64_t h) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; ++i) {
    h ^= bytes[i];
    h *= 1099511628211ULL;
  }
  return h;
}

std::uint64_t fnv1a(const std::string& text, std::uint64_t seed) { return fnv1a(text.data(), text.size(), seed); }

bool touches_inner_border(const cv::Rect& bbox, const cv::Rect& window, cv::Size raster) {
  return (bbox.x == 0 && window.x > 0) || (bbox.y == 0 && window.y > 0) ||
         (bbox.x + bbox.width == window.width && window.x + window.width < raster.width) ||
         (bbox.y + bbox.height == window.height && window.y + window.height < raster.height);
}

int first_window_margin(int halo_px, int tile_px, int max_window_px) {
  return std::max(halo_px, std::min(2 * halo_px, (max_window_px - tile_px) / 2));
}

namespace {

// The window grows around a building that touches its inner border by the halo, and by one
// pixel at least: with no halo, the building would never be read whole (and would be lost).
int growth_px(int halo_px) { return std::max(1, halo_px); }

// Marks the pixels the segment a-b (map coordinates) crosses.
void mark_segment(cv::Mat& mask, const GeoTransform& local, const Vec2& from, const Vec2& to) {
  const Vec2 a = local.to_pixel(from), b = local.to_pixel(to);
  const int steps = int(std::ceil((b - a).norm() * 2)) + 1;
  for (int s = 0; s <= steps; ++s) {
    const Vec2 q = a + (b - a) * (double(s) / steps);
    const int x = int(std::floor(q.x())), y = int(std::floor(q.y()));
    if (x >= 0 && y >= 0 && x < mask.cols && y < mask.rows) mask.at<uint8_t>(y, x) = 1;
  }
}

// Marks the pixels of a window that a footprint covers or its boundary crosses (so that every
// footprint on the window has a pixel, however small); returns one of them, or (-1, -1).
cv::Point mark_footprint(cv::Mat& window_mask, const cv::Rect& window, const CadastralFootprint& footprint, const GeoTransform& transform) {
  cv::Point seed(-1, -1);
  const cv::Rect box = footprint.pixels & window;  // (what it covers of the window)
  cv::Mat mask = window_mask(box - window.tl());
  const GeoTransform local = transform.window(box.x, box.y);
  cv::Mat scratch = cv::Mat::zeros(mask.size(), CV_8U);
  for (const PolygonWithHoles& p : footprint.parts) {
    rasterize(scratch, p, local, 1, 1);  // (holes included: they only join the block)
    for (const Ring* ring : rings_of(p))
      for (std::size_t i = 0; i < ring->size(); ++i) mark_segment(scratch, local, (*ring)[i], (*ring)[(i + 1) % ring->size()]);
  }
  // The parts of a multi-part footprint are joined, so that it lies in one block whatever the window.
  for (std::size_t k = 1; k < footprint.parts.size(); ++k) mark_segment(scratch, local, footprint.parts[0].outer[0], footprint.parts[k].outer[0]);
  for (int y = 0; y < scratch.rows && seed.x < 0; ++y)
    for (int x = 0; x < scratch.cols; ++x)
      if (scratch.at<uint8_t>(y, x)) { seed = {x + box.x - window.x, y + box.y - window.y}; break; }
  mask.setTo(1, scratch);
  return seed;
}

// Does the tile own block g of the window: its first pixel in the tile, and whole in the window?
bool owns_block(const TileWindow& w, int g, const cv::Rect& tile_rect, cv::Size raster) {
  return g > 0 && tile_rect.contains(w.groups.firsts[std::size_t(g)] + w.window.tl()) && !touches_inner_border(component_box(w.groups, g), w.window, raster);
}


}  // namespace

TileWindow find_tile_window(const MaskWindowReader& reader, const TileGrid& grid, int tile, int halo_px,
                            int max_window_px, int connectivity, const Cadastre* cadastre, const GeoTransform* transform) {
  const cv::Rect bounds(0, 0, grid.raster.width, grid.raster.height);
  const cv::Rect tile_rect = grid.rect(tile);
  TileWindow out;
  const int first_margin = first_window_margin(halo_px, grid.tile_px, max_window_px);
  out.window = (tile_rect + cv::Size(2 * first_margin, 2 * first_margin) - cv::Point(first_margin, first_margin)) & bounds;
  while (true) {
    out.mask = reader.read(out.window);
    const auto labeling = std::chrono::steady_clock::now();
    cv::Mat blocks = out.mask;
    if (cadastre) {
      // The window grows around blocks (mask and footprints together), not around the mask's components.
      blocks = out.mask.clone();
      out.footprint_seeds.clear();
      for (int f : cadastre->in_window(out.window)) {
        const cv::Point seed = mark_footprint(blocks, out.window, cadastre->footprints()[std::size_t(f)], *transform);
        if (seed.x >= 0) out.footprint_seeds.emplace_back(f, seed);
      }
    }
    out.components = label_components(blocks, cadastre ? 8 : connectivity);
    out.label_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - labeling).count();
    const int count = out.components.count;
    cv::Rect grown = out.window;
    out.too_large.clear();
    for (int k = 1; k < count; ++k) {
      const cv::Rect box = component_box(out.components, k);
      const cv::Rect global = box + out.window.tl();
      if ((global & tile_rect).empty() || !touches_inner_border(box, out.window, grid.raster)) continue;
      // Possibly owned by this tile and not whole: read around it, if that still fits.
      const int grow = growth_px(halo_px);
      const cv::Rect wanted = grown | ((global + cv::Size(2 * grow, 2 * grow) - cv::Point(grow, grow)) & bounds);
      if (wanted.width > max_window_px || wanted.height > max_window_px) {
        out.too_large.push_back("a building reaching at least from pixel (row " + std::to_string(global.y) + ", col " +
                                std::to_string(global.x) + ") to (row " + std::to_string(global.y + global.height) + ", col " +
                                std::to_string(global.x + global.width) + ") does not fit a window of " +
                                std::to_string(max_window_px) + " pixels (tiling.max_window_m) around tile " + grid.name(tile) +
                                "; it is not modeled");
        continue;
      }
      grown = wanted;
    }
    if (grown == out.window) break;
    out.window = grown;
  }
  const int rect[4] = {out.window.x, out.window.y, out.window.width, out.window.height};
  out.hash = fnv1a(out.mask.data, out.mask.total(), fnv1a(rect, sizeof rect));
  if (cadastre) {
    // The blocks own; the buildings in them are the mask's components.
    out.groups = std::move(out.components);
    const auto labeling = std::chrono::steady_clock::now();
    out.components = label_components(out.mask, connectivity);
    out.label_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - labeling).count();
    // The footprints in the window (their IDs and coordinates, in the cadastre's order, which
    // decides who gets an overlap) are what the tile's buildings depend on, not their places in the
    // whole cadastre: a footprint added or removed elsewhere leaves this tile's checkpoints.
    for (const auto& [f, seed] : out.footprint_seeds) {
      const std::uint64_t s[3] = {std::uint64_t(seed.x), std::uint64_t(seed.y), cadastre->footprints()[std::size_t(f)].hash};
      out.hash = fnv1a(s, sizeof s, out.hash);
    }
  }
  return out;
}

TileBuildings trace_tile(const TileWindow& w, const TileGrid& grid, int tile, const GeoTransform& transform,
                         const ContourOptions& options) {
  const cv::Rect tile_rect = grid.rect(tile);
  const cv::Rect window = w.window;
  const GeoTransform local = transform.window(window.x, window.y);
  const cv::Size raster = grid.raster;
  const ContourResult contours = extract_contours(
      w.components, local, options,
      [&](const cv::Rect& box, const cv::Point& first) {
        if (w.groups.count > 0) return owns_block(w, w.groups.label_at(first), tile_rect, raster);  // with a cadastre
        // Owned (first pixel in the tile) and whole (else it was reported as too large).
        return tile_rect.contains(first + window.tl()) && !touches_inner_border(box, window, raster);
      },
      cv::Rect(-window.tl(), raster));
  TileBuildings out;
  out.buildings = contours.buildings;
  for (BuildingContour& b : out.buildings) {
    b.first_row += window.y;
    b.first_col += window.x;
    b.bbox += window.tl();
  }
  out.dropped_small = contours.dropped_small;
  out.too_large = w.too_large;
  out.window = window;
  return out;
}

std::vector<TileGroup> tile_groups(const TileWindow& w, const TileGrid& grid, int tile, const TileBuildings& buildings,
                                   const Cadastre& cadastre, const GeoTransform& transform) {
  const cv::Rect tile_rect = grid.rect(tile);
  std::map<int, TileGroup> owned;  // by label
  auto group = [&](int g) -> TileGroup* {
    if (!owns_block(w, g, tile_rect, grid.raster)) return nullptr;
    auto [it, added] = owned.try_emplace(g);
    if (added) {
      const cv::Point first = w.groups.firsts[std::size_t(g)] + w.window.tl();
      it->second.id = std::int64_t(first.y) * grid.raster.width + first.x;
    }
    return &it->second;
  };
  for (std::size_t i = 0; i < buildings.buildings.size(); ++i) {
    const BuildingContour& b = buildings.buildings[i];
    if (TileGroup* t = group(w.groups.label_at({b.first_col - w.window.x, b.first_row - w.window.y}))) t->buildings.push_back(int(i));
  }
  const GeoTransform local = transform.window(w.window.x, w.window.y);
  for (const auto& [f, seed] : w.footprint_seeds) {
    TileGroup* t = group(w.groups.label_at(seed));
    if (!t) continue;
    // The share of the footprint's pixels (centres inside it) that is building in the mask.
    const CadastralFootprint& footprint = cadastre.footprints()[std::size_t(f)];
    const cv::Rect box = (footprint.pixels & w.window) - w.window.tl();  // (whole: its block is)
    cv::Mat inside = cv::Mat::zeros(box.size(), CV_8U);
    for (const PolygonWithHoles& p : footprint.parts) rasterize(inside, p, local.window(box.x, box.y), 1, 0);
    const int pixels = cv::countNonZero(inside);
    cv::Mat building;
    cv::bitwise_and(inside, w.mask(box), building);
    t->footprints.push_back(f);
    t->coverage.push_back(pixels > 0 ? double(cv::countNonZero(building)) / pixels : double(w.mask.at<uint8_t>(seed) != 0));
  }
  std::vector<TileGroup> out;
  for (auto& [g, t] : owned) out.push_back(std::move(t));
  std::sort(out.begin(), out.end(), [](const TileGroup& a, const TileGroup& b) { return a.id < b.id; });
  return out;  // (each block's footprints in the cadastre's order: the seeds are, as Cadastre::in_window gives them)
}

}  // namespace lodforge
