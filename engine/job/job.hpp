// A batch job: inputs, tiling, outputs, work directory, threads and every stage option, declared
// once. `lodforge config --defaults` prints it; `lodforge run JOB.yaml` reads it.
#pragma once
#include <string>
#include <vector>

#include "commands/stage_options.hpp"
#include "common/option.hpp"
#include "pipeline/building.hpp"

namespace lodforge {

struct SegmentationInput {
  std::string path;
  std::vector<int> building_values{6};  // class values of buildings (one-band raster)
  std::vector<int> building_rgb;        // or an RGB colour, e.g. [0, 0, 255]; overrides values
  std::vector<double> building_min;     // or [V]: band 1 at or above V (a probability); overrides values

  template <class V>
  void visit(V& v) {
    v("path", path, "segmentation raster (any GDAL format), georeferenced; required");
    v("building_values", building_values, "class values that are buildings in a one-band raster", Check::between(-2147483648.0, 2147483647.0));
    v("building_rgb", building_rgb, "building colour of an RGB raster, e.g. [0, 0, 255] (ISPRS); empty: use building_values", Check::between(0, 65535));
    v("building_min", building_min, "[V]: the buildings are the pixels of a one-band raster whose value is at least V, a network's probability or score, e.g. [0.5] (never its nodata value); empty: use building_values");
  }
};

struct RasterInput {
  std::string path;
  template <class V>
  void visit(V& v) { v("path", path, "raster path (any GDAL format); empty: not used"); }
};

struct FootprintsInput {
  std::string path, layer, id_field;
  template <class V>
  void visit(V& v) {
    v("path", path, "cadastral footprints (any OGR polygon source: GeoPackage, Shapefile, GeoJSON, ...), reprojected to the segmentation's CRS if needed; each footprint the mask confirms becomes a building with the cadastre's ID (stages.footprints); empty: not used");
    v("layer", layer, "the layer of path; empty: the first");
    v("id_field", id_field, "the field holding each footprint's ID (features of one ID are one building); empty: the feature ID (FID)");
  }
};

struct InputOptions {
  SegmentationInput segmentation;
  RasterInput dsm, dtm, orthophoto;
  FootprintsInput footprints;
  std::string on_grid_mismatch = "resample";

  template <class V>
  void visit(V& v) {
    v.section("segmentation", segmentation);
    v.section("dsm", dsm);
    v.section("dtm", dtm);
    v.section("orthophoto", orthophoto);
    v.section("footprints", footprints);
    v("on_grid_mismatch", on_grid_mismatch, "rasters on another grid or CRS than the segmentation: 'resample' them to its grid, or stop with an 'error'", Check::one_of({"resample", "error"}));
  }
};

struct TilingOptions {
  double tile_size_m = 250;     // tiles are squares of this side, in raster order
  double halo_m = 20;           // read around a tile; grown until every building it owns is whole
  double max_window_m = 4000;   // a building larger than this is reported, not processed
  int gdal_cache_mb = 64;       // GDAL's raster block cache; with the tiles in flight, bounds memory
  int noise_survey_windows = 16;       // windows read before the tiles to pool the boundary noise over
  double noise_survey_window_m = 250;  // ... of this side

  template <class V>
  void visit(V& v) {
    v("tile_size_m", tile_size_m, "side of a square tile (m)", Check::above(0));
    v("halo_m", halo_m, "margin around a tile (m): its first window reaches two, and grows to a building's box plus one until every building it owns is whole", Check::at_least(0));
    v("max_window_m", max_window_m, "largest window read for one tile (m); a building that does not fit is reported as failed", Check::above(0));
    v("noise_survey_windows", noise_survey_windows, "windows of the segmentation read before the tiles, spread evenly over it, whose whole buildings' boundary noise is pooled (stages.noise.pooled_floor) into the floor every building allows for: the same for every tiling and shard (0 = none: each building its own noise)", Check::at_least(0));
    v("noise_survey_window_m", noise_survey_window_m, "... each a square of this side (m), a cell of a grid laid from the raster's corner", Check::above(0));
    v("gdal_cache_mb", gdal_cache_mb, "raster block cache (MB): decoded blocks shared by the threads (3/4) and GDAL's own cache (1/4); memory is this plus the windows of the tiles in flight", Check::at_least(1));
  }
};

struct OutputOptions {
  std::string dir = "out";
  std::vector<std::string> formats{"citygml", "cityjson", "obj", "gpkg"};
  bool quicklook = false;
  std::string crs;  // "" = the inputs'

  template <class V>
  void visit(V& v) {
    v("dir", dir, "output directory: one file per tile and format, the tile index and the run report");
    v("crs", crs, "the CRS the 3D outputs declare, as an EPSG code: the inputs' horizontal CRS with a vertical one, e.g. EPSG:7415 (RD New + NAP height) for inputs in EPSG:28992; written as urn:ogc:def:crs:EPSG::7415 in CityGML and https://www.opengis.net/def/crs/EPSG/0/7415 in CityJSON. Nothing is reprojected: its horizontal part must be the inputs' CRS. Empty: the inputs' CRS");
    v("quicklook", quicklook, "a PNG per tile for visual checks: LOD0 outlines over the orthophoto, or over a hillshade of the DSM (about a third of a run's time at 0.25 m)");
    v("formats", formats, "output formats, one file per tile each: citygml (2.0), cityjson (2.0), cityjsonseq (CityJSON Text Sequences, .city.jsonl), obj, gpkg, geojson (RFC 7946), gltf (glTF 2.0 binary, .glb: the LOD1 blocks for web viewers and Blender)", Check::one_of({"citygml", "cityjson", "cityjsonseq", "obj", "gpkg", "geojson", "gltf"}));
  }
};

struct Job {
  InputOptions inputs;
  TilingOptions tiling;
  OutputOptions output;
  std::string work_dir = "work";
  int threads = 0;
  std::string regularizer = "deformation";
  StageOptions stages;

  template <class V>
  void visit(V& v) {
    v.section("inputs", inputs);
    v.section("tiling", tiling);
    v.section("output", output);
    v("work_dir", work_dir, "checkpoints of every tile and stage; a rerun skips what is complete");
    v("threads", threads, "worker threads; 0 = all cores", Check::at_least(0));
    v("regularizer", regularizer, "footprint method: 'deformation' (the paper's chain, route in stages.corners.route), 'cgal' (CGAL Shape_regularization, stages.cgal), 'douglas_peucker' or 'none' (raw contour)", Check::one_of(regularizer_names()));
    v.section("stages", stages);
  }
};

// Reads and validates a job file; relative paths are taken from the file's directory.
// overrides: "path=value" (e.g. "stages.labeling.kappa2=5"), applied after the file.
// Throws InputError listing every problem with its key path, before any work starts.
Job load_job(const std::string& path, const std::vector<std::string>& overrides);

// The default job as commented YAML.
std::string default_job_yaml();

}  // namespace lodforge
