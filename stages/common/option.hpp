// One declaration per option. Every options struct has
//   template <class V> void visit(V& v) { v("name", member, "help", Check{...}); ... }
// and nested sections call v.section("name", member). Visitors print the defaults, apply
// "section.key=value" overrides and validate, so names, help and limits are written once.
#pragma once
#include <limits>
#include <string>
#include <vector>

namespace lodforge {

struct Check {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_exclusive = false;
  std::vector<std::string> choices;  // for string options
  std::vector<double> values;        // for numbers taking one of a few values

  static Check at_least(double v) { Check c; c.min = v; return c; }
  static Check above(double v) { Check c = at_least(v); c.min_exclusive = true; return c; }
  static Check between(double lo, double hi) { Check c = at_least(lo); c.max = hi; return c; }
  static Check one_of(std::vector<std::string> values) {
    Check c;
    c.choices = std::move(values);
    return c;
  }
  static Check one_of_numbers(std::vector<double> allowed) {
    Check c;
    c.values = std::move(allowed);
    return c;
  }
  // Empty when value is allowed, else the message ("must be >= 0").
  std::string problem(double value) const;
  std::string problem(const std::string& value) const;
};

}  // namespace lodforge
