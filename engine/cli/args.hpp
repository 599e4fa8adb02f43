// A small command-line parser: every flag declared once with its help; unknown flags and
// missing values are errors that name the flag.
#pragma once
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace lodforge {

class Args {
 public:
  Args(std::string command, std::string summary) : command_(std::move(command)), summary_(std::move(summary)) {}
  // A flag taking a value ("--out FILE"), repeatable if `repeatable`.
  Args& value(const std::string& name, const std::string& meta, const std::string& help, bool repeatable = false);
  Args& flag(const std::string& name, const std::string& help);  // a switch without value
  // Parses argv; throws InputError for unknown flags, missing values, repeated single flags.
  void parse(int argc, char** argv, int first);
  bool has(const std::string& name) const { return values_.count(name) > 0; }
  std::optional<std::string> get(const std::string& name) const;
  std::string require(const std::string& name) const;  // throws InputError if absent
  std::vector<std::string> all(const std::string& name) const;
  std::string help() const;

 private:
  struct Spec {
    std::string name, meta, help;
    bool takes_value, repeatable;
  };
  std::string command_, summary_;
  std::vector<Spec> specs_;
  std::map<std::string, std::vector<std::string>> values_;
};

}  // namespace lodforge
