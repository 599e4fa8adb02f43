// A whole run at a glance, written by `lodforge merge`: overview.tif, a Cloud-Optimized GeoTIFF
// of the whole area (a hillshade of the DSM, every building's whole outline coloured by its
// status), and report.html beside it: the run's numbers, the status counts, the failed and the
// slowest buildings with their reasons, and the overview.
#pragma once
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace lodforge {

struct Overview {
  std::string jpeg;  // the picture, JPEG bytes (for report.html); empty when there is none
  int width = 0, height = 0;
  double pixel_size = 0;      // map units per pixel
  std::string background;     // what is under the outlines: "DSM hillshade" or "none"
  std::size_t ok = 0, fallback = 0, lod0_only = 0, not_in_mask = 0;  // outlines drawn, by status
};

// Writes tif (a COG in the segmentation's CRS, over its whole extent grown to hold every footprint
// whole, the longest side at most max_pixels and no finer than the segmentation's pixels): a hillshade of the job's DSM (none:
// white) and the footprints of the run's GeoPackage tiles, in tile order: ok red, fallback
// yellow, without LOD1 (no heights) magenta, a cadastral footprint the mask does not confirm cyan. A job that cannot be read (moved since the run) is
// named in a warning and the frame is the footprints' extent. Throws InputError when the file
// cannot be written.
Overview write_overview(const std::string& job_path, const std::vector<std::filesystem::path>& gpkg_tiles,
                        const std::filesystem::path& tif, int max_pixels);

// Writes html: one self-contained page (the overview embedded) from the run's report.json.
void write_report_html(const std::filesystem::path& report_json, const Overview& overview, const std::filesystem::path& html);

}  // namespace lodforge
