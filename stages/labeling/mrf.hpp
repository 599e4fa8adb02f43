// Stage 4: a target direction per edge by the MRF of paper eq. 5–9, minimized by alpha-expansion
// with label costs (Delong et al. 2012) on the Boykov–Kolmogorov max-flow library.
#pragma once
#include <vector>

#include "common/option.hpp"
#include "geometry/types.hpp"

namespace lodforge {

struct MrfOptions {
  double kappa1 = 1.0;   // smoothness weight (eq. 9)
  double kappa2 = 10.0;  // label cost weight (eq. 9)
  double sigma = 0.5;    // smoothness width of eq. 6 (on normal differences, unitless)
  double unit_length_m = 0.1;  // data and smoothness are counted per this much contour length
  int max_cycles = 10;         // expansion cycles over all labels at most
  double group_deg = 2.0;      // consecutive edges whose normals lie this close are labeled as one

  template <class V>
  void visit(V& v) {
    v("kappa1", kappa1, "smoothness weight kappa1 of eq. 9", Check::at_least(0));
    v("kappa2", kappa2, "label cost weight kappa2 of eq. 9", Check::at_least(0));
    v("sigma", sigma, "width of the smoothness weight of eq. 6", Check::above(0));
    v("unit_length_m", unit_length_m, "contour length counted as one term of eq. 5-6 (m), so the energy does not depend on the pixel size", Check::above(0));
    v("max_cycles", max_cycles, "alpha-expansion cycles at most", Check::at_least(1));
    v("group_deg", group_deg, "consecutive edges of a ring whose smoothed normals lie within this of the first one's are labeled as one: their terms summed, the energy of every labeling that keeps them together is unchanged, a label change between them is not tried (degrees; 0 = each edge on its own)", Check::between(0, 10));
  }
};

// One building's labeling problem: per ring, the smoothed normal and length of every edge.
struct LabelingInput {
  std::vector<std::vector<Vec2>> normals;
  std::vector<std::vector<double>> lengths;
  std::vector<Vec2> directions;     // label set: unit normals
  std::vector<double> support;      // per direction, for h_i of eq. 7
};

using EdgeLabels = std::vector<std::vector<int>>;  // per ring, per edge: index into directions

double labeling_energy(const LabelingInput& input, const EdgeLabels& labels, const MrfOptions& o);

// Alpha-expansion from the nearest-direction labeling; never increases the energy.
EdgeLabels label_edges(const LabelingInput& input, const MrfOptions& options);

// Maximal runs of equal labels along a ring: (first edge, edge count), cyclic. A ring whose
// edges all carry one label is one run starting at 0.
std::vector<std::pair<int, int>> label_runs(const std::vector<int>& labels);

}  // namespace lodforge
