// The batch engine end to end: tiling, determinism, kill and resume, shards, job errors.
#include <gtest/gtest.h>
#include <random>
#include <regex>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <csignal>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <gdal_priv.h>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <ogrsf_frmts.h>
#include <set>
#include <sstream>
#include <sys/file.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

#include "io/raster.hpp"
#include "io/raster_writer.hpp"
#include "run/batch.hpp"
#include "run/run_report.hpp"
#include "support/process.hpp"
#include "support/shapes.hpp"

namespace fs = std::filesystem;

namespace lodforge {
namespace {

using Result = test::CommandOutput;
using test::lodforge;
using test::slurp;

// Every file under out/tiles plus the tile index, by relative name.
std::map<std::string, std::string> output_bytes(const fs::path& out) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::directory_iterator(out / "tiles")) files["tiles/" + e.path().filename().string()] = slurp(e.path());
  files["tile_index.geojson"] = slurp(out / "tile_index.geojson");
  return files;
}

// A run report, read as JSON.
nlohmann::json report_of(const fs::path& path) { return nlohmann::json::parse(slurp(path)); }

// The report without what depends on timing or where it ran: seconds, blocks decoded (fewer with
// a larger cache or more threads), the job's path and the shard.
nlohmann::json without_timings(nlohmann::json report) {
  for (const char* key : {"seconds", "core_seconds", "stage_seconds", "blocks_decoded", "job", "shard", "slowest_buildings"}) report.erase(key);
  for (auto& tile : report.at("per_tile")) tile.erase("seconds");
  return report;
}

// id -> footprint WKT over every tile file.
std::map<long, std::string> footprints(const fs::path& out) {
  GDALAllRegister();
  std::map<long, std::string> result;
  for (const auto& e : fs::directory_iterator(out / "tiles")) {
    if (e.path().extension() != ".gpkg") continue;
    GDALDataset* d = static_cast<GDALDataset*>(GDALOpenEx(e.path().c_str(), GDAL_OF_VECTOR, nullptr, nullptr, nullptr));
    if (!d) continue;
    OGRLayer* layer = d->GetLayer(0);
    for (auto& f : *layer) {
      char* wkt = nullptr;
      f->GetGeometryRef()->exportToWkt(&wkt);
      EXPECT_EQ(result.count(f->GetFieldAsInteger64("id")), 0u) << "building in two tiles";
      result[long(f->GetFieldAsInteger64("id"))] = std::string(wkt) + " " + f->GetFieldAsString("status");
      CPLFree(wkt);
    }
    GDALClose(d);
  }
  return result;
}

// The outlines (WKT) of a run's tile files, and of one GeoPackage's first layer: a run and
// `regularize` on the same mask give the same multiset.
std::multiset<std::string> run_outlines(const fs::path& out) {
  std::multiset<std::string> outlines;
  for (const auto& [id, text] : footprints(out)) outlines.insert(text.substr(0, text.rfind(' ')));
  return outlines;
}
std::multiset<std::string> gpkg_outlines(const fs::path& path) {
  std::multiset<std::string> outlines;
  for (const auto& [id, wkt] : test::gpkg_footprints(path)) outlines.insert(wkt);
  return outlines;
}

// A run's noise (its report.json) is regularize's (its --stats), and its footprints regularize's,
// outline for outline: more than `least` of them.
void expect_run_is_regularize(const nlohmann::json& report, const nlohmann::json& stats, const fs::path& run_out, const fs::path& gpkg,
                              std::size_t least) {
  EXPECT_DOUBLE_EQ(report.at("noise_floor_m").get<double>(), stats.at("noise_floor_m").get<double>());
  EXPECT_DOUBLE_EQ(report.at("noise_smoothing_m").get<double>(), stats.at("noise_smoothing_m").get<double>());
  EXPECT_DOUBLE_EQ(report.at("corner_rounding_m").get<double>(), stats.at("corner_rounding").at("pooled_m").get<double>());
  const std::multiset<std::string> run = run_outlines(run_out), regularized = gpkg_outlines(gpkg);
  EXPECT_GT(run.size(), least);
  EXPECT_TRUE(run == regularized) << run.size() << " against " << regularized.size();
}

class Run : public ::testing::Test {
 protected:
  void SetUp() override { dir = test::fresh_test_directory("lodforge_run"); }
  // Writes a job; `extra` is appended verbatim.
  fs::path job(const std::string& name, const std::string& segmentation, double tile_m, const std::string& extra = "") {
    const fs::path p = dir / (name + ".yaml");
    std::ofstream(p) << "inputs:\n  segmentation: {path: " << segmentation << "}\n"
                     << "tiling: {tile_size_m: " << tile_m << "}\n"
                     << "output: {dir: " << name << "_out}\nwork_dir: " << name << "_work\n" << extra;
    return p;
  }
  fs::path dir;
};

