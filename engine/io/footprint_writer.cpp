#include "io/footprint_writer.hpp"

#include <cstdlib>
#include <ctime>

#include <filesystem>
#include <gdal_priv.h>
#include <ogrsf_frmts.h>
#include <unistd.h>

#include "geometry/polygon.hpp"
#include "io/atomic_file.hpp"
#include "io/errors.hpp"
#include "io/ogr_polygon.hpp"

namespace lodforge {

namespace fs = std::filesystem;

namespace {

std::string driver_for(const std::string& path) {
  const std::string ext = fs::path(path).extension().string();
  if (ext == ".gpkg") return "GPKG";
  if (ext == ".geojson" || ext == ".json") return "GeoJSON";
  return {};
}


}  // namespace

void check_output_path(const std::string& path) {
  if (driver_for(path).empty())
    throw InputError("'" + path + "': unknown output format; use a .gpkg or .geojson file name");
  fs::path dir = fs::absolute(path).parent_path();
  if (!fs::is_directory(dir)) throw InputError("'" + path + "': output directory '" + dir.string() + "' does not exist");
  if (access(dir.c_str(), W_OK) != 0) throw InputError("'" + path + "': output directory '" + dir.string() + "' is not writable");
}

struct FootprintFileWriter::Impl {
  std::string path;
  FootprintLayer layer;
  fs::path final_path, temp;
  GDALDataset* dataset = nullptr;
  OGRLayer* ogr_layer = nullptr;
  OGRLayer* lod1_layer = nullptr;  // when layer.write_lod1 (GeoPackage only)
  OGRLayer* parts_layer = nullptr;  // ... and the LoD1.3 parts
  bool transaction = false;

