#include "labeling/mrf.hpp"

#include <algorithm>
#include <cmath>
#include <maxflow.h>
#include <numeric>

namespace lodforge {

namespace {

using Graph = maxflow::Graph_DDD;

double label_cost(const LabelingInput& in, std::size_t l, const MrfOptions& o) {
  const double total = std::accumulate(in.support.begin(), in.support.end(), 0.0);
  const double h = total > 0 ? in.support[l] / total : 0.0;
  return o.kappa2 * (1.0 - h) * (1.0 - h);
}

double data_term(const LabelingInput& in, std::size_t r, std::size_t i, int l, const MrfOptions& o) {
  return in.lengths[r][i] / o.unit_length_m * (in.normals[r][i] - in.directions[l]).norm();
}

// Weight of the smoothness term between edge i and its successor (eq. 6, read as intended: the
// more alike the two normals, the dearer a label change; the printed sqrt(2) - exp(...) rises
// with the difference, the opposite of what the text says).
double smooth_weight(const LabelingInput& in, std::size_t r, std::size_t i, const MrfOptions& o) {
  const std::size_t n = in.normals[r].size();
  const std::size_t j = next_index(i, n);
  const double diff = (in.normals[r][i] - in.normals[r][j]).norm();
  const double length = 0.5 * (in.lengths[r][i] + in.lengths[r][j]) / o.unit_length_m;
  return o.kappa1 * length * std::exp(-diff / (2.0 * o.sigma * o.sigma));
}

// Every term of the energy that does not depend on the labeling, computed once per building
// (an expansion cycle visits each label, and each candidate's energy is evaluated), over groups
// of consecutive edges whose normals lie within group_deg of the group's first one's: a group's
// data term is its edges' summed, its smoothness weight to the next group that of its last edge
// to the next one's first, so the energy of a labeling constant on every group is the same as
// edge by edge. Labels change only between groups: a change between edges that face the same
// way within a degree or two is seldom the cheaper, and at fine pixels a wall's straight
// stretches are hundreds of edges, which the expansions' graphs no longer carry one by one.
struct Terms {
  int labels = 0;
  std::vector<int> offset;            // first group of each ring in the flat numbering
  std::vector<int> first;             // per flat group: its first edge (the ring's index)
  std::vector<double> data;           // per flat group, per label
  std::vector<double> smooth;         // per flat group: weight to its ring successor
  std::vector<double> distance;       // per pair of labels
  std::vector<double> label_cost;     // per label