// Tiles of 32 m give the one-tile run's footprints, and `regularize`'s, on a mask where buildings
// take their neighbours' lattice (lattice.neighbour_radius_m): each tile finds every building
// that may lend to its own around them (lattice_lenders), whatever the tiling. Without the
// neighbours' lattice (radius 0) some outlines differ.
TEST_F(Run, DelftSmallTilesGiveTheSameFootprintsAsOneTile) {
  const std::string seg = test::test_data() + "/delft-ahn3-bgt/derived/top_class_50cm.tif";
  ASSERT_TRUE(fs::exists(seg));
  Result r = lodforge("run " + job("small", seg, 32).string());
  ASSERT_EQ(r.code, 0) << r.output;
  r = lodforge("run " + job("whole", seg, 1000).string());
  ASSERT_EQ(r.code, 0) << r.output;
  const auto small = footprints(dir / "small_out"), whole = footprints(dir / "whole_out");
  EXPECT_GT(whole.size(), 30u);
  EXPECT_EQ(small, whole);
  r = lodforge("regularize --mask " + seg + " --out " + (dir / "r.gpkg").string() + " --stats " + (dir / "r.json").string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_GE(report_of(dir / "r.json").at("lattice_lent").get<int>(), 5);
  EXPECT_TRUE(run_outlines(dir / "small_out") == gpkg_outlines(dir / "r.gpkg"));
  r = lodforge("regularize --mask " + seg + " --out " + (dir / "alone.gpkg").string() + " --set stages.lattice.neighbour_radius_m=0");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_FALSE(gpkg_outlines(dir / "alone.gpkg") == gpkg_outlines(dir / "r.gpkg"));
}

class SynthRun : public Run {
 protected:
  void SetUp() override {
    Run::SetUp();
    const Result r = lodforge("synth --out " + (dir / "city").string() + " --size-m 400 --seed 5");
    ASSERT_EQ(r.code, 0) << r.output;
    seg = (dir / "city" / "seg_class.tif").string();
  }
  std::string seg;
};

TEST_F(SynthRun, OutputsAreByteIdenticalForOneAndTwoThreads) {
  Result r = lodforge("run " + job("one", seg, 60).string() + " --threads 1");
  ASSERT_EQ(r.code, 0) << r.output;
  r = lodforge("run " + job("two", seg, 60).string() + " --threads 2");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto one = output_bytes(dir / "one_out"), two = output_bytes(dir / "two_out");
  EXPECT_GT(one.size(), 10u);
  EXPECT_TRUE(one == two);
  // With heights (DSM and DTM read by readers each thread keeps open) and the quick looks.
  for (const std::string threads : {"1", "2"}) {
    std::ofstream(dir / ("h" + threads + ".yaml")) << "inputs:\n  segmentation: {path: " << seg << "}\n  dsm: {path: " << (dir / "city" / "dsm.tif").string()
                                                    << "}\n  dtm: {path: " << (dir / "city" / "dtm.tif").string() << "}\n"
                                                    << "tiling: {tile_size_m: 60}\noutput: {dir: h" << threads << "_out, quicklook: true}\nwork_dir: h" << threads << "_work\n";
    r = lodforge("run " + (dir / ("h" + threads + ".yaml")).string() + " --threads " + threads);
    ASSERT_EQ(r.code, 0) << r.output;
  }
  const auto h1 = output_bytes(dir / "h1_out"), h2 = output_bytes(dir / "h2_out");
  EXPECT_GT(h1.size(), one.size());  // the PNGs
  EXPECT_TRUE(h1 == h2);
  EXPECT_GT(report_of(dir / "h1_out" / "report.json").at("lod1").get<int>(), 0);
  // A 1 MB block cache: tiles processed in bands one tile wide (not in tile order), blocks evicted
  // and decoded again; the same files, and the index and report still in tile order.
  std::ofstream(dir / "small_cache.yaml") << "inputs:\n  segmentation: {path: " << seg << "}\n  dsm: {path: " << (dir / "city" / "dsm.tif").string()
                                          << "}\n  dtm: {path: " << (dir / "city" / "dtm.tif").string() << "}\n"
                                          << "tiling: {tile_size_m: 60, gdal_cache_mb: 1}\noutput: {dir: small_cache_out, quicklook: true}\nwork_dir: small_cache_work\n";
  r = lodforge("run " + (dir / "small_cache.yaml").string() + " --threads 2");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(output_bytes(dir / "small_cache_out") == h1);
  EXPECT_EQ(without_timings(report_of(dir / "small_cache_out" / "report.json")), without_timings(report_of(dir / "h1_out" / "report.json")));
}

// Issue 17: a GeoPackage's last change is the same for every file of a run (identical runs give
// identical bytes): SOURCE_DATE_EPOCH when set (the reproducible-builds convention), else
// 2000-01-01; a SOURCE_DATE_EPOCH that is not a number stops the run before any output.
TEST_F(SynthRun, GeoPackagesRecordSourceDateEpochAsTheirLastChange) {
  const auto last_change = [](const fs::path& gpkg) {
    GDALAllRegister();
    GDALDataset* d = static_cast<GDALDataset*>(GDALOpenEx(gpkg.c_str(), GDAL_OF_VECTOR, nullptr, nullptr, nullptr));
    if (!d) return std::string("cannot open");
    OGRLayer* rows = d->ExecuteSQL("SELECT DISTINCT last_change FROM gpkg_contents", nullptr, nullptr);
    std::string text;
    for (auto& row : *rows) text += std::string(text.empty() ? "" : ",") + row->GetFieldAsString(0);
    d->ReleaseResultSet(rows);
    GDALClose(d);
    return text;
  };
  Result r = lodforge("run " + job("plain", seg, 100).string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(last_change(dir / "plain_out" / "tiles" / "r0000_c0000.gpkg"), "2000/01/01 00:00:00+00");
  r = test::shell("SOURCE_DATE_EPOCH=1700000000 " + std::string(LODFORGE_BINARY) + " run " + job("dated", seg, 100).string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(last_change(dir / "dated_out" / "tiles" / "r0000_c0000.gpkg"), "2023/11/14 22:13:20+00");  // (as GDAL's SQL gives a date)
  r = test::shell("SOURCE_DATE_EPOCH=yesterday " + std::string(LODFORGE_BINARY) + " run " + job("bad", seg, 100).string());
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("SOURCE_DATE_EPOCH 'yesterday': expected whole seconds since 1970-01-01"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "bad_out"));
}

// Issue 15: lodforge replaces only files it can prove it wrote. A user's files beside the tiles
// stay; a directory or a foreign file at a tile's output name stops the run before any work.
TEST_F(SynthRun, OnlyLodforgesOwnFilesAreReplaced) {
  Result r = lodforge("run " + job("ref", seg, 60).string() + " --threads 2");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto ref = output_bytes(dir / "ref_out");
  std::vector<std::string> gml;
  for (const auto& [name, bytes] : ref)
    if (name.size() > 4 && name.compare(name.size() - 4, 4, ".gml") == 0) gml.push_back(name);
  ASSERT_GT(gml.size(), 6u);
  const fs::path out = dir / "mine_out";
  fs::create_directories(out / "tiles");
  std::ofstream(out / "tiles" / "r0001_c0001.obj.orig") << "x";
  std::ofstream(out / "tiles" / "r0000_c0000.txt") << "y";
  // A directory in the way of a tile's output.
  const std::string blocked = gml[gml.size() / 2];
  fs::create_directories(out / blocked);
  r = lodforge("run " + job("mine", seg, 60).string() + " --threads 2");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("' is in the way of a tile's output and is not a regular file"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("internal error"), std::string::npos) << r.output;
  fs::remove_all(out / blocked);
  // A file lodforge did not write, at a tile's output name.
  std::ofstream(out / blocked) << "someone else's";
  r = lodforge("run " + job("mine", seg, 60).string() + " --threads 2");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("exists and lodforge did not write it"), std::string::npos) << r.output;
  EXPECT_EQ(slurp(out / blocked), "someone else's");
  EXPECT_FALSE(fs::exists(out / "report.json"));
  fs::remove(out / blocked);
  r = lodforge("run " + job("mine", seg, 60).string() + " --threads 2");
  ASSERT_EQ(r.code, 0) << r.output;
  // A rerun with other options replaces every tile's files, and still not the user's.
  r = lodforge("run " + job("mine", seg, 60).string() + " --threads 2 --set stages.labeling.kappa2=2");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(slurp(out / "tiles" / "r0001_c0001.obj.orig"), "x");
  EXPECT_EQ(slurp(out / "tiles" / "r0000_c0000.txt"), "y");
  // ... and back to the first options: the first run's bytes.
  r = lodforge("run " + job("mine", seg, 60).string() + " --threads 2");
  ASSERT_EQ(r.code, 0) << r.output;
  auto mine = output_bytes(out);
  mine.erase("tiles/r0001_c0001.obj.orig");
  mine.erase("tiles/r0000_c0000.txt");
  EXPECT_TRUE(mine == ref);
}

TEST_F(Run, KilledRunResumesToTheSameBytes) {
  // A city large enough that one thread takes a few seconds, so the run can be killed mid-way.
  Result r = lodforge("synth --out " + (dir / "big").string() + " --size-m 900 --seed 8");
  ASSERT_EQ(r.code, 0) << r.output;
  const std::string seg = (dir / "big" / "seg_class.tif").string();
  r = lodforge("run " + job("clean", seg, 50).string() + " --threads 1");
  ASSERT_EQ(r.code, 0) << r.output;
  const fs::path killed = job("killed", seg, 50);
  for (int done_before_kill : {5, 60}) {
    const pid_t pid = fork();
    if (pid == 0) {
      const int null = ::open("/dev/null", O_WRONLY);
      dup2(null, 1);
      dup2(null, 2);
      execl(LODFORGE_BINARY, LODFORGE_BINARY, "run", killed.c_str(), "--threads", "1", nullptr);
      _exit(127);
    }
    // Kill it (SIGKILL, no chance to clean up) once some tiles are complete.
    bool alive = true;
    for (int wait = 0; wait < 3000; ++wait) {
      int count = 0;
      if (fs::exists(dir / "killed_work"))
        for (const auto& e : fs::directory_iterator(dir / "killed_work")) count += e.path().extension() == ".done";
      int status = 0;
      if (waitpid(pid, &status, WNOHANG) == pid) { alive = false; break; }
      if (count >= done_before_kill) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    if (alive) {
      kill(pid, SIGKILL);
      waitpid(pid, nullptr, 0);
    }
    EXPECT_TRUE(alive) << "the run finished before it could be killed; make the test city larger";
  }
  r = lodforge("run " + killed.string() + " --threads 2");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("resumed"), std::string::npos);
  const auto clean_files = output_bytes(dir / "clean_out"), killed_files = output_bytes(dir / "killed_out");
  EXPECT_EQ(clean_files.size(), killed_files.size());
  for (const auto& [name, bytes] : clean_files) {
    const auto it = killed_files.find(name);
    EXPECT_TRUE(it != killed_files.end() && it->second == bytes) << name;
  }
}

TEST_F(SynthRun, RerunResumesAndAStageOptionRecomputesOnlyWhatDependsOnIt) {
  const fs::path j = job("j", seg, 100);
  ASSERT_EQ(lodforge("run " + j.string()).code, 0);
  nlohmann::json report = report_of(dir / "j_out" / "report.json");
  EXPECT_EQ(report.at("tiles_resumed"), 0) << report;
  ASSERT_EQ(lodforge("run " + j.string()).code, 0);
  report = report_of(dir / "j_out" / "report.json");
  EXPECT_EQ(report.at("tiles_processed"), 0) << report;
  EXPECT_EQ(report.at("tiles_resumed"), 16) << report;
  ASSERT_EQ(lodforge("run " + j.string() + " --set stages.labeling.kappa2=5").code, 0);
  report = report_of(dir / "j_out" / "report.json");
  EXPECT_EQ(report.at("checkpoints_reused"), nlohmann::json({{"contours", 16}, {"buildings", 0}})) << report;
}

// Checkpoints and done tiles are keyed by the program too: the same job rerun by another build
// (here the same binary with a byte appended, which runs alike) resumes nothing, its outlines may
// differ; rerun by that build again, it resumes its own tiles. The files an interrupted run of an
// earlier build wrote (no tile index yet; its markers of an older checkpoint version) stay its
// own: the new build replaces them.
TEST_F(SynthRun, AnotherBuildOfLodforgeResumesNothing) {
  const fs::path other = dir / "lodforge_other_build";
  fs::copy_file(LODFORGE_BINARY, other);
  std::ofstream(other, std::ios::binary | std::ios::app) << '\n';
  fs::permissions(other, fs::perms::owner_exec, fs::perm_options::add);
  const fs::path j = job("j", seg, 100);
  ASSERT_EQ(lodforge("run " + j.string()).code, 0);
  // As an interrupted run of a build of checkpoint version 4 leaves it: markers of that version
  // (the header's second word; the checksum covers the payload only), no index, no report.
  std::size_t markers = 0;
  for (const auto& e : fs::directory_iterator(dir / "j_work")) {
    if (e.path().extension() != ".done" && e.path().extension() != ".writing") continue;
    std::fstream f(e.path(), std::ios::binary | std::ios::in | std::ios::out);
    const std::uint32_t version = 4;
    f.seekp(4);
    f.write(reinterpret_cast<const char*>(&version), sizeof version);
    ++markers;
  }
  EXPECT_EQ(markers, 32u);
  fs::remove(dir / "j_out" / "tile_index.geojson");
  fs::remove(dir / "j_out" / "report.json");
  Result r = test::shell(other.string() + " run " + j.string());
  ASSERT_EQ(r.code, 0) << r.output;
  nlohmann::json report = report_of(dir / "j_out" / "report.json");
  EXPECT_EQ(report.at("tiles_resumed"), 0) << report;
  EXPECT_EQ(report.at("tiles_processed"), 16) << report;
  EXPECT_EQ(report.at("checkpoints_reused"), nlohmann::json({{"contours", 0}, {"buildings", 0}})) << report;
  ASSERT_EQ(test::shell(other.string() + " run " + j.string()).code, 0);
  report = report_of(dir / "j_out" / "report.json");
  EXPECT_EQ(report.at("tiles_resumed"), 16) << report;
}

// Each modeled building's outline model (docs/models.md) is in the tile files, as `regularize`
// writes it, and the report counts them: as many as the buildings regularized, again when resumed.
TEST_F(SynthRun, TheFilesAndTheReportTellEachBuildingsModel) {
  const fs::path j = job("j", seg, 100);
  ASSERT_EQ(lodforge("run " + j.string()).code, 0);
  const std::set<std::string> known{"regular", "lines", "lattice", "rectangle", "coarse_lattice", "staircase_lines", "merged_steps", "ellipse"};
  std::map<std::string, long long> in_files;
  std::size_t ok = 0, fallback = 0;
  GDALAllRegister();
  for (const auto& e : fs::directory_iterator(dir / "j_out" / "tiles")) {
    if (e.path().extension() != ".gpkg") continue;
    GDALDataset* d = static_cast<GDALDataset*>(GDALOpenEx(e.path().c_str(), GDAL_OF_VECTOR, nullptr, nullptr, nullptr));
    ASSERT_NE(d, nullptr) << e.path();
    OGRLayer* layer = d->GetLayerByName("footprints");
    ASSERT_NE(layer, nullptr) << e.path();
    const int field = layer->GetLayerDefn()->GetFieldIndex("model");
    ASSERT_GE(field, 0) << e.path();
    for (auto& f : *layer) {
      if (std::string(f->GetFieldAsString("status")) == "fallback") {
        ++fallback;
        EXPECT_TRUE(f->IsFieldNull(field)) << e.path();
        continue;
      }
      ++ok;
      ASSERT_FALSE(f->IsFieldNull(field)) << e.path();
      const std::string model = f->GetFieldAsString(field);
      EXPECT_TRUE(known.count(model)) << model;
      ++in_files[model];
    }
    GDALClose(d);
  }
  EXPECT_GT(ok, 10u);
  nlohmann::json report = report_of(dir / "j_out" / "report.json");
  std::map<std::string, long long> counted;
  for (const auto& [model, count] : report.at("models").items()) counted[model] = count.get<long long>();
  EXPECT_EQ(counted, in_files) << report;
  EXPECT_EQ(report.at("ok").get<std::size_t>(), ok) << report;
  EXPECT_EQ(report.at("fallback").get<std::size_t>(), fallback) << report;
  ASSERT_EQ(lodforge("run " + j.string()).code, 0);
  report = report_of(dir / "j_out" / "report.json");
  EXPECT_EQ(report.at("tiles_resumed"), 16) << report;
  EXPECT_EQ(report.at("models"), nlohmann::json(counted)) << report;
  ASSERT_EQ(lodforge("merge " + (dir / "j_out").string()).code, 0);
  EXPECT_NE(slurp(dir / "j_out" / "merged" / "report.html").find("model " + in_files.begin()->first), std::string::npos);
}

// Shards' reports merged: the counts by model are summed model by model, a model only a later
// shard kept included (a member the first report lacks is not passed over).
TEST(RunReports, ModelCountsOfShardsAreSummedModelByModel) {
  const fs::path dir = test::fresh_test_directory("lodforge_report_merge");
  const auto shard = [&](const std::string& name, const nlohmann::json& models) {
    const nlohmann::json report{{"shard", name}, {"ok", 5}, {"models", models}, {"seconds", 1.0}, {"noise_floor_m", 0.1},
                                {"noise_smoothing_m", 0.0}, {"failed_buildings", nlohmann::json::array()},
                                {"too_large_buildings", nlohmann::json::array()}, {"per_tile", nlohmann::json::array()}};
    std::ofstream(dir / name) << report.dump();
    return dir / name;
  };
  const std::vector<fs::path> parts{shard("a.json", {{"lattice", 2}, {"regular", 3}}), shard("b.json", {{"lattice", 1}, {"rectangle", 4}})};
  merge_run_reports(parts, dir / "merged.json");
  const nlohmann::json merged = nlohmann::json::parse(slurp(dir / "merged.json"));
  EXPECT_EQ(merged.at("models"), nlohmann::json({{"lattice", 3}, {"rectangle", 4}, {"regular", 3}})) << merged;
  EXPECT_EQ(merged.at("ok"), 10) << merged;
}

// The boundary noise every building allows for is pooled over a survey of the raster, not over
// its tile: the same for every tiling. Surveyed in one window, the whole raster, it is the noise
// `regularize` pools over the same buildings.
TEST_F(SynthRun, TheNoiseFloorIsTheRastersWhateverTheTiling) {
  // 64 cells of 50 m, of which 16 are surveyed.
  ASSERT_EQ(lodforge("run " + job("t60", seg, 60).string() + " --set tiling.noise_survey_window_m=50").code, 0);
  ASSERT_EQ(lodforge("run " + job("t100", seg, 100).string() + " --set tiling.noise_survey_window_m=50").code, 0);
  const double floor60 = report_of(dir / "t60_out" / "report.json").at("noise_floor_m").get<double>();
  EXPECT_GT(floor60, 0.0);
  EXPECT_LT(floor60, 1.0);
  EXPECT_EQ(floor60, report_of(dir / "t100_out" / "report.json").at("noise_floor_m").get<double>());
  ASSERT_EQ(lodforge("run " + job("whole", seg, 100, "").string() + " --set tiling.noise_survey_window_m=400").code, 0);
  const Result r = lodforge("regularize --mask " + seg + " --out " + (dir / "r.gpkg").string() + " --stats " + (dir / "r.json").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json stats = report_of(dir / "r.json");
  EXPECT_GT(stats.at("noise_samples").get<int>(), 20) << stats;
  EXPECT_LE(stats.at("lattice_lent").get<int>(), stats.at("buildings").get<int>()) << stats;
  EXPECT_DOUBLE_EQ(report_of(dir / "whole_out" / "report.json").at("noise_floor_m").get<double>(), stats.at("noise_floor_m").get<double>());
  // ... and the run's footprints are regularize's, outline for outline.
  const std::multiset<std::string> run = run_outlines(dir / "whole_out"), regularized = gpkg_outlines(dir / "r.gpkg");
  EXPECT_GT(run.size(), 20u);
  EXPECT_TRUE(run == regularized) << run.size() << " against " << regularized.size();
  // Off: each building its own noise, and some footprints change.
  ASSERT_EQ(lodforge("run " + job("off", seg, 100).string() + " --set tiling.noise_survey_windows=0").code, 0);
  EXPECT_EQ(report_of(dir / "off_out" / "report.json").at("noise_floor_m").get<double>(), 0.0);
  auto on = output_bytes(dir / "t100_out"), off = output_bytes(dir / "off_out");
  on.erase("report.json");
  off.erase("report.json");
  on.erase("tile_index.geojson");
  off.erase("tile_index.geojson");
  ASSERT_EQ(on.size(), off.size());
  EXPECT_FALSE(on == off);
}

// A mask whose boundary wobbles by a metre every 3 m (0.25 m pixels): the survey pools its noise
// in the rounds `regularize` pools it in, keeps the wider smoothing, and the run's buildings are
// smoothed for the same noise: its footprints are regularize's, outline for outline.
TEST_F(Run, AFastWobbleIsSmoothedAlikeInARunAndInRegularize) {
  const Result made = lodforge("synth --out " + (dir / "wobbly").string() +
                               " --size-m 200 --pixel-size 0.25 --seed 7 --set boundary_noise_m=1 --set noise_wavelength_m=3 --set corner_radius_m=2");
  ASSERT_EQ(made.code, 0) << made.output;
  const std::string seg = (dir / "wobbly" / "seg_class.tif").string();
  ASSERT_EQ(lodforge("run " + job("wobbly", seg, 100, "").string() + " --set tiling.noise_survey_window_m=400").code, 0);
  const Result r = lodforge("regularize --mask " + seg + " --out " + (dir / "w.gpkg").string() + " --stats " + (dir / "w.json").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json stats = report_of(dir / "w.json"), report = report_of(dir / "wobbly_out" / "report.json");
  EXPECT_GT(stats.at("noise_smoothing_m").get<double>(), 0.0) << stats;
  // One round alone (the narrow smoothing) pools less of that noise, and smooths for none.
  const Result narrow = lodforge("regularize --mask " + seg + " --out " + (dir / "n.gpkg").string() + " --stats " +
                                 (dir / "n.json").string() + " --set stages.smoothing.noise_rounds=1");
  ASSERT_EQ(narrow.code, 0) << narrow.output;
  const nlohmann::json narrow_stats = report_of(dir / "n.json");
  EXPECT_EQ(narrow_stats.at("noise_smoothing_m").get<double>(), 0.0) << narrow_stats;
  EXPECT_GT(stats.at("noise_floor_m").get<double>(), 1.1 * narrow_stats.at("noise_floor_m").get<double>()) << stats << narrow_stats;
  expect_run_is_regularize(report, stats, dir / "wobbly_out", dir / "w.gpkg", 5);
}

// A metre of wobble at a 2 m wavelength on 0.1 m pixels: the flanks cut the contour's runs short
// and the noise measured at the pixel comes out low (0.27 m), the outline keeps the wobble. The
// noise is measured first on the mask averaged to twice the pixel (stages.noise.coarse_resolved_px):
// 0.65 m there, at least 5 pixels, taken, and the outlines come out regular (N-ratio 0.88 against
// 6.6, IoU 0.93 against 0.88). A run in tiles measures it so too, and gives the same outlines.
TEST_F(Run, AFastMetreWobbleAtFinePixelsIsMeasuredAtTwiceThePixel) {
  const Result made = lodforge("synth --out " + (dir / "fast").string() +
                               " --size-m 150.1 --pixel-size 0.1 --seed 29 --set boundary_noise_m=1 --set noise_wavelength_m=2 --set corner_radius_m=2");
  ASSERT_EQ(made.code, 0) << made.output;
  const std::string seg = (dir / "fast" / "seg_class.tif").string(), truth = (dir / "fast" / "footprints.gpkg").string();
  Result r = lodforge("regularize --mask " + seg + " --out " + (dir / "c.gpkg").string() + " --stats " + (dir / "c.json").string());
  ASSERT_EQ(r.code, 0) << r.output;
  r = lodforge("regularize --mask " + seg + " --out " + (dir / "p.gpkg").string() + " --stats " + (dir / "p.json").string() +
               " --set stages.noise.coarse_resolved_px=0");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json coarse = report_of(dir / "c.json"), at_pixel = report_of(dir / "p.json");
  EXPECT_NEAR(coarse.at("noise_pixel_m").get<double>(), 0.2, 1e-9) << coarse;
  EXPECT_NEAR(at_pixel.at("noise_pixel_m").get<double>(), 0.1, 1e-9) << at_pixel;
  EXPECT_GE(coarse.at("noise_floor_m").get<double>(), 0.5) << coarse;
  EXPECT_LT(at_pixel.at("noise_floor_m").get<double>(), 0.6 * coarse.at("noise_floor_m").get<double>()) << at_pixel;
  const auto scores = [&](const std::string& pred) {
    const Result e = lodforge("eval --pred " + pred + " --gt " + truth + " --json " + (dir / "e.json").string());
    EXPECT_EQ(e.code, 0) << e.output;
    return report_of(dir / "e.json");
  };
  const nlohmann::json with = scores((dir / "c.gpkg").string()), without = scores((dir / "p.gpkg").string());
  EXPECT_LT(with.at("n_ratio").get<double>(), 1.5) << with;
  EXPECT_GT(without.at("n_ratio").get<double>(), 3.0) << without;
  EXPECT_GT(with.at("overall_iou").get<double>(), without.at("overall_iou").get<double>() + 0.02) << with << without;
  r = lodforge("run " + job("fast", seg, 60).string() + " --set tiling.noise_survey_window_m=400");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("of the mask averaged to twice its pixel"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("the raster's noise"), std::string::npos) << r.output;
  expect_run_is_regularize(report_of(dir / "fast_out" / "report.json"), coarse, dir / "fast_out", dir / "c.gpkg", 5);
}

// A mask whose corners the segmentation rounded by 2 m (0.1 m pixels, no wobble): most buildings
// measure that rounding on their own square corners; a few (an L whose rounded corners the outline
// draws with more walls than a corner counts) measure none and take the mask's
// (models.pooled_rounding_share). A run pools it over the noise survey's windows: the same for
// every tiling; surveyed in one window over the whole raster, regularize's, outline for outline.
TEST_F(Run, ACornerRoundingIsPooledAlikeInARunAndInRegularize) {
  const Result made = lodforge("synth --out " + (dir / "rounded").string() +
                               " --size-m 200 --pixel-size 0.1 --seed 7 --set boundary_noise_m=0 --set corner_radius_m=2");
  ASSERT_EQ(made.code, 0) << made.output;
  const std::string seg = (dir / "rounded" / "seg_class.tif").string();
  Result r = lodforge("regularize --mask " + seg + " --out " + (dir / "r.gpkg").string() + " --stats " + (dir / "r.json").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json stats = report_of(dir / "r.json");
  const nlohmann::json& rounding = stats.at("corner_rounding");
  std::cout << rounding << '\n';
  EXPECT_GT(rounding.at("pooled_m").get<double>(), 1.5) << rounding;
  EXPECT_LT(rounding.at("pooled_m").get<double>(), 2.5) << rounding;
  EXPECT_GE(rounding.at("took_pooled").get<int>(), 1) << rounding;
  EXPECT_GE(2 * rounding.at("buildings").get<int>(), rounding.at("measured").get<int>()) << rounding;  // (models.pooled_rounding_share)
  // Off: none pooled, and the buildings that took it come out otherwise.
  r = lodforge("regularize --mask " + seg + " --out " + (dir / "off.gpkg").string() + " --stats " + (dir / "off.json").string() +
               " --set models.pooled_rounding_share=0");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(report_of(dir / "off.json").at("corner_rounding").at("pooled_m").get<double>(), 0.0);
  EXPECT_FALSE(gpkg_outlines(dir / "r.gpkg") == gpkg_outlines(dir / "off.gpkg"));
  // The run, in one survey window: regularize's.
  r = lodforge("run " + job("whole", seg, 100).string() + " --set tiling.noise_survey_window_m=400");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("corner rounding pooled over the"), std::string::npos) << r.output;
  expect_run_is_regularize(report_of(dir / "whole_out" / "report.json"), stats, dir / "whole_out", dir / "r.gpkg", 10);
  // In windows of 50 m, the same in tiles of 60 and 100 m.
  for (const int tile : {60, 100}) {
    r = lodforge("run " + job("t" + std::to_string(tile), seg, tile).string() + " --set tiling.noise_survey_window_m=50");
    ASSERT_EQ(r.code, 0) << r.output;
  }
  const double t60 = report_of(dir / "t60_out" / "report.json").at("corner_rounding_m").get<double>();
  EXPECT_GT(t60, 1.5);
  EXPECT_EQ(t60, report_of(dir / "t100_out" / "report.json").at("corner_rounding_m").get<double>());
  EXPECT_TRUE(run_outlines(dir / "t60_out") == run_outlines(dir / "t100_out"));
  // The noise not pooled (each building its own): the rounding still is, in a run as in regularize.
  r = lodforge("regularize --mask " + seg + " --out " + (dir / "own.gpkg").string() + " --stats " + (dir / "own.json").string() +
               " --set noise.pooled_floor=0");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json own = report_of(dir / "own.json");
  EXPECT_GT(own.at("corner_rounding").at("pooled_m").get<double>(), 1.5) << own;
  r = lodforge("run " + job("own", seg, 100).string() + " --set tiling.noise_survey_window_m=400 --set stages.noise.pooled_floor=0");
  ASSERT_EQ(r.code, 0) << r.output;
  expect_run_is_regularize(report_of(dir / "own_out" / "report.json"), own, dir / "own_out", dir / "own.gpkg", 10);
}

// A mask averaged over 2 x 2 blocks whole and window by window (as a survey reads it) agree,
// at the odd right and bottom edges too: a block half outside the mask is a building only where
// both of its pixels inside are.
TEST(AveragedMask, WholeAndWindowByWindowAgreeAtOddEdges) {
  std::mt19937 random(5);
  MaskRaster mask;
  mask.mask = cv::Mat(23, 37, CV_8U);
  for (int y = 0; y < 23; ++y)
    for (int x = 0; x < 37; ++x) mask.mask.at<uint8_t>(y, x) = uint8_t(random() % 2);
  mask.transform.c = {1000, 0.1, 0, 2000, 0, -0.1};
  const MaskRaster whole = averaged(mask, 2);
  ASSERT_EQ(whole.mask.size(), cv::Size(19, 12));
  EXPECT_NEAR(whole.transform.c[1], 0.2, 1e-12);
  EXPECT_NEAR(whole.transform.c[5], -0.2, 1e-12);
  EXPECT_EQ(whole.transform.c[0], 1000);
  for (const cv::Rect blocks : {cv::Rect(0, 0, 19, 12), cv::Rect(10, 5, 9, 7), cv::Rect(17, 11, 2, 1), cv::Rect(3, 2, 4, 4)}) {
    const cv::Rect fine = cv::Rect(blocks.x * 2, blocks.y * 2, blocks.width * 2, blocks.height * 2) & cv::Rect(0, 0, 37, 23);
    const cv::Mat window = average_blocks(mask.mask(fine), blocks.size(), 2);
    EXPECT_EQ(cv::countNonZero(window != whole.mask(blocks)), 0) << blocks.x << "," << blocks.y;
  }
  // The last column's blocks hold two pixels of their four, a building where both are; the corner's one.
  for (int y = 0; y < 11; ++y)
    EXPECT_EQ(whole.mask.at<uint8_t>(y, 18), uint8_t(mask.mask.at<uint8_t>(2 * y, 36) && mask.mask.at<uint8_t>(2 * y + 1, 36))) << y;
  EXPECT_EQ(whole.mask.at<uint8_t>(11, 18), 0);
  EXPECT_EQ(whole.mask.at<uint8_t>(0, 0), uint8_t(mask.mask.at<uint8_t>(0, 0) + mask.mask.at<uint8_t>(0, 1) + mask.mask.at<uint8_t>(1, 0) +
                                                     mask.mask.at<uint8_t>(1, 1) >= 2));
}

// A network's probability raster, as 32-bit floats and as bytes 0-255, is read by a threshold
// (regularize --building-min, a job's inputs.segmentation.building_min): the class mask's
// buildings, never at the band's nodata value (a strip of it above the threshold). Read by a
// class value it is told what it holds and the threshold to try.
TEST_F(Run, AProbabilityMaskIsReadByAThreshold) {
  const Result made = lodforge("synth --out " + (dir / "city").string() + " --size-m 150 --seed 3");
  ASSERT_EQ(made.code, 0) << made.output;
  GDALAllRegister();
  GDALDataset* classes = static_cast<GDALDataset*>(GDALOpen((dir / "city" / "seg_class.tif").c_str(), GA_ReadOnly));
  ASSERT_NE(classes, nullptr);
  const int w = classes->GetRasterXSize(), h = classes->GetRasterYSize();
  cv::Mat value(h, w, CV_8U);
  ASSERT_EQ(classes->GetRasterBand(1)->RasterIO(GF_Read, 0, 0, w, h, value.data, w, h, GDT_Byte, 0, 0), CE_None);
  RasterMeta meta;
  classes->GetGeoTransform(meta.transform.c.data());
  meta.crs_wkt = classes->GetProjectionRef();
  GDALClose(classes);
  cv::Mat probability(h, w, CV_32F), bytes(h, w, CV_8U);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float spread = 0.45f * float((7 * x + 13 * y) % 100) / 100.0f;
      const bool building = value.at<uint8_t>(y, x) == 6;
      probability.at<float>(y, x) = building ? 0.55f + spread : (y < 10 ? 2.0f : spread);
      bytes.at<uint8_t>(y, x) = uint8_t(std::lround(255 * (building ? 0.55f + spread : spread)));
    }
  RasterMeta with_nodata = meta, nan_nodata = meta;
  with_nodata.nodata = 2, with_nodata.has_nodata = true;
  write_geotiff((dir / "probability.tif").string(), {probability}, with_nodata);
  write_geotiff((dir / "bytes.tif").string(), {bytes}, meta);
  cv::Mat with_nan = probability.clone();
  with_nan.setTo(std::numeric_limits<float>::quiet_NaN(), probability == 2.0f);
  nan_nodata.nodata = std::numeric_limits<double>::quiet_NaN(), nan_nodata.has_nodata = true;
  write_geotiff((dir / "nan.tif").string(), {with_nan}, nan_nodata);
  ASSERT_EQ(lodforge("regularize --mask " + (dir / "city" / "seg_class.tif").string() + " --out " + (dir / "c.gpkg").string()).code, 0);
  Result r = lodforge("regularize --mask " + (dir / "probability.tif").string() + " --building-min 0.5 --out " + (dir / "p.gpkg").string());
  ASSERT_EQ(r.code, 0) << r.output;
  r = lodforge("regularize --mask " + (dir / "bytes.tif").string() + " --building-min 128 --out " + (dir / "b.gpkg").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const std::multiset<std::string> expected = gpkg_outlines(dir / "c.gpkg");
  EXPECT_GT(expected.size(), 5u);
  EXPECT_TRUE(gpkg_outlines(dir / "p.gpkg") == expected);
  EXPECT_TRUE(gpkg_outlines(dir / "b.gpkg") == expected);
  // Read by a class value: what it holds (its nodata value, 2 or a NaN, not among them) and a
  // threshold; a float of 0.85 is not class 1 (GDAL's conversion to integers would round it).
  for (const char* name : {"probability.tif", "nan.tif"}) {
    r = lodforge("regularize --mask " + (dir / name).string() + " --out " + (dir / "x.gpkg").string());
    EXPECT_EQ(r.code, 1) << r.output;
    EXPECT_NE(r.output.find("no building pixel (value 6) in the raster; its band 1 holds"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("different values, from 0 to 0.9955 (a probability or a score?): select the buildings by a threshold "
                            "(regularize --building-min V, e.g. 0.5; a job's inputs.segmentation.building_min)"),
              std::string::npos)
        << name << r.output;
  }
  r = lodforge("regularize --mask " + (dir / "probability.tif").string() + " --building-value 1 --out " + (dir / "x.gpkg").string());
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("no building pixel (value 1) in the raster"), std::string::npos) << r.output;
  // Its bytes read by a class value: a few pixels each of many values, none a building, and a threshold besides.
  r = lodforge("regularize --mask " + (dir / "bytes.tif").string() + " --out " + (dir / "x.gpkg").string());
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("no building of at least 4 m^2 and 2 pixels"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("more values: select the buildings by their value (regularize --building-value V; a job's "
                          "inputs.segmentation.building_values) or, a probability or a score, by a threshold (regularize "
                          "--building-min V, e.g. 127;"),
            std::string::npos)
      << r.output;
  r = lodforge("regularize --mask " + (dir / "bytes.tif").string() + " --building-min 1 --building-value 6 --out " + (dir / "x.gpkg").string());
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("give one of --building-value, --building-rgb and --building-min, not several"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "x.gpkg"));
  // A job's threshold, in tiles: the same buildings; with a colour as well, refused.
  std::ofstream(dir / "p.yaml") << "inputs:\n  segmentation: {path: " << (dir / "probability.tif").string()
                                << ", building_min: [0.5]}\ntiling: {tile_size_m: 60}\noutput: {dir: p_out}\nwork_dir: p_work\n";
  r = lodforge("run " + (dir / "p.yaml").string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(run_outlines(dir / "p_out") == expected);
  std::ofstream(dir / "b.yaml") << "inputs:\n  segmentation: {path: " << (dir / "bytes.tif").string()
                                << ", building_min: [128]}\ntiling: {tile_size_m: 60}\noutput: {dir: b_out}\nwork_dir: b_work\n";
  r = lodforge("run " + (dir / "b.yaml").string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(run_outlines(dir / "b_out") == expected);
  std::ofstream(dir / "both.yaml") << "inputs:\n  segmentation: {path: " << (dir / "probability.tif").string()
                                   << ", building_min: [0.5], building_rgb: [0, 0, 255]}\noutput: {dir: both_out}\nwork_dir: both_work\n";
  r = lodforge("run " + (dir / "both.yaml").string());
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("inputs.segmentation.building_min: give it or building_rgb, not both"), std::string::npos) << r.output;
}

// At 0.1 m pixels (not exact in binary) under a fractional origin and half a metre of wobble,
// tiles of 47 m, one tile and `regularize` give the same outlines (16 buildings): a
// window's coordinates (its origin plus its pixels) come out as the whole raster's.
TEST_F(Run, TilesAndRegularizeAgreeOnAnInexactGrid) {
  const Result made = lodforge("synth --out " + (dir / "w").string() + " --size-m 200 --pixel-size 0.1 --seed 6 --set boundary_noise_m=0.5");
  ASSERT_EQ(made.code, 0) << made.output;
  GDALAllRegister();
  const fs::path moved = dir / "w" / "moved.tif";
  {
    GDALDataset* source = static_cast<GDALDataset*>(GDALOpen((dir / "w" / "seg_class.tif").c_str(), GA_ReadOnly));
    ASSERT_NE(source, nullptr);
    GDALDataset* copy = GetGDALDriverManager()->GetDriverByName("GTiff")->CreateCopy(moved.c_str(), source, FALSE, nullptr, nullptr, nullptr);
    ASSERT_NE(copy, nullptr);
    double gt[6] = {85000.0371, 0.1, 0, 447000.0913, 0, -0.1};
    copy->SetGeoTransform(gt);
    GDALClose(copy);
    GDALClose(source);
  }
  Result r = lodforge("run " + job("small", moved.string(), 47).string());
  ASSERT_EQ(r.code, 0) << r.output;
  r = lodforge("run " + job("whole", moved.string(), 200).string());
  ASSERT_EQ(r.code, 0) << r.output;
  r = lodforge("regularize --mask " + moved.string() + " --out " + (dir / "r.gpkg").string() + " --stats " + (dir / "r.json").string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_GE(report_of(dir / "r.json").at("buildings").get<int>(), 10);
  const auto small = run_outlines(dir / "small_out"), whole = run_outlines(dir / "whole_out"), regularized = gpkg_outlines(dir / "r.gpkg");
  EXPECT_TRUE(small == whole);
  EXPECT_TRUE(whole == regularized) << whole.size() << " against " << regularized.size();
}

// A shed beside a long block whose centre lies 36 m off, beyond the neighbours' radius, takes the
// block's lattice by its box (6 m from the shed's centre, within half the radius): in tiles of 40 m, where
// the shed's tile is not the block's, as in `regularize` (a tile's lenders reach the boxes that
// come within half the radius of its buildings' centres, not only the centres within it).
TEST_F(Run, AShedTakesTheLatticeOfABlockBesideItInEveryTiling) {
  const int size = 60;  // pixels of 2 m: 120 m a side
  const double pixel = 2, west = 85000, north = 447120;
  // (u, v): metres east and north of the raster's south-west corner.
  const auto in_rectangle = [](double u, double v, double cu, double cv, double deg, double length, double width) {
    const double a = deg * M_PI / 180, du = u - cu, dv = v - cv;
    return std::abs(du * std::cos(a) + dv * std::sin(a)) <= length / 2 && std::abs(-du * std::sin(a) + dv * std::cos(a)) <= width / 2;
  };
  std::vector<unsigned char> mask(std::size_t(size * size), 0);
  for (int row = 0; row < size; ++row)
    for (int col = 0; col < size; ++col) {
      const double u = (col + 0.5) * pixel, v = size * pixel - (row + 0.5) * pixel;
      // The block, 80 x 16 m at 24 degrees; the shed, 4 x 4 m, 30 m back along it from its centre
      // and 20 m across (36 m off), in another tile than the block's first pixel (its north-east end).
      if (in_rectangle(u, v, 70, 40, 24, 80, 16) || in_rectangle(u, v, 50.7, 9.5, 0, 4, 4)) mask[std::size_t(row * size + col)] = 6;
    }
  GDALAllRegister();
  const fs::path tif = dir / "shed.tif";
  {
    GDALDataset* d = GetGDALDriverManager()->GetDriverByName("GTiff")->Create(tif.c_str(), size, size, 1, GDT_Byte, nullptr);
    ASSERT_NE(d, nullptr);
    double gt[6] = {west, pixel, 0, north, 0, -pixel};
    d->SetGeoTransform(gt);
    OGRSpatialReference crs;
    crs.importFromEPSG(28992);
    d->SetSpatialRef(&crs);
    ASSERT_EQ(d->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, size, size, mask.data(), size, size, GDT_Byte, 0, 0, nullptr), CE_None);
    GDALClose(d);
  }
  Result r = lodforge("regularize --mask " + tif.string() + " --out " + (dir / "r.gpkg").string() + " --stats " + (dir / "r.json").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json stats = report_of(dir / "r.json");
  ASSERT_EQ(stats.at("buildings").get<int>(), 2);
  EXPECT_EQ(stats.at("lattice_lent").get<int>(), 1);
  r = lodforge("run " + job("small", tif.string(), 40).string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(run_outlines(dir / "small_out") == gpkg_outlines(dir / "r.gpkg"));
  // The block's box (its traced pixels') 6 m from the shed's centre: a radius of 10 m reaches
  // neither its centre nor, at half of it, its box, and the shed keeps the pixel grid.
  r = lodforge("regularize --mask " + tif.string() + " --out " + (dir / "alone.gpkg").string() + " --stats " + (dir / "alone.json").string() +
               " --set stages.lattice.neighbour_radius_m=10");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(report_of(dir / "alone.json").at("lattice_lent").get<int>(), 0);
  EXPECT_FALSE(gpkg_outlines(dir / "alone.gpkg") == gpkg_outlines(dir / "r.gpkg"));
}

// The lenders' margins in pixels follow the geotransform: north-up square pixels (metres over
// the pixel size), pixels turned by 45 degrees (a box of S a side spans S sqrt 2 along either
// pixel axis), and pixels of 0.5 x 0.25 m (twice as many columns, four times as many rows a metre).
TEST(LatticeLenders, MarginsFollowTheGeotransform) {
  LatticeOptions o;
  o.neighbour_radius_m = 30;
  o.neighbour_max_extent_m = 100;
  GeoTransform north;
  north.c = {1000, 0.25, 0, 2000, 0, -0.25};
  LenderMargins m = lender_margins(north, o);
  EXPECT_NEAR(m.reach.x(), 122, 1e-9);
  EXPECT_NEAR(m.reach.y(), 122, 1e-9);
  EXPECT_NEAR(m.extent.x(), 402, 1e-9);
  EXPECT_NEAR(m.window.y(), 122 + 402, 1e-9);
  const double p = 0.5, a = M_PI / 4;
  GeoTransform turned;
  turned.c = {1000, p * std::cos(a), p * std::sin(a), 2000, p * std::sin(a), -p * std::cos(a)};
  m = lender_margins(turned, o);
  EXPECT_NEAR(m.reach.x(), 30 / p + 2, 1e-9);
  EXPECT_NEAR(m.extent.x(), 100 * std::sqrt(2.0) / p + 2, 1e-9);
  EXPECT_NEAR(m.extent.y(), 100 * std::sqrt(2.0) / p + 2, 1e-9);
  GeoTransform oblong;
  oblong.c = {1000, 0.5, 0, 2000, 0, -0.25};
  m = lender_margins(oblong, o);
  EXPECT_NEAR(m.reach.x(), 30 * 2 + 2, 1e-9);
  EXPECT_NEAR(m.reach.y(), 30 * 4 + 2, 1e-9);
  EXPECT_NEAR(m.extent.y(), 100 * 4 + 2, 1e-9);
}

// A neighbours' lattice the tiles cannot lend within the largest window a tile may read is
// refused, naming the keys; without a limit on the lenders' extent the run says it lends none.
TEST_F(Run, LendersBeyondTheLargestWindowAreRefused) {
  const Result made = lodforge("synth --out " + (dir / "c").string() + " --size-m 120 --seed 2");
  ASSERT_EQ(made.code, 0) << made.output;
  const std::string seg = (dir / "c" / "seg_class.tif").string();
  Result r = lodforge("run " + job("wide", seg, 100).string() + " --set tiling.max_window_m=300");
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.output.find("neighbour_max_extent_m"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("tiling.max_window_m"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "wide_out" / "report.json"));
  r = lodforge("run " + job("none", seg, 100).string() + " --set stages.lattice.neighbour_max_extent_m=0");
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("lends no building its neighbours' lattice"), std::string::npos) << r.output;
}

// The buildings a smoothing round is judged on spread over all of them, in order, each once.
TEST(NoiseSurvey, TheJudgedBuildingsSpreadOverTheMask) {
  EXPECT_EQ(spread_indices(10, 4), (std::vector<std::size_t>{0, 2, 5, 7}));
  EXPECT_EQ(spread_indices(3, 128), (std::vector<std::size_t>{0, 1, 2}));
  EXPECT_EQ(spread_indices(1000, 1), (std::vector<std::size_t>{0}));
  EXPECT_TRUE(spread_indices(0, 128).empty());
  const std::vector<std::size_t> s = spread_indices(10000, 128);
  ASSERT_EQ(s.size(), 128u);
  EXPECT_TRUE(std::adjacent_find(s.begin(), s.end(), [](std::size_t a, std::size_t b) { return b - a < 78 || b - a > 79; }) == s.end());
  EXPECT_GE(s.back(), 9921u);
}

// The survey's cells spread over both axes of the raster, not along one column; a raster of
// fewer cells than windows is surveyed whole.
TEST(NoiseSurvey, CellsSpreadOverBothAxes) {
  for (const int side : {16, 32, 64}) {
    const std::vector<cv::Rect> cells = survey_cells(cv::Size(side * 100, side * 100), 100, 16);
    ASSERT_EQ(cells.size(), 16u) << side;
    std::set<int> rows, cols;
    for (const cv::Rect& c : cells) {
      rows.insert(c.y);
      cols.insert(c.x);
      EXPECT_EQ(c.area(), 100 * 100);
    }
    EXPECT_EQ(rows.size(), 4u) << side;
    EXPECT_EQ(cols.size(), 4u) << side;
    EXPECT_GT(*cols.begin(), 0) << side;  // not at the edges
    EXPECT_LT(*cols.rbegin(), (side - 1) * 100) << side;
  }
  // A strip: its rows and columns in proportion.
  const std::vector<cv::Rect> strip = survey_cells(cv::Size(6400, 1600), 100, 16);  // 64 x 16 cells
  std::set<int> strip_rows, strip_cols;
  for (const cv::Rect& c : strip) {
    strip_rows.insert(c.y);
    strip_cols.insert(c.x);
  }
  EXPECT_EQ(strip.size(), 16u);
  EXPECT_EQ(strip_rows.size(), 2u);
  EXPECT_EQ(strip_cols.size(), 8u);
  // Fewer cells than windows: all of them, the last cut by the raster's edge.
  const std::vector<cv::Rect> all = survey_cells(cv::Size(250, 130), 100, 16);
  ASSERT_EQ(all.size(), 6u);
  EXPECT_EQ(all.back(), cv::Rect(200, 100, 50, 30));
  EXPECT_TRUE(survey_cells(cv::Size(250, 130), 100, 0).empty());
}

TEST_F(SynthRun, ShardsTogetherGiveTheSingleRunOutputs) {
  ASSERT_EQ(lodforge("run " + job("single", seg, 60).string()).code, 0);
  const fs::path sharded = job("sharded", seg, 60);
  for (int k = 0; k < 3; ++k) {
    const Result r = lodforge("run " + sharded.string() + " --shard " + std::to_string(k) + "/3");
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_TRUE(fs::exists(dir / "sharded_out" / ("report.shard-" + std::to_string(k) + "-of-3.json")));
  }
  auto single = output_bytes(dir / "single_out"), parts = output_bytes(dir / "sharded_out");
  single.erase("tile_index.geojson");
  parts.erase("tile_index.geojson");
  EXPECT_TRUE(single == parts);
  EXPECT_EQ(lodforge("run " + sharded.string() + " --shard 3/3").code, 1);
  // Merging the shards' tile indexes gives the single run's index.
  ASSERT_EQ(lodforge("merge " + (dir / "sharded_out").string()).code, 0);
  EXPECT_EQ(slurp(dir / "sharded_out" / "tile_index.geojson"), slurp(dir / "single_out" / "tile_index.geojson"));
  // ... and the shards' reports the single run's report, but for the seconds and the shard line.
  const nlohmann::json merged = report_of(dir / "sharded_out" / "report.json");
  EXPECT_EQ(merged.at("shard"), "merged 3") << merged;
  EXPECT_EQ(without_timings(merged), without_timings(report_of(dir / "single_out" / "report.json")));
  // Stage seconds are summed over the shards: each stage took time (no heights: no DSM here), the
  // regularization is the core seconds.
  const nlohmann::json& stages = merged.at("stage_seconds");
  for (const char* stage : {"contours", "regularization", "writing"}) EXPECT_GT(stages.at(stage).get<double>(), 0) << stage << "\n" << merged;
  EXPECT_EQ(stages.at("heights").get<double>(), 0) << merged;
  const double core = merged.at("core_seconds").get<double>();
  EXPECT_NEAR(stages.at("regularization").get<double>(), core, 1e-3 * core);
  // A missing shard report is refused.
  fs::remove(dir / "sharded_out" / "report.shard-1-of-3.json");
  const Result incomplete = lodforge("merge " + (dir / "sharded_out").string());
  EXPECT_EQ(incomplete.code, 1);
  EXPECT_NE(incomplete.output.find("2 of 3 shards' run reports"), std::string::npos) << incomplete.output;
}

// Peak memory of a child process run (KiB).
long peak_rss_kib(const std::string& arguments) {
  const pid_t pid = fork();
  if (pid == 0) {
    const int null = ::open("/dev/null", O_WRONLY);
    dup2(null, 1);
    dup2(null, 2);
    std::vector<std::string> words;
    std::istringstream in(arguments);
    for (std::string w; in >> w;) words.push_back(w);
    std::vector<char*> argv{const_cast<char*>(LODFORGE_BINARY)};
    for (std::string& w : words) argv.push_back(w.data());
    argv.push_back(nullptr);
    execv(LODFORGE_BINARY, argv.data());
    _exit(127);
  }
  int status = 0;
  struct rusage usage {};
  wait4(pid, &status, 0, &usage);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << arguments;
  return usage.ru_maxrss;
}

TEST_F(Run, MemoryIsBoundedByTheTilesInFlightNotByTheArea) {
  // Two cities, the second four times the area; the raster is only ever read in windows and
  // GDAL's cache is capped, so peak memory must not grow with the area.
  for (const char* size : {"500", "1000"})
    ASSERT_EQ(lodforge("synth --out " + (dir / size).string() + " --size-m " + size + " --seed 2").code, 0);
  const std::string extra = "tiling: {tile_size_m: 100, gdal_cache_mb: 8}\n";
  auto job_for = [&](const char* size) {
    const fs::path p = dir / (std::string(size) + ".yaml");
    std::ofstream(p) << "inputs: {segmentation: {path: " << (dir / size / "seg_class.tif").string() << "}}\n"
                     << extra << "output: {dir: " << size << "_out}\nwork_dir: " << size << "_work\n";
    return p.string();
  };
  const long small = peak_rss_kib("run " + job_for("500") + " --threads 2");
  const long large = peak_rss_kib("run " + job_for("1000") + " --threads 2");
  // The 1000 m raster decoded whole would be 4000 x 4000 x 4 bytes = 62,500 KiB more.
  EXPECT_LT(large, small + 20000) << "peak RSS " << small << " KiB at 1x, " << large << " KiB at 4x";
}

TEST_F(Run, JobErrorsAreReportedTogetherWithTheirKeyPaths) {
  const fs::path bad = dir / "bad.yaml";
  std::ofstream(bad) << "inputs:\n  segmentation: {path: nowhere.tif, building_values: [six]}\n"
                     << "tiling: {tile_size_m: -5, colour: red}\nthreads: 1.5\n"
                     << "stages: {labeling: {kappa2: -1}, corners: {route: sideways}}\nextra: 1\n";
  const Result r = lodforge("run " + bad.string());
  EXPECT_EQ(r.code, 1);
  for (const char* expected : {"inputs.segmentation.building_values[0]: expected an integer", "tiling.tile_size_m: must be > 0",
                               "tiling.colour: unknown key", "threads: expected an integer", "stages.labeling.kappa2: must be >= 0",
                               "stages.corners.route: must be one of: original, deformed", "extra: unknown key",
                               "inputs.segmentation.path: '"})
    EXPECT_NE(r.output.find(expected), std::string::npos) << expected << "\n" << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));

  std::ofstream(dir / "broken.yaml") << "inputs: {segmentation: [unclosed\n";
  const Result broken = lodforge("run " + (dir / "broken.yaml").string());
  EXPECT_EQ(broken.code, 1);
  EXPECT_NE(broken.output.find("broken.yaml': not valid YAML: line"), std::string::npos) << broken.output;
  const Result missing = lodforge("run " + (dir / "none.yaml").string());
  EXPECT_NE(missing.output.find("none.yaml': job file not found"), std::string::npos) << missing.output;
}

TEST_F(Run, DefaultJobIsPrintedAndReadsBackUnchanged) {
  const Result r = lodforge("config --defaults");
  ASSERT_EQ(r.code, 0);
  EXPECT_NE(r.output.find("tile_size_m: 250"), std::string::npos);
  EXPECT_NE(r.output.find("    kappa2: 10"), std::string::npos) << r.output;
  // The printed defaults are a valid job once a segmentation is given.
  std::string text = r.output;
  text.replace(text.find("path: \"\""), 8, "path: " + test::test_data() + "/delft-ahn3-bgt/derived/top_class_50cm.tif");
  std::ofstream(dir / "defaults.yaml") << text;
  const Result run = lodforge("run " + (dir / "defaults.yaml").string());
  EXPECT_EQ(run.code, 0) << run.output;
}

}  // namespace
}  // namespace lodforge

