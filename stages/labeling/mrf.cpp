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
  std::vector<int> next, prev;        // per flat group: its ring successor and predecessor (-1: a ring of one group)

  Terms(const LabelingInput& in, const MrfOptions& o) : labels(int(in.directions.size())), offset(in.normals.size() + 1, 0) {
    const double tolerance = 2.0 * std::sin(0.5 * o.group_deg * M_PI / 180.0);
    std::vector<double> dx, dy;  // the directions' coordinates
    for (const Vec2& d : in.directions) dx.push_back(d.x()), dy.push_back(d.y());
    for (std::size_t r = 0; r < in.normals.size(); ++r) {
      const std::size_t m = in.normals[r].size();
      std::size_t groups = 0;
      for (std::size_t i = 0; i < m;) {
        std::size_t j = i + 1;
        while (j < m && (in.normals[r][j] - in.normals[r][i]).norm() < tolerance) ++j;
        first.push_back(int(i));
        const std::size_t g = std::size_t(offset[r]) + groups;
        data.resize(data.size() + std::size_t(labels), 0.0);
        double* sums = data.data() + g * labels;
        for (std::size_t k = i; k < j; ++k) {
          // The data term of eq. 5: the edge's length (in unit_length_m) times its normal's
          // distance to the label's direction; every label's in one loop over arrays.
          const double scale = in.lengths[r][k] / o.unit_length_m, nx = in.normals[r][k].x(), ny = in.normals[r][k].y();
          for (int l = 0; l < labels; ++l) {
            const double ex = nx - dx[std::size_t(l)], ey = ny - dy[std::size_t(l)];
            sums[l] += scale * std::sqrt(ex * ex + ey * ey);
          }
        }
        // The weight to the next group: from this group's last edge (the ring's last edge's
        // to edge 0, the first group's first edge).
        smooth.push_back(m >= 2 ? smooth_weight(in, r, j - 1, o) : 0.0);
        ++groups;
        i = j;
      }
      offset[r + 1] = offset[r] + int(groups);
      for (int g = 0; g < int(groups); ++g) {
        next.push_back(groups < 2 ? -1 : offset[r] + (g + 1 < int(groups) ? g + 1 : 0));
        prev.push_back(groups < 2 ? -1 : offset[r] + (g > 0 ? g - 1 : int(groups) - 1));
      }
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

// The expansion's scratch, kept from one expansion to the next (its memory reused).
struct Scratch {
  std::vector<signed char> state;      // per group: 0 keeps, 1 switches to alpha (either way), 2 the cut decides
  std::vector<int> node;               // per group left to the cut: its graph node
  std::vector<int> opened;             // per graph node: its group
  std::vector<int> open_members;       // per label: its groups left to the cut
  std::vector<int> wrapped;            // graph nodes whose settled predecessor closes their ring
  std::vector<char> anchored;          // per label: one of its groups keeps it
  std::vector<int> open;               // groups to try again
  std::vector<std::vector<int>> members;  // per label: its groups in the labeling expanded (set_members)
  void set_members(const std::vector<int>& labels, int label_count) {
    members.assign(std::size_t(label_count), {});
    for (int p = 0; p < int(labels.size()); ++p) members[std::size_t(labels[std::size_t(p)])].push_back(p);
  }
};

// The groups whose move every minimizer of the expansion shares, found before the cut (a
// persistency bound): a group keeps its label where switching it costs more than it could save
// whatever its neighbours do (its data term's rise against the most its two smoothness terms
// and its label's cost can give back), and switches where keeping it does; a group labeled
// alpha is alpha either way. Their terms with the groups left to the cut are those groups' own:
// the cut, smaller, has the same minimizers. (A margin keeps a group whose bound is within
// rounding of 0 to the cut.)
void fix_groups(const Terms& t, const std::vector<int>& labels, int alpha, bool alpha_unused, Scratch& s) {
  const int n = t.offset.back();
  s.state.assign(std::size_t(n), 2);
  s.anchored.assign(std::size_t(t.labels), 0);
  for (int p = 0; p < n; ++p)
    if (labels[std::size_t(p)] == alpha) s.state[std::size_t(p)] = 1;
  // Whether group p is fixed, its bound taken with the neighbours fixed so far (a fixed
  // neighbour's term is known, an open one's the least or most it can be); the open neighbours
  // and label members of one fixed, to try again.
  const double* to_alpha = &t.distance[std::size_t(alpha) * std::size_t(t.labels)];  // (dist is symmetric, bit for bit)
  const double alpha_cost = t.label_cost[std::size_t(alpha)], appears = alpha_unused ? alpha_cost : 0.0;
  int visited = -1;  // the first pass's group: those after it are tried there, not again
  const auto reopen = [&](int k) {
    if (k <= visited && s.state[std::size_t(k)] == 2) s.open.push_back(k);
  };
  // (Inlined into both loops below, GCC and Clang: called once a group an expansion, a call each
  // cost about a twelfth of the labeling.)
  const auto try_fix = [&](int p) __attribute__((always_inline)) {
    const int a = labels[std::size_t(p)], q = t.next[std::size_t(p)], o = t.prev[std::size_t(p)];
    double low = 0, high = 0, scale = 1;
    if (q >= 0) {
      // The term to the successor (p first) and from the predecessor (p second).
      const double w = t.smooth[std::size_t(p)], v = t.smooth[std::size_t(o)];
      const int b = labels[std::size_t(q)], c = labels[std::size_t(o)];
      // E(switch) - E(keep) of each term, for the neighbour keeping (0) and switching (1).
      const double next0 = w * (to_alpha[b] - t.dist(a, b)), next1 = -w * to_alpha[a];
      const double prev0 = v * (to_alpha[c] - t.dist(c, a)), prev1 = -v * to_alpha[a];
      // A settled neighbour's term is known, an open one's lies between the two.
      const auto least = [&](double kept, double switched, int k) {
        const signed char st = s.state[std::size_t(k)];
        return st == 2 ? std::min(kept, switched) : st == 0 ? kept : switched;
      };
      const auto most = [&](double kept, double switched, int k) {
        const signed char st = s.state[std::size_t(k)];
        return st == 2 ? std::max(kept, switched) : st == 0 ? kept : switched;
      };
      low = least(next0, next1, q) + least(prev0, prev1, o);
      high = most(next0, next1, q) + most(prev0, prev1, o);
      scale += 2.0 * (w + v);
    }
    const double keep = t.d(p, a), move = t.d(p, alpha), rise = move - keep;
    const double gives_back = s.anchored[std::size_t(a)] ? 0.0 : t.label_cost[std::size_t(a)];
    const double margin = 1e-9 * (scale + move + keep + t.label_cost[std::size_t(a)] + alpha_cost);
    if (rise + low - gives_back > margin) {
      s.state[std::size_t(p)] = 0;
      if (!s.anchored[std::size_t(a)]) {
        s.anchored[std::size_t(a)] = 1;
        for (int k : s.members[std::size_t(a)]) reopen(k);
      }
    } else if (rise + high + appears < -margin) {
      s.state[std::size_t(p)] = 1;
    } else {
      return;
    }
    if (q >= 0) reopen(q), reopen(o);
  };
  // Every open group once, then those whose neighbour or label was settled after they were
  // tried, until none is.
  s.open.clear();
  for (int p = 0; p < n; ++p) {
    visited = p;
    if (s.state[std::size_t(p)] == 2) try_fix(p);
  }
  visited = n;
  while (!s.open.empty()) {
    const int p = s.open.back();
    s.open.pop_back();
    if (s.state[std::size_t(p)] == 2) try_fix(p);
  }
}

// One expansion move: into result, labels (flat, per group) with some groups switched to alpha,
// the least energy of all such; whether any was (g: emptied and built again, its memory kept from
// one expansion to the next). The graph is built in the order of the groups, as over every group
// with the settled ones' terms added to their open neighbours where the loop reaches them.
// (result is not labels: the terms are read from labels while result is written.)
bool expand(const Terms& t, const std::vector<int>& labels, int alpha, Graph& g, Scratch& s, std::vector<int>& result) {
  const int n = t.offset.back();
  const bool alpha_unused = s.members[std::size_t(alpha)].empty();
  fix_groups(t, labels, alpha, alpha_unused, s);
  result = labels;
  bool changed = false, any_switch = false;
  s.opened.clear();
  s.open_members.assign(std::size_t(t.labels), 0);
  s.node.resize(std::size_t(n));
  for (int p = 0; p < n; ++p) {
    const signed char state = s.state[std::size_t(p)];
    if (state == 2) {
      s.node[std::size_t(p)] = int(s.opened.size());
      s.opened.push_back(p);
      ++s.open_members[std::size_t(labels[std::size_t(p)])];
    } else if (state == 1) {
      any_switch = true;
      changed |= result[std::size_t(p)] != alpha;
      result[std::size_t(p)] = alpha;
    }
  }
  const int nodes = int(s.opened.size());
  if (nodes == 0) return changed;
  g.reset();
  g.add_node(nodes);
  // The smoothness term of group p and its successor q, as a table over their moves.
  const auto pair_terms = [&](int p, int q, double e[2][2]) {
    const double w = t.smooth[std::size_t(p)];
    const int a = labels[std::size_t(p)], b = labels[std::size_t(q)];
    e[0][0] = w * t.dist(a, b), e[0][1] = w * t.dist(a, alpha), e[1][0] = w * t.dist(alpha, b), e[1][1] = 0.0;
  };
  double e[2][2];
  s.wrapped.clear();
  for (int np = 0; np < nodes; ++np) {
    const int p = s.opened[std::size_t(np)], q = t.next[std::size_t(p)], o = t.prev[std::size_t(p)];
    // From a settled predecessor: before p's own terms, or after them where it closes the ring.
    if (o >= 0 && s.state[std::size_t(o)] != 2) {
      if (o < p) pair_terms(o, p, e), add_unary(g, np, e[s.state[std::size_t(o)]][0], e[s.state[std::size_t(o)]][1]);
      else s.wrapped.push_back(np);
    }
    add_unary(g, np, t.d(p, labels[std::size_t(p)]), t.d(p, alpha));
    if (q < 0) continue;
    pair_terms(p, q, e);
    const int nq = s.node[std::size_t(q)];
    if (s.state[std::size_t(q)] == 2) add_pairwise(g, np, nq, e[0][0], e[0][1], e[1][0], e[1][1]);
    else add_unary(g, np, e[0][s.state[std::size_t(q)]], e[1][s.state[std::size_t(q)]]);
  }
  for (int np : s.wrapped) {
    const int p = s.opened[std::size_t(np)], o = t.prev[std::size_t(p)];
    pair_terms(o, p, e);
    add_unary(g, np, e[s.state[std::size_t(o)]][0], e[s.state[std::size_t(o)]][1]);
  }
  // Label costs (Delong et al. 2012, §3): one auxiliary node per label that may vanish or appear
  // (neither where a group the bound settled settles it).
  for (int l = 0; l < t.labels; ++l) {
    const double h = t.label_cost[std::size_t(l)];
    if (h <= 0) continue;
    const std::vector<int>& members = s.members[std::size_t(l)];
    if (l != alpha && !members.empty()) {
      if (s.anchored[std::size_t(l)] || s.open_members[std::size_t(l)] == 0) continue;
      // h * [some member keeps l] = h - h * prod(x_p): aux y = 1 only if all switch.
      const int y = g.add_node();
      add_unary(g, y, 0.0, -h);
      for (int p : members)
        if (s.state[std::size_t(p)] == 2) g.add_edge(s.node[std::size_t(p)], y, h, 0.0);  // y on sink while p on source costs h
    } else if (l == alpha && alpha_unused) {
      if (any_switch) continue;
      // h * [some node switches to alpha] = h - h * prod(1 - x_p): aux z = 0 only if none does.
      const int z = g.add_node();
      add_unary(g, z, -h, 0.0);
      for (int k = 0; k < nodes; ++k) g.add_edge(z, k, h, 0.0);  // z on source while p on sink costs h
    }
  }
  g.maxflow();
  for (int np = 0; np < nodes; ++np)
    if (g.what_segment(np) == Graph::SINK) result[std::size_t(s.opened[std::size_t(np)])] = alpha, changed = true;
  return changed;
}

double flat_energy(const Terms& t, const std::vector<int>& labels) {
  double e = 0;
  std::vector<char> used(std::size_t(t.labels), 0);
  for (int p = 0; p < t.offset.back(); ++p) {
    const int l = labels[std::size_t(p)], q = t.next[std::size_t(p)];
    e += t.d(p, l);
    used[std::size_t(l)] = 1;
    if (q >= 0) e += t.smooth[std::size_t(p)] * t.dist(l, labels[std::size_t(q)]);
  }
  for (std::size_t l = 0; l < used.size(); ++l) if (used[l]) e += t.label_cost[l];
  return e;
}

}  // namespace

double labeling_energy(const LabelingInput& in, const EdgeLabels& labels, const MrfOptions& o) {
  MrfOptions each_edge = o;  // any labeling, edge by edge
  each_edge.group_deg = 0;
  std::vector<int> flat;
  for (const std::vector<int>& ring : labels) flat.insert(flat.end(), ring.begin(), ring.end());
  return flat_energy(Terms(in, each_edge), flat);
}

EdgeLabels label_edges(const LabelingInput& in, const MrfOptions& o) {
  if (in.directions.size() < 2) {
    EdgeLabels labels(in.normals.size());
    for (std::size_t r = 0; r < in.normals.size(); ++r) labels[r].assign(in.normals[r].size(), 0);
    return labels;
  }
  const Terms terms(in, o);
  // From the nearest direction of every group (the least data term); the groups of every ring in
  // one flat numbering.
  const int groups = terms.offset.back();
  std::vector<int> labels(std::size_t(groups), 0);
  for (int p = 0; p < groups; ++p)
    for (int l = 1; l < terms.labels; ++l)
      if (terms.d(p, l) < terms.d(p, labels[std::size_t(p)])) labels[std::size_t(p)] = l;
  double e0 = flat_energy(terms, labels);
  // An expansion is a function of the labeling: one already tried and refused on the current
  // labeling would be refused again, so it is skipped until the labeling changes.
  std::vector<char> refused(std::size_t(terms.labels), 0);
  // (At most a node per group, one per label and one more; an edge per group to its successor,
  // one per group to its label's node, one per group from alpha's: no reallocation.)
  Graph graph(groups + terms.labels + 1, 3 * groups);
  Scratch scratch;
  scratch.set_members(labels, terms.labels);
  std::vector<int> candidate;
  for (int cycle = 0; cycle < o.max_cycles; ++cycle) {
    bool improved = false;
    for (int alpha = 0; alpha < terms.labels; ++alpha) {
      if (refused[std::size_t(alpha)]) continue;
      // (A move that switches nothing leaves the energy as it is.)
      const bool changed = expand(terms, labels, alpha, graph, scratch, candidate);
      const double e = changed ? flat_energy(terms, candidate) : e0;
      if (e < e0 - 1e-9 * std::max(1.0, std::abs(e0))) {
        e0 = e;
        labels.swap(candidate);
        scratch.set_members(labels, terms.labels);
        improved = true;
        // (Expanding alpha again at once is refused: every labeling that move reaches, this one's
        // move reached too, and this is the least of them.)
        std::fill(refused.begin(), refused.end(), 0);
        refused[std::size_t(alpha)] = 1;
      } else {
        refused[std::size_t(alpha)] = 1;
      }
    }
    if (!improved) break;
  }
  EdgeLabels out(in.normals.size());
  for (std::size_t r = 0; r < out.size(); ++r)
    out[r] = terms.edge_labels(std::vector<int>(labels.begin() + terms.offset[r], labels.begin() + terms.offset[r + 1]), r, in.normals[r].size());
  return out;
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
