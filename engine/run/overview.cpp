#include "run/overview.hpp"

#include <cpl_string.h>
#include <cpl_vsi.h>
#include <gdal_priv.h>
#include <gdal_utils.h>
#include <ogrsf_frmts.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include "geometry/geotransform.hpp"
#include "io/atomic_file.hpp"
#include "io/errors.hpp"
#include "io/model_writers.hpp"
#include "io/ogr_polygon.hpp"
#include "io/quicklook.hpp"
#include "io/raster.hpp"
#include "job/job.hpp"

namespace lodforge {

namespace fs = std::filesystem;

namespace {

enum class Status { ok, fallback, lod0_only, not_in_mask };

struct Outline {
  PolygonWithHoles footprint;
  Status status = Status::ok;
};

// Every footprint of the tiles' GeoPackages (layer "footprints"), in tile and file order; crs
// receives the first layer's CRS.
std::vector<Outline> read_outlines(const std::vector<fs::path>& tiles, std::string& crs) {
  std::vector<Outline> out;
  for (const fs::path& tile : tiles) {
    std::unique_ptr<GDALDataset> d(static_cast<GDALDataset*>(GDALOpenEx(tile.c_str(), GDAL_OF_VECTOR, nullptr, nullptr, nullptr)));
    OGRLayer* layer = d ? d->GetLayerByName("footprints") : nullptr;
    if (!layer) throw InputError("'" + tile.string() + "': no footprints layer; is it a lodforge GeoPackage tile?");
    if (crs.empty() && layer->GetSpatialRef()) {
      char* wkt = nullptr;
      layer->GetSpatialRef()->exportToWkt(&wkt);
      crs = wkt ? wkt : "";
      CPLFree(wkt);
    }
    for (auto& feature : *layer) {
      const OGRGeometry* g = feature->GetGeometryRef();
      if (!g) continue;
      const std::string status = feature->GetFieldAsString("status"), stage = feature->GetFieldAsString("stage");
      const Status s = status == "fallback" ? Status::fallback : status == "not_in_mask" ? Status::not_in_mask
                                                             : stage == "heights" ? Status::lod0_only : Status::ok;
      if (wkbFlatten(g->getGeometryType()) == wkbPolygon) {
        out.push_back({from_ogr_polygon(*g->toPolygon()), s});
      } else if (wkbFlatten(g->getGeometryType()) == wkbMultiPolygon) {
        for (const OGRPolygon* p : *g->toMultiPolygon()) out.push_back({from_ogr_polygon(*p), s});
      }
    }
  }
  return out;
}

// The DSM warped onto the frame (average of its cells), NaN where it has none.
cv::Mat warped_dsm(const std::string& path, const std::string& wkt, const GeoTransform& frame, int width, int height) {
  Dataset dsm = open_raster(path, "inputs.dsm.path");
  const Vec2 a = frame.to_map(0, 0), b = frame.to_map(width, height);
  CPLStringList args;
  for (const std::string& s : {std::string("-of"), std::string("MEM"), std::string("-ot"), std::string("Float32"), std::string("-r"),
                               std::string("average"), std::string("-dstnodata"), std::string("nan"), std::string("-ts"),
                               std::to_string(width), std::to_string(height), std::string("-te"), std::to_string(std::min(a.x(), b.x())),
                               std::to_string(std::min(a.y(), b.y())), std::to_string(std::max(a.x(), b.x())),
                               std::to_string(std::max(a.y(), b.y()))})
    args.AddString(s.c_str());
  if (!wkt.empty()) {
    args.AddString("-t_srs");
    args.AddString(wkt.c_str());
  }
  GDALWarpAppOptions* options = GDALWarpAppOptionsNew(args.List(), nullptr);
  GDALDatasetH source = GDALDataset::ToHandle(dsm.get());
  int usage_error = 0;
  CPLErrorReset();
  GDALDatasetH warped = GDALWarp("", nullptr, 1, &source, options, &usage_error);
  GDALWarpAppOptionsFree(options);
  if (!warped) throw InputError("'" + path + "': cannot be warped onto the overview: " + CPLGetLastErrorMsg());
  cv::Mat out(height, width, CV_32F);
  const CPLErr read = GDALRasterIO(GDALGetRasterBand(warped, 1), GF_Read, 0, 0, width, height, out.data, width, height, GDT_Float32, 0, 0);
  GDALClose(warped);
  if (read != CE_None) throw InputError("'" + path + "': cannot be read for the overview: " + CPLGetLastErrorMsg());
  return out;
}

// image (BGR) as a GDAL dataset in memory, bands in RGB order, georeferenced when wkt is given.
GDALDataset* in_memory(const cv::Mat& image, const GeoTransform& frame, const std::string& wkt) {
  GDALDataset* memory = GetGDALDriverManager()->GetDriverByName("MEM")->Create("", image.cols, image.rows, 3, GDT_Byte, nullptr);
  if (!memory) return nullptr;
  int bgr_to_rgb[3] = {3, 2, 1};
  if (memory->RasterIO(GF_Write, 0, 0, image.cols, image.rows, const_cast<uchar*>(image.data), image.cols, image.rows, GDT_Byte, 3,
                       bgr_to_rgb, 3, GSpacing(image.step), 1, nullptr) != CE_None) {
    GDALClose(memory);
    return nullptr;
  }
  std::array<double, 6> gt = frame.c;
  memory->SetGeoTransform(gt.data());
  if (!wkt.empty()) memory->SetProjection(wkt.c_str());
  return memory;
}


}  // namespace

Overview write_overview(const std::string& job_path, const std::vector<fs::path>& gpkg_tiles, const fs::path& tif, int max_pixels) {
  GDALAllRegister();
  std::string crs;
  const std::vector<Outline> outlines = read_outlines(gpkg_tiles, crs);
  // The frame: the segmentation's extent and CRS; without the job, the footprints' extent.
  GeoTransform frame;
  int width = 0, height = 0;
  std::string dsm_path;
  try {
    const Job job = load_job(job_path, {});
    Dataset seg = open_raster(job.inputs.segmentation.path, "inputs.segmentation.path");
    GeoTransform g;
    if (seg->GetGeoTransform(g.c.data()) != CE_None) throw InputError("'" + job.inputs.segmentation.path + "': has no georeference");
    if (const OGRSpatialReference* srs = seg->GetSpatialRef()) {
      char* wkt = nullptr;
      srs->exportToWkt(&wkt);
      crs = wkt ? wkt : crs;
      CPLFree(wkt);
    }
    const int columns = seg->GetRasterXSize(), rows = seg->GetRasterYSize();
    const int step = std::max(1, int(std::ceil(double(std::max(columns, rows)) / max_pixels)));
    width = (columns + step - 1) / step;
    height = (rows + step - 1) / step;
    frame.c = {g.c[0], g.c[1] * step, g.c[2] * step, g.c[3], g.c[4] * step, g.c[5] * step};
    dsm_path = job.inputs.dsm.path;
  } catch (const std::exception& e) {
    spdlog::warn("overview: the run's job cannot be read ({}); the overview shows the footprints alone, over their extent", e.what());
    constexpr double inf = std::numeric_limits<double>::infinity();
    double x0 = inf, y0 = inf, x1 = -inf, y1 = -inf;
    for (const Outline& o : outlines)
      for (const Vec2& p : o.footprint.outer) {
        x0 = std::min(x0, p.x()), y0 = std::min(y0, p.y());
        x1 = std::max(x1, p.x()), y1 = std::max(y1, p.y());
      }
    if (outlines.empty()) x0 = y0 = 0, x1 = y1 = 100;
    const double margin = 10, pixel = std::max(0.1, std::max(x1 - x0, y1 - y0) / max_pixels);
    width = int(std::ceil((x1 - x0 + 2 * margin) / pixel));
    height = int(std::ceil((y1 - y0 + 2 * margin) / pixel));
    frame.c = {x0 - margin, pixel, 0, y1 + margin, 0, -pixel};
  }
  // Grown by whole pixels to hold every footprint whole (an outline may reach past the raster's
  // edge, where its building was cut by it).
  {
    double c0 = 0, r0 = 0, c1 = width, r1 = height;
    for (const Outline& o : outlines)
      for (const Vec2& p : o.footprint.outer) {
        const Vec2 q = frame.to_pixel(p);
        c0 = std::min(c0, std::floor(q.x()) - 1), r0 = std::min(r0, std::floor(q.y()) - 1);
        c1 = std::max(c1, std::ceil(q.x()) + 1), r1 = std::max(r1, std::ceil(q.y()) + 1);
      }
    // (an outline far off the raster, which a run does not make, grows it by max_pixels at most)
    c0 = std::max(c0, -double(max_pixels)), r0 = std::max(r0, -double(max_pixels));
    c1 = std::min(c1, double(width + max_pixels)), r1 = std::min(r1, double(height + max_pixels));
    frame = frame.window(c0, r0);
    width = int(c1 - c0);
    height = int(r1 - r0);
  }
  Overview result;
  result.width = width;
  result.height = height;
  result.pixel_size = frame.pixel_size();
  cv::Mat image(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  result.background = "none";
  if (!dsm_path.empty()) {
    const cv::Mat dsm = warped_dsm(dsm_path, crs, frame, width, height);
    const cv::Mat valid = dsm == dsm;  // not NaN
    image = hillshade(dsm, valid, result.pixel_size);
    result.background = "DSM hillshade";
  }
  // Whole outlines (not clipped to tiles), ok first so that the others show on top of them.
  constexpr int shift = 3;
  const int thickness = std::max(1, int(std::lround(std::max(width, height) / 1000.0)));
  for (const Status pass : {Status::ok, Status::lod0_only, Status::fallback, Status::not_in_mask}) {
    const cv::Scalar colour = pass == Status::ok ? cv::Scalar(40, 40, 230) : pass == Status::fallback ? cv::Scalar(0, 220, 255)
                              : pass == Status::lod0_only ? cv::Scalar(230, 40, 230) : cv::Scalar(230, 200, 0);
    for (const Outline& o : outlines) {
      if (o.status != pass) continue;
      (pass == Status::ok ? result.ok : pass == Status::fallback ? result.fallback : pass == Status::lod0_only ? result.lod0_only : result.not_in_mask)++;
      std::vector<std::vector<cv::Point>> rings;
      const auto add = [&](const Ring& ring) {
        rings.emplace_back();
        for (const Vec2& p : ring) {
          const Vec2 q = frame.to_pixel(p);
          rings.back().emplace_back(int(std::lround(q.x() * (1 << shift))), int(std::lround(q.y() * (1 << shift))));
        }
      };
      add(o.footprint.outer);
      for (const Ring& h : o.footprint.holes) add(h);
      cv::polylines(image, rings, true, colour, thickness, cv::LINE_AA, shift);
    }
  }
  // The COG (deflate, 512 px blocks, overviews), and the PNG for the report.
  GDALDataset* memory = in_memory(image, frame, crs);
  GDALDriver* cog = GetGDALDriverManager()->GetDriverByName("COG");
  GDALDriver* jpeg = GetGDALDriverManager()->GetDriverByName("JPEG");
  if (!memory || !cog || !jpeg) {
    if (memory) GDALClose(memory);
    throw InputError("'" + tif.string() + "': cannot write the overview: GDAL has no MEM, COG or JPEG driver");
  }
  CPLErrorReset();
  const char* cog_options[] = {"COMPRESS=DEFLATE", "PREDICTOR=YES", "BLOCKSIZE=512", "RESAMPLING=AVERAGE", nullptr};
  GDALDataset* written = cog->CreateCopy(tif.c_str(), memory, FALSE, const_cast<char**>(cog_options), nullptr, nullptr);
  bool ok = written != nullptr;
  if (written) GDALClose(written);
  // The report's copy as JPEG: a tenth of the bytes of a PNG of a hillshade, and no worse to the eye.
  const std::string vsi = "/vsimem/lodforge_overview_" + std::to_string(getpid()) + ".jpg";
  const char* jpeg_options[] = {"QUALITY=85", "WRITE_EXIF_METADATA=NO", nullptr};
  GDALDataset* picture = ok ? jpeg->CreateCopy(vsi.c_str(), memory, FALSE, const_cast<char**>(jpeg_options), nullptr, nullptr) : nullptr;
  if (picture) {
    GDALClose(picture);
    vsi_l_offset length = 0;
    GByte* bytes = VSIGetMemFileBuffer(vsi.c_str(), &length, TRUE);
    if (bytes) result.jpeg.assign(reinterpret_cast<const char*>(bytes), std::size_t(length));
    CPLFree(bytes);
  }
  VSIUnlink((vsi + ".aux.xml").c_str());  // (the georeference GDAL may keep beside a JPEG)
  GDALClose(memory);
  if (!ok) throw InputError("'" + tif.string() + "': cannot write the overview: " + CPLGetLastErrorMsg());
  return result;
}

namespace {
void write_page(const nlohmann::json& report, const Overview& overview, const fs::path& html);
}  // namespace

void write_report_html(const fs::path& report_json, const Overview& overview, const fs::path& html) {
  std::ifstream in(report_json);
  nlohmann::json r;
  try {
    r = nlohmann::json::parse(in);
    if (!r.is_object()) throw std::runtime_error("not a JSON object");
    write_page(r, overview, html);
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError("'" + report_json.string() + "': not a lodforge run report: " + e.what());
  }
}

namespace {

void write_page(const nlohmann::json& r, const Overview& overview, const fs::path& html) {
  const auto number = [&](const char* key) { return r.value(key, nlohmann::json(0)).dump(); };
  const auto seconds = [](const nlohmann::json& v) {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%.2f", v.is_number() ? v.get<double>() : 0.0);
    return std::string(buffer);
  };
  const long long buildings = r.value("buildings", 0LL), lod1 = r.value("lod1", 0LL);
  std::string o;
  o += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>lodforge run report</title>\n<style>\n"
       "body { font-family: sans-serif; margin: 2em; color: #222; }\n"
       "table { border-collapse: collapse; margin-bottom: 1em; }\n"
       "td, th { border: 1px solid #ccc; padding: 2px 8px; text-align: left; }\n"
       "td.n { text-align: right; font-variant-numeric: tabular-nums; }\n"
       ".key { display: inline-block; width: 1.5em; height: 0.6em; margin: 0 0.4em 0 1.2em; }\n"
       ".picture { overflow: auto; max-height: 90vh; border: 1px solid #ccc; }\n"
       "</style>\n</head>\n<body>\n<h1>lodforge run report</h1>\n";
  o += "<p>Job <code>" + xml_escape(r.value("job", "")) + "</code>, shard " + xml_escape(r.value("shard", "")) + ". Wall time " +
       seconds(r.value("seconds", nlohmann::json(0))) + " s.</p>\n";
  o += "<h2>Numbers</h2>\n<table>\n";
  const auto row = [&o](const std::string& name, const std::string& value) { o += "<tr><th>" + name + "</th><td class=\"n\">" + value + "</td></tr>\n"; };
  row("tiles", number("tiles"));
  row("tiles computed", number("tiles_processed"));
  row("tiles resumed", number("tiles_resumed"));
  row("tiles without buildings", number("tiles_empty"));
  row("buildings", number("buildings"));
  row("&nbsp;&nbsp;regularized (ok)", number("ok"));
  // By the outline the chain chose (docs/models.md), most first.
  std::vector<std::pair<long long, std::string>> models;
  const nlohmann::json model_counts = r.value("models", nlohmann::json::object());  // (a copy: items() of a temporary would dangle)
  for (const auto& [model, count] : model_counts.items())
    if (count.is_number_integer()) models.emplace_back(-count.get<long long>(), model);
  std::sort(models.begin(), models.end());
  for (const auto& [count, model] : models) row("&nbsp;&nbsp;&nbsp;&nbsp;model " + xml_escape(model), std::to_string(-count));
  row("&nbsp;&nbsp;fallback footprint", number("fallback"));
  row("&nbsp;&nbsp;with LOD1", number("lod1"));
  row("&nbsp;&nbsp;without LOD1 (no heights)", std::to_string(buildings - lod1));
  if (r.contains("cadastre")) {
    const nlohmann::json& c = r.at("cadastre");
    row("cadastral footprints confirmed by the mask", c.value("confirmed", nlohmann::json(0)).dump());
    row("buildings not in the footprints", c.value("not_in_footprints", nlohmann::json(0)).dump());
    row("footprints not in the mask (not modeled)", c.value("not_in_mask", nlohmann::json(0)).dump());
  }
  row("small components dropped", number("dropped_small"));
  row("buildings too large for a window", number("too_large"));
  const nlohmann::json stages = r.value("stage_seconds", nlohmann::json::object());
  for (const auto& [stage, value] : stages.items())
    row("one-core seconds, " + xml_escape(stage), seconds(value));
  o += "</table>\n";
  o += "<h2>Overview</h2>\n";
  if (overview.jpeg.empty()) {
    o += "<p>No overview.</p>\n";
  } else {
    // A scale bar of 1, 2 or 5 times a power of ten metres, about a fifth of the picture.
    const double target = overview.width * overview.pixel_size / 5;
    const double decade = std::pow(10.0, std::floor(std::log10(std::max(target, 1e-3))));
    double length = decade;
    for (const double f : {2.0, 5.0})
      if (decade * f <= target) length = decade * f;
    const int bar = int(std::lround(length / overview.pixel_size));
    char scale[160];
    std::snprintf(scale, sizeof scale, "%g m (%.2f m a pixel; %d &times; %d pixels)", length, overview.pixel_size, overview.width, overview.height);
    o += "<p>overview.tif beside this page (a Cloud-Optimized GeoTIFF, georeferenced), background: " + overview.background + ".";
    o += "<span class=\"key\" style=\"background:#e62828\"></span>ok (" + std::to_string(overview.ok) + ")";
    o += "<span class=\"key\" style=\"background:#ffdc00\"></span>fallback (" + std::to_string(overview.fallback) + ")";
    o += "<span class=\"key\" style=\"background:#e628e6\"></span>without LOD1 (" + std::to_string(overview.lod0_only) + ")";
    if (overview.not_in_mask)
      o += "<span class=\"key\" style=\"background:#00c8e6\"></span>footprint not in the mask (" + std::to_string(overview.not_in_mask) + ")";
    o += "</p>\n";
    o += "<p><span style=\"display:inline-block;width:" + std::to_string(bar) + "px;height:6px;background:#222\"></span> " + scale + "</p>\n";
    char* base64 = CPLBase64Encode(int(overview.jpeg.size()), reinterpret_cast<const GByte*>(overview.jpeg.data()));
    o += "<div class=\"picture\"><img width=\"" + std::to_string(overview.width) + "\" height=\"" + std::to_string(overview.height) +
         "\" alt=\"the run's buildings over the DSM\" src=\"data:image/jpeg;base64," + std::string(base64 ? base64 : "") + "\"></div>\n";
    CPLFree(base64);
  }
  const nlohmann::json failed = r.value("failed_buildings", nlohmann::json::array());
  constexpr std::size_t kRows = 500;
  o += "<h2>Failed buildings (" + std::to_string(failed.size()) + ")</h2>\n";
  o += "<p>A failed building is still written: a fallback footprint (Douglas&ndash;Peucker of its contour) or LOD0 alone without heights.</p>\n";
  if (!failed.empty()) {
    o += "<table>\n<tr><th>id</th><th>tile</th><th>stage</th><th>reason</th></tr>\n";
    for (std::size_t i = 0; i < failed.size() && i < kRows; ++i)
      o += "<tr><td class=\"n\">" + xml_escape(failed[i].value("id", nlohmann::json(0)).dump()) + "</td><td>" + xml_escape(failed[i].value("tile", "")) +
           "</td><td>" + xml_escape(failed[i].value("stage", "")) + "</td><td>" + xml_escape(failed[i].value("reason", "")) + "</td></tr>\n";
    o += "</table>\n";
    if (failed.size() > kRows) o += "<p>&hellip; and " + std::to_string(failed.size() - kRows) + " more in report.json.</p>\n";
  }
  const nlohmann::json too_large = r.value("too_large_buildings", nlohmann::json::array());
  if (!too_large.empty()) {
    o += "<h2>Buildings too large for a window (" + std::to_string(too_large.size()) + ")</h2>\n<ul>\n";
    for (const auto& t : too_large) o += "<li>" + xml_escape(t.is_string() ? t.get<std::string>() : t.dump()) + "</li>\n";
    o += "</ul>\n";
  }
  const nlohmann::json slowest = r.value("slowest_buildings", nlohmann::json::array());
  o += "<h2>Slowest buildings</h2>\n";
  if (!slowest.empty()) {
    o += "<table>\n<tr><th>id</th><th>tile</th><th>seconds (one core)</th></tr>\n";
    for (const auto& b : slowest) {
      char s[32];
      std::snprintf(s, sizeof s, "%.3f", b.value("seconds", 0.0));
      o += "<tr><td class=\"n\">" + xml_escape(b.value("id", nlohmann::json(0)).dump()) + "</td><td>" + xml_escape(b.value("tile", "")) +
           "</td><td class=\"n\">" + s + "</td></tr>\n";
    }
    o += "</table>\n";
  }
  o += "</body>\n</html>\n";
  write_text_atomically(html, o);
}

}  // namespace

}  // namespace lodforge
