// The command line of every subcommand, parsed by CLI11: every option declared once with its
// help; options and positional arguments in any order; -h/--help everywhere; short forms where
// GDAL's utilities have them (-j threads). Usage errors (an unknown option, with the nearest
// known one suggested; a missing value; a repeated single option) throw UsageError (exit 2).
// CLI11 stays inside args.cpp.
#pragma once
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace lodforge {

// Edits (insertions, deletions, substitutions) from a to b: the "did you mean" of commands and options.
std::size_t edit_distance(const std::string& a, const std::string& b);

// Sets the level of the logs (trace, debug, info, warn, error); throws UsageError for another word.
void set_log_level(const std::string& level);

// Thrown by Args::parse when asked for the option list (--list-options, used to generate the
// shell completion): every option the command declares, separated by spaces.
struct ListedOptions {
  std::string options;
};

class Args {
 public:
  Args(std::string command, std::string summary);
  ~Args();
  Args(const Args&) = delete;
  Args& operator=(const Args&) = delete;
  // An option taking a value ("--out FILE", "--out=FILE"; "-j 2" with short_name "j"),
  // repeatable if `repeatable`.
  Args& value(const std::string& name, const std::string& meta, const std::string& help, bool repeatable = false,
              const std::string& short_name = "");
  Args& flag(const std::string& name, const std::string& help, const std::string& short_name = "");  // a switch
  // A positional argument (the job file, the output directory), optional for the parser: the
  // command says when it is missing.
  Args& positional(const std::string& name, const std::string& meta, const std::string& help);
  // Parses argv[first..]; throws UsageError. "-h"/"--help" sets has("help"). Applies the options
  // every command has: -q, -v, --log-level (the logs' level) and --config KEY VALUE (GDAL's).
  void parse(int argc, char** argv, int first);
  bool has(const std::string& name) const { return values_.count(name) > 0; }
  std::optional<std::string> get(const std::string& name) const;
  std::string require(const std::string& name) const;  // throws UsageError if absent
  std::vector<std::string> all(const std::string& name) const;
  std::string help() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string command_;
  std::map<std::string, std::vector<std::string>> values_;
};

}  // namespace lodforge
