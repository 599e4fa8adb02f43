#include "job/job.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "io/errors.hpp"
#include "job/yaml_reader.hpp"

namespace lodforge {

namespace fs = std::filesystem;

Job load_job(const std::string& path, const std::vector<std::string>& overrides) {
  if (!fs::exists(path)) throw InputError("'" + path + "': job file not found");
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::ParserException& e) {
    throw InputError("'" + path + "': not valid YAML: line " + std::to_string(e.mark.line + 1) + ", column " +
                     std::to_string(e.mark.column + 1) + ": " + e.msg);
  } catch (const YAML::Exception& e) {
    throw InputError("'" + path + "': cannot read: " + e.what());
  }
  if (!root.IsMap()) throw InputError("'" + path + "': a job is a YAML mapping (inputs:, tiling:, output:, ...)");
  Job job;
  YamlReader reader(root);
  try {
    job.visit(reader);
    reader.report_unknown();
  } catch (const YAML::Exception& e) {
    throw InputError("'" + path + "': unexpected YAML structure: " + e.what());
  }
  std::vector<std::string> errors = reader.errors;

  set_and_validate(job, split_assignments(overrides, "--set", errors), errors);

  // Paths relative to the job file.
  const fs::path base = fs::absolute(path).parent_path();
  auto resolve = [&base](std::string& p) {
    if (!p.empty() && fs::path(p).is_relative() && p.rfind("/vsi", 0) != 0) p = (base / p).lexically_normal().string();
  };
  for (std::string* p : {&job.inputs.segmentation.path, &job.inputs.dsm.path, &job.inputs.dtm.path,
                         &job.inputs.orthophoto.path, &job.inputs.footprints.path, &job.output.dir, &job.work_dir})
    resolve(*p);
  if (job.inputs.segmentation.path.empty()) errors.push_back("inputs.segmentation.path: required");
  if (job.output.formats.empty())
    errors.push_back("output.formats: needs at least one format (citygml, cityjson, obj, gpkg, geojson); a run without one writes no model");
  if (job.tiling.max_window_m < job.tiling.tile_size_m + 2 * job.tiling.halo_m)
    errors.push_back("tiling.max_window_m: must be >= tile_size_m + 2 * halo_m (" +
                     std::to_string(job.tiling.tile_size_m + 2 * job.tiling.halo_m) + ")");
  const auto& rgb = job.inputs.segmentation.building_rgb;
  if (!rgb.empty() && rgb.size() != 3) errors.push_back("inputs.segmentation.building_rgb: needs three values [R, G, B]");
  const auto& min = job.inputs.segmentation.building_min;
  if (min.size() > 1) errors.push_back("inputs.segmentation.building_min: needs one value [V] (or none)");
  if (!min.empty() && !rgb.empty()) errors.push_back("inputs.segmentation.building_min: give it or building_rgb, not both");
  if (rgb.empty() && min.empty() && job.inputs.segmentation.building_values.empty())
    errors.push_back("inputs.segmentation.building_values: needs at least one value (or give building_rgb or building_min)");
  for (auto [key, p] : {std::pair{"inputs.segmentation.path", job.inputs.segmentation.path},
                        {"inputs.dsm.path", job.inputs.dsm.path}, {"inputs.dtm.path", job.inputs.dtm.path},
                        {"inputs.orthophoto.path", job.inputs.orthophoto.path}}) {
    if (!p.empty() && p.rfind("/vsi", 0) != 0 && !fs::exists(p)) errors.push_back(std::string(key) + ": '" + p + "': file not found");
  }
  if (!errors.empty()) {
    std::string text = "'" + path + "': " + std::to_string(errors.size()) + " problem(s):";
    for (const std::string& e : errors) text += "\n  " + e;
    throw InputError(text);
  }
  return job;
}

std::string default_job_yaml() {
  Job job;
  OptionPrinter printer;
  job.visit(printer);
  return "# lodforge job: every option with its default. Paths are relative to this file.\n" + printer.str();
}

}  // namespace lodforge
