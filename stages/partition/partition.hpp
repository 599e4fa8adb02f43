// Buildings, not blocks: a segmented block split among the cadastral footprints it covers.
// A segmentation has one class for every building, so houses sharing walls come out as one
// block. Given the footprints of a cadastre, each footprint the mask confirms gets the part of
// the block's regularized outline that lies in its cell: the footprint itself (earlier footprints
// win where two overlap) and its part of the band within extension_m around the footprints (roof
// overhangs), split among them as a mitered offset of their union splits it. The cells do not
// overlap, so houses sharing a wall share it exactly. The outline outside every cell is the mask's
// own (a building the cadastre lacks). Pure computation (CGAL's exact Boolean operations).
#pragma once
#include <string>
#include <vector>

#include "common/option.hpp"
#include "geometry/types.hpp"

namespace lodforge {

struct PartitionOptions {
  double min_coverage = 0.5;          // a footprint is confirmed when this share of it is building in the mask
  double extension_m = 2.0;           // mask area outside every footprint joins the nearest within this distance
  std::string lod0 = "regularized";  // the LOD0 of a confirmed footprint: its share of the outline, or the cadastre's polygon

  template <class V>
  void visit(V& v) {
    v("min_coverage", min_coverage, "with inputs.footprints: a footprint is a building when at least this share of its pixels is building in the mask; below, it is reported with cadastre: not_in_mask", Check::between(0, 1));
    v("extension_m", extension_m, "with inputs.footprints: mask area outside every footprint within this distance of them (roof overhangs, a mask drawn wide) joins the footprint whose wall it faces; farther, it is a building of its own with cadastre: not_in_footprints (m)", Check::at_least(0));
    v("lod0", lod0, "with inputs.footprints: a confirmed footprint's LOD0 is its share of the regularized outline ('regularized') or the cadastre's own polygon ('cadastre'); heights come from it either way", Check::one_of({"regularized", "cadastre"}));
  }
};

struct FootprintShare {
  PolygonWithHoles polygon;  // empty outer ring: none (see note)
  std::string note;          // why the share is not the outline's part (cadastre polygon taken, parts dropped), else empty
};

struct Partition {
  std::vector<FootprintShare> shares;  // one per footprint, in the footprints' order
  std::vector<PolygonWithHoles> rest;  // parts of the outlines in no footprint's cell, at least min_area_m2, largest first
  int dropped_small = 0;               // parts of the outlines below min_area_m2 left out (and pinched parts, counted once)
};

// outlines: the block's regularized outlines (valid polygons). footprints: the confirmed
// footprints, each one or more valid polygons (a multi-part footprint), earlier ones first where
// they overlap. absorb_rest: each part of the outlines outside every cell joins the share it
// borders longest instead (when the two make one polygon), so the shares cover the outlines.
Partition partition_outlines(const std::vector<PolygonWithHoles>& outlines,
                             const std::vector<std::vector<PolygonWithHoles>>& footprints, const PartitionOptions& options,
                             double min_area_m2, bool absorb_rest = false);

}  // namespace lodforge
