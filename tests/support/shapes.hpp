// Test helpers: rasterize a true polygon, degrade it like a segmentation, trace it back, and
// compare polygons exactly (GEOS through OGR).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "contour/contour.hpp"
#include "geometry/types.hpp"

namespace lodforge::test {

// A polygon rotated by angle_deg about its first vertex's bounding box centre, placed at
// (500000, 5000000) in map metres.
PolygonWithHoles rotated(const PolygonWithHoles& p, double angle_deg);

struct RasterizedShape {
  cv::Mat mask;
  GeoTransform transform;
  std::vector<BuildingContour> buildings;
};

// Rasterizes at pixel_size with a margin, optionally degrades (noise_px > 0 adds the synth
// boundary wobble, corner rounding of corner_radius_px), and extracts the contours.
RasterizedShape rasterize_shape(const PolygonWithHoles& truth, double pixel_size, double noise_px,
                                double corner_radius_px, std::uint64_t seed);

// The same with the degradation given in metres, as a network's at any pixel size: a boundary
// wobble of amplitude wobble_m and wavelength wavelength_m along the boundary, corners rounded
// by radius_m, the mask blurred by blur_m (synth's boundary_noise_m, noise_wavelength_m,
// corner_radius_m, blur_m).
RasterizedShape rasterize_shape_m(const PolygonWithHoles& truth, double pixel_size, double wobble_m, double wavelength_m,
                                  double radius_m, std::uint64_t seed, double blur_m = 0);

double iou(const PolygonWithHoles& a, const PolygonWithHoles& b);

// The open data sets the tests read: tests/data (LODFORGE_TEST_DATA overrides).
std::string test_data();

// A directory holding the official schemas, citygml2-schemas/ and cityjson2-schemas/:
// LODFORGE_SCHEMAS, else ../shared/data beside the clone when it has them; empty when neither.
std::string schemas();
// Why a schema validation was skipped, and how to run it.
inline constexpr const char* kNoSchemas =
    "no CityGML 2.0 / CityJSON 2.0 schemas found: set LODFORGE_SCHEMAS to a directory holding citygml2-schemas/ "
    "and cityjson2-schemas/ (the official schemas; scripts/get-schemas.sh fetches them) to validate the outputs against them";

}  // namespace lodforge::test