  Terms(const LabelingInput& in, const MrfOptions& o) : labels(int(in.directions.size())), offset(in.normals.size() + 1, 0) {
    const double tolerance = 2.0 * std::sin(0.5 * o.group_deg * M_PI / 180.0);
    for (std::size_t r = 0; r < in.normals.size(); ++r) {
      const std::size_t m = in.normals[r].size();
      std::size_t groups = 0;
      for (std::size_t i = 0; i < m;) {
        std::size_t j = i + 1;
        while (j < m && (in.normals[r][j] - in.normals[r][i]).norm() < tolerance) ++j;
        first.push_back(int(i));
        const std::size_t g = std::size_t(offset[r]) + groups;
        data.resize(data.size() + std::size_t(labels), 0.0);
        for (std::size_t k = i; k < j; ++k)
          for (int l = 0; l < labels; ++l) data[g * labels + l] += data_term(in, r, k, l, o);
        // The weight to the next group: from this group's last edge (the ring's last edge's
        // to edge 0, the first group's first edge).
        smooth.push_back(m >= 2 ? smooth_weight(in, r, j - 1, o) : 0.0);
        ++groups;
        i = j;
      }
      offset[r + 1] = offset[r] + int(groups);
    }
    distance.resize(std::size_t(labels) * labels);
    for (int a = 0; a < labels; ++a)
      for (int b = 0; b < labels; ++b) distance[std::size_t(a) * labels + b] = (in.directions[a] - in.directions[b]).norm();
    for (int l = 0; l < labels; ++l) label_cost.push_back(lodforge::label_cost(in, std::size_t(l), o));
  }
  double d(int p, int l) const { return data[std::size_t(p) * labels + l]; }
  double dist(int a, int b) const { return distance[std::size_t(a) * labels + b]; }
  int groups(std::size_t r) const { return offset[r + 1] - offset[r]; }
  // A ring's edge labels from its group labels.
  std::vector<int> edge_labels(const std::vector<int>& group_labels, std::size_t r, std::size_t edges) const {
    std::vector<int> out(edges);
    for (int g = 0; g < groups(r); ++g) {
      const std::size_t end = g + 1 < groups(r) ? std::size_t(first[std::size_t(offset[r] + g + 1)]) : edges;
      std::fill(out.begin() + first[std::size_t(offset[r] + g)], out.begin() + long(end), group_labels[std::size_t(g)]);
    }
    return out;
  }
};

double energy(const Terms& t, const EdgeLabels& labels) {
  double e = 0;
  std::vector<char> used(std::size_t(t.labels), 0);
  for (std::size_t r = 0; r < labels.size(); ++r) {
    const std::size_t m = labels[r].size();
    for (std::size_t i = 0; i < m; ++i) {
      const int p = t.offset[r] + int(i);
      e += t.d(p, labels[r][i]);
      used[labels[r][i]] = 1;
      if (m >= 2) e += t.smooth[p] * t.dist(labels[r][i], labels[r][next_index(i, m)]);
    }
  }
  for (std::size_t l = 0; l < used.size(); ++l) if (used[l]) e += t.label_cost[l];
  return e;
}

// Adds E(x) with x = 0 (source side, keep) and x = 1 (sink side, switch to alpha).
void add_unary(Graph& g, int node, double e0, double e1) { g.add_tweights(node, e1, e0); }

// Adds the pairwise E(x_p, x_q) table; requires e00 + e11 <= e01 + e10 (metric labels).
void add_pairwise(Graph& g, int p, int q, double e00, double e01, double e10, double e11) {
  add_unary(g, p, 0.0, e10 - e00);
  add_unary(g, q, 0.0, e11 - e10);
  const double c = e01 + e10 - e00 - e11;
  if (c > 0) g.add_edge(p, q, c, 0.0);  // paid when p keeps and q switches
  // the constant e00 does not change the minimizer
}

// (g: emptied and built again, its memory kept from one expansion to the next; members: the
// same, per label its nodes.)
EdgeLabels expand(const Terms& t, const EdgeLabels& labels, int alpha, Graph& g, std::vector<std::vector<int>>& members) {
  const int n = t.offset.back();
  g.reset();
  g.add_node(n);
  for (std::size_t r = 0; r < labels.size(); ++r) {
    const std::size_t m = labels[r].size();
    for (std::size_t i = 0; i < m; ++i) {
      const int p = t.offset[r] + int(i);
      add_unary(g, p, t.d(p, labels[r][i]), t.d(p, alpha));
      if (m < 2) continue;
      const std::size_t j = next_index(i, m);
      const int q = t.offset[r] + int(j);
      const double w = t.smooth[p];
      const int a = labels[r][i], b = labels[r][j];
      add_pairwise(g, p, q, w * t.dist(a, b), w * t.dist(a, alpha), w * t.dist(alpha, b), 0.0);
    }
  }
  // Label costs (Delong et al. 2012, §3): one auxiliary node per label that may vanish or appear.
  members.resize(std::size_t(t.labels));
  for (std::vector<int>& m : members) m.clear();
  for (std::size_t r = 0; r < labels.size(); ++r)
    for (std::size_t i = 0; i < labels[r].size(); ++i) members[labels[r][i]].push_back(t.offset[r] + int(i));
  for (int l = 0; l < t.labels; ++l) {
    const double h = t.label_cost[l];
    if (h <= 0) continue;
    if (l != alpha && !members[l].empty()) {
      // h * [some member keeps l] = h - h * prod(x_p): aux y = 1 only if all switch.
      const int y = g.add_node();
      add_unary(g, y, 0.0, -h);
      for (int p : members[l]) g.add_edge(p, y, h, 0.0);  // y on sink while p on source costs h
    } else if (l == alpha && members[l].empty()) {
      // h * [some node switches to alpha] = h - h * prod(1 - x_p): aux z = 0 only if none does.
      const int z = g.add_node();
      add_unary(g, z, -h, 0.0);
      for (int p = 0; p < n; ++p) g.add_edge(z, p, h, 0.0);  // z on source while p on sink costs h
    }
  }
  g.maxflow();
  EdgeLabels result = labels;
  for (std::size_t r = 0; r < labels.size(); ++r)
    for (std::size_t i = 0; i < labels[r].size(); ++i)
      if (g.what_segment(t.offset[r] + int(i)) == Graph::SINK) result[r][i] = alpha;
  return result;
}

}  // namespace

double labeling_energy(const LabelingInput& in, const EdgeLabels& labels, const MrfOptions& o) {
  MrfOptions each_edge = o;  // any labeling, edge by edge
  each_edge.group_deg = 0;
  return energy(Terms(in, each_edge), labels);
}

EdgeLabels label_edges(const LabelingInput& in, const MrfOptions& o) {
  if (in.directions.size() < 2) {
    EdgeLabels labels(in.normals.size());
    for (std::size_t r = 0; r < in.normals.size(); ++r) labels[r].assign(in.normals[r].size(), 0);
    return labels;
  }
  const Terms terms(in, o);
  // From the nearest direction of every group (the least data term).
  EdgeLabels labels(in.normals.size());
  for (std::size_t r = 0; r < in.normals.size(); ++r) {
    labels[r].resize(std::size_t(terms.groups(r)));
    for (int g = 0; g < terms.groups(r); ++g) {
      const int p = terms.offset[r] + g;
      int best = 0;
      for (int l = 1; l < terms.labels; ++l)
        if (terms.d(p, l) < terms.d(p, best)) best = l;
      labels[r][std::size_t(g)] = best;
    }
  }
  double e0 = energy(terms, labels);
  // An expansion is a function of the labeling: one already tried and refused on the current
  // labeling would be refused again, so it is skipped until the labeling changes.
  std::vector<char> refused(std::size_t(terms.labels), 0);
  // (At most a node per group, one per label and one more; an edge per group to its successor,
  // one per group to its label's node, one per group from alpha's: no reallocation.)
  const int groups = terms.offset.back();
  Graph graph(groups + terms.labels + 1, 3 * groups);
  std::vector<std::vector<int>> members;
  for (int cycle = 0; cycle < o.max_cycles; ++cycle) {
    bool improved = false;
    for (int alpha = 0; alpha < terms.labels; ++alpha) {
      if (refused[alpha]) continue;
      EdgeLabels candidate = expand(terms, labels, alpha, graph, members);
      const double e = energy(terms, candidate);
      if (e < e0 - 1e-9 * std::max(1.0, std::abs(e0))) {
        e0 = e;
        labels.swap(candidate);
        improved = true;
        // (Expanding alpha again at once is refused: every labeling that move reaches, this one's
        // move reached too, and this is the least of them.)
        std::fill(refused.begin(), refused.end(), 0);
        refused[alpha] = 1;
      } else {
        refused[alpha] = 1;
      }
    }
    if (!improved) break;
  }
  for (std::size_t r = 0; r < labels.size(); ++r) labels[r] = terms.edge_labels(labels[r], r, in.normals[r].size());
  return labels;
}

std::vector<std::pair<int, int>> label_runs(const std::vector<int>& labels) {
  const int n = int(labels.size());
  std::vector<std::pair<int, int>> runs;
  if (n == 0) return runs;
  int start = 0;
  while (start < n && labels[start] == labels[(start + n - 1) % n]) ++start;
  if (start == n) return {{0, n}};
  for (int k = 0; k < n;) {
    const int first = (start + k) % n;
    int count = 1;
    while (k + count < n && labels[(start + k + count) % n] == labels[first]) ++count;
    runs.push_back({first, count});
    k += count;
  }
  return runs;
}

}  // namespace lodforge
