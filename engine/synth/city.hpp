// A procedural city for demos, tests and benchmarks: true footprints, a building mask that
// looks like a segmentation network's output, a DSM and a DTM. Seeded and deterministic.
#pragma once
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

#include "common/option.hpp"
#include "contour/contour.hpp"
#include "geometry/rasterize.hpp"
#include "geometry/types.hpp"

namespace lodforge {

struct SynthOptions {
  double width_m = 300, height_m = 300;   // extent
  double pixel_size_m = 0.25;
  std::uint64_t seed = 1;
  double origin_x = 85000, origin_y = 447000;  // upper-left corner, map metres
  int epsg = 28992;
  double boundary_noise_px = 0.8;  // amplitude of the smooth boundary wobble
  double corner_radius_px = 2.0;   // corners rounded like a network's output
  double speckle_per_km2 = 400;    // small false holes and blobs
  // The same degradation in metres, so that it stays the same physical noise whatever the pixel
  // size (each, when >= 0, replaces its pixel counterpart).
  double boundary_noise_m = -1;    // amplitude of the boundary's wobble (m): its RMS displacement times sqrt 2, as a wave's
  double noise_wavelength_m = -1;  // mean wavelength of the wobble along the boundary (m);
                                   // unset: a Gaussian correlation of 3 px (about 27 px)
  double corner_radius_m = -1;     // corner rounding radius (m)
  double speckle_size_m = -1;      // side of a speckle (m, at least a pixel); unset: 1 or 2 px
  double blur_m = 0;               // a network's smoothing: the Gaussian blur of the true mask (m)
  double bias_m = 0;               // a network's over- (> 0) or under-segmentation (< 0): the boundary moved out (m)

  template <class V>
  void visit(V& v) {
    v("width_m", width_m, "extent east-west (m)", Check::above(0));
    v("height_m", height_m, "extent north-south (m)", Check::above(0));
    v("pixel_size_m", pixel_size_m, "ground sampling distance (m)", Check::above(0));
    v("seed", seed, "random seed", Check::at_least(0));
    v("origin_x", origin_x, "x of the upper-left corner (m)");
    v("origin_y", origin_y, "y of the upper-left corner (m)");
    v("epsg", epsg, "EPSG code of the projected CRS", Check::at_least(1));
    v("boundary_noise_px", boundary_noise_px, "boundary noise amplitude (pixels)", Check::at_least(0));
    v("corner_radius_px", corner_radius_px, "corner rounding radius (pixels)", Check::at_least(0));
    v("speckle_per_km2", speckle_per_km2, "false holes and blobs per km^2", Check::at_least(0));
    v("boundary_noise_m", boundary_noise_m, "boundary wobble amplitude in metres, that of a wave of the same RMS displacement (replaces boundary_noise_px when >= 0; the wobble then moves the boundary along its normal)", Check::at_least(-1));
    v("noise_wavelength_m", noise_wavelength_m, "mean wavelength of the boundary wobble along the boundary in metres (-1: a correlation of 3 pixels)", Check::at_least(-1));
    v("corner_radius_m", corner_radius_m, "corner rounding radius in metres (replaces corner_radius_px when >= 0)", Check::at_least(-1));
    v("speckle_size_m", speckle_size_m, "side of a speckle in metres, at least one pixel (-1: 1 or 2 pixels)", Check::at_least(-1));
    v("blur_m", blur_m, "a network's smoothing: the true mask blurred by a Gaussian of this many metres and cut where a straight wall's blurred edge is (corners cut and filled along a few blurs; the wobble and bias_m then move the boundary by at most four blurs; 0: none)", Check::at_least(0));
    v("bias_m", bias_m, "a network's over- (> 0) or under-segmentation (< 0): the boundary moved out by this many metres along its normal (with blur_m, at most four blurs)");
  }
};

struct SynthBuilding {
  PolygonWithHoles footprint;  // map metres
  std::string kind;            // rectangle, l_shape, t_shape, u_shape, cut45, courtyard, row_house, round, irregular
  double ground_height = 0, roof_height = 0;
};

struct SynthCity {
  std::vector<SynthBuilding> buildings;
  GeoTransform transform;
  cv::Mat building_mask;  // CV_8U, 1 = building (noisy, as segmented)
  cv::Mat dsm, dtm;       // CV_32F
};

// Pure: the same options give the same city.
SynthCity generate_city(const SynthOptions& options);

// The segmentation of given true footprints (map metres): rasterized at options.pixel_size_m
// on a grid covering them with a 10 m margin (origin snapped to whole pixels), then degraded as
// generate_city degrades its own (noise, rounded corners, speckles). No DSM or DTM. Seeded.
SynthCity segment_footprints(const std::vector<PolygonWithHoles>& footprints, const SynthOptions& options);

// Degrades a clean 0/1 mask like a segmentation network's output: rounded corners, a smooth
// boundary wobble of RMS noise_px pixels, correlated along the boundary by a Gaussian of
// correlation_px pixels (the field's blur; its mean wavelength is about 8.9 times that). Corners
// are rounded by an opening and a closing with a disc of the radius rounded to whole pixels.
// physical: the disc is exact for any real radius, and the wobble displaces the boundary along
// its normal (the noise is taken at the nearest boundary pixel), so that an amplitude near the
// wobble's wavelength still gives one boundary, not a fringe of islands; and, after the disc,
// blur_px > 0 blurs the mask by a Gaussian and cuts it where a straight wall's blurred edge is
// (a network's smoothing), bias_px moves the boundary out along its normal. Seeded.
cv::Mat degrade_mask(const cv::Mat& mask, double noise_px, double corner_radius_px, std::uint64_t seed,
                     double correlation_px = 3.0, bool physical = false, double blur_px = 0, double bias_px = 0);

// The wobble in metres as degrade_mask takes it in pixels: the RMS displacement of a wave of that
// amplitude, and the Gaussian correlation whose mean wavelength along the boundary is wavelength_m.
double wobble_rms_px(double amplitude_m, double pixel_size);
double wobble_correlation_px(double wavelength_m, double pixel_size);

}  // namespace lodforge
