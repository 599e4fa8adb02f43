// The CRS of a run's inputs: read from the rasters and compared, now or when first needed.
#pragma once
#include <array>
#include <memory>
#include <string>
#include <vector>

namespace lodforge {

// The CRS of a raster as WKT ("" when it has none). The first CRS a process reads starts PROJ
// (its database and context: ~12 ms); the next take well under a millisecond.
std::string raster_crs_wkt(const std::string& path, const std::string& key);

// "EPSG:28992" for a CRS with an EPSG code, else empty.
std::string epsg_of(const std::string& wkt);

// output.crs checked against the inputs' CRS (wkt): "EPSG:NNNN" for a CRS GDAL knows by that EPSG
// code whose horizontal part (a compound CRS less its vertical one) is the inputs' CRS; otherwise
// an InputError naming output.crs. Empty stays empty.
std::string declared_output_crs(const std::string& output_crs, const std::string& wkt);

// The points (in the CRS of wkt) as WGS 84 longitude, latitude (RFC 7946's order); empty when
// the CRS is unknown or PROJ cannot transform them.
std::vector<std::array<double, 2>> to_lon_lat(const std::string& wkt, const std::vector<std::array<double, 2>>& points);

// Why a raster in the CRS of wkt cannot be measured in metres, as the text after its name: a
// geographic CRS (degrees) or a projected one in another unit (US feet), with the gdalwarp (for a
// vector source, ogr2ogr) that reprojects it onto target_epsg when given (the other inputs' CRS),
// else onto the UTM zone where (centre_x, centre_y) lies. Empty when the CRS is in metres, or
// unknown (wkt empty: its coordinates taken as metres).
std::string metric_crs_problem(const std::string& wkt, double centre_x, double centre_y, bool vector = false,
                               const std::string& target_epsg = {});

// Whether a source says its CRS is geographic while its point (x, y) is no longitude and latitude:
// its CRS is missing or wrong (GDAL reads a GeoJSON without a "crs" member as WGS 84).
bool degrees_out_of_range(const std::string& wkt, double x, double y);

// Whether two CRS have the same horizontal part (a compound CRS less its vertical one: 7415 is
// 28992 plus NAP heights): by their EPSG codes where both have one, else as equivalent
// definitions; an empty one (unknown) matches any.
bool same_horizontal_crs(const std::string& wkt_a, const std::string& wkt_b);

// "Amersfoort / RD New (EPSG:28992)": a CRS's name, with its EPSG code when it has one; "no CRS"
// when wkt is empty.
std::string crs_label(const std::string& wkt);

// Whether two CRS are the same; an empty one (unknown) matches any.
bool same_crs(const std::string& wkt_a, const std::string& wkt_b);

// The segmentation raster's CRS, and the check that each companion raster (DSM, DTM, orthophoto)
// on its very grid (same size and geotransform) is in the same CRS. The companions' read when
// first asked for, so that a run starts its first tiles meanwhile: the tiles need the CRS only to
// write their files, so an input in another CRS still fails before any output is written. Thread-safe; a failure
// (InputError naming the companion's key and file) is thrown to every caller.
class InputCrs {
 public:
  struct Companion {
    std::string key, path;
  };
  // Already known (the inputs were checked before the run). output_crs: output.crs (see epsg()).
  explicit InputCrs(std::string wkt, std::string output_crs = {});
  // The segmentation's CRS (wkt) known; the companions' checked on first use: one in another CRS
  // fails when `strict` (on_grid_mismatch: error).
  InputCrs(std::string wkt, std::vector<Companion> companions, bool strict, std::string output_crs = {});
  ~InputCrs();
  const std::string& wkt() const;
  // The CRS the 3D outputs declare, "EPSG:7415": output.crs when given (checked on first use:
  // an EPSG code whose horizontal part is the inputs' CRS), else epsg_of(wkt()); worked out once.
  const std::string& epsg() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lodforge
