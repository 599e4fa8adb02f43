#include "common/option.hpp"

#include <cmath>
#include <sstream>

namespace lodforge {

namespace {
std::string number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}
}  // namespace

std::string Check::problem(double value) const {
  if (!std::isfinite(value)) return "must be a finite number";
  if (min_exclusive ? value <= min : value < min) {
    return std::string("must be ") + (min_exclusive ? "> " : ">= ") + number(min);
  }
  if (value > max) return "must be <= " + number(max);
  if (!values.empty()) {
    std::string all;
    for (double v : values) {
      if (v == value) return {};
      all += (all.empty() ? "" : " or ") + number(v);
    }
    return "must be " + all;
  }
  return {};
}

std::string Check::problem(const std::string& value) const {
  if (choices.empty()) return {};
  for (const std::string& c : choices) if (c == value) return {};
  std::string all;
  for (const std::string& c : choices) all += (all.empty() ? "" : ", ") + c;
  return "must be one of: " + all;
}

}  // namespace lodforge
