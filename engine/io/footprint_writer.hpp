// Writes LOD0 footprints with their attributes to a GeoPackage (or any OGR vector format
// chosen by the file extension), atomically: a temporary file renamed on success, so a failed
// run never leaves a file that looks complete.
#pragma once
#include <string>
#include <vector>

#include "geometry/types.hpp"
#include "lod1/solid.hpp"

namespace lodforge {

// The heights every format writes beside ground_height and roof_height (the LOD1 block's), as
// 3DBAG publishes them: roof_min, roof_50p, roof_70p, roof_max (the DSM inside the footprint),
// volume_lod1 (m^3), dsm_coverage (share of the DSM cells inside the footprint with data) and
// dsm_cells (those cells, with data or not: an integer).
struct HeightStatistic {
  std::string name;
  bool integer = false;
};
const std::vector<HeightStatistic>& height_statistic_fields();

struct FootprintRecord {
  long id = 0;
  PolygonWithHoles polygon;
  std::string status, failed_stage, reason;
  std::string regularizer;
  std::string model;             // the outline the chain chose (BuildingResult::model), when write_model; empty: NULL
  std::string kind;              // synthetic truth: the shape; run outputs: the tile
  bool has_heights = true;       // false: the heights are written as null
  double roof_height = 0, ground_height = 0;  // written when write_heights
  std::vector<double> height_statistics;       // ... with these, named by height_statistic_fields()
  std::vector<Face> lod1_faces;  // the LOD1 block's faces, when write_lod1 and it has one
  struct Part {  // a LoD1.3 part: when write_lod1, in the GeoPackage's layer "parts"
    PolygonWithHoles polygon;
    double ground_height = 0, roof_height = 0;
    std::vector<double> height_statistics;
  };
  std::vector<Part> parts;
  std::string cadastre_id, cadastre;  // when write_cadastre: the id (if empty, id as text) and the relation to the cadastre
  double coverage = -1;               // ... and the footprint's mask coverage (null when negative)
};

struct FootprintLayer {
  std::string name = "footprints";
  std::string crs_wkt;
  bool write_status = true;   // status, stage, reason, regularizer
  bool write_model = false;   // model, after them (lodforge regularize)
  bool write_heights = false; // roof_height, ground_height
  std::string kind_field;     // name of the field holding `kind` ("kind", "tile"); empty: none
  bool write_lod1 = false;    // a GeoPackage also gets a layer "lod1": each block's faces as a MultiPolygon Z, and "parts": the LoD1.3 parts
  bool rfc7946 = false;       // GeoJSON as RFC 7946: WGS 84 longitude, latitude (7 decimals), no crs member
  bool write_cadastre = false;  // id as text (the cadastral ID), cadastre and cadastre_coverage
};

// GDAL's GeoJSON layer creation options for RFC 7946: WGS 84 longitude, latitude to 7 decimals
// (about 1 cm), no crs member. (A CSL list, null-terminated, for CreateLayer.)
char** rfc7946_layer_options();

// The time GeoPackages record as their last change (OGR_CURRENT_DATE), the same for every file
// of a run so that identical runs give identical bytes: SOURCE_DATE_EPOCH (seconds since 1970, the
// reproducible-builds convention) when the environment sets it, else 2000-01-01T00:00:00Z.
// Returns the ISO 8601 text set; InputError when SOURCE_DATE_EPOCH is not a whole number.
std::string set_gpkg_timestamp();

// Checks up front that path can be written (directory exists and is writable, extension known).
void check_output_path(const std::string& path);

// Streams features into a temporary file; finish() moves it into place, destruction without
// finish() removes it.
class FootprintFileWriter {
 public:
  FootprintFileWriter(const std::string& path, const FootprintLayer& layer);
  ~FootprintFileWriter();
  FootprintFileWriter(const FootprintFileWriter&) = delete;
  FootprintFileWriter& operator=(const FootprintFileWriter&) = delete;
  void add(const FootprintRecord& record);
  void finish();

 private:
  struct Impl;
  Impl* impl_;
};

void write_footprints(const std::string& path, const FootprintLayer& layer, const std::vector<FootprintRecord>& records);

}  // namespace lodforge
