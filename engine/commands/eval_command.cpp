// lodforge eval: footprint quality of a prediction against ground truth (any OGR polygon source).
#include <filesystem>
#include <fstream>
#include <iostream>
#include <spdlog/spdlog.h>

#include "cli/args.hpp"
#include "commands/commands.hpp"
#include "eval/metrics.hpp"
#include "io/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/input_crs.hpp"
#include "io/ogr_polygon.hpp"

namespace lodforge {

int run_eval(int argc, char** argv) {
  Args args("eval", "Scores predicted footprints against ground truth: overall IoU, matching at IoU >= 0.5 (precision,\n"
                    "recall, F1, mean IoU), C-IoU, N-ratio, PoLiS, Hausdorff, blob IoU. All in metres: the files in one CRS\n"
                    "in metres (checked; a CRS in degrees or another CRS than --pred's is refused, with the ogr2ogr to use).");
  args.value("pred", "FILE", "predicted footprints (any OGR polygon source: GeoPackage, GeoJSON, ...)")
      .value("gt", "FILE", "ground-truth footprints")
      .value("aoi", "FILE", "area of interest: only what lies inside counts")
      .value("json", "FILE", "also write the metrics as JSON")
      .flag("help", "show this help");
  args.parse(argc, argv, 2);
  if (args.has("help")) { std::cout << args.help(); return 0; }
  // Every source in one CRS, in metres (PoLiS, Hausdorff and the areas are measured there). A
  // source whose CRS says degrees but whose coordinates are not (a GeoJSON without a "crs" member,
  // read as WGS 84) is taken as in an unknown CRS, which matches any.
  // reference: --pred's CRS, which the others must share (null: this is --pred).
  const auto check = [](const std::string& key, const std::string& path, const std::vector<PolygonWithHoles>& polygons, std::string& crs,
                        const std::string* reference) {
    if (polygons.empty() || polygons.front().outer.empty()) return;
    const Vec2 at = polygons.front().outer[0];
    if (degrees_out_of_range(crs, at.x(), at.y())) {
      spdlog::warn("{} '{}': its CRS, {}, is in degrees, but its coordinates ({:.1f}, {:.1f}) are not: taken as in --pred's", key, path,
                   crs_label(crs), at.x(), at.y());
      crs.clear();
      return;
    }
    const std::string reference_epsg = reference ? epsg_of(*reference) : std::string();
    if (const std::string problem = metric_crs_problem(crs, at.x(), at.y(), true, reference_epsg); !problem.empty())
      throw InputError(key + " '" + path + "': " + problem);
    if (reference && !same_horizontal_crs(crs, *reference))
      throw InputError(key + " '" + path + "': is in " + crs_label(crs) + ", --pred in " + crs_label(*reference) +
                       "; the footprints must share a CRS: reproject one, e.g. 'ogr2ogr -t_srs " +
                       (reference_epsg.empty() ? std::string("<the CRS of --pred>") : reference_epsg) + " OUT IN'");
  };
  std::string pred_crs, gt_crs, aoi_crs;
  const auto predicted = read_polygons(args.require("pred"), "--pred", &pred_crs);
  check("--pred", args.require("pred"), predicted, pred_crs, nullptr);
  const auto truth = read_polygons(args.require("gt"), "--gt", &gt_crs);
  check("--gt", args.require("gt"), truth, gt_crs, &pred_crs);
  std::optional<PolygonWithHoles> aoi;
  if (auto a = args.get("aoi")) {
    const auto area = read_polygons(*a, "--aoi", &aoi_crs);
    check("--aoi", *a, area, aoi_crs, &pred_crs);
    aoi = area.front();
  }
  const EvalResult r = evaluate(predicted, truth, aoi);
  std::cout << eval_table(r);
  if (auto j = args.get("json")) write_text_atomically(*j, eval_json(r) + "\n");
  return 0;
}

}  // namespace lodforge