namespace lodforge {
namespace {

TEST(Config, CommittedDefaultJobMatchesTheBinary) {
  const Result r = lodforge("config --defaults");
  ASSERT_EQ(r.code, 0);
  EXPECT_EQ(slurp(fs::path(LODFORGE_SOURCE_DIR) / "config" / "default.yaml"), r.output)
      << "regenerate with: build/lodforge config --defaults > config/default.yaml";
}

TEST(Config, ExampleJobsAreValid) {
  for (const char* name : {"examples/delft.yaml", "examples/isprs_colours.yaml"}) {
    const fs::path job = fs::path(LODFORGE_SOURCE_DIR) / "config" / name;
    const fs::path out = fs::temp_directory_path() / ("lodforge_example_" + std::to_string(::getpid()));
    fs::remove_all(out);
    // Run with outputs redirected to a temporary place (and the fast route: the file itself is
    // validated in full before overrides apply).
    const Result r = lodforge("run " + job.string() + " --set output.dir=" + (out / "out").string() +
                              " --set work_dir=" + (out / "work").string() + " --set stages.corners.route=original");
    EXPECT_EQ(r.code, 0) << name << ": " << r.output;
    EXPECT_TRUE(fs::exists(out / "out" / "report.json")) << name;
    fs::remove_all(out);
  }
}

}  // namespace
}  // namespace lodforge

