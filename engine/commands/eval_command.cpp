// lodforge eval: footprint quality of a prediction against ground truth (any OGR polygon source).
#include <filesystem>
#include <fstream>
#include <gdal_priv.h>
#include <iostream>
#include <ogrsf_frmts.h>

#include "cli/args.hpp"
#include "commands/commands.hpp"
#include "eval/metrics.hpp"
#include "geometry/polygon.hpp"
#include "io/errors.hpp"

namespace lodforge {

namespace {

Ring ring_of(const OGRLinearRing* r, bool outer) {
  Ring out;
  for (int i = 0; i + 1 < r->getNumPoints(); ++i) out.emplace_back(r->getX(i), r->getY(i));
  if (!out.empty() && (signed_area(out) > 0) != outer) std::reverse(out.begin(), out.end());
  return out;
}

void add_polygon(const OGRPolygon* p, std::vector<PolygonWithHoles>& out) {
  if (!p->getExteriorRing() || p->getExteriorRing()->getNumPoints() < 4) return;
  PolygonWithHoles poly{ring_of(p->getExteriorRing(), true), {}};
  for (int k = 0; k < p->getNumInteriorRings(); ++k) poly.holes.push_back(ring_of(p->getInteriorRing(k), false));
  out.push_back(std::move(poly));
}

// Every polygon of every layer (multipolygons split into their parts).
std::vector<PolygonWithHoles> read_polygons(const std::string& path, const std::string& flag) {
  if (!std::filesystem::exists(path)) throw InputError(flag + " '" + path + "': file not found");
  GDALDataset* d = static_cast<GDALDataset*>(GDALOpenEx(path.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
  if (!d) throw InputError(flag + " '" + path + "': not a vector file GDAL can read");
  std::vector<PolygonWithHoles> out;
  for (OGRLayer* layer : d->GetLayers()) {
    for (auto& f : *layer) {
      const OGRGeometry* g = f->GetGeometryRef();
      if (!g) continue;
      const auto type = wkbFlatten(g->getGeometryType());
      if (type == wkbPolygon) add_polygon(g->toPolygon(), out);
      else if (type == wkbMultiPolygon)
        for (const OGRPolygon* part : *g->toMultiPolygon()) add_polygon(part, out);
    }
  }
  GDALClose(d);
  if (out.empty()) throw InputError(flag + " '" + path + "': holds no polygon");
  return out;
}

}  // namespace

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
  if (auto j = args.get("json")) {
    std::ofstream out(*j);
    out << eval_json(r) << '\n';
    if (!out) throw InputError("--json '" + *j + "': cannot write");
  }
  return 0;
}

}  // namespace lodforge
