// lodforge eval: footprint quality of a prediction against ground truth (any OGR polygon source).
#include <filesystem>
#include <fstream>
#include <iostream>

#include "cli/args.hpp"
#include "commands/commands.hpp"
#include "eval/metrics.hpp"
#include "io/errors.hpp"
#include "io/atomic_file.hpp"
#include "io/ogr_polygon.hpp"

namespace lodforge {

int run_eval(int argc, char** argv) {
  Args args("eval", "Scores predicted footprints against ground truth: overall IoU, matching at IoU >= 0.5 (precision,\n"
                    "recall, F1, mean IoU), C-IoU, N-ratio, PoLiS, Hausdorff, blob IoU. All in metres, same CRS expected.");
  args.value("pred", "FILE", "predicted footprints (any OGR polygon source: GeoPackage, GeoJSON, ...)")
      .value("gt", "FILE", "ground-truth footprints")
      .value("aoi", "FILE", "area of interest: only what lies inside counts")
      .value("json", "FILE", "also write the metrics as JSON")
      .flag("help", "show this help");
  args.parse(argc, argv, 2);
  if (args.has("help")) { std::cout << args.help(); return 0; }
  const auto predicted = read_polygons(args.require("pred"), "--pred");
  const auto truth = read_polygons(args.require("gt"), "--gt");
  std::optional<PolygonWithHoles> aoi;
  if (auto a = args.get("aoi")) aoi = read_polygons(*a, "--aoi").front();
  const EvalResult r = evaluate(predicted, truth, aoi);
  std::cout << eval_table(r);
  if (auto j = args.get("json")) write_text_atomically(*j, eval_json(r) + "\n");
  return 0;
}

}  // namespace lodforge
