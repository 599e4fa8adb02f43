// Tiling: the raster is split into square tiles in raster order. A building belongs to exactly
// one tile, the one holding its first pixel in raster order (top row first, then leftmost), and
// is processed whole: the window read around a tile grows until every building it owns lies
// inside it, however far it crosses the tile's border.
#pragma once
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "contour/contour.hpp"
#include "io/raster.hpp"

namespace lodforge {

struct TileGrid {
  cv::Size raster;  // pixels
  int tile_px = 0;  // side of a tile
  int cols = 0, rows = 0;
  TileGrid(cv::Size raster_size, int tile_side_px);
  int count() const { return cols * rows; }
  cv::Rect rect(int tile) const;  // clipped to the raster
  std::string name(int tile) const;  // "r0012_c0003": row, column; names sort in tile order
};

// Reads windows of a segmentation raster as a 0/1 building mask. One per thread (GDAL dataset
// handles are not shared between threads).
class BlockCache;

class MaskWindowReader {
 public:
  // cache: blocks shared with the other threads' readers (nullptr: GDAL's own, per handle).
  MaskWindowReader(const std::string& path, const BuildingSelector& selector, BlockCache* cache = nullptr);
  ~MaskWindowReader();
  MaskWindowReader(const MaskWindowReader&) = delete;
  MaskWindowReader& operator=(const MaskWindowReader&) = delete;
  cv::Mat read(const cv::Rect& window) const;  // CV_8U, 1 = building

 private:
  struct Impl;
  Impl* impl_;
};

// Does bbox (window coordinates) touch a side of the window that is not the raster's edge? (A
// component that does may go on beyond the window.)
bool touches_inner_border(const cv::Rect& bbox, const cv::Rect& window, cv::Size raster);

struct TileBuildings {
  std::vector<BuildingContour> buildings;  // first_row/first_col and bbox in raster pixels
  int dropped_small = 0;
  std::vector<std::string> too_large;      // buildings that do not fit max_window_px
  cv::Rect window;                         // the window finally read
};

// The window around a tile that holds every building the tile owns, and its mask.
struct TileWindow {
  cv::Rect window;
  cv::Mat mask;
  std::vector<std::string> too_large;  // owned buildings that do not fit max_window_px
  std::uint64_t hash = 0;              // of the mask and the window, for checkpoints
  Components components;               // of the mask, for the tracing
  double label_seconds = 0;            // spent labeling them (the contour stage's first step)
  // With a cadastre: the blocks, components of the mask and the footprints' pixels together
  // (8-connected), which tiles own as they own buildings without one; and for each footprint
  // in the window (by index in the cadastre) a pixel of it in the window.
  Components groups;
  std::vector<std::pair<int, cv::Point>> footprint_seeds;
};
// The margin of a tile's first window: two halos (a building crossing a one-halo window and the
// tile needs its box plus a halo, and reading and labeling a window again cost more than labeling
// a wider one once), within max_window_px, and at least one halo.
int first_window_margin(int halo_px, int tile_px, int max_window_px);

class Cadastre;

// cadastre (optional): the footprints, on the raster's grid transform.
TileWindow find_tile_window(const MaskWindowReader& reader, const TileGrid& grid, int tile, int halo_px,
                            int max_window_px, int connectivity, const Cadastre* cadastre = nullptr,
                            const GeoTransform* transform = nullptr);

// A block of a tile with a cadastre: the buildings (mask components) in it and the footprints
// that touch it, with the share of each footprint's pixels that is building in the mask.
struct TileGroup {
  std::int64_t id = 0;          // its first pixel in raster order: row * raster width + col
  std::vector<int> buildings;   // indices into TileBuildings::buildings
  std::vector<int> footprints;  // indices into the cadastre, ascending
  std::vector<double> coverage; // per footprint
};

// The blocks the tile owns, in raster order of their first pixels, that hold a building or a footprint.
std::vector<TileGroup> tile_groups(const TileWindow& window, const TileGrid& grid, int tile, const TileBuildings& buildings,
                                   const Cadastre& cadastre, const GeoTransform& transform);

// Traces the buildings the tile owns in its window (contours in map coordinates).
TileBuildings trace_tile(const TileWindow& window, const TileGrid& grid, int tile, const GeoTransform& transform,
                         const ContourOptions& options);

// FNV-1a, stable across runs and machines.
std::uint64_t fnv1a(const void* data, std::size_t size, std::uint64_t seed = 1469598103934665603ULL);
std::uint64_t fnv1a(const std::string& text, std::uint64_t seed = 1469598103934665603ULL);

}  // namespace lodforge