namespace lodforge {
namespace {

class Rerun : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = test::fresh_test_directory("lodforge_rerun");
    ASSERT_EQ(lodforge("synth --out " + (dir / "city").string() + " --size-m 200 --seed 6").code, 0);
  }
  fs::path write_job(const std::string& formats, const std::string& extra = "") {
    std::ofstream(dir / "job.yaml") << "inputs: {segmentation: {path: city/seg_class.tif}}\ntiling: {tile_size_m: 50}\n"
                                    << "output: {dir: out, formats: [" << formats << "], quicklook: false}\nwork_dir: work\n" << extra;
    return dir / "job.yaml";
  }
  fs::path dir;
};

TEST_F(Rerun, FilesOfAnEarlierRunDoNotOutliveItAndMergeTakesTheIndexedFiles) {
  ASSERT_EQ(lodforge("run " + write_job("gpkg, obj").string()).code, 0);
  std::size_t obj = 0;
  for (const auto& e : fs::directory_iterator(dir / "out" / "tiles")) obj += e.path().extension() == ".obj";
  ASSERT_GT(obj, 0u);
  // The same job without OBJ: every tile is recomputed and its old OBJ goes.
  ASSERT_EQ(lodforge("run " + write_job("gpkg").string()).code, 0);
  for (const auto& e : fs::directory_iterator(dir / "out" / "tiles")) EXPECT_NE(e.path().extension(), ".obj") << e.path();
  // A stray file in tiles/ is not merged: merge reads the tile index.
  fs::copy_file(dir / "out" / "tiles" / "r0000_c0000.gpkg", dir / "out" / "tiles" / "r9999_c9999.gpkg");
  ASSERT_EQ(lodforge("merge " + (dir / "out").string()).code, 0);
  GDALAllRegister();
  auto count = [](const fs::path& p) {
    GDALDataset* d = static_cast<GDALDataset*>(GDALOpenEx(p.c_str(), GDAL_OF_VECTOR, nullptr, nullptr, nullptr));
    const long n = d ? long(d->GetLayer(0)->GetFeatureCount()) : -1;
    if (d) GDALClose(d);
    return n;
  };
  long tiles_total = 0;
  for (const auto& e : fs::directory_iterator(dir / "out" / "tiles"))
    if (e.path().extension() == ".gpkg" && e.path().filename() != "r9999_c9999.gpkg") tiles_total += count(e.path());
  EXPECT_EQ(count(dir / "out" / "merged" / "lodforge.gpkg"), tiles_total);
  EXPECT_FALSE(fs::exists(dir / "out" / "merged" / "lodforge.obj"));
}

