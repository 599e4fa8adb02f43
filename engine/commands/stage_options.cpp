#include "commands/stage_options.hpp"

#include "common/option_visitors.hpp"
#include "io/errors.hpp"

namespace lodforge {

std::map<std::string, std::string> split_assignments(const std::vector<std::string>& assignments, const std::string& flag,
                                                     std::vector<std::string>& errors) {
  std::map<std::string, std::string> values;
  for (const std::string& a : assignments) {
    const auto eq = a.find('=');
    if (eq == std::string::npos || eq == 0) errors.push_back(flag + " " + a + ": expected KEY=VALUE, e.g. labeling.kappa2=5");
    else values[a.substr(0, eq)] = a.substr(eq + 1);
  }
  return values;
}

void apply_overrides(StageOptions& options, const std::vector<std::string>& assignments) {
  std::vector<std::string> errors;
  // The keys as a job spells them (stages.labeling.kappa2) or without the section (labeling.kappa2).
  std::map<std::string, std::string> values;
  for (auto& [key, value] : split_assignments(assignments, "--set", errors))
    values[key.rfind("stages.", 0) == 0 ? key.substr(7) : key] = value;
  set_and_validate(options, values, errors);
  if (!errors.empty()) throw input_errors(errors);
}

std::string print_defaults() {
  StageOptions defaults;
  OptionPrinter printer;
  defaults.visit(printer);
  return printer.str();
}

}  // namespace lodforge
