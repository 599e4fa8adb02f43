// Heights, LOD1 shells and the model files (CityGML, CityJSON, OBJ, GeoPackage).
#include <gtest/gtest.h>
#include <set>

#include <regex>

#include <array>
#include <filesystem>
#include <fstream>
#include <limits>
#include <gdal_priv.h>
#include <map>
#include <nlohmann/json.hpp>
#include <ogrsf_frmts.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <tiny_gltf.h>

#include "geometry/polygon.hpp"
#include "heights/heights.hpp"
#include "io/height_reader.hpp"
#include "io/ogr_polygon.hpp"
#include "io/raster_writer.hpp"
#include "lod1/solid.hpp"
#include "run/checkpoint.hpp"
#include "support/process.hpp"
#include "support/shapes.hpp"

namespace fs = std::filesystem;

namespace lodforge {
namespace {

TEST(Solid, ExtrudedPolygonWithHoleIsAValidClosedOutwardShell) {
  const PolygonWithHoles p{{{0, 0}, {10, 0}, {10, 8}, {0, 8}}, {{{3, 3}, {3, 5}, {6, 5}, {6, 3}}}};
  const Solid s = extrude(p, 2.0, 14.0);
  EXPECT_EQ(s.faces.size(), 2u + 4u + 4u);
  EXPECT_EQ(shell_problem(s), "");
  EXPECT_NEAR(volume(s), (80.0 - 6.0) * 12.0, 1e-9);
}

TEST(Solid, BrokenShellsAreCaught) {
  const PolygonWithHoles p{{{0, 0}, {10, 0}, {10, 8}, {0, 8}}, {}};
  Solid open = extrude(p, 0, 5);
  open.faces.pop_back();
  EXPECT_NE(shell_problem(open).find("not closed"), std::string::npos);
  Solid flipped = extrude(p, 0, 5);
  std::reverse(flipped.faces[3].rings[0].begin(), flipped.faces[3].rings[0].end());
  EXPECT_NE(shell_problem(flipped).find("same direction"), std::string::npos);
  Solid inward = extrude(p, 0, 5);
  for (Face& f : inward.faces) for (Ring3& r : f.rings) std::reverse(r.begin(), r.end());
  EXPECT_NE(shell_problem(inward).find("inward"), std::string::npos);
  Solid warped = extrude(p, 0, 5);
  warped.faces[1].rings[0][0].z() += 0.5;
  EXPECT_NE(shell_problem(warped), "");
}

HeightRaster constant_raster(float value, float nodata_value, bool all_nodata) {
  HeightRaster r;
  r.transform.c = {0, 0.5, 0, 20, 0, -0.5};
  r.values = cv::Mat(40, 40, CV_32F, cv::Scalar(value));
  r.valid = cv::Mat(40, 40, CV_8U, cv::Scalar(all_nodata ? 0 : 1));
  (void)nodata_value;
  return r;
}

TEST(Heights, StatisticsAndNodata) {
  const PolygonWithHoles square{{{5, 5}, {15, 5}, {15, 15}, {5, 15}}, {}};
  HeightRaster dsm = constant_raster(2.0f, -9999, false);
  // Roof 12 m inside the square, with one hot pixel (a chimney) of 40 m.
  for (int y = 10; y < 30; ++y)
    for (int x = 10; x < 30; ++x) dsm.values.at<float>(y, x) = 12.0f;
  dsm.values.at<float>(20, 20) = 40.0f;
  HeightOptions o;
  Heights h = building_heights(square, dsm, nullptr, o);
  ASSERT_TRUE(h.ok) << h.reason;
  EXPECT_NEAR(h.roof, 12.0, 1e-9);  // the default: the 70th percentile (3DBAG's LoD1.2)
  // The statistics 3DBAG publishes, whatever the LOD1 statistic.
  EXPECT_NEAR(h.roof_min, 12.0, 1e-9);
  EXPECT_NEAR(h.roof_50p, 12.0, 1e-9);
  EXPECT_NEAR(h.roof_70p, 12.0, 1e-9);
  EXPECT_NEAR(h.roof_max, 40.0, 1e-9);
  EXPECT_EQ(h.dsm_cells, 400);
  EXPECT_NEAR(h.dsm_coverage, 1.0, 1e-12);
  o.roof = "mean";
  h = building_heights(square, dsm, nullptr, o);
  EXPECT_EQ(h.roof_samples, 400);
  EXPECT_NEAR(h.roof, (399 * 12.0 + 40.0) / 400, 1e-9);  // the paper's mean
  EXPECT_NEAR(h.ground, 2.0, 1e-9);                      // the ring around it, no DTM
  o.roof = "median";
  EXPECT_NEAR(building_heights(square, dsm, nullptr, o).roof, 12.0, 1e-9);
  const HeightRaster empty = constant_raster(0, -9999, true);
  h = building_heights(square, empty, nullptr, o);
  EXPECT_FALSE(h.ok);
  EXPECT_EQ(h.reason, "no valid DSM value inside the footprint");
  const HeightRaster dtm = constant_raster(1.5f, -9999, false);
  h = building_heights(square, dsm, &dtm, o);
  EXPECT_NEAR(h.ground, 1.5, 1e-9);
  // A quarter of the roof without data: the coverage says so, the statistics use the rest.
  for (int y = 10; y < 20; ++y)
    for (int x = 10; x < 20; ++x) dsm.valid.at<uint8_t>(y, x) = 0;
  h = building_heights(square, dsm, &dtm, o);
  ASSERT_TRUE(h.ok) << h.reason;
  EXPECT_EQ(h.dsm_cells, 400);
  EXPECT_EQ(h.roof_samples, 300);
  EXPECT_NEAR(h.dsm_coverage, 0.75, 1e-12);
  EXPECT_NEAR(h.roof_max, 40.0, 1e-9);
  // Percentiles by linear interpolation: 70 % of 10 values 1..10 lie at or below 7.3.
  std::vector<float> ten{10, 9, 8, 7, 6, 5, 4, 3, 2, 1};
  EXPECT_NEAR(percentile(ten, 70.0), 7.3, 1e-6);
}

std::string delft(const std::string& name) { return test::test_data() + "/delft-ahn3-bgt/" + name; }

// The BGT footprints by lokaalid, oriented as the core expects.
std::map<std::string, PolygonWithHoles> bgt_footprints() {
  GDALAllRegister();
  std::map<std::string, PolygonWithHoles> out;
  GDALDataset* d = static_cast<GDALDataset*>(GDALOpenEx(delft("derived/bgt_pand_buildings.geojson").c_str(), GDAL_OF_VECTOR, nullptr, nullptr, nullptr));
  for (auto& f : *d->GetLayer(0)) {
    const OGRGeometry* g = f->GetGeometryRef();
    const OGRPolygon* poly = wkbFlatten(g->getGeometryType()) == wkbMultiPolygon ? g->toMultiPolygon()->getGeometryRef(0) : g->toPolygon();
    const PolygonWithHoles p = from_ogr_polygon(*poly);
    out[f->GetFieldAsString("lokaalid")] = p;
  }
  GDALClose(d);
  return out;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

TEST(Heights, AgreeWith3dfierOnTheDelftFootprints) {
  const auto footprints = bgt_footprints();
  ASSERT_GT(footprints.size(), 100u);
  GDALAllRegister();
  GDALDataset* seg = static_cast<GDALDataset*>(GDALOpen(delft("derived/dsm_50cm.tif").c_str(), GA_ReadOnly));
  GeoTransform grid;
  seg->GetGeoTransform(grid.c.data());
  const cv::Rect all(0, 0, seg->GetRasterXSize(), seg->GetRasterYSize());
  GDALClose(seg);
  const HeightRaster dsm = HeightWindowReader(delft("derived/dsm_50cm.tif")).read(all, grid);
  const HeightRaster dtm = HeightWindowReader(delft("derived/dtm_50cm.tif")).read(all, grid);
  HeightOptions o;
  o.roof = "percentile";  // 3dfier's 90th percentile
  o.roof_percentile = 90;
  std::ifstream csv(delft("reference/reference_lod1_heights_3dfier.csv"));
  std::string line;
  std::getline(csv, line);
  std::vector<double> roof_error, ground_error;
  while (std::getline(csv, line)) {
    std::vector<std::string> f;
    std::stringstream s(line);
    for (std::string x; std::getline(s, x, ',');) f.push_back(x);
    auto it = footprints.find(f[1]);
    if (it == footprints.end()) continue;
    const Heights h = building_heights(it->second, dsm, &dtm, o);
    if (!h.ok) continue;
    roof_error.push_back(std::abs(h.roof - std::stod(f[6])));
    ground_error.push_back(std::abs(h.ground - std::stod(f[5])));
  }
  ASSERT_GT(roof_error.size(), 140u);
  EXPECT_LT(median(roof_error), 1.0);
  EXPECT_LT(median(ground_error), 1.0);
  std::cout << "matched " << roof_error.size() << ", median |roof - 3dfier| = " << median(roof_error)
            << " m, median |ground - 3dfier| = " << median(ground_error) << " m\n";
}

}  // namespace
}  // namespace lodforge

namespace lodforge {
namespace {

using Output = test::CommandOutput;
using test::shell;

std::string slurp_file(const fs::path& p) { return test::slurp(p); }

class ModelFiles : public ::testing::Test {
 protected:
  void SetUp() override { dir = test::fresh_test_directory("lodforge_models"); }
  fs::path dir;
};

TEST_F(ModelFiles, HeightWindowsMarkNodataNanAndInfinityInvalid) {
  cv::Mat dsm(3, 4, CV_32F, cv::Scalar(12.5f));
  dsm.at<float>(0, 1) = -9999.0f;                                     // nodata
  dsm.at<float>(1, 2) = std::numeric_limits<float>::quiet_NaN();
  dsm.at<float>(2, 3) = std::numeric_limits<float>::infinity();
  dsm.at<float>(2, 0) = -std::numeric_limits<float>::infinity();
  RasterMeta meta;
  meta.transform.c = {1000, 0.5, 0, 2000, 0, -0.5};
  meta.has_nodata = true;
  meta.nodata = -9999;
  const std::string path = (dir / "dsm.tif").string();
  write_geotiff(path, {dsm}, meta);
  const HeightRaster r = HeightWindowReader(path).read(cv::Rect(0, 1, 4, 2), meta.transform);
  ASSERT_EQ(r.valid.size(), cv::Size(4, 2));
  const std::vector<uint8_t> expected = {1, 1, 0, 1, 0, 1, 1, 0};  // rows 1 and 2
  EXPECT_EQ(std::vector<uint8_t>(r.valid.begin<uint8_t>(), r.valid.end<uint8_t>()), expected);
  EXPECT_FLOAT_EQ(r.values.at<float>(0, 0), 12.5f);
  EXPECT_DOUBLE_EQ(r.transform.c[3], 2000 - 0.5);  // the window's origin, one row down
  // Without a nodata value, -9999 is a height like any other.
  meta.has_nodata = false;
  write_geotiff(path, {dsm}, meta);
  EXPECT_EQ(HeightWindowReader(path).read(cv::Rect(0, 0, 4, 1), meta.transform).valid.at<uint8_t>(0, 1), 1);
}

std::vector<fs::path> files_with(const fs::path& d, const std::string& suffix) {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(d))
    if (e.path().string().size() > suffix.size() && e.path().string().compare(e.path().string().size() - suffix.size(), suffix.size(), suffix) == 0)
      out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

TEST_F(ModelFiles, DelftOutputsValidateAgainstTheOfficialSchemasAndEveryShellIsClosed) {
  const std::string data = test::test_data();
  std::ofstream(dir / "job.yaml") << "inputs:\n  segmentation: {path: " << data << "/delft-ahn3-bgt/derived/top_class_50cm.tif}\n"
                                  << "  dsm: {path: " << data << "/delft-ahn3-bgt/derived/dsm_50cm.tif}\n"
                                  << "  dtm: {path: " << data << "/delft-ahn3-bgt/derived/dtm_50cm.tif}\n"
                                  << "tiling: {tile_size_m: 64}\noutput: {dir: out, quicklook: true}\nwork_dir: work\n"
                                  << "stages: {heights: {roof: percentile, roof_percentile: 90}}\n";
  const Output run = shell(std::string(LODFORGE_BINARY) + " run " + (dir / "job.yaml").string());
  ASSERT_EQ(run.code, 0) << run.output;
  const std::string report = slurp_file(dir / "out" / "report.json");
  // Every building is written with LOD1; at most a few take the fallback footprint.
  const nlohmann::json counts = nlohmann::json::parse(report);
  EXPECT_EQ(counts.at("buildings"), 55);
  EXPECT_EQ(counts.at("lod1"), 55);
  EXPECT_GE(counts.at("ok").get<int>(), 52) << report;
  EXPECT_EQ(counts.at("ok").get<int>() + counts.at("fallback").get<int>(), 55);

  const auto gml = files_with(dir / "out" / "tiles", ".gml");
  ASSERT_GT(gml.size(), 5u);
  std::string all;
  for (const fs::path& p : gml) all += " " + p.string();
  const std::string schemas = test::schemas();
  if (!schemas.empty()) {
    const Output xml = shell("XML_CATALOG_FILES=" + schemas + "/citygml2-schemas/catalog.xml xmllint --noout --nonet --schema " + schemas +
                             "/citygml2-schemas/citygml/profiles/base/2.0/CityGML.xsd" + all);
    EXPECT_EQ(xml.code, 0) << xml.output;
    for (const fs::path& p : gml) EXPECT_NE(xml.output.find(p.string() + " validates"), std::string::npos) << p;

    std::string cityjson;
    for (const fs::path& p : files_with(dir / "out" / "tiles", ".city.json")) cityjson += " " + p.string();
    const Output cj = shell("/usr/bin/python3 " + std::string(LODFORGE_SOURCE_DIR) + "/scripts/validate/cityjson.py " + schemas +
                            "/cityjson2-schemas/cityjson.min.schema.json" + cityjson);
    EXPECT_EQ(cj.code, 0) << cj.output;
  }

  // OBJ: one object per building with LOD1, all faces referring to existing vertices. Each
  // object's faces share its vertices (issue 17: each point once per object), so that each object
  // is a closed mesh as mesh tools see it: every edge used once in each direction.
  int objects = 0;
  for (const fs::path& p : files_with(dir / "out" / "tiles", ".obj")) {
    std::ifstream in(p);
    int vertices = 0;
    std::set<std::string> object_points;
    std::map<std::pair<int, int>, int> directed;  // this object's edges
    const auto check_closed = [&](const std::string& where) {
      for (const auto& [edge, n] : directed) {
        EXPECT_EQ(n, 1) << where << ": edge " << edge.first << "-" << edge.second << " used " << n << " times";
        EXPECT_EQ(directed.count({edge.second, edge.first}), 1u) << where << ": edge " << edge.first << "-" << edge.second << " has no twin";
      }
      directed.clear();
    };
    std::string object;
    for (std::string line; std::getline(in, line);) {
      if (line.rfind("o ", 0) == 0) {
        check_closed(p.string() + " " + object);
        object = line;
        ++objects;
        object_points.clear();
      }
      if (line.rfind("v ", 0) == 0) {
        ++vertices;
        EXPECT_TRUE(object_points.insert(line).second) << p << " " << object << ": " << line << " written twice";
      }
      if (line.rfind("f ", 0) == 0) {
        std::istringstream f(line.substr(2));
        std::vector<int> ids;
        for (int id; f >> id;) {
          EXPECT_TRUE(id >= 1 && id <= vertices) << p << ": " << line;
          ids.push_back(id);
        }
        for (std::size_t k = 0; k < ids.size(); ++k) ++directed[{ids[k], ids[(k + 1) % ids.size()]}];
      }
    }
    check_closed(p.string() + " " + object);
  }
  EXPECT_EQ(objects, 55);
  // Each OBJ's origin (header) is the one the tile index records for its tile.
  std::map<std::string, nlohmann::json> origins;  // tile -> its origin in the index
  const nlohmann::json index = nlohmann::json::parse(slurp_file(dir / "out" / "tile_index.geojson"));
  for (const auto& f : index.at("features"))
    origins[f.at("properties").at("tile").get<std::string>()] = f.at("properties").at("origin");
  for (const fs::path& p : files_with(dir / "out" / "tiles", ".obj")) {
    std::ifstream in(p);
    std::string line;
    std::getline(in, line);
    std::getline(in, line);
    double ox = 0, oy = 0;
    std::istringstream(line.substr(std::string("# origin ").size())) >> ox >> oy;
    const std::string tile = p.filename().string().substr(0, 11);
    ASSERT_TRUE(origins.count(tile)) << tile;
    EXPECT_DOUBLE_EQ(origins[tile].at(0).get<double>(), ox) << tile;
    EXPECT_DOUBLE_EQ(origins[tile].at(1).get<double>(), oy) << tile;
  }

  // A quick-look picture per tile with buildings: the tile's size, outlines drawn in red.
  for (const fs::path& p : gml) {
    const fs::path png = fs::path(p).replace_extension(".png");
    const cv::Mat image = cv::imread(png.string());
    ASSERT_FALSE(image.empty()) << png;
    EXPECT_LE(image.cols, 128);  // 64 m tiles at 0.5 m
    cv::Mat red;
    cv::inRange(image, cv::Scalar(0, 0, 150), cv::Scalar(120, 120, 255), red);
    EXPECT_GT(cv::countNonZero(red), 10) << png;
  }
  if (schemas.empty()) GTEST_SKIP() << test::kNoSchemas;  // (everything above was checked)
}

TEST_F(ModelFiles, BuildingWithoutHeightsIsReportedAndStillWrittenAsLod0) {
  ASSERT_EQ(shell(std::string(LODFORGE_BINARY) + " synth --out " + (dir / "city").string() + " --size-m 150 --seed 4").code, 0);
  // A DSM that is nodata everywhere.
  GDALAllRegister();
  GDALDataset* seg = static_cast<GDALDataset*>(GDALOpen((dir / "city" / "seg_class.tif").c_str(), GA_ReadOnly));
  RasterMeta meta;
  seg->GetGeoTransform(meta.transform.c.data());
  meta.crs_wkt = seg->GetProjectionRef();
  meta.has_nodata = true;
  meta.nodata = -9999;
  const cv::Mat nodata(seg->GetRasterYSize(), seg->GetRasterXSize(), CV_32F, cv::Scalar(-9999));
  GDALClose(seg);
  write_geotiff((dir / "empty_dsm.tif").string(), {nodata}, meta);
  std::ofstream(dir / "job.yaml") << "inputs:\n  segmentation: {path: city/seg_class.tif}\n  dsm: {path: empty_dsm.tif}\n"
                                  << "tiling: {tile_size_m: 1000}\noutput: {dir: out, formats: [citygml, gpkg]}\nwork_dir: work\n";
  const Output run = shell(std::string(LODFORGE_BINARY) + " run " + (dir / "job.yaml").string());
  ASSERT_EQ(run.code, 0) << run.output;
  const nlohmann::json report = nlohmann::json::parse(slurp_file(dir / "out" / "report.json"));
  EXPECT_EQ(report.at("lod1"), 0) << report;
  ASSERT_FALSE(report.at("failed_buildings").empty()) << report;
  for (const auto& failed : report.at("failed_buildings")) {
    EXPECT_EQ(failed.at("stage"), "heights") << failed;
    EXPECT_EQ(failed.at("reason"), "no valid DSM value inside the footprint (LOD0 only)") << failed;
  }
  const std::string gml = slurp_file(dir / "out" / "tiles" / "r0000_c0000.gml");
  const auto count = [&gml](const std::string& what) {
    std::size_t n = 0;
    for (std::size_t at = gml.find(what); at != std::string::npos; at = gml.find(what, at + 1)) ++n;
    return n;
  };
  EXPECT_GT(count("<bldg:lod0FootPrint>"), 5u);
  EXPECT_EQ(count("<bldg:lod1Solid>"), 0u);
  EXPECT_EQ(count("<gen:value>lod0_only</gen:value>"), count("<bldg:Building "));
}

}  // namespace
}  // namespace lodforge

namespace lodforge {
namespace {

TEST_F(ModelFiles, DsmOnAnotherGridIsResampledOrRefusedAsConfigured) {
  const std::string data = test::test_data();
  const std::string dsm = data + "/delft-ahn3-bgt/derived/dsm_50cm.tif";
  // The same DSM at 1 m pixels with a shifted origin: another grid.
  const Output warp = shell("gdalwarp -q -tr 1 1 -te 84810 447415 85070 447640 -r average " + dsm + " " + (dir / "dsm_1m.tif").string());
  ASSERT_EQ(warp.code, 0) << warp.output;
  auto job = [&](const std::string& name, const std::string& raster, const std::string& extra) {
    std::ofstream(dir / (name + ".yaml")) << "inputs:\n  segmentation: {path: " << data << "/delft-ahn3-bgt/derived/top_class_50cm.tif}\n"
                                          << "  dsm: {path: " << raster << "}\n" << extra
                                          << "tiling: {tile_size_m: 1000}\noutput: {dir: " << name << "_out, formats: [gpkg]}\nwork_dir: " << name << "_work\n";
    return (dir / (name + ".yaml")).string();
  };
  const Output refused = shell(std::string(LODFORGE_BINARY) + " run " + job("strict", (dir / "dsm_1m.tif").string(), "  on_grid_mismatch: error\n"));
  EXPECT_EQ(refused.code, 1);
  EXPECT_NE(refused.output.find("inputs.dsm.path: '" + (dir / "dsm_1m.tif").string() + "': is on another grid"), std::string::npos) << refused.output;
  EXPECT_FALSE(fs::exists(dir / "strict_out" / "report.json"));

  ASSERT_EQ(shell(std::string(LODFORGE_BINARY) + " run " + job("same", dsm, "")).code, 0);
  const Output resampled = shell(std::string(LODFORGE_BINARY) + " run " + job("warped", (dir / "dsm_1m.tif").string(), ""));
  ASSERT_EQ(resampled.code, 0) << resampled.output;
  EXPECT_NE(resampled.output.find("resampled onto the segmentation's grid"), std::string::npos) << resampled.output;
  // Roof heights from the resampled DSM stay close to those from the original.
  auto roofs = [](const fs::path& file) {
    GDALAllRegister();
    std::map<long, double> out;
    GDALDataset* d = static_cast<GDALDataset*>(GDALOpenEx(file.c_str(), GDAL_OF_VECTOR, nullptr, nullptr, nullptr));
    EXPECT_NE(d, nullptr) << file;
    if (!d) return out;
    for (auto& f : *d->GetLayer(0)) out[long(f->GetFieldAsInteger64("id"))] = f->GetFieldAsDouble("roof_height");
    GDALClose(d);
    return out;
  };
  const auto a = roofs(dir / "same_out" / "tiles" / "r0000_c0000.gpkg"), b = roofs(dir / "warped_out" / "tiles" / "r0000_c0000.gpkg");
  ASSERT_EQ(a.size(), b.size());
  std::vector<double> differences;
  for (const auto& [id, roof] : a) differences.push_back(std::abs(roof - b.at(id)));
  std::sort(differences.begin(), differences.end());
  EXPECT_LT(differences[differences.size() / 2], 0.5);
}

}  // namespace
}  // namespace lodforge

namespace lodforge {
namespace {

// Absolute OBJ vertices (mm) as a sorted list.
std::vector<std::array<long long, 3>> obj_vertices(const fs::path& file) {
  std::ifstream in(file);
  double ox = 0, oy = 0;
  std::vector<std::array<long long, 3>> out;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("# origin ", 0) == 0) std::istringstream(line.substr(9)) >> ox >> oy;
    if (line.rfind("v ", 0) == 0) {
      double x, y, z;
      std::istringstream(line.substr(2)) >> x >> y >> z;
      out.push_back({std::llround((x + ox) * 1000), std::llround((y + oy) * 1000), std::llround(z * 1000)});
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());  // distinct points (triangles repeat them)
  return out;
}

TEST_F(ModelFiles, DsmOnTheSameGridInAnotherCrsIsRefusedBeforeAnyOutput) {
  // The rasters' CRS are compared while the first tile is processed (reading a CRS starts PROJ);
  // a DSM with the very grid numbers but another CRS must still stop the run before any file.
  const std::string data = test::test_data();
  const Output relabel = shell("gdal_translate -q -a_srs EPSG:32631 " + data + "/delft-ahn3-bgt/derived/dsm_50cm.tif " + (dir / "dsm_utm.tif").string());
  ASSERT_EQ(relabel.code, 0) << relabel.output;
  std::ofstream(dir / "crs.yaml") << "inputs:\n  segmentation: {path: " << data << "/delft-ahn3-bgt/derived/top_class_50cm.tif}\n"
                                  << "  dsm: {path: " << (dir / "dsm_utm.tif").string() << "}\n  on_grid_mismatch: error\n"
                                  << "tiling: {tile_size_m: 1000}\noutput: {dir: crs_out}\nwork_dir: crs_work\n";
  const Output refused = shell(std::string(LODFORGE_BINARY) + " run " + (dir / "crs.yaml").string() + " --threads 2");
  EXPECT_EQ(refused.code, 1) << refused.output;
  EXPECT_NE(refused.output.find("inputs.dsm.path: '" + (dir / "dsm_utm.tif").string() + "': is on another grid and CRS"), std::string::npos)
      << refused.output;
  std::vector<std::string> written;
  for (const auto& entry : fs::recursive_directory_iterator(dir / "crs_out"))
    if (entry.is_regular_file()) written.push_back(entry.path().string());
  EXPECT_TRUE(written.empty()) << written.front();
}

// Issue 17: glTF 2.0 (.glb) per tile and merged, for web viewers and Blender. Each tile's file
// holds its LOD1 blocks (one mesh each, as many as the OBJ's objects) at the OBJ's very points
// (glTF frame and origin undone, to the millimetre), each mesh closed (every edge once in each
// direction); read back by tinygltf and checked against the GLB layout rules by
// scripts/validate/glb.py; the merged file has every block, its tiles placed by their origins.
TEST_F(ModelFiles, GltfHoldsTheObjBlocksClosedAndValidates) {
  const std::string data = test::test_data();
  std::ofstream(dir / "gltf.yaml") << "inputs:\n  segmentation: {path: " << data << "/delft-ahn3-bgt/derived/top_class_50cm.tif}\n"
                                   << "  dsm: {path: " << data << "/delft-ahn3-bgt/derived/dsm_50cm.tif}\n"
                                   << "tiling: {tile_size_m: 64}\noutput: {dir: gltf_out, formats: [gltf, obj]}\nwork_dir: gltf_work\n";
  ASSERT_EQ(shell(std::string(LODFORGE_BINARY) + " run " + (dir / "gltf.yaml").string()).code, 0);
  ASSERT_EQ(shell(std::string(LODFORGE_BINARY) + " merge " + (dir / "gltf_out").string()).code, 0);
  tinygltf::TinyGLTF io;
  std::size_t blocks = 0;
  std::string all;
  for (const fs::path& glb : files_with(dir / "gltf_out" / "tiles", ".glb")) {
    all += " " + glb.string();
    tinygltf::Model model;
    std::string error, warning;
    ASSERT_TRUE(io.LoadBinaryFromFile(&model, &error, &warning, glb.string())) << glb << ": " << error;
    const tinygltf::Value& origin = model.asset.extras.Get("origin");
    ASSERT_TRUE(origin.IsArray()) << glb;
    const double ox = origin.Get(0).GetNumberAsDouble(), oy = origin.Get(1).GetNumberAsDouble();
    fs::path obj = glb;
    obj.replace_extension(".obj");
    std::size_t objects = 0;
    for (std::ifstream in(obj); !in.eof();) {
      std::string line;
      std::getline(in, line);
      objects += line.rfind("o ", 0) == 0;
    }
    EXPECT_EQ(model.meshes.size(), objects) << glb;
    blocks += model.meshes.size();
    std::vector<std::array<long long, 3>> points;
    for (const tinygltf::Mesh& mesh : model.meshes) {
      ASSERT_EQ(mesh.primitives.size(), 1u);
      const tinygltf::Primitive& p = mesh.primitives[0];
      const tinygltf::Accessor& positions = model.accessors[p.attributes.at("POSITION")];
      const tinygltf::Accessor& indices = model.accessors[p.indices];
      ASSERT_EQ(positions.componentType, TINYGLTF_COMPONENT_TYPE_FLOAT);
      ASSERT_EQ(indices.componentType, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT);
      const auto& pv = model.bufferViews[positions.bufferView];
      const auto& iv = model.bufferViews[indices.bufferView];
      const auto* xyz = reinterpret_cast<const float*>(model.buffers[pv.buffer].data.data() + pv.byteOffset + positions.byteOffset);
      const auto* ids = reinterpret_cast<const std::uint32_t*>(model.buffers[iv.buffer].data.data() + iv.byteOffset + indices.byteOffset);
      for (std::size_t v = 0; v < positions.count; ++v)  // glTF (x, height, -y) back to the map
        points.push_back({std::llround((xyz[3 * v] + ox) * 1000), std::llround((oy - xyz[3 * v + 2]) * 1000), std::llround(xyz[3 * v + 1] * 1000)});
      ASSERT_EQ(indices.count % 3, 0u);
      std::map<std::pair<std::uint32_t, std::uint32_t>, int> directed;
      for (std::size_t t = 0; t < indices.count; t += 3)
        for (int k = 0; k < 3; ++k) directed[{ids[t + k], ids[t + (k + 1) % 3]}]++;
      for (const auto& [edge, n] : directed) {
        EXPECT_EQ(n, 1) << glb << " " << mesh.name;
        EXPECT_EQ(directed.count({edge.second, edge.first}), 1u) << glb << " " << mesh.name << ": an edge without its twin";
      }
    }
    // The same points (single precision in metres from the origin: within a millimetre).
    std::sort(points.begin(), points.end());
    points.erase(std::unique(points.begin(), points.end()), points.end());
    const auto expected = obj_vertices(obj);
    const std::set<std::array<long long, 3>> obj_points(expected.begin(), expected.end());
    EXPECT_EQ(points.size(), expected.size()) << glb;
    for (const auto& q : points) {
      bool found = false;
      for (int d = 0; d < 27 && !found; ++d) found = obj_points.count({q[0] + d % 3 - 1, q[1] + d / 3 % 3 - 1, q[2] + d / 9 - 1}) > 0;
      EXPECT_TRUE(found) << glb << ": " << q[0] << " " << q[1] << " " << q[2] << " is no OBJ point";
    }
  }
  EXPECT_EQ(blocks, 55u);
  const fs::path merged = dir / "gltf_out" / "merged" / "lodforge.glb";
  tinygltf::Model model;
  std::string error, warning;
  ASSERT_TRUE(io.LoadBinaryFromFile(&model, &error, &warning, merged.string())) << error;
  EXPECT_EQ(model.meshes.size(), blocks);
  const Output layout = shell("/usr/bin/python3 " + std::string(LODFORGE_SOURCE_DIR) + "/scripts/validate/glb.py" + all + " " + merged.string());
  EXPECT_EQ(layout.code, 0) << layout.output;
}

// Issue 17: output.crs declares the inputs' CRS with a vertical one; one that is not an EPSG code,
// or whose horizontal part is not the inputs' CRS (nothing is reprojected), stops the run before
// any output, naming the key.
TEST_F(ModelFiles, AnOutputCrsThatIsNotTheInputsIsRefusedBeforeAnyOutput) {
  const std::string data = test::test_data();
  const auto run = [&](const std::string& name, const std::string& crs) {
    std::ofstream(dir / (name + ".yaml")) << "inputs:\n  segmentation: {path: " << data << "/delft-ahn3-bgt/derived/top_class_50cm.tif}\n"
                                          << "tiling: {tile_size_m: 1000}\noutput: {dir: " << name << "_out, crs: \"" << crs << "\"}\n"
                                          << "work_dir: " << name << "_work\n";
    return shell(std::string(LODFORGE_BINARY) + " run " + (dir / (name + ".yaml")).string() + " --threads 2");
  };
  const Output utm = run("utm", "EPSG:32631");
  EXPECT_EQ(utm.code, 1) << utm.output;
  EXPECT_NE(utm.output.find("output.crs: 'EPSG:32631' is horizontally WGS 84 / UTM zone 31N (EPSG:32631), but the inputs are in "
                            "Amersfoort / RD New (EPSG:28992)"), std::string::npos) << utm.output;
  const Output bad = run("bad", "RD+NAP");
  EXPECT_EQ(bad.code, 1) << bad.output;
  EXPECT_NE(bad.output.find("output.crs: 'RD+NAP' is not an EPSG code GDAL knows"), std::string::npos) << bad.output;
  const Output vertical = run("vertical", "EPSG:5709");
  EXPECT_EQ(vertical.code, 1) << vertical.output;
  EXPECT_NE(vertical.output.find("output.crs: 'EPSG:5709' (NAP height) has no horizontal CRS"), std::string::npos) << vertical.output;
  for (const char* out : {"utm_out", "bad_out", "vertical_out"}) {
    std::vector<std::string> written;
    if (fs::exists(dir / out))
      for (const auto& entry : fs::recursive_directory_iterator(dir / out))
        if (entry.is_regular_file()) written.push_back(entry.path().string());
    EXPECT_TRUE(written.empty()) << written.front();
  }
  const Output same = run("same", "EPSG:28992");  // the inputs' own CRS: accepted
  EXPECT_EQ(same.code, 0) << same.output;
}

// Issue 17: CityJSON Text Sequences per tile and merged: one feature per building, the same
// buildings and coordinates as the CityJSON files, valid against the CityJSONFeature schema.
TEST_F(ModelFiles, CityJsonSeqHoldsTheSameBuildingsAsCityJsonAndValidates) {
  const std::string data = test::test_data();
  std::ofstream(dir / "seq.yaml") << "inputs:\n  segmentation: {path: " << data << "/delft-ahn3-bgt/derived/top_class_50cm.tif}\n"
                                  << "  dsm: {path: " << data << "/delft-ahn3-bgt/derived/dsm_50cm.tif}\n"
                                  << "tiling: {tile_size_m: 64}\noutput: {dir: seq_out, formats: [cityjson, cityjsonseq]}\nwork_dir: seq_work\n";
  Output r = shell(std::string(LODFORGE_BINARY) + " run " + (dir / "seq.yaml").string());
  ASSERT_EQ(r.code, 0) << r.output;
  r = shell(std::string(LODFORGE_BINARY) + " merge " + (dir / "seq_out").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const fs::path merged = dir / "seq_out" / "merged";
  ASSERT_TRUE(fs::exists(merged / "lodforge.city.jsonl"));
  // Every building of the CityJSON, with the same real coordinates (mm), in its feature.
  const std::string compare = R"py(
import json, sys
def points(translate, vertices, o):
    out = []
    def walk(b):
        if isinstance(b, list):
            for x in b: walk(x)
        else:
            v = vertices[b]; out.append(tuple(round(translate[k] * 1000) + v[k] for k in range(3)))
    for g in o["geometry"]: walk(g["boundaries"])
    return sorted(out)
city = json.load(open(sys.argv[1]))
lines = open(sys.argv[2]).read().splitlines()
head = json.loads(lines[0])
assert head["type"] == "CityJSON" and head["CityObjects"] == {} and head["vertices"] == []
seq = {}
for line in lines[1:]:
    f = json.loads(line)
    objects = f["CityObjects"]
    # The building first, then its LoD1.3 parts (its children), each naming it as its parent.
    assert f["type"] == "CityJSONFeature" and list(objects)[0] == f["id"], f["id"]
    assert list(objects)[1:] == objects[f["id"]].get("children", []), f["id"]
    assert all(objects[c]["type"] == "BuildingPart" and objects[c]["parents"] == [f["id"]] for c in list(objects)[1:]), f["id"]
    for i, o in objects.items(): seq[i] = points(head["transform"]["translate"], f["vertices"], o)
whole = {i: points(city["transform"]["translate"], city["vertices"], o) for i, o in city["CityObjects"].items()}
assert sorted(seq) == sorted(whole), (len(seq), len(whole))
for i in whole: assert seq[i] == whole[i], i
print("same", len(lines) - 1, "buildings,", len(seq) - len(lines) + 1, "parts")
)py";
  std::ofstream(dir / "compare.py") << compare;
  r = shell("/usr/bin/python3 " + (dir / "compare.py").string() + " " + (merged / "lodforge.city.json").string() + " " +
            (merged / "lodforge.city.jsonl").string());
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("same 55 buildings"), std::string::npos) << r.output;
  const std::string schemas = test::schemas();
  if (schemas.empty()) GTEST_SKIP() << test::kNoSchemas;
  std::string files = " " + (merged / "lodforge.city.jsonl").string();
  for (const auto& e : fs::directory_iterator(dir / "seq_out" / "tiles"))
    if (e.path().string().size() > 6 && e.path().string().substr(e.path().string().size() - 6) == ".jsonl") files += " " + e.path().string();
  r = shell("/usr/bin/python3 " + std::string(LODFORGE_SOURCE_DIR) + "/scripts/validate/cityjsonseq.py " + schemas + "/cityjson2-schemas" + files);
  EXPECT_EQ(r.code, 0) << r.output;
}

TEST_F(ModelFiles, MergedTilesEqualOneTileAndValidate) {
  const std::string data = test::test_data();
  auto job = [&](const std::string& name, double tile) {
    std::ofstream(dir / (name + ".yaml")) << "inputs:\n  segmentation: {path: " << data << "/delft-ahn3-bgt/derived/top_class_50cm.tif}\n"
                                          << "  dsm: {path: " << data << "/delft-ahn3-bgt/derived/dsm_50cm.tif}\n"
                                          << "tiling: {tile_size_m: " << tile << "}\noutput: {dir: " << name << "_out, crs: \"EPSG:7415\"}\n"
                                          << "work_dir: " << name << "_work\n";
    const Output r = shell(std::string(LODFORGE_BINARY) + " run " + (dir / (name + ".yaml")).string());
    EXPECT_EQ(r.code, 0) << r.output;
  };
  job("tiled", 64);
  job("whole", 1000);
  const Output merge = shell(std::string(LODFORGE_BINARY) + " merge " + (dir / "tiled_out").string());
  ASSERT_EQ(merge.code, 0) << merge.output;
  const fs::path merged = dir / "tiled_out" / "merged";
  EXPECT_EQ(test::gpkg_footprints(merged / "lodforge.gpkg"), test::gpkg_footprints(dir / "whole_out" / "tiles" / "r0000_c0000.gpkg"));
  // The same points to the millimetre (each file rounds relative to its own origin).
  const auto merged_points = obj_vertices(merged / "lodforge.obj"), whole_points = obj_vertices(dir / "whole_out" / "tiles" / "r0000_c0000.obj");
  ASSERT_EQ(merged_points.size(), whole_points.size());
  for (std::size_t i = 0; i < merged_points.size(); ++i)
    for (int k = 0; k < 3; ++k) EXPECT_LE(std::llabs(merged_points[i][k] - whole_points[i][k]), 1) << i;
  const std::string schemas = test::schemas();
  if (!schemas.empty()) {
    const Output xml = shell("XML_CATALOG_FILES=" + schemas + "/citygml2-schemas/catalog.xml xmllint --noout --nonet --schema " + schemas +
                             "/citygml2-schemas/citygml/profiles/base/2.0/CityGML.xsd " + (merged / "lodforge.gml").string());
    EXPECT_EQ(xml.code, 0) << xml.output;
    const Output cj = shell("/usr/bin/python3 " + std::string(LODFORGE_SOURCE_DIR) + "/scripts/validate/cityjson.py " + schemas +
                            "/cityjson2-schemas/cityjson.min.schema.json " + (merged / "lodforge.city.json").string());
    EXPECT_EQ(cj.code, 0) << cj.output;
  }
  const std::string gml = slurp_file(merged / "lodforge.gml"), whole = slurp_file(dir / "whole_out" / "tiles" / "r0000_c0000.gml");
  const auto buildings = [](const std::string& text) {
    std::size_t n = 0;
    for (std::size_t at = text.find("<bldg:Building "); at != std::string::npos; at = text.find("<bldg:Building ", at + 1)) ++n;
    return n;
  };
  EXPECT_EQ(buildings(gml), 55u);
  EXPECT_EQ(buildings(gml), buildings(whole));
  EXPECT_EQ(gml.find("<?xml"), gml.rfind("<?xml"));  // one header
  // The merged GeoPackage has the LOD1 blocks beside the footprints (issue 17): a MultiPolygon Z
  // per building with LOD1, its faces at its ground and roof heights.
  {
    GDALAllRegister();
    GDALDataset* d = static_cast<GDALDataset*>(GDALOpenEx((merged / "lodforge.gpkg").c_str(), GDAL_OF_VECTOR, nullptr, nullptr, nullptr));
    ASSERT_NE(d, nullptr);
    OGRLayer* blocks = d->GetLayerByName("lod1");
    ASSERT_NE(blocks, nullptr);
    EXPECT_EQ(blocks->GetGeomType(), wkbMultiPolygon25D);
    long n = 0;
    for (auto& f : *blocks) {
      ++n;
      const double ground = f->GetFieldAsDouble("ground_height"), roof = f->GetFieldAsDouble("roof_height");
      const auto* faces = f->GetGeometryRef()->toMultiPolygon();
      EXPECT_GE(faces->getNumGeometries(), 5);  // bottom, top, three walls at least
      OGREnvelope3D box;
      faces->getEnvelope(&box);
      EXPECT_NEAR(box.MinZ, ground, 1e-6);
      EXPECT_NEAR(box.MaxZ, roof, 1e-6);
    }
    EXPECT_EQ(n, 55);
    GDALClose(d);
  }
  // Heights as 3DBAG publishes them (issue 18), in the GeoPackage and in CityJSON: the LOD1 roof
  // is the 70th percentile by default, between the minimum and the maximum; the volume is the
  // block's; the coverage a share.
  {
    GDALDataset* d = static_cast<GDALDataset*>(GDALOpenEx((merged / "lodforge.gpkg").c_str(), GDAL_OF_VECTOR, nullptr, nullptr, nullptr));
    ASSERT_NE(d, nullptr);
    long with_heights = 0;
    for (auto& f : *d->GetLayerByName("footprints")) {
      if (f->IsFieldNull(f->GetFieldIndex("roof_height"))) continue;
      ++with_heights;
      const double roof = f->GetFieldAsDouble("roof_height"), ground = f->GetFieldAsDouble("ground_height");
      EXPECT_DOUBLE_EQ(roof, f->GetFieldAsDouble("roof_70p"));
      EXPECT_LE(f->GetFieldAsDouble("roof_min"), f->GetFieldAsDouble("roof_50p"));
      EXPECT_LE(f->GetFieldAsDouble("roof_50p"), f->GetFieldAsDouble("roof_70p"));
      EXPECT_LE(f->GetFieldAsDouble("roof_70p"), f->GetFieldAsDouble("roof_max"));
      EXPECT_NEAR(f->GetFieldAsDouble("volume_lod1"), f->GetFieldAsDouble("area_m2") * (roof - ground), 1e-6 * f->GetFieldAsDouble("volume_lod1"));
      EXPECT_GT(f->GetFieldAsDouble("dsm_coverage"), 0.0);
      EXPECT_LE(f->GetFieldAsDouble("dsm_coverage"), 1.0);
      EXPECT_GE(f->GetFieldAsInteger("dsm_cells"), 1);
    }
    GDALClose(d);
    EXPECT_EQ(with_heights, 55);
    const nlohmann::json objects = nlohmann::json::parse(slurp_file(merged / "lodforge.city.json")).at("CityObjects");
    for (const auto& [id, object] : objects.items())
      for (const char* name : {"ground_height", "roof_height", "roof_min", "roof_50p", "roof_70p", "roof_max", "volume_lod1", "dsm_coverage", "dsm_cells"})
        EXPECT_TRUE(object.at("attributes").contains(name)) << id << " " << name;
  }
  // The merged files name the run, not their first tile.
  EXPECT_NE(gml.find("<gml:name>lodforge, merged from "), std::string::npos);
  EXPECT_EQ(gml.find("<gml:name>lodforge tile "), std::string::npos);
  const std::string cityjson = slurp_file(merged / "lodforge.city.json"), whole_cityjson = slurp_file(dir / "whole_out" / "tiles" / "r0000_c0000.city.json");
  const nlohmann::json merged_json = nlohmann::json::parse(cityjson), whole_json = nlohmann::json::parse(whole_cityjson);
  EXPECT_EQ(merged_json.at("metadata").at("title"), "lodforge, merged from 16 tiles");
  // The CRS the job declares (output.crs: RD New + NAP height, issue 17), in each format's form.
  EXPECT_NE(gml.find("srsName=\"urn:ogc:def:crs:EPSG::7415\""), std::string::npos);
  EXPECT_EQ(gml.find("srsName=\"EPSG:"), std::string::npos);
  EXPECT_EQ(merged_json.at("metadata").at("referenceSystem"), "https://www.opengis.net/def/crs/EPSG/0/7415");
  EXPECT_NE(slurp_file(merged / "lodforge.obj").find("CRS EPSG:7415"), std::string::npos);
  // The merged extent (the union of the tiles') is the one-tile run's, and holds every vertex.
  const std::regex envelope(R"(<gml:lowerCorner>([^<]*)</gml:lowerCorner><gml:upperCorner>([^<]*)</gml:upperCorner>)");
  std::smatch merged_box, whole_box;
  ASSERT_TRUE(std::regex_search(gml, merged_box, envelope));
  ASSERT_TRUE(std::regex_search(whole, whole_box, envelope));
  EXPECT_EQ(merged_box[1], whole_box[1]);
  EXPECT_EQ(merged_box[2], whole_box[2]);
  EXPECT_EQ(merged_json.at("metadata").at("geographicalExtent"), whole_json.at("metadata").at("geographicalExtent"));
  long merged_buildings = 0;
  for (const auto& [id, object] : merged_json.at("CityObjects").items()) merged_buildings += object.at("type") == "Building";
  EXPECT_EQ(merged_buildings, 55);
  std::istringstream lower(merged_box[1].str()), upper(merged_box[2].str());
  double box[6];
  lower >> box[0] >> box[1] >> box[2];
  upper >> box[3] >> box[4] >> box[5];
  const std::regex pos(R"(<gml:posList>([^<]*)</gml:posList>)");
  for (std::sregex_iterator it(gml.begin(), gml.end(), pos), stop; it != stop; ++it) {
    std::istringstream numbers((*it)[1].str());
    double v[3];
    for (int k = 0; numbers >> v[k % 3]; ++k)
      if (k % 3 == 2)
        for (int c = 0; c < 3; ++c) {
          EXPECT_GE(v[c], box[c] - 1e-3);
          EXPECT_LE(v[c], box[c + 3] + 1e-3);
        }
  }
  // The whole area at a glance (issue 17): overview.tif, a georeferenced COG on the segmentation's
  // grid (no finer than it), with every building's whole outline drawn: a coloured pixel within
  // two of each footprint vertex, tiles' borders or not; the same bytes from a second merge.
  {
    GDALAllRegister();
    GDALDataset* seg = static_cast<GDALDataset*>(GDALOpen((data + "/delft-ahn3-bgt/derived/top_class_50cm.tif").c_str(), GA_ReadOnly));
    GDALDataset* overview = static_cast<GDALDataset*>(GDALOpen((merged / "overview.tif").c_str(), GA_ReadOnly));
    ASSERT_NE(seg, nullptr);
    ASSERT_NE(overview, nullptr);
    const char* layout = overview->GetMetadataItem("LAYOUT", "IMAGE_STRUCTURE");
    EXPECT_STREQ(layout ? layout : "", "COG");
    double a[6], b[6];
    seg->GetGeoTransform(a);
    overview->GetGeoTransform(b);
    // The segmentation's pixels (Delft is smaller than 4,096 of them), its extent grown by whole
    // pixels to hold the footprints that reach past its edge.
    for (int k : {1, 2, 4, 5}) EXPECT_DOUBLE_EQ(a[k], b[k]) << k;
    const double columns = (a[0] - b[0]) / a[1], rows = (a[3] - b[3]) / a[5];
    EXPECT_NEAR(columns, std::round(columns), 1e-6);
    EXPECT_NEAR(rows, std::round(rows), 1e-6);
    EXPECT_GE(columns, 0);
    EXPECT_GE(rows, 0);
    EXPECT_GE(overview->GetRasterXSize(), seg->GetRasterXSize() + columns);
    EXPECT_GE(overview->GetRasterYSize(), seg->GetRasterYSize() + rows);
    ASSERT_NE(overview->GetSpatialRef(), nullptr);
    EXPECT_STREQ(overview->GetSpatialRef()->GetAuthorityCode(nullptr), "28992");
    const int w = overview->GetRasterXSize(), h = overview->GetRasterYSize();
    std::vector<std::uint8_t> rgb(std::size_t(3) * w * h);
    ASSERT_EQ(overview->RasterIO(GF_Read, 0, 0, w, h, rgb.data(), w, h, GDT_Byte, 3, nullptr, 3, 3 * w, 1, nullptr), CE_None);
    GDALClose(overview);
    GDALClose(seg);
    const auto coloured = [&](int x, int y) {
      const std::uint8_t* p = &rgb[3 * (std::size_t(y) * w + x)];
      return p[0] > 150 && std::min(p[1], p[2]) < 120;  // red, yellow or magenta: not the grey hillshade
    };
    GDALDataset* d = static_cast<GDALDataset*>(GDALOpenEx((merged / "lodforge.gpkg").c_str(), GDAL_OF_VECTOR, nullptr, nullptr, nullptr));
    ASSERT_NE(d, nullptr);
    int vertices = 0, drawn = 0;
    for (auto& f : *d->GetLayerByName("footprints")) {
      const OGRPolygon* polygon = f->GetGeometryRef()->toPolygon();
      for (const OGRPoint& v : *polygon->getExteriorRing()) {
        const int x = int((v.getX() - b[0]) / b[1]), y = int((v.getY() - b[3]) / b[5]);
        bool near = false;
        for (int dy = -2; dy <= 2; ++dy)
          for (int dx = -2; dx <= 2; ++dx) near = near || (x + dx >= 0 && y + dy >= 0 && x + dx < w && y + dy < h && coloured(x + dx, y + dy));
        ++vertices;
        drawn += near;
      }
    }
    GDALClose(d);
    EXPECT_GT(vertices, 200);
    EXPECT_EQ(drawn, vertices);
    // report.html: well-formed HTML with the run's numbers, every failed building and the picture.
    const nlohmann::json report = nlohmann::json::parse(slurp_file(dir / "tiled_out" / "report.json"));
    const std::string html = slurp_file(merged / "report.html");
    const Output lint = shell("xmllint --html --noout " + (merged / "report.html").string());
    EXPECT_EQ(lint.code, 0) << lint.output;
    EXPECT_NE(html.find("<tr><th>buildings</th><td class=\"n\">" + report.at("buildings").dump() + "</td></tr>"), std::string::npos);
    EXPECT_NE(html.find("<img width=\"" + std::to_string(w) + "\" height=\"" + std::to_string(h) + "\""), std::string::npos);
    EXPECT_NE(html.find("src=\"data:image/jpeg;base64,"), std::string::npos);
    EXPECT_NE(html.find("<h2>Failed buildings (" + std::to_string(report.at("failed_buildings").size()) + ")</h2>"), std::string::npos);
    for (const auto& failed : report.at("failed_buildings"))
      EXPECT_NE(html.find("<tr><td class=\"n\">" + failed.at("id").dump() + "</td>"), std::string::npos) << failed;
    EXPECT_EQ(report.at("slowest_buildings").size(), 20u);
    const std::string first = slurp_file(merged / "overview.tif");
    ASSERT_EQ(shell(std::string(LODFORGE_BINARY) + " merge " + (dir / "tiled_out").string() + " --formats obj").code, 0);
    EXPECT_TRUE(slurp_file(merged / "overview.tif") == first);
    ASSERT_EQ(shell(std::string(LODFORGE_BINARY) + " merge " + (dir / "whole_out").string() + " --overview-px 0").code, 0);
    EXPECT_FALSE(fs::exists(dir / "whole_out" / "merged" / "overview.tif"));
    EXPECT_FALSE(fs::exists(dir / "whole_out" / "merged" / "report.html"));
  }
  if (schemas.empty()) GTEST_SKIP() << test::kNoSchemas;  // (everything above was checked)
}

// Issue 17: merge parses the tiles (libxml2, nlohmann-json, OBJ line by line) and refuses what is
// not a lodforge tile, naming the file and line; a failed merge leaves nothing behind, and an
// earlier merge's files as they were.
TEST_F(ModelFiles, AMergeOfABrokenTileStopsNamingItAndLeavesNothingBehind) {
  const std::string data = test::test_data();
  std::ofstream(dir / "job.yaml") << "inputs:\n  segmentation: {path: " << data << "/delft-ahn3-bgt/derived/top_class_50cm.tif}\n"
                                  << "  dsm: {path: " << data << "/delft-ahn3-bgt/derived/dsm_50cm.tif}\n"
                                  << "tiling: {tile_size_m: 128}\noutput: {dir: out, formats: [citygml, cityjson, obj]}\nwork_dir: work\n";
  ASSERT_EQ(shell(std::string(LODFORGE_BINARY) + " run " + (dir / "job.yaml").string()).code, 0);
  const fs::path out = dir / "out", merged = out / "merged";
  ASSERT_EQ(shell(std::string(LODFORGE_BINARY) + " merge " + out.string()).code, 0);
  const std::string good_gml = slurp_file(merged / "lodforge.gml"), good_json = slurp_file(merged / "lodforge.city.json");
  // A tile broken after the run (its fingerprint in the index updated, so that only parsing can tell).
  const auto break_tile = [&](const std::string& name, const std::string& from, const std::string& to) {
    const fs::path tile = out / "tiles" / name;
    std::string text = slurp_file(tile);
    const std::string old_print = file_fingerprint(tile.string());
    const std::size_t at = text.find(from);
    ASSERT_NE(at, std::string::npos) << name;
    text.replace(at, from.size(), to);
    std::ofstream(tile, std::ios::binary) << text;
    std::string index = slurp_file(out / "tile_index.geojson");
    index.replace(index.find(old_print), old_print.size(), file_fingerprint(tile.string()));
    std::ofstream(out / "tile_index.geojson", std::ios::binary) << index;
  };
  const auto merge = [&](const std::string& formats) { return shell(std::string(LODFORGE_BINARY) + " merge " + out.string() + " --formats " + formats); };
  break_tile("r0001_c0001.gml", "</bldg:Building>", "</bldg:Buildin>");
  Output r = merge("obj,citygml");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("r0001_c0001.gml': line "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("not well-formed XML"), std::string::npos) << r.output;
  break_tile("r0001_c0001.city.json", "\"vertices\": [", "\"vertices\": [[1, 2],");
  r = merge("cityjson");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("r0001_c0001.city.json': not a lodforge CityJSON tile"), std::string::npos) << r.output;
  break_tile("r0001_c0001.obj", "\nf ", "\nf 0 ");
  r = merge("obj");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("r0001_c0001.obj': line "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("'0' is not one of the"), std::string::npos) << r.output;
  // Nothing half-written: the earlier merge's files as they were, no temporaries.
  EXPECT_EQ(slurp_file(merged / "lodforge.gml"), good_gml);
  EXPECT_EQ(slurp_file(merged / "lodforge.city.json"), good_json);
  std::set<std::string> files;
  for (const auto& e : fs::directory_iterator(merged)) files.insert(e.path().filename().string());
  EXPECT_EQ(files, (std::set<std::string>{"lodforge.gml", "lodforge.city.json", "lodforge.obj", "overview.tif", "report.html"}));
  // An unknown format is refused before anything is merged.
  fs::remove_all(merged);
  r = merge("citygml,json");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("unknown format 'json'"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(merged / "lodforge.gml"));
}

}  // namespace
}  // namespace lodforge