TEST_F(Rerun, MergeRefusesAnIncompleteSetOfShards) {
  const fs::path job = write_job("gpkg");
  ASSERT_EQ(lodforge("run " + job.string() + " --shard 0/3").code, 0);
  ASSERT_EQ(lodforge("run " + job.string() + " --shard 2/3").code, 0);
  const Result r = lodforge("merge " + (dir / "out").string());
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("2 of 3 shards' tile indexes are there"), std::string::npos) << r.output;
}

TEST_F(Rerun, WindowSmallerThanATileIsRefused) {
  const Result r = lodforge("run " + write_job("gpkg", "").string() + " --set tiling.max_window_m=60");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("tiling.max_window_m: must be >= tile_size_m + 2 * halo_m"), std::string::npos) << r.output;
}

// Issue 15: every building of the mask is in the outputs whatever the tiling: tile sizes that
// cut buildings, with no halo or a small one, give the one-tile run's footprints.
TEST_F(SynthRun, EveryTilingGivesTheOneTileRunsBuildings) {
  Result r = lodforge("run " + job("whole", seg, 400).string());
  ASSERT_EQ(r.code, 0) << r.output;
  const auto whole = footprints(dir / "whole_out");
  ASSERT_GT(whole.size(), 20u);
  int k = 0;
  for (const double tile : {37.0, 60.0, 100.0})
    for (const double halo : {0.0, 0.3, 3.0}) {
      const std::string name = std::string("t").append(std::to_string(k++));
      r = lodforge("run " + job(name, seg, tile).string() + " --set tiling.halo_m=" + std::to_string(halo));
      ASSERT_EQ(r.code, 0) << r.output;
      EXPECT_TRUE(footprints(dir / (name + "_out")) == whole) << "tile " << tile << " m, halo " << halo << " m";
    }
}

