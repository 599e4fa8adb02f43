// Cadastral footprints as an input (inputs.footprints): Delft's segmentation with the BGT.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <ogrsf_frmts.h>
#include <set>
#include <sstream>

#include "eval/metrics.hpp"
#include "geometry/polygon.hpp"
#include "io/ogr_polygon.hpp"
#include "support/process.hpp"
#include "support/shapes.hpp"

namespace fs = std::filesystem;

namespace lodforge {
namespace {

std::string delft(const std::string& file) { return test::test_data() + "/delft-ahn3-bgt/" + file; }

void write_job(const fs::path& dir, const std::string& out, double tile_m, const std::string& extra = "") {
  std::ofstream(dir / (out + ".yaml")) << "inputs:\n  segmentation: {path: " << delft("derived/top_class_50cm.tif") << "}\n"
                                       << "  dsm: {path: " << delft("derived/dsm_50cm.tif") << "}\n"
                                       << "  dtm: {path: " << delft("derived/dtm_50cm.tif") << "}\n"
                                       << "  footprints: {path: " << delft("derived/bgt_pand_buildings.geojson")
                                       << ", id_field: identificatiebagpnd}\n"
                                       << "tiling: {tile_size_m: " << tile_m << "}\n"
                                       << "output: {dir: " << out << ", formats: [citygml, cityjson, gpkg]}\nwork_dir: work_" << out << "\n"
                                       << "stages: {heights: {roof: percentile, roof_percentile: 90}}\n" << extra;
}

struct Written {
  std::string cadastre, wkt;
  double roof = -1, coverage = -1;
  PolygonWithHoles polygon;
};

// Every building of a run's GeoPackages by id; an id twice fails the test.
std::map<std::string, Written> read_run(const fs::path& out) {
  GDALAllRegister();
  std::map<std::string, Written> all;
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(out / "tiles"))
    if (e.path().extension() == ".gpkg") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  for (const fs::path& p : files) {
    std::unique_ptr<GDALDataset> d(static_cast<GDALDataset*>(GDALOpenEx(p.c_str(), GDAL_OF_VECTOR, nullptr, nullptr, nullptr)));
    if (!d || !d->GetLayerByName("footprints")) {
      ADD_FAILURE() << p << ": no footprints layer";
      continue;
    }
    OGRLayer* layer = d->GetLayerByName("footprints");
    for (auto& f : *layer) {
      Written w;
      w.cadastre = f->GetFieldAsString("cadastre");
      if (!f->IsFieldNull(f->GetFieldIndex("roof_height"))) w.roof = f->GetFieldAsDouble("roof_height");
      if (!f->IsFieldNull(f->GetFieldIndex("cadastre_coverage"))) w.coverage = f->GetFieldAsDouble("cadastre_coverage");
      char* wkt = nullptr;
      f->GetGeometryRef()->exportToWkt(&wkt);
      w.wkt = wkt;
      CPLFree(wkt);
      w.polygon = from_ogr_polygon(*f->GetGeometryRef()->toPolygon());
      const std::string id = f->GetFieldAsString("id");
      EXPECT_EQ(all.count(id), 0u) << id << " written twice (" << p << ")";
      all[id] = w;
    }
  }
  return all;
}

// Delft's mask merges 160 houses into 55 blocks; with the BGT footprints as input each house the
// mask confirms is a building with its BAG ID, its share of the block, its own heights.
TEST(CadastreRun, DelftWithTheBgtFootprintsGivesOneBuildingPerHouseWithItsIdAndHeights) {
  const fs::path dir = test::fresh_test_directory("cadastre_delft");
  write_job(dir, "small_tiles", 64);
  const test::CommandOutput run = test::lodforge("run " + (dir / "small_tiles.yaml").string() + " --progress none");
  ASSERT_EQ(run.code, 0) << run.output;
  const std::map<std::string, Written> buildings = read_run(dir / "small_tiles");

  // Every BGT ID once: confirmed, or reported as not in the mask.
  std::map<std::string, double> reference_roof;
  {
    std::ifstream csv(delft("reference/reference_lod1_heights_3dfier.csv"));
    std::string line;
    std::getline(csv, line);
    while (std::getline(csv, line)) {
      std::vector<std::string> f;
      std::stringstream s(line);
      for (std::string v; std::getline(s, v, ',');) f.push_back(v);
      reference_roof[f[0]] = std::stod(f[6]);
    }
  }
  ASSERT_EQ(reference_roof.size(), 160u);
  int confirmed = 0;
  std::vector<double> roof_error;
  for (const auto& [id, roof] : reference_roof) {
    const auto it = buildings.find(id);
    ASSERT_NE(it, buildings.end()) << "BGT building " << id << " missing";
    EXPECT_TRUE(it->second.cadastre == "confirmed" || it->second.cadastre == "not_in_mask") << id << ": " << it->second.cadastre;
    if (it->second.cadastre != "confirmed") {
      EXPECT_LT(it->second.coverage, 0.5) << id;
      continue;
    }
    ++confirmed;
    EXPECT_GE(it->second.coverage, 0.5) << id;
    ASSERT_GT(it->second.roof, 0) << id;
    roof_error.push_back(std::abs(it->second.roof - roof));
  }
  EXPECT_GE(confirmed, 155);
  // The report counts them (a footprint not in the mask is no building).
  const nlohmann::json report = nlohmann::json::parse(test::slurp(dir / "small_tiles" / "report.json"));
  EXPECT_EQ(report.at("cadastre").at("confirmed"), confirmed);
  EXPECT_EQ(report.at("cadastre").at("not_in_mask"), 160 - confirmed);
  EXPECT_EQ(report.at("buildings").get<int>(), confirmed + report.at("cadastre").at("not_in_footprints").get<int>());
  // ... and by their outline model: a house takes its block's where the block's outlines share
  // one (docs/engine.md), so most of them, never more than the buildings regularized.
  long long modeled = 0;
  for (const auto& [model, count] : report.at("models").items()) modeled += count.get<long long>();
  EXPECT_LE(modeled, report.at("ok").get<long long>()) << report;
  EXPECT_GE(modeled, 0.8 * report.at("ok").get<double>()) << report;
  // 3dfier's roof (the 90th percentile over the BGT polygon): within 0.3 m (median).
  std::nth_element(roof_error.begin(), roof_error.begin() + roof_error.size() / 2, roof_error.end());
  EXPECT_LE(roof_error[roof_error.size() / 2], 0.3);

  // Per-building F1 at IoU >= 0.5 inside the area the BGT covers (without footprints: 0.15).
  std::vector<PolygonWithHoles> predicted;
  double area_sum = 0;
  auto all = std::make_unique<OGRMultiPolygon>();
  for (const auto& [id, w] : buildings) {
    if (w.cadastre == "not_in_mask") continue;
    EXPECT_EQ(polygon_problem(w.polygon), "") << id;
    predicted.push_back(w.polygon);
    if (w.cadastre != "confirmed") continue;
    area_sum += area(w.polygon);
    all->addGeometryDirectly(to_ogr_polygon(w.polygon).release());
  }
  const std::vector<PolygonWithHoles> truth = read_polygons(delft("derived/bgt_pand_buildings.geojson"), "truth");
  const std::vector<PolygonWithHoles> aoi = read_polygons(delft("derived/gt_coverage_aoi.geojson"), "aoi");
  const EvalResult e = evaluate(predicted, truth, aoi.front());
  EXPECT_GE(e.f1, 0.90) << "precision " << e.precision << " recall " << e.recall;
  // No two houses overlap (houses sharing a wall share it exactly): their areas sum to their union's.
  // (Not so the mask's own buildings: two outlines regularized apart may overlap by a sliver.)
  std::unique_ptr<OGRGeometry> united(all->UnionCascaded());
  ASSERT_TRUE(united);
  EXPECT_NEAR(area_sum, dynamic_cast<OGRSurface*>(united.get()) ? dynamic_cast<OGRSurface*>(united.get())->get_Area()
                                                                 : dynamic_cast<OGRGeometryCollection*>(united.get())->get_Area(), 1e-3);

  // Another tiling and one thread: the same buildings, byte for byte.
  write_job(dir, "one_tile", 300);
  const test::CommandOutput again = test::lodforge("run " + (dir / "one_tile.yaml").string() + " --progress none --threads 1");
  ASSERT_EQ(again.code, 0) << again.output;
  const std::map<std::string, Written> other = read_run(dir / "one_tile");
  ASSERT_EQ(other.size(), buildings.size());
  for (const auto& [id, w] : buildings) {
    ASSERT_EQ(other.count(id), 1u) << id;
    EXPECT_EQ(other.at(id).wkt, w.wkt) << id;
    EXPECT_EQ(other.at(id).roof, w.roof) << id;
  }
  // And in three shards of the small tiles (one process each, as on a cluster): the same again.
  write_job(dir, "shards", 64);
  for (const char* shard : {"0/3", "1/3", "2/3"}) {
    const test::CommandOutput part = test::lodforge("run " + (dir / "shards.yaml").string() + " --progress none --shard " + shard);
    ASSERT_EQ(part.code, 0) << part.output;
  }
  const std::map<std::string, Written> sharded = read_run(dir / "shards");  // (an ID in two shards fails)
  ASSERT_EQ(sharded.size(), buildings.size());
  for (const auto& [id, w] : buildings) {
    ASSERT_EQ(sharded.count(id), 1u) << id;
    EXPECT_EQ(sharded.at(id).wkt, w.wkt) << id;
  }

  // The 3D formats name each building by its ID and validate.
  const std::string gml = test::slurp(dir / "one_tile" / "tiles" / "r0000_c0000.gml");
  EXPECT_NE(gml.find("gml:id=\"id_" + reference_roof.begin()->first + "\""), std::string::npos);
  EXPECT_NE(gml.find("<gen:stringAttribute name=\"cadastre_id\"><gen:value>" + reference_roof.begin()->first), std::string::npos);
  const std::string schemas = test::schemas();
  if (schemas.empty()) GTEST_SKIP() << test::kNoSchemas;
  const test::CommandOutput xml = test::shell("XML_CATALOG_FILES=" + schemas + "/citygml2-schemas/catalog.xml xmllint --noout --nonet --schema " +
                                              schemas + "/citygml2-schemas/citygml/profiles/base/2.0/CityGML.xsd " +
                                              (dir / "one_tile" / "tiles" / "r0000_c0000.gml").string());
  EXPECT_EQ(xml.code, 0) << xml.output;
  const test::CommandOutput cj = test::shell("/usr/bin/python3 " + std::string(LODFORGE_SOURCE_DIR) + "/scripts/validate/cityjson.py " + schemas +
                                             "/cityjson2-schemas/cityjson.min.schema.json " +
                                             (dir / "one_tile" / "tiles" / "r0000_c0000.city.json").string());
  EXPECT_EQ(cj.code, 0) << cj.output;
}

// A footprint source that cannot be used stops the run before any output, naming the key.
TEST(CadastreRun, UnusableFootprintsStopTheRunNamingTheKey) {
  const fs::path dir = test::fresh_test_directory("cadastre_errors");
  const auto error_of = [&](const std::string& footprints) {
    std::ofstream(dir / "job.yaml") << "inputs:\n  segmentation: {path: " << delft("derived/top_class_50cm.tif") << "}\n"
                                    << "  footprints: " << footprints << "\noutput: {dir: out}\nwork_dir: work\n";
    const test::CommandOutput r = test::lodforge("run " + (dir / "job.yaml").string() + " --progress none");
    EXPECT_NE(r.code, 0);
    EXPECT_FALSE(fs::exists(dir / "out" / "tile_index.geojson"));
    return r.output;
  };
  const std::string bgt = delft("derived/bgt_pand_buildings.geojson");
  EXPECT_NE(error_of("{path: missing.gpkg}").find("inputs.footprints.path: '" + (dir / "missing.gpkg").string() + "': file not found"),
            std::string::npos);
  const std::string field = error_of("{path: " + bgt + ", id_field: pand_id}");
  EXPECT_NE(field.find("inputs.footprints.id_field: 'pand_id' is not a field of"), std::string::npos) << field;
  EXPECT_NE(field.find("identificatiebagpnd"), std::string::npos) << field;  // (the fields it has)
  EXPECT_NE(error_of("{path: " + bgt + ", layer: pand}").find("inputs.footprints.layer: 'pand' is not a layer of"), std::string::npos);
  // Without a CRS (a CSV's WKT column has none).
  std::ofstream(dir / "no_crs.csv") << "WKT,id\n\"POLYGON ((84900 447500,84910 447500,84910 447510,84900 447510,84900 447500))\",1\n";
  const std::string no_crs = error_of("{path: " + (dir / "no_crs.csv").string() + "}");
  EXPECT_NE(no_crs.find("has no CRS"), std::string::npos) << no_crs;
  // Two IDs that would be one object ID in the files.
  const std::string square = R"("geometry": {"type": "Polygon", "coordinates": [[[84900, 447500], [84910, 447500], [84910, 447510], [84900, 447510], [84900, 447500]]]})";
  std::ofstream(dir / "clash.geojson") << R"({"type": "FeatureCollection", "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::28992"}}, "features": [)"
                                       << R"({"type": "Feature", "properties": {"pid": "a b"}, )" << square << "}, "
                                       << R"({"type": "Feature", "properties": {"pid": "a_b"}, )" << square << "}]}";
  const std::string clash = error_of("{path: " + (dir / "clash.geojson").string() + ", id_field: pid}");
  EXPECT_NE(clash.find("the IDs 'a b' and 'a_b' of"), std::string::npos) << clash;
}

// A footprint of two parts far apart (one ID, a MultiPolygon) is one building, written once,
// whatever the tiling: its parts join one block.
TEST(CadastreRun, AMultiPartFootprintIsOneBuildingWhateverTheTiling) {
  GDALAllRegister();
  const fs::path dir = test::fresh_test_directory("cadastre_multipart");
  {
    std::unique_ptr<GDALDataset> in(static_cast<GDALDataset*>(
        GDALOpenEx(delft("derived/bgt_pand_buildings.geojson").c_str(), GDAL_OF_VECTOR, nullptr, nullptr, nullptr)));
    ASSERT_TRUE(in);
    OGRLayer* source = in->GetLayer(0);
    GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GeoJSON");
    std::unique_ptr<GDALDataset> out(driver->Create((dir / "multi.geojson").c_str(), 0, 0, 0, GDT_Unknown, nullptr));
    OGRLayer* layer = out->CreateLayer("pand", source->GetSpatialRef(), wkbUnknown, nullptr);
    OGRFieldDefn field("pand_id", OFTString);
    ASSERT_EQ(layer->CreateField(&field), OGRERR_NONE);
    // The first and the last footprint (two blocks apart, far more than a tile's window) as one.
    std::vector<std::unique_ptr<OGRGeometry>> geometries;
    for (auto& f : *source) geometries.emplace_back(f->GetGeometryRef()->clone());
    ASSERT_GT(geometries.size(), 2u);
    for (std::size_t k = 1; k + 1 < geometries.size(); ++k) {
      OGRFeature f(layer->GetLayerDefn());
      f.SetField("pand_id", ("p" + std::to_string(k)).c_str());
      f.SetGeometry(geometries[k].get());
      ASSERT_EQ(layer->CreateFeature(&f), OGRERR_NONE);
    }
    OGRMultiPolygon both;
    both.addGeometry(geometries.front().get());
    both.addGeometry(geometries.back().get());
    OGRFeature f(layer->GetLayerDefn());
    f.SetField("pand_id", "both");
    f.SetGeometry(&both);
    ASSERT_EQ(layer->CreateFeature(&f), OGRERR_NONE);
  }
  std::map<std::string, std::string> first;
  for (const double tile_m : {10.0, 300.0}) {
    const std::string name = "tiles_" + std::to_string(int(tile_m));
    std::ofstream(dir / (name + ".yaml")) << "inputs:\n  segmentation: {path: " << delft("derived/top_class_50cm.tif") << "}\n"
                                          << "  footprints: {path: multi.geojson, id_field: pand_id}\n"
                                          << "tiling: {tile_size_m: " << tile_m << ", halo_m: 1}\noutput: {dir: " << name << ", formats: [gpkg]}\n"
                                          << "work_dir: work_" << name << "\n";
    const test::CommandOutput run = test::lodforge("run " + (dir / (name + ".yaml")).string() + " --progress none");
    ASSERT_EQ(run.code, 0) << run.output;
    const std::map<std::string, Written> buildings = read_run(dir / name);  // (an ID twice fails)
    ASSERT_EQ(buildings.count("both"), 1u) << name;
    EXPECT_NE(buildings.at("both").cadastre, "");
    if (first.empty()) {
      for (const auto& [id, w] : buildings) first[id] = w.wkt;
    } else {
      EXPECT_EQ(buildings.size(), first.size());
      for (const auto& [id, w] : buildings) EXPECT_EQ(first[id], w.wkt) << id;
    }
  }
}

// Resuming after an edit of the cadastre: the tiles whose windows hold no changed footprint keep
// their checkpoints, and the files equal a fresh run's with the edited cadastre.
// Removing a footprint from the cadastre, the first or the last, redoes only the tiles it
// touches: a tile's checkpoints hang on the footprints in its window (IDs, shapes and order), not
// on their places in the whole cadastre; the resumed run's files are the fresh run's.
TEST(CadastreRun, RemovingAFootprintRedoesOnlyTheTilesItTouches) {
  GDALAllRegister();
  const std::string bgt = test::slurp(delft("derived/bgt_pand_buildings.geojson"));
  const std::string feature = "{ \"type\": \"Feature\"";
  for (const bool first : {false, true}) {
    const fs::path dir = test::fresh_test_directory(first ? "cadastre_edit_first" : "cadastre_edit_last");
    std::ofstream(dir / "before.geojson") << bgt;
    std::string edited;
    if (first) {  // the first feature and the line break after it go
      const std::size_t a = bgt.find(feature), b = bgt.find(feature, a + 1);
      ASSERT_NE(b, std::string::npos);
      edited = bgt.substr(0, a) + bgt.substr(b);
    } else {  // the last feature and the comma before it go
      const std::size_t last = bgt.rfind(feature);
      ASSERT_NE(last, std::string::npos);
      edited = bgt.substr(0, last);
      edited.erase(edited.find_last_of(','));
      edited += "\n]\n}\n";
    }
    std::ofstream(dir / "after.geojson") << edited;
    const auto run = [&](const std::string& footprints, const std::string& work, const std::string& out) {
      std::ofstream(dir / "job.yaml") << "inputs:\n  segmentation: {path: " << delft("derived/top_class_50cm.tif") << "}\n"
                                      << "  footprints: {path: " << footprints << ", id_field: identificatiebagpnd}\n"
                                      << "tiling: {tile_size_m: 32}\noutput: {dir: " << out << ", formats: [gpkg, cityjson]}\nwork_dir: " << work << "\n"
                                      << "stages: {parts: {enabled: false}}\n";
      const test::CommandOutput r = test::lodforge("run " + (dir / "job.yaml").string() + " --progress none");
      EXPECT_EQ(r.code, 0) << r.output;
      return nlohmann::json::parse(test::slurp(dir / out / "report.json"));
    };
    run("before.geojson", "work", "out_before");
    const nlohmann::json resumed = run("after.geojson", "work", "out_resumed");
    const nlohmann::json fresh = run("after.geojson", "work_fresh", "out_fresh");
    EXPECT_EQ(resumed.at("cadastre").at("confirmed").get<int>() + resumed.at("cadastre").at("not_in_mask").get<int>(), 159) << first;
    // Most tiles' contours come from the checkpoints; those whose windows hold the removed
    // footprint are traced again: at 32 m tiles a window spans its neighbours', so 18-21 of the 72
    // (68 when the key held each footprint's place in the cadastre).
    const int tiles = resumed.at("tiles").get<int>(), reused = resumed.at("checkpoints_reused").at("contours").get<int>();
    EXPECT_LE(tiles - reused, tiles / 3) << (first ? "first" : "last") << ": " << reused << " of " << tiles;
    EXPECT_LT(reused, tiles) << (first ? "first" : "last");
    // Every tile file (CityJSON and GeoPackage), byte for byte, and no other.
    std::set<std::string> fresh_files, resumed_files;
    for (const auto& e : fs::directory_iterator(dir / "out_fresh" / "tiles")) {
      fresh_files.insert(e.path().filename().string());
      EXPECT_EQ(test::slurp(e.path()), test::slurp(dir / "out_resumed" / "tiles" / e.path().filename())) << e.path();
    }
    for (const auto& e : fs::directory_iterator(dir / "out_resumed" / "tiles")) resumed_files.insert(e.path().filename().string());
    EXPECT_EQ(fresh_files, resumed_files);
    EXPECT_GT(fresh_files.size(), 0u);  // (the loop compared something)
  }
}

}  // namespace
}  // namespace lodforge
