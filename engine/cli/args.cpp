#include "cli/args.hpp"

#include <sstream>

#include "io/errors.hpp"

namespace lodforge {

Args& Args::value(const std::string& name, const std::string& meta, const std::string& help, bool repeatable) {
  specs_.push_back({name, meta, help, true, repeatable});
  return *this;
}

Args& Args::flag(const std::string& name, const std::string& help) {
  specs_.push_back({name, "", help, false, false});
  return *this;
}

void Args::parse(int argc, char** argv, int first) {
  for (int i = first; i < argc; ++i) {
    std::string arg = argv[i];
    std::string inline_value;
    bool has_inline = false;
    if (auto eq = arg.find('='); arg.rfind("--", 0) == 0 && eq != std::string::npos) {
      inline_value = arg.substr(eq + 1);
      arg = arg.substr(0, eq);
      has_inline = true;
    }
    const Spec* spec = nullptr;
    for (const Spec& s : specs_) if ("--" + s.name == arg) spec = &s;
    if (!spec) throw InputError("unknown argument '" + arg + "' (see lodforge " + command_ + " --help)");
    if (!spec->takes_value) {
      values_[spec->name].push_back("true");
      continue;
    }
    if (!has_inline) {
      if (i + 1 >= argc) throw InputError(arg + " needs a value (" + spec->meta + ")");
      inline_value = argv[++i];
    }
    if (!spec->repeatable && values_.count(spec->name))
      throw InputError(arg + " given more than once");
    values_[spec->name].push_back(inline_value);
  }
}

std::optional<std::string> Args::get(const std::string& name) const {
  auto it = values_.find(name);
  if (it == values_.end()) return std::nullopt;
  return it->second.back();
}

std::string Args::require(const std::string& name) const {
  auto v = get(name);
  if (!v) throw InputError("--" + name + " is required (see lodforge " + command_ + " --help)");
  return *v;
}

std::vector<std::string> Args::all(const std::string& name) const {
  auto it = values_.find(name);
  return it == values_.end() ? std::vector<std::string>{} : it->second;
}

std::string Args::help() const {
  std::ostringstream s;
  s << "usage: lodforge " << command_ << " [options]\n\n" << summary_ << "\n\noptions:\n";
  for (const Spec& spec : specs_) {
    std::string left = "  --" + spec.name + (spec.takes_value ? " " + spec.meta : "");
    if (left.size() < 30) left.resize(30, ' ');
    else left += "\n" + std::string(30, ' ');
    s << left << spec.help << (spec.repeatable ? " (repeatable)" : "") << '\n';
  }
  return s.str();
}

}  // namespace lodforge
