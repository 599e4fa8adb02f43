// Writers of a tile's building models, one per format behind one small interface. Each streams
// its file (no document is built in memory) to a temporary name and renames it on finish().
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "geometry/types.hpp"
#include "lod1/solid.hpp"

namespace lodforge {

// A LoD1.3 part of a building (where its roof steps), with its own block.
struct PartModel {
  PolygonWithHoles footprint;
  double ground = 0, roof = 0;
  std::vector<double> height_statistics;  // named by height_statistic_fields(), as the building's
  Solid solid;
};

struct BuildingModel {
  std::int64_t id = 0;
  std::string tile;
  PolygonWithHoles footprint;   // LOD0
  bool has_lod1 = false;        // heights known
  double ground = 0, roof = 0;  // when has_lod1
  std::vector<double> height_statistics;  // when has_lod1: named by height_statistic_fields() (io/footprint_writer.hpp)
  Solid solid;                  // when has_lod1
  std::string status, stage, reason, regularizer;
  std::string model;  // the outline the chain chose (docs/models.md); empty: none (a fallback, the cadastre's polygon, a peer)
  // With inputs.footprints: the cadastre's ID (empty for a building it lacks), how the building
  // relates to it (confirmed, not_in_footprints, not_in_mask) and the footprint's mask coverage.
  std::string cadastre_id, cadastre;
  double coverage = -1;
  // LoD1.3: the parts where the roof steps, tiling the footprint (none: the building is one part).
  // CityGML BuildingParts, CityJSON BuildingPart children with "lod": "1.3", GeoPackage layer
  // "parts"; IDs object_id(m) + "-" + their number from 1.
  std::vector<PartModel> parts;
};

// A model's object ID in every format: lodforge_b<first pixel>, or its cadastral ID (made an XML
// NCName: id_ before a leading digit, other characters as _).
std::string object_id(const BuildingModel& model);
std::string cadastral_object_id(const std::string& cadastre_id);  // (the second case)

// Text for XML (or HTML) content and attribute values: & < > " escaped.
std::string xml_escape(const std::string& s);

// The 3D box of some models: min x, y, z, max x, y, z (CityJSON's geographicalExtent order).
using Extent = std::array<double, 6>;
Extent extent_of(const std::vector<BuildingModel>& models);

struct WriterContext {
  std::string crs_wkt;
  std::string epsg;  // "EPSG:7415": the CRS the 3D formats declare (output.crs, else the inputs'), or empty
  std::string tile;
  Vec2 origin = Vec2::Zero();  // the tile's lower-left corner: OBJ and CityJSON are relative to it
  Extent extent{};             // of the file's models: CityGML's gml:boundedBy, CityJSON's geographicalExtent
  bool cadastre = false;       // inputs.footprints given: the cadastre's attributes, a text id in GeoPackage/GeoJSON
};

class ModelWriter {
 public:
  virtual ~ModelWriter() = default;
  virtual void add(const BuildingModel& model) = 0;
  virtual void finish() = 0;  // completes and moves the file into place
};

// format: citygml, cityjson, obj, gpkg, geojson. The file extension follows the format.
std::unique_ptr<ModelWriter> make_model_writer(const std::string& format, const std::string& path, const WriterContext& context);
// Every output format by name (output.formats), in the order merge writes them.
const std::vector<std::string>& model_formats();
std::string extension_of(const std::string& format);  // ".gml", ".city.json", ".obj", ".gpkg", ".geojson"

}  // namespace lodforge
