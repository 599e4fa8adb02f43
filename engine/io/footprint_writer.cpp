#include "io/footprint_writer.hpp"

#include <filesystem>
#include <gdal_priv.h>
#include <ogrsf_frmts.h>
#include <unistd.h>

#include "geometry/polygon.hpp"
#include "io/errors.hpp"

namespace lodforge {

namespace fs = std::filesystem;

namespace {

std::string driver_for(const std::string& path) {
  const std::string ext = fs::path(path).extension().string();
  if (ext == ".gpkg") return "GPKG";
  if (ext == ".geojson" || ext == ".json") return "GeoJSON";
  return {};
}

OGRLinearRing to_ogr(const Ring& ring) {
  OGRLinearRing out;
  for (const Vec2& p : ring) out.addPoint(p.x(), p.y());
  out.addPoint(ring.front().x(), ring.front().y());
  return out;
}

}  // namespace

void check_output_path(const std::string& path) {
  if (driver_for(path).empty())
    throw InputError("'" + path + "': unknown output format; use a .gpkg or .geojson file name");
  fs::path dir = fs::absolute(path).parent_path();
  if (!fs::is_directory(dir)) throw InputError("'" + path + "': output directory '" + dir.string() + "' does not exist");
  if (access(dir.c_str(), W_OK) != 0) throw InputError("'" + path + "': output directory '" + dir.string() + "' is not writable");
}

void write_footprints(const std::string& path, const FootprintLayer& layer, const std::vector<FootprintRecord>& records) {
  GDALAllRegister();
  CPLErrorReset();
  check_output_path(path);
  const std::string driver_name = driver_for(path);
  const fs::path final_path = fs::absolute(path);
  const fs::path temp = final_path.parent_path() /
                        (final_path.stem().string() + ".partial-" + std::to_string(getpid()) + final_path.extension().string());
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName(driver_name.c_str());
  if (!driver) throw InputError("GDAL driver " + driver_name + " is not available");
  fs::remove(temp);
  GDALDataset* ds = driver->Create(temp.c_str(), 0, 0, 0, GDT_Unknown, nullptr);
  if (!ds) throw InputError("'" + path + "': cannot create: " + CPLGetLastErrorMsg());
  auto fail = [&](const std::string& what) {
    GDALClose(ds);
    fs::remove(temp);
    throw InputError("'" + path + "': " + what + ": " + CPLGetLastErrorMsg());
  };
  OGRSpatialReference srs;
  OGRSpatialReference* srs_ptr = nullptr;
  if (!layer.crs_wkt.empty() && srs.importFromWkt(layer.crs_wkt.c_str()) == OGRERR_NONE) {
    srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    srs_ptr = &srs;
  }
  OGRLayer* l = ds->CreateLayer(layer.name.c_str(), srs_ptr, wkbPolygon, nullptr);
  if (!l) fail("cannot create layer");
  auto field = [&](const char* name, OGRFieldType type) {
    OGRFieldDefn def(name, type);
    if (l->CreateField(&def) != OGRERR_NONE) fail(std::string("cannot create field ") + name);
  };
  field("id", OFTInteger64);
  if (layer.write_status) {
    field("status", OFTString);
    field("stage", OFTString);
    field("reason", OFTString);
    field("regularizer", OFTString);
  }
  if (!layer.kind_field.empty()) field(layer.kind_field.c_str(), OFTString);
  if (layer.write_heights) {
    field("ground_height", OFTReal);
    field("roof_height", OFTReal);
  }
  field("vertex_count", OFTInteger);
  field("area_m2", OFTReal);
  const bool transaction = ds->StartTransaction() == OGRERR_NONE;  // GeoPackage yes, GeoJSON no
  for (const FootprintRecord& r : records) {
    OGRFeature feature(l->GetLayerDefn());
    feature.SetField("id", static_cast<GIntBig>(r.id));
    if (layer.write_status) {
      feature.SetField("status", r.status.c_str());
      feature.SetField("stage", r.failed_stage.c_str());
      feature.SetField("reason", r.reason.c_str());
      feature.SetField("regularizer", r.regularizer.c_str());
    }
    if (!layer.kind_field.empty()) feature.SetField(layer.kind_field.c_str(), r.kind.c_str());
    if (layer.write_heights && r.has_heights) {
      feature.SetField("roof_height", r.roof_height);
      feature.SetField("ground_height", r.ground_height);
    } else if (layer.write_heights) {
      feature.SetFieldNull(feature.GetFieldIndex("roof_height"));
      feature.SetFieldNull(feature.GetFieldIndex("ground_height"));
    }
    int vertices = int(r.polygon.outer.size());
    for (const Ring& h : r.polygon.holes) vertices += int(h.size());
    feature.SetField("vertex_count", vertices);
    feature.SetField("area_m2", area(r.polygon));
    OGRPolygon polygon;
    OGRLinearRing outer = to_ogr(r.polygon.outer);
    polygon.addRing(&outer);
    for (const Ring& h : r.polygon.holes) {
      OGRLinearRing hole = to_ogr(h);
      polygon.addRing(&hole);
    }
    feature.SetGeometry(&polygon);
    if (l->CreateFeature(&feature) != OGRERR_NONE) fail("cannot write feature " + std::to_string(r.id));
  }
  if (transaction && ds->CommitTransaction() != OGRERR_NONE) fail("cannot commit");
  GDALClose(ds);
  if (CPLGetLastErrorType() == CE_Failure) {
    fs::remove(temp);
    throw InputError("'" + path + "': writing failed: " + CPLGetLastErrorMsg());
  }
  std::error_code ec;
  fs::rename(temp, final_path, ec);
  if (ec) {
    fs::remove(temp);
    throw InputError("'" + path + "': cannot move the finished file into place: " + ec.message());
  }
}

}  // namespace lodforge
