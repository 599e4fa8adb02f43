// Per-stage micro-benchmarks on rasterized noisy buildings of growing size, so the growth of each
// stage's cost with the contour's edge count is visible. Run: build/bench/stages_bench
#include <benchmark/benchmark.h>

#include <filesystem>
#include <charconv>
#include <gdal_priv.h>
#include <libxml/xmlwriter.h>
#include <unistd.h>

#include "corners/corners.hpp"
#include "heights/heights.hpp"
#include "io/model_writers.hpp"
#include "lod1/solid.hpp"
#include "deformation/deform.hpp"
#include "directions/ransac.hpp"
#include "directions/refine.hpp"
#include "labeling/mrf.hpp"
#include "normals/smoothing.hpp"
#include "pipeline/building.hpp"
#include "synth/city.hpp"
#include "triangulation/triangulate.hpp"

#include <Eigen/Geometry>

namespace lodforge {
namespace {

// An L-shaped building, 30° rotated, scaled so that its contour has about `edges` pixel edges
// at 0.25 m, degraded like a segmentation.
struct Raster {
  cv::Mat mask;
  GeoTransform transform;
};

Raster building_raster(int edges) {
  const double pixel = 0.25;
  // The unit L (16 x 14 m) has ~330 staircase edges at 0.25 m when rotated 30°.
  const double scale = edges / 330.0;
  PolygonWithHoles l{{{0, 0}, {16, 0}, {16, 6}, {6, 6}, {6, 14}, {0, 14}}, {}};
  Vec2 lo(1e18, 1e18), hi(-1e18, -1e18);
  for (Vec2& p : l.outer) {
    p = Vec2(1000, 1000) + Eigen::Rotation2Dd(M_PI / 6) * (p * scale);
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  GeoTransform t;
  t.c = {std::floor(lo.x() - 5), pixel, 0, std::ceil(hi.y() + 5), 0, -pixel};
  cv::Mat mask = cv::Mat::zeros(int((hi.y() - lo.y() + 10) / pixel) + 2, int((hi.x() - lo.x() + 10) / pixel) + 2, CV_8U);
  rasterize(mask, l, t);
  return {degrade_mask(mask, 0.5, 2.0, 7), t};
}

std::vector<Ring> building(int edges) {
  const Raster r = building_raster(edges);
  return extract_contours(r.mask, r.transform, ContourOptions{}).buildings.at(0).rings;
}

// The chain's inputs up to a stage, computed once outside the timed loop.
struct Prepared {
  std::vector<Ring> rings;
  LabelingInput input;
  EdgeLabels labels;
  std::vector<double> weights;
  std::vector<Vec2> normals;
};

Prepared prepare(int edges) {
  Prepared p;
  p.rings = building(edges);
  const CoreOptions o;
  for (const Ring& ring : p.rings) {
    p.input.normals.push_back(smooth_normals(ring, 0.25, o.smoothing));
    p.input.lengths.emplace_back();
    for (std::size_t i = 0; i < ring.size(); ++i) p.input.lengths.back().push_back(edge_vector(ring, i).norm());
    p.normals.insert(p.normals.end(), p.input.normals.back().begin(), p.input.normals.back().end());
    p.weights.insert(p.weights.end(), p.input.lengths.back().begin(), p.input.lengths.back().end());
  }
  for (const DominantDirection& d : detect_directions(p.normals, p.weights, o.directions)) {
    p.input.directions.push_back(d.normal);
    p.input.support.push_back(d.support);
  }
  p.labels = label_edges(p.input, o.labeling);
  return p;
}

void set_edges(benchmark::State& state, const std::vector<Ring>& rings) {
  std::size_t n = 0;
  for (const Ring& r : rings) n += r.size();
  state.counters["edges"] = double(n);
}

void BM_Smoothing(benchmark::State& state) {
  const auto rings = building(int(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(smooth_normals(rings[0], 0.25, SmoothingOptions{}));
  set_edges(state, rings);
}

void BM_WholeChainOriginalRoute(benchmark::State& state) {
  const auto rings = building(int(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(regularize_building(rings, 0.25, CoreOptions{}));
  set_edges(state, rings);
}

void BM_WholeChainDeformedRoute(benchmark::State& state) {
  const auto rings = building(int(state.range(0)));
  CoreOptions o;
  o.corners.route = "deformed";
  for (auto _ : state) benchmark::DoNotOptimize(regularize_building(rings, 0.25, o));
  set_edges(state, rings);
}

// The deformed route on a coarse mesh: runs simplified to 1 px, mesh edges up to 20 px.
void BM_WholeChainDeformedRouteCoarse(benchmark::State& state) {
  const auto rings = building(int(state.range(0)));
  CoreOptions o;
  o.corners.route = "deformed";
  o.deformation.simplify_px = 1.0;
  o.triangulation.size_bound_px = 20.0;
  for (auto _ : state) benchmark::DoNotOptimize(regularize_building(rings, 0.25, o));
  set_edges(state, rings);
}

void BM_Triangulation(benchmark::State& state) {
  auto rings = building(int(state.range(0)));
  const Vec2 origin = rings[0][0];
  for (Ring& r : rings) for (Vec2& p : r) p = (p - origin) / 0.25;
  for (auto _ : state) benchmark::DoNotOptimize(triangulate(rings, 5.0, TriangulationOptions{}));
  set_edges(state, rings);
}

void BM_Contour(benchmark::State& state) {
  const Raster r = building_raster(int(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(extract_contours(r.mask, r.transform, ContourOptions{}));
  set_edges(state, building(int(state.range(0))));
}

void BM_Ransac(benchmark::State& state) {
  const Prepared p = prepare(int(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(detect_directions(p.normals, p.weights, RansacOptions{}));
  set_edges(state, p.rings);
}

void BM_Mrf(benchmark::State& state) {
  const Prepared p = prepare(int(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(label_edges(p.input, MrfOptions{}));
  set_edges(state, p.rings);
}

void BM_Corners(benchmark::State& state) {
  const Prepared p = prepare(int(state.range(0)));
  std::string problem;
  for (auto _ : state) benchmark::DoNotOptimize(extract_corners(p.rings[0], p.labels[0], p.input.directions, 0.25, CornerOptions{}, &problem));
  set_edges(state, p.rings);
}

void BM_Deformation(benchmark::State& state) {
  const Prepared p = prepare(int(state.range(0)));
  const Vec2 origin = p.rings[0][0];
  std::vector<Ring> px = p.rings;
  for (Ring& r : px) for (Vec2& v : r) v = (v - origin) / 0.25;
  const CoreOptions o;
  const TriangleMesh mesh = triangulate(px, o.triangulation.size_bound_px, o.triangulation);
  std::vector<Vec2> targets;
  for (const BoundaryEdge& b : mesh.boundary) targets.push_back(p.input.directions[p.labels[b.ring][b.edge]]);
  DeformationResult last;
  for (auto _ : state) benchmark::DoNotOptimize(last = deform(mesh, targets, o.deformation, [] { return false; }));
  set_edges(state, p.rings);
  state.counters["iterations"] = last.iterations;
  state.counters["rounds"] = last.rounds;
  state.counters["triangles"] = double(mesh.triangles.size());
}

void BM_Heights(benchmark::State& state) {
  const Raster r = building_raster(int(state.range(0)));
  const PolygonWithHoles footprint = regularize_building(building(int(state.range(0))), 0.25, CoreOptions{}).footprint;
  HeightRaster dsm{cv::Mat(r.mask.size(), CV_32F, cv::Scalar(12.0f)), cv::Mat::ones(r.mask.size(), CV_8U), r.transform};
  HeightRaster dtm{cv::Mat(r.mask.size(), CV_32F, cv::Scalar(2.0f)), cv::Mat::ones(r.mask.size(), CV_8U), r.transform};
  for (auto _ : state) benchmark::DoNotOptimize(building_heights(footprint, dsm, &dtm, HeightOptions{}));
  set_edges(state, building(int(state.range(0))));
}

// A writer on N buildings (the 500-edge L, its LOD1 block), to a file in /tmp.
void BM_Writer(benchmark::State& state, const std::string& format) {
  const PolygonWithHoles footprint = regularize_building(building(500), 0.25, CoreOptions{}).footprint;
  BuildingModel model;
  model.footprint = footprint;
  model.has_lod1 = true;
  model.ground = 2;
  model.roof = 12;
  model.solid = extrude(footprint, 2, 12);
  model.status = "ok";
  model.regularizer = "deformation_original";
  WriterContext context;
  context.tile = "r0000_c0000";
  context.origin = footprint.outer[0];
  const std::string path = "/tmp/lodforge_bench_" + std::to_string(::getpid()) + extension_of(format);
  for (auto _ : state) {
    auto writer = make_model_writer(format, path, context);
    for (int i = 0; i < state.range(0); ++i) {
      model.id = i;
      writer->add(model);
    }
    writer->finish();
  }
  std::filesystem::remove(path);
  state.counters["buildings"] = double(state.range(0));
}

// Issue 17: the same CityGML through libxml2's xmlTextWriter (indented, every text escaped by
// libxml2), to weigh it against BM_Writer/citygml, our stream writer: the same elements, the same
// three-decimal coordinates.
void BM_CityGmlLibxml2(benchmark::State& state) {
  const PolygonWithHoles footprint = regularize_building(building(500), 0.25, CoreOptions{}).footprint;
  const Solid solid = extrude(footprint, 2, 12);
  const std::string path = "/tmp/lodforge_bench_xml_" + std::to_string(::getpid()) + ".gml";
  const auto x = [](const char* s) { return reinterpret_cast<const xmlChar*>(s); };
  std::string pos;
  const auto number = [&pos](double v) {
    char buffer[64];
    const auto r = std::to_chars(buffer, buffer + sizeof buffer, v, std::chars_format::fixed, 3);
    pos.append(buffer, r.ptr);
  };
  for (auto _ : state) {
    xmlTextWriterPtr w = xmlNewTextWriterFilename(path.c_str(), 0);
    xmlTextWriterSetIndent(w, 1);
    xmlTextWriterSetIndentString(w, x("  "));
    xmlTextWriterStartDocument(w, "1.0", "UTF-8", nullptr);
    xmlTextWriterStartElement(w, x("core:CityModel"));
    for (const char* ns : {"xmlns:core", "xmlns:bldg", "xmlns:gen", "xmlns:gml"}) xmlTextWriterWriteAttribute(w, x(ns), x("http://www.opengis.net/x"));
    xmlTextWriterWriteElement(w, x("gml:name"), x("lodforge tile r0000_c0000"));
    const auto polygon = [&](const Face& f) {
      xmlTextWriterStartElement(w, x("gml:Polygon"));
      for (std::size_t r = 0; r < f.rings.size(); ++r) {
        xmlTextWriterStartElement(w, x(r == 0 ? "gml:exterior" : "gml:interior"));
        xmlTextWriterStartElement(w, x("gml:LinearRing"));
        pos.clear();
        for (std::size_t i = 0; i <= f.rings[r].size(); ++i) {
          const Vec3& p = f.rings[r][i % f.rings[r].size()];
          if (i) pos += ' ';
          number(p.x());
          pos += ' ';
          number(p.y());
          pos += ' ';
          number(p.z());
        }
        xmlTextWriterWriteElement(w, x("gml:posList"), x(pos.c_str()));
        xmlTextWriterEndElement(w);
        xmlTextWriterEndElement(w);
      }
      xmlTextWriterEndElement(w);
    };
    for (int i = 0; i < state.range(0); ++i) {
      xmlTextWriterStartElement(w, x("core:cityObjectMember"));
      xmlTextWriterStartElement(w, x("bldg:Building"));
      xmlTextWriterWriteAttribute(w, x("gml:id"), x(("lodforge_b" + std::to_string(i)).c_str()));
      for (const auto& [name, value] : {std::pair{"status", "ok"}, {"regularizer", "deformation_original"}, {"tile", "r0000_c0000"}}) {
        xmlTextWriterStartElement(w, x("gen:stringAttribute"));
        xmlTextWriterWriteAttribute(w, x("name"), x(name));
        xmlTextWriterWriteElement(w, x("gen:value"), x(value));
        xmlTextWriterEndElement(w);
      }
      xmlTextWriterStartElement(w, x("bldg:measuredHeight"));
      xmlTextWriterWriteAttribute(w, x("uom"), x("m"));
      xmlTextWriterWriteString(w, x("10.000"));
      xmlTextWriterEndElement(w);
      xmlTextWriterStartElement(w, x("bldg:lod0FootPrint"));
      xmlTextWriterStartElement(w, x("gml:MultiSurface"));
      xmlTextWriterStartElement(w, x("gml:surfaceMember"));
      Face base;
      for (const Ring* r = &footprint.outer; r; r = nullptr) {
        Ring3 ring;
        for (const Vec2& p : *r) ring.emplace_back(p.x(), p.y(), 2.0);
        base.rings.push_back(ring);
      }
      polygon(base);
      xmlTextWriterEndElement(w);
      xmlTextWriterEndElement(w);
      xmlTextWriterEndElement(w);
      xmlTextWriterStartElement(w, x("bldg:lod1Solid"));
      xmlTextWriterStartElement(w, x("gml:Solid"));
      xmlTextWriterStartElement(w, x("gml:exterior"));
      xmlTextWriterStartElement(w, x("gml:CompositeSurface"));
      for (const Face& f : solid.faces) {
        xmlTextWriterStartElement(w, x("gml:surfaceMember"));
        polygon(f);
        xmlTextWriterEndElement(w);
      }
      for (int k = 0; k < 6; ++k) xmlTextWriterEndElement(w);  // CompositeSurface ... cityObjectMember
    }
    xmlTextWriterEndDocument(w);
    xmlFreeTextWriter(w);
  }
  std::filesystem::remove(path);
  state.counters["buildings"] = double(state.range(0));
}

BENCHMARK(BM_Contour)->Arg(100)->Arg(500)->Arg(2000)->Arg(10000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Ransac)->Arg(100)->Arg(500)->Arg(2000)->Arg(10000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Mrf)->Arg(100)->Arg(500)->Arg(2000)->Arg(10000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Corners)->Arg(100)->Arg(500)->Arg(2000)->Arg(10000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Deformation)->Arg(100)->Arg(500)->Arg(2000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Heights)->Arg(100)->Arg(500)->Arg(2000)->Arg(10000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Writer, citygml, std::string("citygml"))->Arg(100)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Writer, cityjson, std::string("cityjson"))->Arg(100)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Writer, obj, std::string("obj"))->Arg(100)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Writer, gpkg, std::string("gpkg"))->Arg(100)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CityGmlLibxml2)->Arg(100)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Smoothing)->Arg(100)->Arg(500)->Arg(2000)->Arg(10000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_WholeChainOriginalRoute)->Arg(100)->Arg(500)->Arg(2000)->Arg(10000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Triangulation)->Arg(100)->Arg(500)->Arg(2000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_WholeChainDeformedRoute)->Arg(100)->Arg(500)->Arg(2000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_WholeChainDeformedRouteCoarse)->Arg(100)->Arg(500)->Arg(2000)->Arg(10000)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace lodforge

int main(int argc, char** argv) {
  GDALAllRegister();  // the GeoPackage writer
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
