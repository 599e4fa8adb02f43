// Every stage option of a job, as one tree: contour extraction plus the per-building core.
// Paths like "labeling.kappa2" address one option (--set on the command line).
#pragma once
#include <map>
#include <string>
#include <vector>

#include "contour/contour.hpp"
#include "heights/heights.hpp"
#include "partition/partition.hpp"
#include "parts/parts.hpp"
#include "pipeline/core_options.hpp"

namespace lodforge {

struct StageOptions {
  ContourOptions contour;
  CoreOptions core;
  HeightOptions heights;
  PartitionOptions footprints;
  PartOptions parts;

  template <class V>
  void visit(V& v) {
    v.section("contour", contour);
    core.visit(v);
    v.section("heights", heights);
    v.section("footprints", footprints);
    v.section("parts", parts);
  }
};

// Splits "path=value" assignments; malformed ones are added to errors (named by flag).
std::map<std::string, std::string> split_assignments(const std::vector<std::string>& assignments, const std::string& flag,
                                                     std::vector<std::string>& errors);

// Applies "path=value" assignments, then validates everything; throws InputError listing every
// problem at once, each with its key path.
void apply_overrides(StageOptions& options, const std::vector<std::string>& assignments);

std::string print_defaults();

}  // namespace lodforge
