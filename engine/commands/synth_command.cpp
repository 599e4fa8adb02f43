// lodforge synth: writes a procedural city (segmentation, DSM, DTM, true footprints).
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <string>
#include <ogr_spatialref.h>
#include <opencv2/core.hpp>
#include <spdlog/spdlog.h>

#include "cli/args.hpp"
#include "commands/commands.hpp"
#include "commands/stage_options.hpp"
#include "common/option_visitors.hpp"
#include "io/errors.hpp"
#include "io/footprint_writer.hpp"
#include "io/ogr_polygon.hpp"
#include "io/raster_writer.hpp"
#include "synth/city.hpp"

namespace lodforge {

namespace fs = std::filesystem;

int run_synth(int argc, char** argv) {
  Args args("synth", "Generates a seeded procedural city: seg_class.tif (building = 6, ground = 2), seg_isprs.tif\n"
                     "(ISPRS colours, building = (0,0,255)), dsm.tif, dtm.tif and the true footprints.gpkg.\n"
                     "With --from, the true footprints are the file's polygons (e.g. a cadastre): their segmentation\n"
                     "is simulated the same way (rasterized, rounded corners, boundary noise, speckles), without DSM/DTM.");
  args.value("out", "DIR", "output directory (created if missing)")
      .value("size-m", "W[xH]", "extent in metres (default 300x300)")
      .value("pixel-size", "M", "ground sampling distance in metres (default 0.25)")
      .value("seed", "N", "random seed (default 1)")
      .value("from", "FOOTPRINTS", "simulate the segmentation of these true footprints (any OGR polygon source; --size-m is ignored)")
      .value("set", "KEY=VALUE", "any other option (listed below), e.g. boundary_noise_m=0.5", true)
      .flag("help", "show this help");
  args.parse(argc, argv, 2);
  if (args.has("help")) {
    // (The options --set takes, from the one declaration the values are read and checked by.)
    SynthOptions defaults;
    OptionPrinter printer;
    defaults.visit(printer);
    std::cout << args.help() << "\nOptions for --set (key: default  # meaning):\n";
    std::istringstream lines(printer.str());
    for (std::string line; std::getline(lines, line);) std::cout << "  " << line << '\n';
    return 0;
  }
  set_gpkg_timestamp();  // (the same city, the same bytes)
  const fs::path out = args.require("out");
  std::vector<std::string> errors;
  std::map<std::string, std::string> values = split_assignments(args.all("set"), "--set", errors);
  // The flags' values are checked under the flags' names (the options they set are named in --set).
  const auto number = [](const std::string& text) {
    char* end = nullptr;
    std::strtod(text.c_str(), &end);
    return !text.empty() && end && *end == '\0';
  };
  if (auto size = args.get("size-m")) {
    const auto x = size->find('x');
    const std::string w = size->substr(0, x), h = x == std::string::npos ? *size : size->substr(x + 1);
    if (!number(w) || !number(h)) throw UsageError("--size-m '" + *size + "': expected metres, W or WxH (e.g. 400 or 500x300)");
    values["width_m"] = w;
    values["height_m"] = h;
  }
  if (auto v = args.get("pixel-size")) {
    if (!number(*v)) throw UsageError("--pixel-size '" + *v + "': expected metres, e.g. 0.25");
    values["pixel_size_m"] = *v;
  }
  if (auto v = args.get("seed")) {
    if (v->empty() || v->find_first_not_of("0123456789") != std::string::npos) throw UsageError("--seed '" + *v + "': expected a whole number");
    values["seed"] = *v;
  }
  SynthOptions options;
  set_and_validate(options, values, errors);
  if (!errors.empty()) throw input_errors(errors);
  std::vector<PolygonWithHoles> given;
  std::string given_crs;
  if (auto from = args.get("from")) {
    given = read_polygons(*from, "--from", &given_crs);
    // Pixel size and margin are metres: the footprints must be in a projected CRS.
    OGRSpatialReference srs;
    if (given_crs.empty() || srs.importFromWkt(given_crs.c_str()) != OGRERR_NONE)
      throw InputError("--from '" + *from + "': has no CRS; give the footprints in a projected CRS in metres (e.g. ogr2ogr -t_srs EPSG:28992)");
    if (srs.IsGeographic())
      throw InputError("--from '" + *from + "': is in a geographic CRS (degrees); reproject it to a projected CRS in metres first (e.g. ogr2ogr -t_srs EPSG:28992)");
  }

  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) throw InputError("'" + out.string() + "': cannot create directory: " + ec.message());
  if (!given.empty())
    spdlog::info("simulating the segmentation of {} footprints at {} m per pixel, seed {}", given.size(), options.pixel_size_m, options.seed);
  else
    spdlog::info("generating a {} x {} m city at {} m per pixel, seed {}", options.width_m, options.height_m,
                 options.pixel_size_m, options.seed);
  const SynthCity city = given.empty() ? generate_city(options) : segment_footprints(given, options);
  RasterMeta meta{city.transform, given.empty() || given_crs.empty() ? epsg_wkt(options.epsg) : given_crs};
  cv::Mat classes = city.building_mask * 4 + 2;  // 6 = building, 2 = ground
  write_geotiff((out / "seg_class.tif").string(), {classes}, meta);
  cv::Mat background = 255 * (1 - city.building_mask);
  cv::Mat blue = cv::Mat::ones(classes.size(), CV_8U) * 255;
  write_geotiff((out / "seg_isprs.tif").string(), {background, background.clone(), blue}, meta);
  if (!city.dsm.empty()) write_geotiff((out / "dsm.tif").string(), {city.dsm}, meta);
  if (!city.dtm.empty()) write_geotiff((out / "dtm.tif").string(), {city.dtm}, meta);
  std::vector<FootprintRecord> truth;
  for (std::size_t i = 0; i < city.buildings.size(); ++i) {
    const SynthBuilding& b = city.buildings[i];
    FootprintRecord r;
    r.id = long(i) + 1;
    r.polygon = b.footprint;
    r.kind = b.kind;
    r.roof_height = b.roof_height;
    r.ground_height = b.ground_height;
    truth.push_back(std::move(r));
  }
  FootprintLayer layer;
  layer.crs_wkt = meta.crs_wkt;
  layer.write_status = false;
  layer.write_heights = given.empty();
  layer.kind_field = "kind";
  write_footprints((out / "footprints.gpkg").string(), layer, truth);
  spdlog::info("wrote {} true footprints and rasters of {} x {} pixels to {}", truth.size(), classes.cols, classes.rows,
               out.string());
  return 0;
}

}  // namespace lodforge
