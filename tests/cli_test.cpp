#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <tuple>
#include <gdal_priv.h>
#include <ogrsf_frmts.h>

#include "eval/metrics.hpp"
#include "geometry/polygon.hpp"
#include "io/ogr_polygon.hpp"
#include "io/raster_writer.hpp"
#include "support/process.hpp"
#include "support/shapes.hpp"

namespace fs = std::filesystem;

namespace lodforge {
namespace {

using CommandRun = test::CommandOutput;
using test::lodforge;

class Cli : public ::testing::Test {
 protected:
  void SetUp() override { dir = test::fresh_test_directory("lodforge_cli"); }
  std::string path(const std::string& name) const { return (dir / name).string(); }
  fs::path dir;
};

TEST_F(Cli, MissingFileIsNamed) {
  const CommandRun r = lodforge("regularize --mask " + path("nope.tif") + " --out " + path("out.gpkg"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("nope.tif': file not found"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("out.gpkg")));
}

TEST_F(Cli, NotARaster) {
  std::ofstream(path("text.tif")) << "hello";
  const CommandRun r = lodforge("regularize --mask " + path("text.tif") + " --out " + path("out.gpkg"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("text.tif': not a raster GDAL can read"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("out.gpkg")));
}

TEST_F(Cli, NoGeoreference) {
  GDALAllRegister();
  GDALDataset* d = GetGDALDriverManager()->GetDriverByName("GTiff")->Create(path("plain.tif").c_str(), 8, 8, 1, GDT_Byte, nullptr);
  GDALClose(d);
  const CommandRun r = lodforge("regularize --mask " + path("plain.tif") + " --out " + path("out.gpkg"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("plain.tif': has no georeference"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("out.gpkg")));
}

// A mask in degrees (WGS 84) or in US feet is refused with the reprojection that fixes it (the UTM
// zone of its centre), by regularize and by a run, before any output is written; in metres it runs.
TEST_F(Cli, AMaskNotInMetresIsRefusedWithItsReprojection) {
  cv::Mat mask = cv::Mat::zeros(40, 40, CV_8U);
  mask(cv::Rect(10, 10, 20, 14)).setTo(6);
  RasterMeta degrees;  // Delft: UTM zone 31 north
  degrees.transform.c = {4.35, 1e-5, 0, 52.01, 0, -1e-5};
  degrees.crs_wkt = epsg_wkt(4326);
  write_geotiff(path("degrees.tif"), {mask}, degrees);
  RasterMeta feet;  // New York, Long Island: zone 18 north
  feet.transform.c = {1000000, 2, 0, 200000, 0, -2};
  feet.crs_wkt = epsg_wkt(2263);
  write_geotiff(path("feet.tif"), {mask}, feet);
  RasterMeta metres;
  metres.transform.c = {85000, 0.5, 0, 447000, 0, -0.5};
  metres.crs_wkt = epsg_wkt(28992);
  write_geotiff(path("metres.tif"), {mask}, metres);

  CommandRun r = lodforge("regularize --mask " + path("degrees.tif") + " --out " + path("d.gpkg"));
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("degrees.tif': is in WGS 84 (EPSG:4326), a geographic CRS, its coordinates in degrees"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("gdalwarp -t_srs EPSG:32631 -r near"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("d.gpkg")));
  r = lodforge("regularize --mask " + path("feet.tif") + " --out " + path("f.gpkg"));
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("(EPSG:2263), a CRS in US survey foot"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("gdalwarp -t_srs EPSG:32618 -r near"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("f.gpkg")));
  r = lodforge("regularize --mask " + path("metres.tif") + " --out " + path("m.gpkg"));
  EXPECT_EQ(r.code, 0) << r.output;
  RasterMeta wrong = metres;  // metres, but labelled WGS 84
  wrong.crs_wkt = epsg_wkt(4326);
  write_geotiff(path("wrong.tif"), {mask}, wrong);
  r = lodforge("regularize --mask " + path("wrong.tif") + " --out " + path("w.gpkg"));
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("wrong.tif': says it is in WGS 84 (EPSG:4326), in degrees, but its coordinates (85010.0, 446990.0) are not"),
            std::string::npos)
      << r.output;

  std::ofstream(path("job.yaml")) << "inputs: {segmentation: {path: degrees.tif}}\n"
                                  << "output: {dir: out, formats: [gpkg], quicklook: false}\nwork_dir: work\n";
  r = lodforge("run " + path("job.yaml") + " --progress none");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("inputs.segmentation.path: '" + path("degrees.tif") + "': is in WGS 84"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("out")));  // (refused before the output directory is made)
}

// eval measures in metres, every source in one CRS: footprints in degrees or in another CRS than
// the prediction's are refused, naming the file, both CRS and the ogr2ogr that fixes it.
TEST_F(Cli, EvalRefusesFootprintsInAnotherCrsOrInDegrees) {
  const auto square = [&](const std::string& name, const std::string& crs, double x, double y, double side) {
    std::ofstream(path(name)) << "{\"type\": \"FeatureCollection\", " << (crs.empty() ? "" : "\"crs\": {\"type\": \"name\", \"properties\": {\"name\": \"urn:ogc:def:crs:EPSG::" + crs + "\"}}, ")
                              << "\"features\": [{\"type\": \"Feature\", \"properties\": {}, \"geometry\": {\"type\": \"Polygon\", \"coordinates\": [["
                              << "[" << x << ", " << y << "], [" << x + side << ", " << y << "], [" << x + side << ", " << y + side << "], ["
                              << x << ", " << y + side << "], [" << x << ", " << y << "]]]}}]}";
  };
  square("rd.geojson", "28992", 85000, 447000, 10);
  square("rd_shifted.geojson", "28992", 85001, 447000, 10);
  square("utm.geojson", "32631", 585000, 5763000, 10);
  square("wgs84.geojson", "", 4.35, 52.01, 1e-4);
  CommandRun r = lodforge("eval --pred " + path("rd.geojson") + " --gt " + path("rd_shifted.geojson"));
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("overall IoU              0.8182"), std::string::npos) << r.output;  // 90 / 110
  r = lodforge("eval --pred " + path("rd.geojson") + " --gt " + path("utm.geojson") + " --json " + path("e.json"));
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("--gt '" + path("utm.geojson") + "': is in WGS 84 / UTM zone 31N (EPSG:32631), --pred in Amersfoort / RD New (EPSG:28992)"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("ogr2ogr -t_srs EPSG:28992 OUT IN"), std::string::npos) << r.output;
  r = lodforge("eval --pred " + path("rd.geojson") + " --gt " + path("rd.geojson") + " --aoi " + path("wgs84.geojson") + " --json " + path("e.json"));
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("--aoi '" + path("wgs84.geojson") + "': is in WGS 84 (EPSG:4326), a geographic CRS"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("ogr2ogr -t_srs EPSG:28992 OUT IN' (EPSG:28992: the CRS of the other inputs)"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("e.json")));
  // The same horizontal CRS with heights (RD New + NAP, as 3DBAG ships), and a GeoJSON without a
  // "crs" member holding RD coordinates (GDAL reads it as WGS 84): both scored, the latter with a word.
  square("rd_nap.geojson", "7415", 85001, 447000, 10);
  square("no_crs.geojson", "", 85001, 447000, 10);
  for (const char* gt : {"rd_nap.geojson", "no_crs.geojson"}) {
    r = lodforge("eval --pred " + path("rd.geojson") + " --gt " + path(gt));
    EXPECT_EQ(r.code, 0) << gt << r.output;
    EXPECT_NE(r.output.find("overall IoU              0.8182"), std::string::npos) << gt << r.output;
  }
  EXPECT_NE(r.output.find("its CRS, WGS 84 (EPSG:4326), is in degrees, but its coordinates (85001.0, 447000.0) are not: taken as in --pred's"),
            std::string::npos)
      << r.output;
}

TEST_F(Cli, EmptyMaskAndWrongBands) {
  RasterMeta meta;
  meta.transform.c = {1000, 0.5, 0, 2000, 0, -0.5};
  write_geotiff(path("empty.tif"), {cv::Mat::zeros(20, 20, CV_8U)}, meta);
  CommandRun r = lodforge("regularize --mask " + path("empty.tif") + " --out " + path("out.gpkg"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("empty.tif': no building pixel (value 6) in the raster; its band 1 holds 0 (100.0 %)"), std::string::npos) << r.output;
  // A network's binary mask (255 = building), read with the default class: the values it holds.
  cv::Mat binary = cv::Mat::zeros(20, 20, CV_8U);
  binary(cv::Rect(0, 0, 20, 5)).setTo(255);
  write_geotiff(path("binary.tif"), {binary}, meta);
  r = lodforge("regularize --mask " + path("binary.tif") + " --out " + path("out.gpkg"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("its band 1 holds 0 (75.0 %), 255 (25.0 %): select the buildings by their value (regularize --building-value V"),
            std::string::npos)
      << r.output;
  // An ISPRS colour mask read with a class value, then with another colour than its buildings'.
  cv::Mat red = cv::Mat::zeros(20, 20, CV_8U), blue = cv::Mat::zeros(20, 20, CV_8U);
  blue(cv::Rect(0, 0, 20, 5)).setTo(255);
  red(cv::Rect(0, 5, 20, 15)).setTo(255);
  write_geotiff(path("colours.tif"), {red, cv::Mat::zeros(20, 20, CV_8U), blue}, meta);
  r = lodforge("regularize --mask " + path("colours.tif") + " --out " + path("out.gpkg"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("in 3 bands: a colour mask's buildings are selected by their colour (regularize --building-rgb 0,0,255"),
            std::string::npos)
      << r.output;
  r = lodforge("regularize --mask " + path("colours.tif") + " --building-rgb 0,255,0 --out " + path("out.gpkg"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("its colours are (255, 0, 0) (75.0 %), (0, 0, 255) (25.0 %)"), std::string::npos) << r.output;
  r = lodforge("regularize --mask " + path("empty.tif") + " --building-rgb 0,0,255 --out " + path("out.gpkg"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("needs an RGB raster with 3 bands"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("out.gpkg")));
}

TEST_F(Cli, UnwritableOutputAndBadOptions) {
  CommandRun r = lodforge("regularize --mask x.tif --out " + path("missing/out.gpkg"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("does not exist"), std::string::npos) << r.output;
  r = lodforge("regularize --mask x.tif --out " + path("out.gpkg") + " --set labeling.kappa2=-1 --set smoothing.bogus=1");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("labeling.kappa2: must be >= 0"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("smoothing.bogus: unknown option"), std::string::npos) << r.output;
  r = lodforge("regularize --frobnicate");
  EXPECT_EQ(r.code, 2);  // a usage error
  EXPECT_NE(r.output.find("unknown argument '--frobnicate'"), std::string::npos) << r.output;
}

// Issue 16: a command line like the tools people know (CLI11 underneath).
TEST_F(Cli, OptionsAnywhereShortFormsHelpAndSuggestions) {
  ASSERT_EQ(lodforge("synth --out " + path("city") + " --size-m 120 --seed 3").code, 0);
  std::ofstream(path("job.yaml")) << "inputs: {segmentation: {path: city/seg_class.tif}}\ntiling: {tile_size_m: 60}\n"
                                  << "output: {dir: out, formats: [gpkg], quicklook: false}\nwork_dir: work\n";
  // Options before the job file, the short form of --threads, a job key spelled as in the job.
  CommandRun r = lodforge("run --threads 1 -j 2 " + path("job.yaml"));
  EXPECT_EQ(r.code, 2) << r.output;  // --threads given twice
  EXPECT_NE(r.output.find("--threads"), std::string::npos) << r.output;
  r = lodforge("run -j 2 --set stages.labeling.kappa2=5 " + path("job.yaml") + " --progress none");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(r.output.find("{\"progress\""), std::string::npos) << r.output;
  // regularize takes the same spelling of stage keys as a job (and the short one).
  r = lodforge("regularize -j 1 --mask " + path("city/seg_class.tif") + " --out " + path("r.gpkg") + " --set stages.labeling.kappa2=-1");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("labeling.kappa2: must be >= 0"), std::string::npos) << r.output;
  // -h and --help on every command, with the exit codes.
  for (const char* command : {"run", "merge", "eval", "config", "regularize", "synth", "options"}) {
    for (const char* help : {"-h", "--help"}) {
      r = lodforge(std::string(command) + " " + help);
      EXPECT_EQ(r.code, 0) << command << " " << help << "\n" << r.output;
      EXPECT_NE(r.output.find("exit codes: 0 done, 1 error in the input or the run, 2 usage error"), std::string::npos) << command;
    }
  }
  // synth's help lists the options --set takes, with their defaults.
  r = lodforge("synth --help");
  for (const char* key : {"boundary_noise_m: -1", "corner_radius_m: -1", "blur_m: 0", "bias_m: 0", "speckle_size_m: -1"})
    EXPECT_NE(r.output.find(key), std::string::npos) << key << "\n" << r.output;
  // Did you mean: a mistyped command or option.
  r = lodforge("rnu " + path("job.yaml"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("unknown command 'rnu'; did you mean 'run'?"), std::string::npos) << r.output;
  r = lodforge("run " + path("job.yaml") + " --threds 2");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("unknown argument '--threds'; did you mean --threads?"), std::string::npos) << r.output;
  // Flags' values are checked under the flags' names.
  r = lodforge("synth --out " + path("x") + " --size-m abc");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("--size-m 'abc': expected metres"), std::string::npos) << r.output;
  r = lodforge("run");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("give a job file"), std::string::npos) << r.output;
}

// Issue 16: logs on standard error at the level asked for; data on standard output.
TEST_F(Cli, LogsGoToStandardErrorAtTheLevelAskedFor) {
  ASSERT_EQ(lodforge("synth --out " + path("city") + " --size-m 120 --seed 3").code, 0);
  const std::string bin = LODFORGE_BINARY;
  const std::string regularize = bin + " regularize --mask " + path("city/seg_class.tif") + " --out " + path("r.gpkg");
  // (test::shell adds 2>&1 after the command: the redirections inside the parentheses come first)
  CommandRun r = test::shell("(" + regularize + " 2>/dev/null)");
  EXPECT_EQ(r.code, 0);
  EXPECT_EQ(r.output, "");  // nothing on stdout
  r = test::shell("(" + regularize + " 2>&1 >/dev/null)");
  EXPECT_NE(r.output.find("[info] wrote"), std::string::npos) << r.output;
  for (const std::string quiet : {" -q", " --log-level warn", " --log-level=error"}) {
    r = test::shell(regularize + quiet + " 2>&1");
    EXPECT_EQ(r.code, 0) << quiet << r.output;
    EXPECT_EQ(r.output.find("[info]"), std::string::npos) << quiet << "\n" << r.output;
  }
  r = test::shell("LODFORGE_LOG_LEVEL=warn " + regularize + " 2>&1");
  EXPECT_EQ(r.output.find("[info]"), std::string::npos) << r.output;
  r = test::shell(regularize + " --log-level loud 2>&1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("log level 'loud': must be one of trace, debug, info, warn, error"), std::string::npos) << r.output;
  // config --defaults prints the job (data) on standard output.
  r = test::shell("(" + bin + " config --defaults 2>/dev/null)");
  EXPECT_NE(r.output.find("inputs:"), std::string::npos);
  // --version names the revision and the libraries.
  r = test::shell(bin + " --version");
  EXPECT_EQ(r.code, 0);
  for (const char* name : {"(git ", "GDAL 3.", "CGAL 5.", "TBB ", "OpenCV 4.", "Ceres "}) EXPECT_NE(r.output.find(name), std::string::npos) << name << r.output;
}

// Issue 17: a building modeled as asked has no stage or reason: NULL in the GeoPackage, not ''.
TEST_F(Cli, EmptyStageAndReasonAreNull) {
  ASSERT_EQ(lodforge("synth --out " + path("city") + " --size-m 120 --seed 3").code, 0);
  ASSERT_EQ(lodforge("regularize --mask " + path("city/seg_class.tif") + " --out " + path("r.gpkg")).code, 0);
  GDALAllRegister();
  GDALDataset* d = static_cast<GDALDataset*>(GDALOpenEx(path("r.gpkg").c_str(), GDAL_OF_VECTOR, nullptr, nullptr, nullptr));
  ASSERT_NE(d, nullptr);
  int ok = 0;
  for (auto& f : *d->GetLayer(0)) {
    if (std::string(f->GetFieldAsString("status")) != "ok") continue;
    ++ok;
    EXPECT_TRUE(f->IsFieldNull(f->GetFieldIndex("stage"))) << f->GetFID();
    EXPECT_TRUE(f->IsFieldNull(f->GetFieldIndex("reason"))) << f->GetFID();
  }
  GDALClose(d);
  EXPECT_GT(ok, 0);
}

// Issue 16: bash completion generated from the commands' own option declarations.
TEST_F(Cli, BashCompletionKnowsEveryCommandsOptions) {
  const std::string script = path("lodforge.bash");
  ASSERT_EQ(test::shell("(" + std::string(LODFORGE_BINARY) + " completion bash > " + script + ")").code, 0);
  const auto complete = [&](const std::string& words, int word) {
    return test::shell("bash -c 'source " + script + "; COMP_WORDS=(" + words + "); COMP_CWORD=" + std::to_string(word) +
                       "; _lodforge; echo \"${COMPREPLY[*]}\"'").output;
  };
  EXPECT_EQ(complete("lodforge re", 1), "regularize\n");
  EXPECT_EQ(complete("lodforge run --thr", 2), "--threads\n");
  EXPECT_EQ(complete("lodforge regularize --building-v", 2), "--building-value\n");
  EXPECT_EQ(complete("lodforge merge --thr", 2), "\n");  // merge has no --threads
  EXPECT_EQ(lodforge("completion zsh").code, 2);
}

// Issue 16: inputs through GDAL's virtual file systems, and GDAL configuration options.
TEST_F(Cli, GdalVirtualFileSystemsAndConfigOptions) {
  ASSERT_EQ(lodforge("synth --out " + path("city") + " --size-m 120 --seed 3").code, 0);
  ASSERT_EQ(test::shell("/usr/bin/python3 -c \"import zipfile; zipfile.ZipFile('" + path("city/city.zip") + "', 'w').write('" +
                        path("city/seg_class.tif") + "', 'seg_class.tif')\"").code, 0);
  CommandRun r = lodforge("regularize --mask /vsizip/" + path("city/city.zip") + "/seg_class.tif --out " + path("z.gpkg") +
                          " --config GDAL_CACHEMAX 64");
  ASSERT_EQ(r.code, 0) << r.output;
  CommandRun direct = lodforge("regularize --mask " + path("city/seg_class.tif") + " --out " + path("d.gpkg"));
  ASSERT_EQ(direct.code, 0) << direct.output;
  EXPECT_EQ(test::slurp(path("z.gpkg")).size(), test::slurp(path("d.gpkg")).size());
  r = lodforge("regularize --mask /vsizip/" + path("city/city.zip") + "/missing.tif --out " + path("m.gpkg"));
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("not a raster GDAL can read"), std::string::npos) << r.output;
}

long feature_count(const std::string& file) {
  GDALAllRegister();
  GDALDataset* d = static_cast<GDALDataset*>(GDALOpenEx(file.c_str(), GDAL_OF_VECTOR, nullptr, nullptr, nullptr));
  if (!d) return -1;
  const long n = long(d->GetLayer(0)->GetFeatureCount());
  GDALClose(d);
  return n;
}

TEST_F(Cli, SynthThenRegularizeClassAndColourGiveTheSameBuildings) {
  CommandRun r = lodforge("synth --out " + path("city") + " --size-m 150 --seed 3");
  ASSERT_EQ(r.code, 0) << r.output;
  r = lodforge("regularize --mask " + path("city/seg_class.tif") + " --out " + path("a.gpkg") + " --threads 2");
  ASSERT_EQ(r.code, 0) << r.output;
  r = lodforge("regularize --mask " + path("city/seg_isprs.tif") + " --building-rgb 0,0,255 --out " + path("b.gpkg"));
  ASSERT_EQ(r.code, 0) << r.output;
  const long a = feature_count(path("a.gpkg"));
  EXPECT_GT(a, 5);
  EXPECT_EQ(a, feature_count(path("b.gpkg")));
  for (const auto& entry : fs::directory_iterator(dir)) EXPECT_EQ(entry.path().string().find(".partial"), std::string::npos);
}

// --stats says how far the segmentation rounded the buildings' corners (models.rounding_noise):
// a clean synthetic city rounded by 2 m, most of its buildings, at about 2 m; unrounded, none.
TEST_F(Cli, StatsMeasureTheCornerRounding) {
  const auto rounding = [&](const std::string& name, double radius_m) {
    CommandRun r = lodforge("synth -q --out " + path(name) + " --size-m 200 --seed 3 --set boundary_noise_m=0 --set speckle_per_km2=0" +
                            " --set corner_radius_m=" + std::to_string(radius_m));
    EXPECT_EQ(r.code, 0) << r.output;
    r = lodforge("regularize --mask " + path(name + "/seg_class.tif") + " --out " + path(name + ".gpkg") + " --stats " +
                 path(name + ".json"));
    EXPECT_EQ(r.code, 0) << r.output;
    std::ifstream in(path(name + ".json"));
    const nlohmann::json stats = nlohmann::json::parse(in);
    return std::make_tuple(stats.at("buildings").get<int>(), stats.at("corner_rounding").at("buildings").get<int>(),
                           stats.at("corner_rounding").at("radius_m_median").get<double>(), r.output);
  };
  const auto [all, rounded, radius, log] = rounding("rounded", 2.0);
  EXPECT_GT(all, 10);
  EXPECT_GT(2 * rounded, all);
  EXPECT_NEAR(radius, 2.0, 0.4);
  EXPECT_NE(log.find("corners the segmentation rounded"), std::string::npos) << log;
  const auto [all_sharp, rounded_sharp, radius_sharp, log_sharp] = rounding("sharp", 0.0);
  EXPECT_EQ(all_sharp, all);
  EXPECT_EQ(rounded_sharp, 0);
  EXPECT_EQ(radius_sharp, 0.0);
}

// A cadastre's footprints through a simulated segmentation (lodforge synth --from), each
// regularizer on it, scored by eval: the benchmark's path (bench/quality.sh) end to end.
TEST_F(Cli, SynthFromFootprintsRegularizeWithEachMethodAndEvaluate) {
  std::ofstream(path("truth.geojson"))
      << R"({"type": "FeatureCollection", "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::28992"}}, "features": [)"
      << R"({"type": "Feature", "properties": {}, "geometry": {"type": "Polygon", "coordinates": [[[85000, 447000], [85020, 447000], [85020, 447012], [85000, 447012], [85000, 447000]]]}},)"
      << R"({"type": "Feature", "properties": {}, "geometry": {"type": "Polygon", "coordinates": [[[85040, 447030], [85058, 447036], [85054, 447048], [85036, 447042], [85040, 447030]]]}}]})";
  CommandRun r = lodforge("synth --from " + path("truth.geojson") + " --pixel-size 0.25 --seed 2 --out " + path("sim"));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(fs::exists(path("sim/seg_class.tif")));
  EXPECT_FALSE(fs::exists(path("sim/dsm.tif")));  // no heights for given footprints
  GDALAllRegister();
  GDALDataset* d = static_cast<GDALDataset*>(GDALOpen(path("sim/seg_class.tif").c_str(), GA_ReadOnly));
  ASSERT_NE(d, nullptr);
  double gt[6];
  d->GetGeoTransform(gt);
  EXPECT_LE(gt[0], 85000 - 10 + 1e-9);  // the grid covers the footprints with a 10 m margin
  EXPECT_GE(gt[3], 447048 + 10 - 1e-9);
  EXPECT_NEAR(gt[1], 0.25, 1e-12);
  EXPECT_NE(std::string(d->GetProjectionRef()).find("28992"), std::string::npos);
  GDALClose(d);
  for (const std::string name : {"deformation", "cgal", "douglas_peucker", "none"}) {
    r = lodforge("regularize --mask " + path("sim/seg_class.tif") + " --regularizer " + name + " --out " + path(name + ".gpkg") +
                 " --stats " + path(name + ".json"));
    ASSERT_EQ(r.code, 0) << name << ": " << r.output;
    const nlohmann::json stats = nlohmann::json::parse(test::slurp(dir / (name + ".json")));
    EXPECT_EQ(stats.at("regularizer"), name);
    EXPECT_EQ(stats.at("route"), "original");
    EXPECT_EQ(stats.at("buildings"), 2);
    EXPECT_EQ(stats.at("ok"), 2);
    EXPECT_GE(stats.at("seconds_p99").get<double>(), stats.at("seconds_median").get<double>());
    // Every building in one size class.
    int in_classes = 0;
    for (const auto& [size, entry] : stats.at("by_size").items()) in_classes += entry.at("buildings").get<int>();
    EXPECT_EQ(in_classes, 2) << stats.dump();
    // Where the paper's chain spends it: its stages' means add up to the mean a building, every
    // one of them spent (a start, a labeling, an outline); none for a peer.
    if (name == "deformation") {
      const nlohmann::json& stages = stats.at("chain_seconds_mean");
      double sum = 0;
      for (const char* stage : {"start", "labeling", "outline", "other"}) sum += stages.at(stage).get<double>();
      EXPECT_NEAR(sum, stats.at("seconds_mean").get<double>(), 1e-9 + 1e-6 * sum) << stats.dump();
      for (const char* stage : {"start", "labeling", "outline"}) EXPECT_GT(stages.at(stage).get<double>(), 0.0) << stage;
      for (const auto& [size, entry] : stats.at("by_size").items())
        if (entry.at("buildings").get<int>() > 0) {
          EXPECT_TRUE(entry.contains("chain_seconds_mean")) << size;
        }
    } else {
      EXPECT_FALSE(stats.contains("chain_seconds_mean")) << name;
    }
    // Each footprint names the outline the chain kept (NULL for a peer); --stats counts them.
    std::map<std::string, int> models;
    GDALDataset* out = static_cast<GDALDataset*>(GDALOpenEx(path(name + ".gpkg").c_str(), GDAL_OF_VECTOR, nullptr, nullptr, nullptr));
    ASSERT_NE(out, nullptr);
    for (auto& f : *out->GetLayer(0)) {
      const int field = f->GetFieldIndex("model");
      ASSERT_GE(field, 0) << name;
      if (f->IsFieldNull(field)) ++models["NULL"];
      else ++models[f->GetFieldAsString(field)];
    }
    GDALClose(out);
    if (name == "deformation") {
      const std::set<std::string> known = {"regular", "lines", "lattice", "rectangle", "coarse_lattice", "staircase_lines", "merged_steps", "ellipse"};
      for (const auto& [model, n] : models) EXPECT_TRUE(known.count(model)) << model;
      EXPECT_EQ((stats.at("models").get<std::map<std::string, int>>()), models) << stats.dump();
    } else {
      EXPECT_EQ(models, (std::map<std::string, int>{{"NULL", 2}})) << name;
      EXPECT_FALSE(stats.contains("models")) << stats.dump();
    }
    r = lodforge("eval --pred " + path(name + ".gpkg") + " --gt " + path("truth.geojson") + " --json " + path(name + ".eval.json"));
    ASSERT_EQ(r.code, 0) << r.output;
    const nlohmann::json metrics = nlohmann::json::parse(test::slurp(dir / (name + ".eval.json")));
    EXPECT_GE(metrics.at("overall_iou").get<double>(), 0.95) << name << metrics;
  }
  r = lodforge("regularize --mask " + path("sim/seg_class.tif") + " --regularizer bogus --out " + path("x.gpkg"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("must be one of: deformation, cgal, douglas_peucker, none"), std::string::npos) << r.output;
  // Footprints in degrees (a GeoJSON without "crs" is WGS 84) are refused, not rasterized at 0.25°.
  std::ofstream(path("lonlat.geojson")) << R"({"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {}, "geometry": )"
                                        << R"({"type": "Polygon", "coordinates": [[[4.37, 52.0], [4.371, 52.0], [4.371, 52.001], [4.37, 52.0]]]}}]})";
  r = lodforge("synth --from " + path("lonlat.geojson") + " --out " + path("sim3"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("is in a geographic CRS (degrees)"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("sim3/seg_class.tif")));
  r = lodforge("synth --from " + path("missing.geojson") + " --out " + path("sim2"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("--from '" + path("missing.geojson") + "': file not found"), std::string::npos) << r.output;
}

// `lodforge synth` arguments that simulate a network's segmentation of the campus's row-house
// extract (tests/data): pixel size, seed, wobble amplitude and wavelength, corner radius (m), with
// 400 speckles of 0.5 m a square kilometre; into the directory `out`.
std::string extract_segmentation(const std::string& pixel, int seed, const std::string& wobble_m, const std::string& wavelength_m,
                                 const std::string& radius_m, const std::string& out) {
  return "synth -q --from " + test::test_data() + "/tudelft-campus-bag/campus_row_extract.geojson --pixel-size " + pixel +
         " --seed " + std::to_string(seed) + " --set boundary_noise_m=" + wobble_m + " --set noise_wavelength_m=" + wavelength_m +
         " --set corner_radius_m=" + radius_m + " --set speckle_per_km2=400 --set speckle_size_m=0.5 --out " + out;
}

// A long thin row of houses of the TU Delft campus (BAG), about 100 m x 8 m, in a simulated
// segmentation at 15 cm under 0.7 m of wobble: no direction was found for its ends (their normals
// spread by the wobble's flanks), its ends' contour joined its long walls' runs, those bowed round
// the ends and were drawn along the wobble as curves, 66 vertices turning by tens of degrees.
// With the lattice's missing axis added where that happens (refinement.missing_axis_deg) the row
// has square ends and straight walls.
TEST_F(Cli, AThinRowUnderAWobbleHasSquareEnds) {
  CommandRun r = lodforge(extract_segmentation("0.15", 1, "0.7", "6", "1.4", path("sim")));
  ASSERT_EQ(r.code, 0) << r.output;
  GDALAllRegister();
  // The row's outline (the footprint holding a point inside it): its vertices, and its corners
  // (turning by over 5 degrees) and those of them within 5 degrees of a right angle or of
  // straight on (eval's right angles).
  struct Row {
    std::size_t vertices = 0, right = 0, corners = 0;
  };
  const auto row = [&](const std::string& name, const std::string& options) {
    r = lodforge("regularize -q --mask " + path("sim/seg_class.tif") + " " + options + " --out " + path(name));
    EXPECT_EQ(r.code, 0) << r.output;
    Row found;
    for (const PolygonWithHoles& p : read_polygons(path(name), name))
      if (point_in_ring(Vec2(85640, 446590), p.outer)) {
        found.vertices = p.outer.size();
        std::tie(found.right, found.corners) = right_angle_corners(p);
      }
    return found;
  };
  const Row with = row("default.gpkg", "");
  EXPECT_GE(with.vertices, 4u);
  EXPECT_LE(with.vertices, 12u);
  EXPECT_EQ(with.right, with.corners);
  const Row without = row("without.gpkg", "--set stages.refinement.missing_axis_deg=0");
  EXPECT_GT(without.corners - without.right, 20u)
      << "without the missing axis the row no longer comes out drawn along its wobble (" << without.vertices << " vertices, "
      << without.right << " of " << without.corners << " corners square): the test no longer shows the case";
}

// Row houses of the TU Delft campus (BAG) in a simulated segmentation at 50 cm under a metre of
// wobble at a 2 m wavelength (seed 2): the wobble closes a gap between two houses of a row into a
// hole, and the hole's outline crosses the row's outer ring; every outline of the row was
// invalid and the row was written as its Douglas-Peucker fallback, 75 vertices along the wobble
// (3 of 4 corners square over the extract). Only its holes invalid, the row keeps its outline
// and the holes that fit: no fallback, the row square.
TEST_F(Cli, AHoleDrawnAcrossTheOuterRingIsLeftOutNotTheBuilding) {
  CommandRun r = lodforge(extract_segmentation("0.5", 2, "1", "2", "0", path("sim")));
  ASSERT_EQ(r.code, 0) << r.output;
  r = lodforge("regularize --mask " + path("sim/seg_class.tif") + " --out " + path("rows.gpkg") + " --stats " + path("stats.json"));
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json stats = nlohmann::json::parse(test::slurp(dir / "stats.json"));
  EXPECT_EQ(stats.at("fallback").get<int>(), 0) << r.output;
  EXPECT_EQ(stats.at("ok").get<int>(), stats.at("buildings").get<int>());
  GDALAllRegister();
  bool found = false;
  for (const PolygonWithHoles& p : read_polygons(path("rows.gpkg"), "rows.gpkg"))
    if (point_in_ring(Vec2(85600, 446686), p.outer)) {
      found = true;
      const auto [right, corners] = right_angle_corners(p);
      EXPECT_LE(p.outer.size(), 20u);
      EXPECT_GE(double(right), 0.9 * double(corners)) << right << " of " << corners;
    }
  EXPECT_TRUE(found) << "no footprint holds the row's point: the test no longer shows the case";
  // The hole left out is said in the row's reason, the others' have none.
  GDALDataset* d = static_cast<GDALDataset*>(GDALOpenEx(path("rows.gpkg").c_str(), GDAL_OF_VECTOR, nullptr, nullptr, nullptr));
  ASSERT_NE(d, nullptr);
  std::vector<std::string> reasons;
  for (auto& f : *d->GetLayer(0))
    if (!f->IsFieldNull(f->GetFieldIndex("reason"))) reasons.push_back(f->GetFieldAsString("reason"));
  GDALClose(d);
  ASSERT_EQ(reasons.size(), 1u);
  EXPECT_TRUE(reasons[0].rfind("its outline covers 1 hole of the mask (", 0) == 0) << reasons[0];
  EXPECT_NE(r.output.find("1 building(s) cover holes of the mask"), std::string::npos) << r.output;
}

// Row houses of the TU Delft campus (BAG) in a simulated segmentation at 25 cm under half a metre
// of wobble (8 m wavelength), corners rounded by 1 m: three buildings' outlines (the chain's
// regular one, one of them then simplified by merging its steps) followed the contour closer than
// its noise leaves it, along the wobble, with more vertices than their lattice outlines, which
// explain the contour within that noise (models.noise_fit). With the rule the right angles rise from
// 0.83 to 0.87 of the corners, the overall IoU from 0.9226 to 0.9238.
TEST_F(Cli, AnOutlineDrawnCloserThanTheNoiseGivesWayToTheLatticeOutline) {
  const std::string extract = test::test_data() + "/tudelft-campus-bag/campus_row_extract.geojson";
  CommandRun r = lodforge(extract_segmentation("0.25", 3, "0.5", "8", "1", path("sim")));
  ASSERT_EQ(r.code, 0) << r.output;
  const auto scored = [&](const std::string& name, const std::string& options) {
    r = lodforge("regularize -q --mask " + path("sim/seg_class.tif") + " " + options + " --out " + path(name + ".gpkg"));
    EXPECT_EQ(r.code, 0) << r.output;
    r = lodforge("eval -q --pred " + path(name + ".gpkg") + " --gt " + extract + " --json " + path(name + ".json"));
    EXPECT_EQ(r.code, 0) << r.output;
    return nlohmann::json::parse(test::slurp(dir / (name + ".json")));
  };
  const nlohmann::json with = scored("default", "");
  const nlohmann::json without = scored("without", "--set stages.models.noise_fit=0");
  const double right = with.at("right_angle_share").get<double>(), right_without = without.at("right_angle_share").get<double>();
  const double iou = with.at("overall_iou").get<double>(), iou_without = without.at("overall_iou").get<double>();
  std::cerr << "right angles " << right << " (without the rule " << right_without << "), IoU " << iou << " (" << iou_without << ")\n";
  EXPECT_GE(right, right_without + 0.03);
  EXPECT_GE(iou, iou_without - 0.001);
  // At 2 m pixels the noise (half a metre of wobble) is under a pixel: an outline drawn closer than
  // it follows the staircase and jogs of a pixel or two, and the rule stays out
  // (models.noise_fit_min_px). The default draws every building as without the rule; at any noise
  // (noise_fit_min_px=0) one of them would take its lattice outline.
  r = lodforge(extract_segmentation("2", 3, "0.5", "8", "1", path("coarse")));
  ASSERT_EQ(r.code, 0) << r.output;
  GDALAllRegister();
  const auto outlines = [&](const std::string& name, const std::string& options) {
    r = lodforge("regularize -q --mask " + path("coarse/seg_class.tif") + " " + options + " --out " + path(name));
    EXPECT_EQ(r.code, 0) << r.output;
    std::vector<std::vector<Vec2>> rings;
    for (const PolygonWithHoles& p : read_polygons(path(name), name)) rings.push_back(p.outer);
    return rings;
  };
  const auto coarse = outlines("coarse.gpkg", "");
  EXPECT_FALSE(coarse.empty());
  EXPECT_EQ(coarse, outlines("coarse_without.gpkg", "--set stages.models.noise_fit=0"));
  EXPECT_NE(coarse, outlines("coarse_any.gpkg", "--set stages.models.noise_fit_min_px=0"))
      << "at any noise the rule no longer changes a building at 2 m: the test no longer shows the bound";
}

// A tile cut from a larger mask: the buildings its edge cuts are drawn up to the edge and no
// farther (traced swept out across the edge, stages.contour.edge_sweep_m, and clipped back; that
// the sweep carries their walls on along their own directions, Contour tests).
TEST_F(Cli, TheBuildingsATilesEdgeCutsEndOnIt) {
  CommandRun r = lodforge("synth -q --size-m 200x200 --pixel-size 0.1 --seed 3 --set boundary_noise_m=0.5 --set noise_wavelength_m=8"
                          " --set corner_radius_m=1 --out " + path("sim"));
  ASSERT_EQ(r.code, 0) << r.output;
  GDALAllRegister();
  // The tile: the mask's 120 m from the west (its east edge cuts buildings).
  {
    GDALDataset* src = static_cast<GDALDataset*>(GDALOpen(path("sim/seg_class.tif").c_str(), GA_ReadOnly));
    ASSERT_NE(src, nullptr);
    GDALDriver* gtiff = GetGDALDriverManager()->GetDriverByName("GTiff");
    GDALDataset* tile = gtiff->Create(path("tile.tif").c_str(), 1200, src->GetRasterYSize(), 1, GDT_Byte, nullptr);
    double gt[6];
    src->GetGeoTransform(gt);
    tile->SetGeoTransform(gt);
    tile->SetProjection(src->GetProjectionRef());
    std::vector<uint8_t> rows(std::size_t(1200) * std::size_t(src->GetRasterYSize()));
    ASSERT_EQ(src->GetRasterBand(1)->RasterIO(GF_Read, 0, 0, 1200, src->GetRasterYSize(), rows.data(), 1200, src->GetRasterYSize(), GDT_Byte, 0, 0),
              CE_None);
    ASSERT_EQ(tile->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, 1200, src->GetRasterYSize(), rows.data(), 1200, src->GetRasterYSize(), GDT_Byte, 0, 0),
              CE_None);
    GDALClose(tile);
    GDALClose(src);
  }
  const double east = 85000 + 120;  // (synth's city starts at 85000)
  // Per run: the footprints reaching past the tile's east edge, and those ending on it.
  const auto count = [&](const std::string& name, const std::string& options) {
    r = lodforge("regularize -q --mask " + path("tile.tif") + " " + options + " --out " + path(name));
    EXPECT_EQ(r.code, 0) << r.output;
    std::size_t beyond = 0, on = 0;
    for (const PolygonWithHoles& p : read_polygons(path(name), name)) {
      double max_x = -1e300;
      for (const Vec2& v : p.outer) max_x = std::max(max_x, v.x());
      beyond += max_x > east + 1e-6;
      on += std::abs(max_x - east) <= 1e-6;
    }
    return std::pair{beyond, on};
  };
  const auto [beyond, on] = count("default.gpkg", "");
  EXPECT_EQ(beyond, 0u);
  EXPECT_GE(on, 3u);
  const auto [beyond_before, on_before] = count("cut.gpkg", "--set stages.contour.edge_sweep_m=0");
  EXPECT_GE(beyond_before, 2u) << "traced as cut, no outline reaches past the edge any more: the test no longer shows the case";
}

TEST_F(Cli, OptionsPrintsDefaults) {
  const CommandRun r = lodforge("options");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.output.find("kappa2: 10"), std::string::npos);
}

}  // namespace
}  // namespace lodforge
