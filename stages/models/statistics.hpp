// Small statistics the models share.
#pragma once
#include <algorithm>
#include <utility>
#include <vector>

namespace lodforge {

// The weighted q-quantile of (value, weight) pairs: the least value whose weight and the weights
// of all smaller values reach q of the total. 0 for no values.
inline double weighted_quantile(std::vector<std::pair<double, double>> values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  double total = 0, acc = 0;
  for (const auto& v : values) total += v.second;
  for (const auto& [value, weight] : values) {
    acc += weight;
    if (acc >= q * total) return value;
  }
  return values.back().first;
}

}  // namespace lodforge
