// The CRS of a run's inputs: read from the rasters and compared, now or when first needed.
#pragma once
#include <memory>
#include <string>
#include <vector>

namespace lodforge {

// The CRS of a raster as WKT ("" when it has none). The first CRS a process reads starts PROJ
// (its database and context: ~12 ms); the next take well under a millisecond.
std::string raster_crs_wkt(const std::string& path, const std::string& key);

// "EPSG:28992" for a CRS with an EPSG code, else empty.
std::string epsg_of(const std::string& wkt);

// Whether two CRS are the same; an empty one (unknown) matches any.
bool same_crs(const std::string& wkt_a, const std::string& wkt_b);

// The segmentation raster's CRS, and the check that each companion raster (DSM, DTM, orthophoto)
// on its very grid (same size and geotransform) is in the same CRS. Read when first asked for, so
// that a run starts its first tiles meanwhile: the tiles need the CRS only to write their files,
// so an input in another CRS still fails before any output is written. Thread-safe; a failure
// (InputError naming the companion's key and file) is thrown to every caller.
class InputCrs {
 public:
  struct Companion {
    std::string key, path;
  };
  // Already known (the inputs were checked before the run).
  explicit InputCrs(std::string wkt);
  // Checked on first use; a companion in another CRS fails when `strict` (on_grid_mismatch: error).
  InputCrs(std::string segmentation_path, std::string segmentation_key, std::vector<Companion> companions, bool strict);
  ~InputCrs();
  const std::string& wkt() const;
  const std::string& epsg() const;  // epsg_of(wkt()), worked out once

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lodforge
