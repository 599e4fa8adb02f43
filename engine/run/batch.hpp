// The buildings of one mask (regularize) or one tile (run) through a regularizer, in parallel,
// and the boundary noise pooled over a mask's buildings that each of them allows for.
#pragma once
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "contour/contour.hpp"
#include "directions/lattice.hpp"
#include "pipeline/building.hpp"

namespace lodforge {

class MaskWindowReader;

// Whether buildings regularized together pool their noise: the deformation chain with
// noise.pooled_floor above 0 (the peers use no noise).
bool pools_noise(const std::string& regularizer, const CoreOptions& options);
// ... and their corner rounding: the deformation chain with models.pooled_rounding_share and
// rounding_noise above 0.
bool pools_rounding(const std::string& regularizer, const CoreOptions& options);

// The boundary noise pooled over a mask's buildings: the floor every building allows for, and the
// noise their normals are smoothed for (smoothing.noise_neighbourhood; 0: the narrowest smoothing).
// With them, the corner rounding of the mask (pooled_rounding) that a building measuring none of
// its own takes: none given, regularize_batch pools it over its own buildings (a whole mask).
struct MaskNoise {
  double floor_m = 0;
  double smoothing_m = 0;
  std::optional<double> rounding_m;
};

// The noise pooled over these buildings (in rounds, as regularize_batch pools it), alone; *samples
// (when given): the buildings measured; *seconds: the time of each start and round, summed.
MaskNoise pooled_noise(const std::vector<BuildingContour>& buildings, double pixel_size, const CoreOptions& options,
                       std::size_t* samples = nullptr, double* seconds = nullptr);

// Whether a mask of this pixel has its noise measured first at twice it (noise.coarse_resolved_px
// and coarse_max_m; noise.pooled_floor on), and the noise so measured as the mask's, to smooth
// and regularize at the pixel with, where it is at least coarse_resolved_px of the mask's own
// pixels (none where it is less).
bool tries_coarse_noise(double pixel_size, const CoreOptions& options);
std::optional<MaskNoise> coarse_noise_taken(const MaskNoise& coarse, double pixel_size, const CoreOptions& options);

struct RegularizedBatch {
  std::vector<BuildingResult> results;  // in the buildings' order
  double noise_floor_m = 0;             // the noise floor they were regularized with
  double noise_smoothing_m = 0;         // ... and the noise their normals were smoothed for
  std::size_t noise_samples = 0;        // how many of them it was pooled over (0: given, or none)
  double rounding_m = 0;                // the corner rounding those measuring none of their own took (0: none)
  std::size_t rounding_samples = 0;     // how many measured theirs, that it was pooled over (0: given, or none)
};

// Whose lattices a batch's buildings may take (lattice.neighbour_radius_m, neighbour_lattices):
// none, the batch's own buildings (a whole mask, as regularize holds it), or those given (a
// tile's: lattice_lenders, every building that may lend to the tile's, whatever the tiling).
struct Lenders {
  enum class From { none, batch, given };
  From from = From::none;
  std::vector<LatticeLender> given;  // with From::given, ids as contour_id gives them
};

// A building's id among lenders: its first pixel (row, column) in the raster.
std::int64_t contour_id(const BuildingContour& building);

// The buildings through the regularizer. For the deformation chain, with the mask's noise given
// (a run's survey), or else pooled over these buildings: each one started (start_building), their
// noise samples pooled (pooled_noise_floor), in rounds, each smoothing the normals for the noise
// the round before pooled and kept only where that measures more noise (smoothing.noise_rounds,
// noise_gain), and each regularized from its start. The same results
// whatever the thread count: samples are pooled in the buildings' order. Each building is also
// lent its neighbours' lattice from `lenders` (the deformation chain only). The mask's corner
// rounding: given with the noise, or else pooled over these buildings' results (pooled_rounding)
// and taken by those that measured none of their own (take_mask_rounding). A building's seconds
// count its start's. on_done is called after each building's chain (from any thread).
RegularizedBatch regularize_batch(const std::string& regularizer, const std::vector<BuildingContour>& buildings,
                                  double pixel_size, const CoreOptions& options, std::optional<MaskNoise> noise = std::nullopt,
                                  const Lenders& lenders = {}, const std::function<void()>& on_done = {});

// In pixels along the raster's columns and rows (x, y), for any geotransform: how far a lender's
// centre, or its box, may lie from a building's centre (the radius), how wide and tall a lender's box may be
// (the extent), and the margin around the buildings' centres within which every lender lies
// (both), each with two pixels to spare.
struct LenderMargins {
  Vec2 reach = Vec2::Zero(), extent = Vec2::Zero(), window = Vec2::Zero();
};
LenderMargins lender_margins(const GeoTransform& transform, const LatticeOptions& lattice);

// The buildings that may lend their lattice to those given (lattice.neighbour_radius_m): every
// building of the raster, traced whole, whose outer ring's box is at most
// neighbour_max_extent_m wide and tall and that may lend to one of them (its centre within the
// radius of theirs, or its box within half of it: neighbour_lattices), read in one window (their
// centres' box with the radius and that extent as margin, and a pixel). The
// same lattices as the whole mask lends, whatever the tiling. Empty when no lattice is lent
// (the radius or the extent 0, or no buildings).
std::vector<LatticeLender> lattice_lenders(const MaskWindowReader& mask, cv::Size raster, const GeoTransform& transform,
                                           const ContourOptions& contour, const LatticeOptions& lattice,
                                           const std::vector<BuildingContour>& buildings);

// k of the indices 0..n-1 spread evenly over them (j n / k for j < k; all of them when k >= n):
// the buildings a wider smoothing round is judged on (smoothing.noise_gain_buildings).
std::vector<std::size_t> spread_indices(std::size_t n, std::size_t k);

// The cells a survey reads: squares of window_px pixels of a grid laid over the raster from its
// corner (the last row and column cut by the raster's edges), all of them when there are at most
// `windows`, else rows and columns of them spread evenly over both axes (a x b <= windows, a / b
// about the grid's rows / columns).
std::vector<cv::Rect> survey_cells(cv::Size raster, int window_px, int windows);

// The noise floor of a raster too large to read whole: pooled, in rounds as regularize_batch
// pools it, over the buildings whose first pixel lies in one of the survey's cells, each read with a margin of a quarter of window_px so that a
// building crossing the cell's edge is whole (larger ones are left out). The same for every
// tiling and shard of the raster.
struct NoiseSurvey {
  MaskNoise noise;
  std::size_t buildings = 0;  // sampled
  int windows = 0;            // read
};
// raster, transform and window_px: the mask's own, in its pixels. factor: on the mask averaged over
// blocks of that many pixels a side from its first pixel (average_blocks, as `averaged` makes a
// whole mask), the survey's cells and windows in blocks (as many metres), the noise at that pixel.
NoiseSurvey survey_noise(const MaskWindowReader& mask, cv::Size raster, const GeoTransform& transform, const ContourOptions& contour,
                         const CoreOptions& options, int window_px, int windows, int factor = 1);

// The corner rounding of such a raster (pools_rounding): pooled over the buildings of the same
// survey's cells (survey_cells, each read with the same margin, at the mask's pixel), each
// regularized with the noise the survey pooled (`noise`), its cell's buildings lending their
// lattices to each other. The same for every tiling and shard of the raster; with one cell over the
// whole raster, regularize's.
struct RoundingSurvey {
  double rounding_m = 0;
  std::size_t measured = 0;  // buildings whose rounding was measured (measured_rounding)
  std::size_t rounded = 0;   // ... and found above 0
};
RoundingSurvey survey_rounding(const MaskWindowReader& mask, cv::Size raster, const GeoTransform& transform, const ContourOptions& contour,
                               const CoreOptions& options, int window_px, int windows, const MaskNoise& noise);

}  // namespace lodforge
