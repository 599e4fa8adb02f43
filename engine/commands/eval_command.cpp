// lodforge eval: footprint quality of a prediction against ground truth (any OGR polygon source).
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
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
      .value("scores", "FILE", "also write a CSV with a row per prediction (inside the AOI, in the file's order): its feature (its id field, else its FID; .K for a multipolygon's K-th part), the truth feature it matched (IoU >= 0.5; empty: none), the IoU (unmatched: its best with any truth), vertex counts, PoLiS, Hausdorff and max tangent angle of the match, its corners and right-angled corners: to find the buildings that cost the most")
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
  std::vector<std::string> pred_names, truth_names;
  const auto predicted = read_polygons(args.require("pred"), "--pred", &pred_crs, &pred_names);
  check("--pred", args.require("pred"), predicted, pred_crs, nullptr);
  const auto truth = read_polygons(args.require("gt"), "--gt", &gt_crs, &truth_names);
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
  if (auto path = args.get("scores")) {
    const auto csv_field = [](const std::string& v) {  // (quoted where it holds a comma or a quote)
      if (v.find_first_of(",\"\r\n") == std::string::npos) return v;
      std::string q = "\"";
      for (char c : v) q += c == '"' ? std::string("\"\"") : std::string(1, c);
      return q + "\"";
    };
    std::ostringstream csv;
    csv << "prediction,truth,iou,vertices,truth_vertices,polis_m,hausdorff_m,max_tangent_deg,corners,right_corners\n";
    for (const PredictionScore& s : r.scores) {
      csv << csv_field(pred_names[s.predicted]) << ',' << (s.truth >= 0 ? csv_field(truth_names[std::size_t(s.truth)]) : "") << ','
          << fmt::format("{:.4f}", s.iou) << ',' << s.vertices << ',';
      if (s.truth >= 0)
        csv << fmt::format("{},{:.3f},{:.3f},{:.2f}", s.truth_vertices, s.polis, s.hausdorff, s.max_tangent_angle_deg);
      else
        csv << ",,,";
      csv << ',' << s.corners << ',' << s.right_corners << '\n';
    }
    write_text_atomically(*path, csv.str());
  }
  return 0;
}

}  // namespace lodforge
