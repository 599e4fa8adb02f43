#include "cli/args.hpp"

#include <CLI/CLI.hpp>
#include <cpl_conv.h>
#include <spdlog/spdlog.h>
#include <algorithm>
#include <cctype>
#include <list>

#include "io/errors.hpp"

namespace lodforge {

std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

struct Args::Impl {
  CLI::App app;
  struct Declared {
    std::string name;
    CLI::Option* option;
    std::vector<std::string>* values;  // for options with values
  };
  std::list<std::vector<std::string>> storage;  // stable addresses for CLI11 to fill
  std::vector<Declared> declared;
  Impl(const std::string& summary, const std::string& name) : app(summary, name) {}
};

Args::Args(std::string command, std::string summary)
    : impl_(std::make_unique<Impl>(std::move(summary), "lodforge " + command)), command_(std::move(command)) {
  impl_->app.get_formatter()->column_width(32);
  impl_->app.footer("exit codes: 0 done, 1 error in the input or the run, 2 usage error");
  // Every command's logging options (applied by parse).
  value("log-level", "LEVEL", "trace, debug, info (default), warn or error; also LODFORGE_LOG_LEVEL");
  flag("quiet", "warnings and errors only, no progress", "q");
  flag("verbose", "debug messages too", "v");
  {  // GDAL configuration options, as GDAL's utilities take them (applied by parse)
    std::vector<std::string>& values = impl_->storage.emplace_back();
    CLI::Option* o = impl_->app.add_option("--config", values, "a GDAL configuration option, e.g. --config GDAL_CACHEMAX 512 (repeatable)");
    o->type_name("KEY VALUE")->expected(2)->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
    impl_->declared.push_back({"config", o, &values});
  }
}

Args::~Args() = default;

Args& Args::value(const std::string& name, const std::string& meta, const std::string& help, bool repeatable,
                  const std::string& short_name) {
  std::vector<std::string>& values = impl_->storage.emplace_back();
  CLI::Option* o = impl_->app.add_option((short_name.empty() ? "" : "-" + short_name + ",") + "--" + name, values, help);
  o->type_name(meta)->expected(1)->allow_extra_args(false);
  if (repeatable) o->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  else o->multi_option_policy(CLI::MultiOptionPolicy::Throw);
  impl_->declared.push_back({name, o, &values});
  return *this;
}

Args& Args::flag(const std::string& name, const std::string& help, const std::string& short_name) {
  if (name == "help") return *this;  // -h/--help is every command's
  CLI::Option* o = impl_->app.add_flag((short_name.empty() ? "" : "-" + short_name + ",") + "--" + name, help);
  impl_->declared.push_back({name, o, nullptr});
  return *this;
}

Args& Args::positional(const std::string& name, const std::string& meta, const std::string& help) {
  std::vector<std::string>& values = impl_->storage.emplace_back();
  CLI::Option* o = impl_->app.add_option(name, values, help);
  o->type_name(meta)->expected(1);
  impl_->declared.push_back({name, o, &values});
  return *this;
}

void Args::parse(int argc, char** argv, int first) {
  if (first < argc && std::string(argv[first]) == "--list-options") {
    std::string names = "-h --help";
    for (const auto& d : impl_->declared)
      for (const std::string& n : d.option->get_snames()) names += " -" + n;
    for (const auto& d : impl_->declared)
      for (const std::string& n : d.option->get_lnames()) names += " --" + n;
    throw ListedOptions{names};
  }
  // An option nobody declared is named, with the nearest declared one if it is close (checked
  // first: CLI11 would hand the value after it to a positional argument and complain of that).
  for (int i = first; i < argc; ++i) {
    const std::string argument = argv[i];
    const bool option = argument.rfind("--", 0) == 0 || (argument.size() == 2 && argument[0] == '-' && std::isalpha(static_cast<unsigned char>(argument[1])));
    if (!option) continue;
    const std::string word = argument.substr(0, argument.find('='));
    if (word == "-h" || word == "--help") continue;
    const auto it = std::find_if(impl_->declared.begin(), impl_->declared.end(), [&](const auto& d) { return d.option->check_name(word); });
    if (it != impl_->declared.end()) {
      if (word == argument) i += it->option->get_items_expected_min();  // its values, whatever they look like
      continue;
    }
    std::string suggestion;
    std::size_t best = 3;
    for (const auto& d : impl_->declared) {
      if (d.option->get_lnames().empty()) continue;  // a positional argument
      const std::size_t distance = edit_distance(word, "--" + d.name);
      if (distance < best) { best = distance; suggestion = "--" + d.name; }
    }
    throw UsageError("unknown argument '" + word + "'" + (suggestion.empty() ? "" : "; did you mean " + suggestion + "?") +
                     " (see lodforge " + command_ + " --help)");
  }
  std::vector<std::string> arguments;
  for (int i = argc - 1; i >= first; --i) arguments.emplace_back(argv[i]);  // CLI11 takes them reversed
  try {
    impl_->app.parse(arguments);
  } catch (const CLI::CallForHelp&) {
    values_["help"] = {"true"};
    return;
  } catch (const CLI::ParseError& e) {
    throw UsageError(std::string(e.what()) + " (see lodforge " + command_ + " --help)");
  }
  for (const auto& d : impl_->declared) {
    if (d.option->count() == 0) continue;
    values_[d.name] = d.values ? *d.values : std::vector<std::string>{"true"};
  }
  // Every command's logging and GDAL options take effect here, before the command's work.
  if (auto level = has("quiet") ? std::optional<std::string>("warn") : has("verbose") ? std::optional<std::string>("debug") : get("log-level"))
    set_log_level(*level);
  const std::vector<std::string> config = all("config");
  for (std::size_t k = 0; k + 1 < config.size(); k += 2) CPLSetConfigOption(config[k].c_str(), config[k + 1].c_str());
}

void set_log_level(const std::string& level) {
  static const std::vector<std::string> levels{"trace", "debug", "info", "warn", "error"};
  if (std::find(levels.begin(), levels.end(), level) == levels.end())
    throw UsageError("log level '" + level + "': must be one of trace, debug, info, warn, error");
  spdlog::set_level(spdlog::level::from_str(level));
}

std::optional<std::string> Args::get(const std::string& name) const {
  auto it = values_.find(name);
  if (it == values_.end() || it->second.empty()) return std::nullopt;
  return it->second.back();
}

std::string Args::require(const std::string& name) const {
  auto v = get(name);
  if (!v) throw UsageError("--" + name + " is required (see lodforge " + command_ + " --help)");
  return *v;
}

std::vector<std::string> Args::all(const std::string& name) const {
  auto it = values_.find(name);
  return it == values_.end() ? std::vector<std::string>{} : it->second;
}

std::string Args::help() const { return impl_->app.help(); }

}  // namespace lodforge