  [[noreturn]] void fail(const std::string& what) {
    const std::string message = "'" + path + "': " + what + ": " + CPLGetLastErrorMsg() + disk_full_note(path);
    close_and_remove();
    throw InputError(message);
  }
  void close_and_remove() {
    if (dataset) GDALClose(dataset);
    dataset = nullptr;
    std::error_code ec;
    fs::remove(temp, ec);
  }
};

const std::vector<HeightStatistic>& height_statistic_fields() {
  static const std::vector<HeightStatistic> fields{{"roof_min"}, {"roof_50p"}, {"roof_70p"}, {"roof_max"},
                                                   {"volume_lod1"}, {"dsm_coverage"}, {"dsm_cells", true}};
  return fields;
}

char** rfc7946_layer_options() {
  static const char* options[] = {"RFC7946=YES", "COORDINATE_PRECISION=7", nullptr};
  return const_cast<char**>(options);
}

std::string set_gpkg_timestamp() {
  std::string text = "2000-01-01T00:00:00.000Z";
  if (const char* epoch = std::getenv("SOURCE_DATE_EPOCH"); epoch && *epoch) {
    const std::string value = epoch;
    if (value.size() > 12 || value.find_first_not_of("0123456789") != std::string::npos)
      throw InputError("SOURCE_DATE_EPOCH '" + value + "': expected whole seconds since 1970-01-01 (the environment's, for the GeoPackages' last change)");
    const std::time_t t = std::time_t(std::stoll(value));
    std::tm utc{};
    gmtime_r(&t, &utc);
    char buffer[40];
    std::strftime(buffer, sizeof buffer, "%Y-%m-%dT%H:%M:%S.000Z", &utc);
    text = buffer;
  }
  CPLSetConfigOption("OGR_CURRENT_DATE", text.c_str());
  return text;
}

FootprintFileWriter::FootprintFileWriter(const std::string& path, const FootprintLayer& layer) : impl_(new Impl) {
  GDALAllRegister();
  CPLErrorReset();
  impl_->path = path;
  impl_->layer = layer;
  try {
    check_output_path(path);
  } catch (...) {
    delete impl_;
    throw;
  }
  const std::string driver_name = driver_for(path);
  impl_->final_path = fs::absolute(path);
  impl_->temp = impl_->final_path.parent_path() / (impl_->final_path.stem().string() + ".partial-" + std::to_string(getpid()) +
                                                   impl_->final_path.extension().string());
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName(driver_name.c_str());
  fs::remove(impl_->temp);
  // A GeoPackage is an SQLite database written to a temporary name and renamed when complete, so
  // SQLite's rollback journal and its syncs protect nothing here (an interrupted file is never
  // renamed); without them a tile's file is written about twice as fast. Nor does it need
  // SpatiaLite's SQL functions, which GDAL sets up for every connection (with a PROJ context of
  // their own): a third of a small file's time. The same bytes. This thread only.
  CPLSetThreadLocalConfigOption("OGR_SQLITE_JOURNAL", "MEMORY");
  CPLSetThreadLocalConfigOption("OGR_SQLITE_SYNCHRONOUS", "OFF");
  CPLSetThreadLocalConfigOption("SPATIALITE_LOAD", "NO");
  impl_->dataset = driver ? driver->Create(impl_->temp.c_str(), 0, 0, 0, GDT_Unknown, nullptr) : nullptr;
  CPLSetThreadLocalConfigOption("OGR_SQLITE_JOURNAL", nullptr);
  CPLSetThreadLocalConfigOption("OGR_SQLITE_SYNCHRONOUS", nullptr);
  CPLSetThreadLocalConfigOption("SPATIALITE_LOAD", nullptr);
  if (!impl_->dataset) {
    const std::string message = "'" + path + "': cannot create: " + CPLGetLastErrorMsg() + disk_full_note(path);
    delete impl_;
    throw InputError(message);
  }
  OGRSpatialReference srs;
  OGRSpatialReference* srs_ptr = nullptr;
  if (!layer.crs_wkt.empty() && srs.importFromWkt(layer.crs_wkt.c_str()) == OGRERR_NONE) {
    srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    srs_ptr = &srs;
  }
  try {
    impl_->ogr_layer = impl_->dataset->CreateLayer(layer.name.c_str(), srs_ptr, wkbPolygon,
                                                   layer.rfc7946 && driver_name == "GeoJSON" ? rfc7946_layer_options() : nullptr);
    if (!impl_->ogr_layer) impl_->fail("cannot create layer");
    auto field = [&](const char* name, OGRFieldType type) {
      OGRFieldDefn def(name, type);
      if (impl_->ogr_layer->CreateField(&def) != OGRERR_NONE) impl_->fail(std::string("cannot create field ") + name);
    };
    field("id", layer.write_cadastre ? OFTString : OFTInteger64);
    if (layer.write_cadastre) {
      field("cadastre", OFTString);
      field("cadastre_coverage", OFTReal);
    }
    if (layer.write_status) {
      field("status", OFTString);
      field("stage", OFTString);
      field("reason", OFTString);
      field("regularizer", OFTString);
      if (layer.write_model) field("model", OFTString);
    }
    if (!layer.kind_field.empty()) field(layer.kind_field.c_str(), OFTString);
    if (layer.write_heights) {
      field("ground_height", OFTReal);
      field("roof_height", OFTReal);
      for (const HeightStatistic& h : height_statistic_fields()) field(h.name.c_str(), h.integer ? OFTInteger : OFTReal);
    }
    field("vertex_count", OFTInteger);
    field("area_m2", OFTReal);
    if (layer.write_lod1 && driver_name == "GPKG") {
      impl_->lod1_layer = impl_->dataset->CreateLayer("lod1", srs_ptr, wkbMultiPolygon25D, nullptr);
      if (!impl_->lod1_layer) impl_->fail("cannot create layer lod1");
      for (const auto& [name, type] : {std::pair{"id", layer.write_cadastre ? OFTString : OFTInteger64}, std::pair{"ground_height", OFTReal}, std::pair{"roof_height", OFTReal}}) {
        OGRFieldDefn def(name, type);
        if (impl_->lod1_layer->CreateField(&def) != OGRERR_NONE) impl_->fail(std::string("cannot create field lod1.") + name);
      }
      impl_->parts_layer = impl_->dataset->CreateLayer("parts", srs_ptr, wkbPolygon, nullptr);
      if (!impl_->parts_layer) impl_->fail("cannot create layer parts");
      std::vector<std::pair<std::string, OGRFieldType>> fields{{"id", layer.write_cadastre ? OFTString : OFTInteger64}, {"part", OFTInteger},
                                                              {"ground_height", OFTReal}, {"roof_height", OFTReal}};
      for (const HeightStatistic& h : height_statistic_fields()) fields.emplace_back(h.name, h.integer ? OFTInteger : OFTReal);
      for (const auto& [name, type] : fields) {
        OGRFieldDefn def(name.c_str(), type);
        if (impl_->parts_layer->CreateField(&def) != OGRERR_NONE) impl_->fail("cannot create field parts." + name);
      }
    }
    impl_->transaction = impl_->dataset->StartTransaction() == OGRERR_NONE;  // GeoPackage yes, GeoJSON no
  } catch (...) {
    delete impl_;
    throw;
  }
}

FootprintFileWriter::~FootprintFileWriter() {
  if (impl_->dataset) impl_->close_and_remove();
  delete impl_;
}

void FootprintFileWriter::add(const FootprintRecord& r) {
  const FootprintLayer& layer = impl_->layer;
  OGRFeature feature(impl_->ogr_layer->GetLayerDefn());
  const std::string text_id = r.cadastre_id.empty() ? std::to_string(r.id) : r.cadastre_id;
  auto set_id = [&](OGRFeature& f) {
    if (layer.write_cadastre) f.SetField("id", text_id.c_str());
    else f.SetField("id", static_cast<GIntBig>(r.id));
  };
  set_id(feature);
  if (layer.write_cadastre) {
    feature.SetField("cadastre", r.cadastre.c_str());
    if (r.coverage >= 0) feature.SetField("cadastre_coverage", r.coverage);
    else feature.SetFieldNull(feature.GetFieldIndex("cadastre_coverage"));
  }
  if (layer.write_status) {
    feature.SetField("status", r.status.c_str());
    // No stage or reason (a building modeled as asked): NULL, not an empty text.
    for (const auto& [field, text] : {std::pair{"stage", &r.failed_stage}, std::pair{"reason", &r.reason}}) {
      if (text->empty()) feature.SetFieldNull(feature.GetFieldIndex(field));
      else feature.SetField(field, text->c_str());
    }
    feature.SetField("regularizer", r.regularizer.c_str());
    if (layer.write_model) {
      if (r.model.empty()) feature.SetFieldNull(feature.GetFieldIndex("model"));
      else feature.SetField("model", r.model.c_str());
    }
  }
  if (!layer.kind_field.empty()) feature.SetField(layer.kind_field.c_str(), r.kind.c_str());
  if (layer.write_heights && r.has_heights) {
    feature.SetField("roof_height", r.roof_height);
    feature.SetField("ground_height", r.ground_height);
    for (std::size_t i = 0; i < height_statistic_fields().size() && i < r.height_statistics.size(); ++i) {
      const HeightStatistic& h = height_statistic_fields()[i];
      if (h.integer) feature.SetField(h.name.c_str(), int(std::llround(r.height_statistics[i])));
      else feature.SetField(h.name.c_str(), r.height_statistics[i]);
    }
  } else if (layer.write_heights) {
    feature.SetFieldNull(feature.GetFieldIndex("roof_height"));
    feature.SetFieldNull(feature.GetFieldIndex("ground_height"));
    for (const HeightStatistic& h : height_statistic_fields()) feature.SetFieldNull(feature.GetFieldIndex(h.name.c_str()));
  }
  feature.SetField("vertex_count", int(vertex_count(r.polygon)));
  feature.SetField("area_m2", area(r.polygon));
  feature.SetGeometry(to_ogr_polygon(r.polygon).get());
  if (impl_->ogr_layer->CreateFeature(&feature) != OGRERR_NONE) impl_->fail("cannot write feature " + text_id);
  if (impl_->lod1_layer && !r.lod1_faces.empty()) {
    OGRFeature block(impl_->lod1_layer->GetLayerDefn());
    set_id(block);
    block.SetField("ground_height", r.ground_height);
    block.SetField("roof_height", r.roof_height);
    OGRMultiPolygon faces;
    for (const Face& f : r.lod1_faces) {
      OGRPolygon polygon;
      for (const Ring3& ring : f.rings) {
        OGRLinearRing linear;
        for (const Vec3& p : ring) linear.addPoint(p.x(), p.y(), p.z());
        linear.closeRings();
        polygon.addRing(&linear);
      }
      faces.addGeometry(&polygon);
    }
    block.SetGeometry(&faces);
    if (impl_->lod1_layer->CreateFeature(&block) != OGRERR_NONE) impl_->fail("cannot write the LOD1 block of " + text_id);
  }
  if (impl_->parts_layer)
    for (std::size_t k = 0; k < r.parts.size(); ++k) {
      OGRFeature part(impl_->parts_layer->GetLayerDefn());
      set_id(part);
      part.SetField("part", int(k) + 1);
      part.SetField("ground_height", r.parts[k].ground_height);
      part.SetField("roof_height", r.parts[k].roof_height);
      for (std::size_t i = 0; i < height_statistic_fields().size() && i < r.parts[k].height_statistics.size(); ++i) {
        const HeightStatistic& h = height_statistic_fields()[i];
        if (h.integer) part.SetField(h.name.c_str(), int(std::llround(r.parts[k].height_statistics[i])));
        else part.SetField(h.name.c_str(), r.parts[k].height_statistics[i]);
      }
      part.SetGeometry(to_ogr_polygon(r.parts[k].polygon).get());
      if (impl_->parts_layer->CreateFeature(&part) != OGRERR_NONE) impl_->fail("cannot write part " + std::to_string(k + 1) + " of " + text_id);
    }
}

void FootprintFileWriter::finish() {
  if (impl_->transaction && impl_->dataset->CommitTransaction() != OGRERR_NONE) impl_->fail("cannot commit");
  CPLErrorReset();
  impl_->dataset->FlushCache(true);  // GDAL 3.6: errors are reported through CPLGetLastErrorType
  if (CPLGetLastErrorType() == CE_Failure) impl_->fail("cannot flush (disk full?)");
  GDALClose(impl_->dataset);  // GeoJSON writes its closing bytes here
  impl_->dataset = nullptr;
  if (CPLGetLastErrorType() == CE_Failure) {
    const std::string message = "'" + impl_->path + "': writing failed: " + CPLGetLastErrorMsg() + disk_full_note(impl_->path);
    impl_->close_and_remove();
    throw InputError(message);
  }
  std::error_code ec;
  fs::rename(impl_->temp, impl_->final_path, ec);
  if (ec) {
    fs::remove(impl_->temp, ec);
    throw InputError("'" + impl_->path + "': cannot move the finished file into place: " + ec.message());
  }
}

void write_footprints(const std::string& path, const FootprintLayer& layer, const std::vector<FootprintRecord>& records) {
  FootprintFileWriter writer(path, layer);
  for (const FootprintRecord& r : records) writer.add(r);
  writer.finish();
}

}  // namespace lodforge