// Issue 15: a checkpoint or an output that changed after it was written is not trusted: the
// tile is computed again, and merge refuses files that are not as the run wrote them.
TEST_F(Rerun, ChangedCheckpointsAndOutputsAreNotTrusted) {
  const fs::path job = write_job("gpkg, obj, cityjson");
  ASSERT_EQ(lodforge("run " + job.string()).code, 0);
  const auto ref = output_bytes(dir / "out");
  // One coordinate byte changed in a footprint checkpoint (the tile's done marker removed).
  const fs::path buildings = dir / "work" / "r0001_c0001.buildings";
  ASSERT_TRUE(fs::exists(buildings));
  std::string bytes = slurp(buildings);
  bytes[bytes.size() / 2] ^= 0x10;
  std::ofstream(buildings, std::ios::binary | std::ios::trunc) << bytes;
  fs::remove(dir / "work" / "r0001_c0001.done");
  Result r = lodforge("run " + job.string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(output_bytes(dir / "out") == ref);
  // An output deleted, another truncated: merge names them and writes nothing ...
  fs::remove(dir / "out" / "tiles" / "r0001_c0001.obj");
  fs::resize_file(dir / "out" / "tiles" / "r0001_c0002.city.json", 100);
  r = lodforge("merge " + (dir / "out").string());
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("r0001_c0001.obj' is missing"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("r0001_c0002.city.json' changed since the run wrote it"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out" / "merged"));
  // ... a rerun writes those tiles again, and merge takes them.
  r = lodforge("run " + job.string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("r0001_c0001.obj is missing or changed"), std::string::npos) << r.output;
  EXPECT_TRUE(output_bytes(dir / "out") == ref);
  ASSERT_EQ(lodforge("merge " + (dir / "out").string()).code, 0);
  for (const auto& e : fs::directory_iterator(dir / "out" / "merged"))
    EXPECT_EQ(e.path().filename().string().find("partial"), std::string::npos) << e.path();
}

// Issue 15: a rerun with other options removes the earlier index and report as it starts, so a
// rerun killed part-way cannot leave an index that merge takes with a mix of tiles.
TEST_F(Rerun, AnInterruptedRerunLeavesNoIndexToMerge) {
  const fs::path job = write_job("gpkg");
  ASSERT_EQ(lodforge("run " + job.string()).code, 0);
  ASSERT_TRUE(fs::exists(dir / "out" / "tile_index.geojson"));
  const pid_t pid = fork();
  if (pid == 0) {
    const int null = ::open("/dev/null", O_WRONLY);
    dup2(null, 1);
    dup2(null, 2);
    execl(LODFORGE_BINARY, LODFORGE_BINARY, "run", job.c_str(), "--threads", "1", "--set", "stages.labeling.kappa2=2", nullptr);
    _exit(127);
  }
  for (int wait = 0; wait < 20000 && fs::exists(dir / "out" / "tile_index.geojson"); ++wait)
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  kill(pid, SIGKILL);
  waitpid(pid, nullptr, 0);
  ASSERT_FALSE(fs::exists(dir / "out" / "tile_index.geojson")) << "the rerun finished before it could be killed; make the city larger";
  EXPECT_FALSE(fs::exists(dir / "out" / "report.json"));
  {
    const Result r = lodforge("merge " + (dir / "out").string());
    EXPECT_EQ(r.code, 1) << r.output;
    EXPECT_NE(r.output.find("no tile_index.geojson"), std::string::npos) << r.output;
  }
  // The rerun completed gives what an uninterrupted one gives.
  const Result r = lodforge("run " + job.string() + " --set stages.labeling.kappa2=2");
  ASSERT_EQ(r.code, 0) << r.output;
  ASSERT_EQ(lodforge("merge " + (dir / "out").string()).code, 0);
}

// Issue 15: one run at a time in a work directory; temporary files of killed runs are cleaned.
TEST_F(Rerun, ASecondRunIsRefusedAndStaleTemporariesAreRemoved) {
  const fs::path job = write_job("gpkg");
  fs::create_directories(dir / "work");
  const int fd = ::open((dir / "work" / "lodforge.lock").c_str(), O_RDWR | O_CREAT, 0644);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(flock(fd, LOCK_EX | LOCK_NB), 0);
  ASSERT_EQ(::write(fd, "4242\n", 5), 5);
  Result r = lodforge("run " + job.string());
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("another lodforge run (pid 4242) is using it"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out" / "tile_index.geojson"));
  ::close(fd);
  // A checkpoint half-written by a killed run (a pid no process has, an hour old).
  const fs::path stale = dir / "work" / "r0000_c0000.contours.tmp-4194305";
  std::ofstream(stale) << "half";
  fs::last_write_time(stale, fs::file_time_type::clock::now() - std::chrono::hours(1));
  r = lodforge("run " + job.string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_FALSE(fs::exists(stale));
}

// Issue 15: options and arguments that used to be taken silently are refused, naming the key.
TEST_F(Rerun, QuietlyWrongOptionsAreRefused) {
  const auto refused = [&](const std::string& extra, const std::string& args, const std::string& expected) {
    const Result r = lodforge("run " + write_job("gpkg", extra).string() + args);
    EXPECT_EQ(r.code, 1) << extra << args << "\n" << r.output;
    EXPECT_NE(r.output.find(expected), std::string::npos) << extra << args << "\n" << r.output;
    EXPECT_EQ(r.output.find("lodforge run: error: lodforge run:"), std::string::npos) << r.output;
  };
  refused("tiling: {tile_size_m: 20}\n", "", "tiling: given twice");
  refused("", " --set stages.contour.connectivity=5", "stages.contour.connectivity: must be 4 or 8");
  refused("", " --set output.formats=", "output.formats: needs at least one format");
  refused("", " --shard 1/3x", "--shard '1/3x': expected K/N with two whole numbers");
  refused("", " --set tiling.tile_size_m=0.01", "tiling.tile_size_m: 0.010000 m is less than 16 pixels");
  EXPECT_FALSE(fs::exists(dir / "out" / "tiles" / "r0000_c0000.gpkg"));
}

// A raster of any size as a VRT without sources (every pixel 0): nothing is stored.
void write_empty_vrt(const fs::path& path, long width, long height, int bands) {
  std::ofstream vrt(path);
  vrt << "<VRTDataset rasterXSize=\"" << width << "\" rasterYSize=\"" << height << "\">\n"
      << "  <GeoTransform>85000, 0.25, 0, 447000, 0, -0.25</GeoTransform>\n";
  for (int b = 1; b <= bands; ++b) vrt << "  <VRTRasterBand dataType=\"Byte\" band=\"" << b << "\"/>\n";
  vrt << "</VRTDataset>\n";
}

// Issue 15: inputs that used to give an empty result without a word.
TEST_F(Rerun, EmptyOrMisreadMasksAreToldNotSilent) {
  // A mask without any building pixel: the run ends, and says what to check.
  write_empty_vrt(dir / "zeros.vrt", 400, 400, 1);
  std::ofstream(dir / "zeros.yaml") << "inputs: {segmentation: {path: zeros.vrt}}\ntiling: {tile_size_m: 50}\noutput: {dir: zeros_out}\nwork_dir: zeros_work\n";
  Result r = lodforge("run " + (dir / "zeros.yaml").string());
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("no building found in"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("inputs.segmentation.building_values right for this raster? Its band 1 holds 0 (100.0 %)"), std::string::npos)
      << r.output;
  // A three-band (colour) raster read with class values is refused, with the key to use.
  write_empty_vrt(dir / "rgb.vrt", 400, 400, 3);
  std::ofstream(dir / "rgb.yaml") << "inputs: {segmentation: {path: rgb.vrt, building_values: [6]}}\noutput: {dir: rgb_out}\nwork_dir: rgb_work\n";
  r = lodforge("run " + (dir / "rgb.yaml").string());
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("has 3 bands; building values are read from a one-band class raster"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("building_rgb"), std::string::npos) << r.output;
  // regularize reads a mask whole: 10^10 pixels are refused with advice, not asked of the allocator.
  write_empty_vrt(dir / "huge.vrt", 100000, 100000, 1);
  r = lodforge("regularize --mask " + (dir / "huge.vrt").string() + " --out " + (dir / "huge.gpkg").string());
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("100000 x 100000 pixels is more than this command reads at once"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("lodforge run JOB.yaml"), std::string::npos) << r.output;
}

// Issue 15: a full disk stops the run with a message that says so, and nothing that looks
// complete; with room again, the rerun gives the same files as a run that never failed.
// (Needs a small tmpfs: mounted when the tests run as root, else skipped.)
TEST_F(Rerun, AFullDiskIsReportedAndTheRerunCompletes) {
  const fs::path job = write_job("gpkg, obj");
  ASSERT_EQ(lodforge("run " + job.string()).code, 0);
  const auto ref = output_bytes(dir / "out");
  const fs::path small = dir / "small_disk";
  fs::create_directories(small);
  if (test::shell("mount -t tmpfs -o size=400k tmpfs " + small.string() + " 2>&1").code != 0)
    GTEST_SKIP() << "cannot mount a small tmpfs here (not root?): the full-disk case is not tested";
  struct Unmount {
    fs::path at;
    ~Unmount() { test::shell("umount " + at.string() + " 2>/dev/null"); }
  } unmount{small};
  std::ofstream(dir / "full.yaml") << "inputs: {segmentation: {path: city/seg_class.tif}}\ntiling: {tile_size_m: 50}\n"
                                   << "output: {dir: small_disk/out, formats: [gpkg, obj], quicklook: false}\nwork_dir: full_work\n";
  Result r = lodforge("run " + (dir / "full.yaml").string());
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("is full ("), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("internal error"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(small / "out" / "tile_index.geojson"));
  EXPECT_FALSE(fs::exists(small / "out" / "report.json"));
  for (const auto& e : fs::recursive_directory_iterator(small))
    EXPECT_EQ(e.path().filename().string().find("partial"), std::string::npos) << e.path();
  // Room again: the same disk, larger.
  ASSERT_EQ(test::shell("mount -o remount,size=64m " + small.string() + " 2>&1").code, 0);
  r = lodforge("run " + (dir / "full.yaml").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const auto rerun = output_bytes(small / "out");
  EXPECT_TRUE(rerun == ref);
}

// Issue 15, fault injection: random bytes of random checkpoints flipped, random outputs deleted;
// each rerun ends in the clean run's bytes.
TEST_F(Rerun, RandomFaultsEndInTheSameBytesAfterARerun) {
  const fs::path job = write_job("gpkg, obj");
  ASSERT_EQ(lodforge("run " + job.string()).code, 0);
  const auto ref = output_bytes(dir / "out");
  std::mt19937 rng(15);
  for (int round = 0; round < 6; ++round) {
    std::vector<fs::path> checkpoints, outputs;
    for (const auto& e : fs::directory_iterator(dir / "work"))
      if (e.path().extension() != ".lock") checkpoints.push_back(e.path());
    for (const auto& e : fs::directory_iterator(dir / "out" / "tiles")) outputs.push_back(e.path());
    std::sort(checkpoints.begin(), checkpoints.end());
    std::sort(outputs.begin(), outputs.end());
    ASSERT_FALSE(checkpoints.empty());
    const fs::path victim = checkpoints[rng() % checkpoints.size()];
    std::string bytes = slurp(victim);
    if (!bytes.empty()) {
      bytes[rng() % bytes.size()] ^= char(1 << (rng() % 8));
      std::ofstream(victim, std::ios::binary | std::ios::trunc) << bytes;
    }
    // The tile's done marker goes too (half of the time), so the changed checkpoint would be used.
    if (rng() % 2) fs::remove(victim.parent_path() / (victim.stem().string() + ".done"));
    const fs::path gone = outputs[rng() % outputs.size()];
    fs::remove(gone);
    const Result r = lodforge("run " + job.string());
    ASSERT_EQ(r.code, 0) << victim << "\n" << r.output;
    EXPECT_TRUE(output_bytes(dir / "out") == ref) << "round " << round << ": " << victim << " changed, " << gone << " deleted";
  }
  ASSERT_EQ(lodforge("merge " + (dir / "out").string()).code, 0);
}

// Issue 15: merge takes the shards of one run only.
TEST_F(Rerun, MergeRefusesShardsOfDifferentRuns) {
  const fs::path job = write_job("gpkg");
  ASSERT_EQ(lodforge("run " + job.string() + " --shard 0/2").code, 0);
  ASSERT_EQ(lodforge("run " + job.string() + " --shard 1/2 --set stages.labeling.kappa2=2").code, 0);
  const Result r = lodforge("merge " + (dir / "out").string());
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("from a run with other inputs, options or build of lodforge"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out" / "merged"));
}

// Issue 17: the tile index and the geojson format are RFC 7946 GeoJSON: WGS 84 longitude and
// latitude, no crs member, exterior rings counter-clockwise; the index reads as JSON (a parser,
// not patterns) with every tile's outputs and fingerprints.
TEST_F(Rerun, TileIndexAndGeoJsonAreRfc7946) {
  ASSERT_EQ(lodforge("run " + write_job("gpkg, geojson").string()).code, 0);
  ASSERT_EQ(lodforge("merge " + (dir / "out").string()).code, 0);
  const nlohmann::json index = nlohmann::json::parse(slurp(dir / "out" / "tile_index.geojson"));
  ASSERT_EQ(index.at("type"), "FeatureCollection");
  EXPECT_FALSE(index.contains("crs"));
  ASSERT_EQ(index.at("features").size(), 16u);
  // The synthetic city lies in the Netherlands (EPSG:28992): longitude 3-8 E, latitude 50-54 N.
  const auto in_the_netherlands = [](const nlohmann::json& point) {
    return point.at(0).get<double>() > 3 && point.at(0).get<double>() < 8 && point.at(1).get<double>() > 50 && point.at(1).get<double>() < 54;
  };
  for (const fs::path& geojson : {dir / "out" / "tiles" / "r0000_c0000.geojson", dir / "out" / "merged" / "lodforge.geojson"}) {
    const nlohmann::json footprints = nlohmann::json::parse(slurp(geojson));
    EXPECT_FALSE(footprints.contains("crs")) << geojson;
    ASSERT_FALSE(footprints.at("features").empty()) << geojson;
    for (const auto& feature : footprints.at("features"))
      EXPECT_TRUE(in_the_netherlands(feature.at("geometry").at("coordinates").at(0).at(0))) << geojson << ": " << feature.dump();
  }
  for (const auto& feature : index.at("features")) {
    const auto& ring = feature.at("geometry").at("coordinates").at(0);
    ASSERT_EQ(ring.size(), 5u);
    EXPECT_EQ(ring.front(), ring.back());
    EXPECT_TRUE(in_the_netherlands(ring.front())) << ring.dump();
    double twice_area = 0;
    for (std::size_t i = 0; i + 1 < ring.size(); ++i)
      twice_area += ring[i][0].get<double>() * ring[i + 1][1].get<double>() - ring[i + 1][0].get<double>() * ring[i][1].get<double>();
    EXPECT_GT(twice_area, 0) << feature.at("properties").at("tile");
    EXPECT_EQ(feature.at("properties").at("outputs").size(), feature.at("properties").at("fingerprints").size());
  }
}

}  // namespace
}  // namespace lodforge
