// LoD1.3 (stages.parts): buildings split where the roof steps, on the synthetic city whose rows
// of houses have a roof height each and come out of the mask as one block per row.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <ogrsf_frmts.h>

#include "eval/metrics.hpp"
#include "geometry/polygon.hpp"
#include "io/ogr_polygon.hpp"
#include "support/process.hpp"

namespace fs = std::filesystem;

namespace lodforge {
namespace {

struct RunParts {
  std::vector<PolygonWithHoles> models;  // each building's parts, or the building where it has none
  std::map<long, double> building_area, parts_area;
  long buildings = 0, with_parts = 0, parts = 0;
};

RunParts read_parts(const fs::path& gpkg) {
  GDALAllRegister();
  RunParts out;
  std::unique_ptr<GDALDataset> d(static_cast<GDALDataset*>(GDALOpenEx(gpkg.c_str(), GDAL_OF_VECTOR, nullptr, nullptr, nullptr)));
  if (!d || !d->GetLayerByName("parts")) {
    ADD_FAILURE() << gpkg << ": no parts layer";
    return out;
  }
  std::map<long, std::vector<PolygonWithHoles>> parts;
  for (auto& f : *d->GetLayerByName("parts")) {
    const PolygonWithHoles p = from_ogr_polygon(*f->GetGeometryRef()->toPolygon());
    EXPECT_EQ(polygon_problem(p), "");
    EXPECT_GT(f->GetFieldAsDouble("roof_height"), f->GetFieldAsDouble("ground_height"));
    EXPECT_GE(f->GetFieldAsInteger("dsm_cells"), 1);  // (the 3DBAG statistics, per part too)
    parts[long(f->GetFieldAsInteger64("id"))].push_back(p);
    out.parts_area[long(f->GetFieldAsInteger64("id"))] += area(p);
    ++out.parts;
  }
  for (auto& f : *d->GetLayerByName("footprints")) {
    const long id = long(f->GetFieldAsInteger64("id"));
    const PolygonWithHoles p = from_ogr_polygon(*f->GetGeometryRef()->toPolygon());
    ++out.buildings;
    out.building_area[id] = area(p);
    if (parts.count(id)) {
      ++out.with_parts;
      for (const PolygonWithHoles& q : parts[id]) out.models.push_back(q);
    } else {
      out.models.push_back(p);
    }
  }
  return out;
}

TEST(Lod13, RowsOfHousesOfDifferentHeightsComeBackAsPartsOfTheirBlock) {
  GDALAllRegister();
  const fs::path dir = test::fresh_test_directory("lod13");
  const test::CommandOutput synth = test::lodforge("synth --out " + (dir / "city").string() + " --size-m 300 --seed 3");
  ASSERT_EQ(synth.code, 0) << synth.output;
  const auto job = [&](const std::string& name, const std::string& extra) {
    std::ofstream(dir / (name + ".yaml")) << "inputs:\n  segmentation: {path: city/seg_class.tif}\n  dsm: {path: city/dsm.tif}\n"
                                          << "  dtm: {path: city/dtm.tif}\noutput: {dir: " << name << ", formats: [gpkg, citygml, cityjson]}\n"
                                          << "work_dir: work_" << name << "\n" << extra;
    const test::CommandOutput run = test::lodforge("run " + (dir / (name + ".yaml")).string() + " --progress none");
    EXPECT_EQ(run.code, 0) << run.output;
    const test::CommandOutput merge = test::lodforge("merge " + (dir / name).string());
    EXPECT_EQ(merge.code, 0) << merge.output;
    return read_parts(dir / name / "merged" / "lodforge.gpkg");
  };
  const std::vector<PolygonWithHoles> truth = read_polygons((dir / "city" / "footprints.gpkg").string(), "truth");
  const RunParts lod13 = job("lod13", "");
  ASSERT_GT(lod13.with_parts, 0);
  // The parts tile their building: no gap, no overlap.
  for (const auto& [id, parts_area] : lod13.parts_area) EXPECT_NEAR(parts_area, lod13.building_area.at(id), 1e-6 * parts_area) << id;
  // >= 80 % of the true houses are a part (or a building) at IoU >= 0.5; as blocks, about half.
  const EvalResult with_parts = evaluate(lod13.models, truth);
  EXPECT_GE(with_parts.recall, 0.8);
  EXPECT_GE(with_parts.precision, 0.8);
  const RunParts blocks = job("blocks", "stages: {parts: {enabled: false}}\n");
  EXPECT_EQ(blocks.parts, 0);
  EXPECT_LT(evaluate(blocks.models, truth).recall, with_parts.recall - 0.2);

  // lodforge eval reads a run's footprints (not the LOD1 faces beside them): one prediction per building.
  const test::CommandOutput eval = test::lodforge("eval --pred " + (dir / "lod13" / "merged" / "lodforge.gpkg").string() + " --gt " +
                                                  (dir / "city" / "footprints.gpkg").string() + " --json " + (dir / "eval.json").string());
  ASSERT_EQ(eval.code, 0) << eval.output;
  EXPECT_EQ(nlohmann::json::parse(test::slurp(dir / "eval.json")).at("predicted"), lod13.buildings);

  // The 3D files: a Building per block with a BuildingPart per part.
  const nlohmann::json city = nlohmann::json::parse(test::slurp(dir / "lod13" / "merged" / "lodforge.city.json"));
  long parts = 0;
  for (const auto& [id, object] : city.at("CityObjects").items()) {
    if (object.at("type") != "BuildingPart") continue;
    ++parts;
    ASSERT_EQ(object.at("parents").size(), 1u);
    EXPECT_EQ(object.at("geometry").at(0).at("lod"), "1.3");
    const nlohmann::json& children = city.at("CityObjects").at(object.at("parents").at(0).get<std::string>()).at("children");
    EXPECT_NE(std::find(children.begin(), children.end(), id), children.end()) << id;
  }
  EXPECT_EQ(parts, lod13.parts);
  EXPECT_NE(test::slurp(dir / "lod13" / "merged" / "lodforge.gml").find("<bldg:consistsOfBuildingPart>"), std::string::npos);

  // Written again from the checkpoints (the parts read back from work_dir): the same files.
  const test::CommandOutput again = test::lodforge("run " + (dir / "lod13.yaml").string() + " --progress none --set output.dir=" +
                                                   (dir / "lod13_again").string());
  ASSERT_EQ(again.code, 0) << again.output;
  for (const auto& e : fs::directory_iterator(dir / "lod13" / "tiles"))
    if (e.path().extension() == ".json" || e.path().extension() == ".gml") {
      EXPECT_EQ(test::slurp(e.path()), test::slurp(dir / "lod13_again" / "tiles" / e.path().filename())) << e.path();
    }
  // (The heights and parts were read back, not computed: no time in the heights stage.)
  EXPECT_EQ(nlohmann::json::parse(test::slurp(dir / "lod13_again" / "report.json")).at("stage_seconds").at("heights"), 0.0);
}

}  // namespace
}  // namespace lodforge
