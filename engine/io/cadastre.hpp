// Cadastral footprints (inputs.footprints): any OGR polygon source, reprojected to the
// segmentation's CRS, kept with their IDs and found by the pixels they cover.
#pragma once
#include <cstdint>
#include <opencv2/core/types.hpp>
#include <string>
#include <vector>

#include "geometry/geotransform.hpp"
#include "geometry/types.hpp"

namespace lodforge {

struct CadastralFootprint {
  std::string id;                       // the id_field's value (or the feature's FID)
  std::vector<PolygonWithHoles> parts;  // valid, in the segmentation's CRS; several for a multipolygon or repeated ID
  cv::Rect pixels;                      // the raster pixels its parts touch (their box, clipped to the raster)
  std::uint64_t hash = 0;               // of its ID and coordinates
};

class Cadastre {
 public:
  // Reads path's layer (empty: the first) with IDs from id_field (empty: the FID). Features of
  // one ID are one footprint. Throws InputError naming the key and the file for a missing or
  // unreadable source, an unknown layer or field, a layer without CRS, an ID with a tab or line
  // break, and when no polygon overlaps the raster. Features that are no polygon, empty or
  // invalid beyond repair, and footprints wholly outside the raster, are counted in notes().
  Cadastre(const std::string& path, const std::string& layer, const std::string& id_field, const std::string& raster_crs_wkt,
           const GeoTransform& transform, cv::Size raster);
  const std::vector<CadastralFootprint>& footprints() const { return footprints_; }
  // The footprints whose pixel box meets window, by index in footprints(), ascending.
  std::vector<int> in_window(const cv::Rect& window) const;
  // What was left out reading the source, for the log and the report (empty when nothing).
  const std::vector<std::string>& notes() const { return notes_; }
  std::uint64_t hash() const { return hash_; }  // of every footprint's ID and coordinates

 private:
  std::vector<CadastralFootprint> footprints_;
  std::vector<std::string> notes_;
  int bucket_px_ = 256, bucket_cols_ = 0, bucket_rows_ = 0;
  std::vector<std::vector<int>> buckets_;
  std::uint64_t hash_ = 0;
};

}  // namespace lodforge
