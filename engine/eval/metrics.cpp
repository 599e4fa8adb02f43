#include "eval/metrics.hpp"

#include <nlohmann/json.hpp>

#include "geometry/polygon.hpp"
#include "io/ogr_polygon.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <ogr_geometry.h>
#include <sstream>
#include <tuple>

namespace lodforge {

namespace {

using Geometry = std::unique_ptr<OGRGeometry>;

Geometry to_ogr(const PolygonWithHoles& p) { return to_ogr_polygon(p); }

double area_of(const OGRGeometry* g) {
  if (!g) return 0;
  if (auto s = dynamic_cast<const OGRSurface*>(g)) return s->get_Area();
  if (auto c = dynamic_cast<const OGRGeometryCollection*>(g)) return c->get_Area();
  return 0;
}

Geometry union_of(const std::vector<Geometry>& parts) {
  auto collection = std::make_unique<OGRMultiPolygon>();
  for (const Geometry& g : parts) collection->addGeometry(g.get());
  return Geometry(collection->UnionCascaded());
}

double iou(const OGRGeometry* a, const OGRGeometry* b) {
  const Geometry inter(a->Intersection(b)), uni(a->Union(b));
  const double u = area_of(uni.get());
  return u > 0 ? area_of(inter.get()) / u : 0;
}

double point_segment(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

double distance_to_boundary(const Vec2& p, const PolygonWithHoles& poly) {
  double best = std::numeric_limits<double>::infinity();
  auto scan = [&](const Ring& r) {
    for (std::size_t i = 0; i < r.size(); ++i) best = std::min(best, point_segment(p, r[i], r[(i + 1) % r.size()]));
  };
  scan(poly.outer);
  for (const Ring& h : poly.holes) scan(h);
  return best;
}

std::vector<Vec2> all_vertices(const PolygonWithHoles& p) {
  std::vector<Vec2> out(p.outer.begin(), p.outer.end());
  for (const Ring& h : p.holes) out.insert(out.end(), h.begin(), h.end());
  return out;
}

// Boundary points every `step` metres (and every vertex).
std::vector<Vec2> densified(const PolygonWithHoles& p, double step) {
  std::vector<Vec2> out;
  auto walk = [&](const Ring& r) {
    for (std::size_t i = 0; i < r.size(); ++i) {
      const Vec2 a = r[i], b = r[(i + 1) % r.size()];
      const int n = std::max(1, int(std::ceil((b - a).norm() / step)));
      for (int k = 0; k < n; ++k) out.push_back(a + (b - a) * (double(k) / n));
    }
  };
  walk(p.outer);
  for (const Ring& h : p.holes) walk(h);
  return out;
}

}  // namespace

double polygon_iou(const PolygonWithHoles& a, const PolygonWithHoles& b) {
  const Geometry pa = to_ogr(a), pb = to_ogr(b);
  return iou(pa.get(), pb.get());
}

double polis(const PolygonWithHoles& a, const PolygonWithHoles& b) {
  auto one_way = [](const PolygonWithHoles& from, const PolygonWithHoles& to) {
    const auto v = all_vertices(from);
    double sum = 0;
    for (const Vec2& p : v) sum += distance_to_boundary(p, to);
    return sum / double(v.size());
  };
  return 0.5 * (one_way(a, b) + one_way(b, a));
}

double hausdorff(const PolygonWithHoles& a, const PolygonWithHoles& b) {
  auto one_way = [](const PolygonWithHoles& from, const PolygonWithHoles& to) {
    double worst = 0;
    for (const Vec2& p : densified(from, 0.05)) worst = std::max(worst, distance_to_boundary(p, to));
    return worst;
  };
  return std::max(one_way(a, b), one_way(b, a));
}

double max_tangent_angle_deg(const PolygonWithHoles& predicted, const PolygonWithHoles& truth) {
  // Every boundary segment of the prediction, to find the nearest one and its direction.
  std::vector<std::pair<Vec2, Vec2>> segments;
  auto collect = [&](const Ring& r) {
    for (std::size_t i = 0; i < r.size(); ++i) segments.push_back({r[i], r[(i + 1) % r.size()]});
  };
  collect(predicted.outer);
  for (const Ring& h : predicted.holes) collect(h);
  const std::vector<Vec2> truth_corners = all_vertices(truth);
  double worst = 0;
  auto scan = [&](const Ring& r) {
    for (std::size_t i = 0; i < r.size(); ++i) {
      const Vec2 a = r[i], b = r[(i + 1) % r.size()];
      const double length = (b - a).norm();
      const Vec2 t = (b - a) / length;
      for (double s = 0.5; s <= length - 0.5; s += 0.25) {
        const Vec2 p = a + s * t;
        double best = std::numeric_limits<double>::infinity();
        Vec2 direction = t;
        for (const auto& [u, v] : segments) {
          if ((v - u).squaredNorm() == 0) continue;
          const double d = point_segment(p, u, v);
          const Vec2 dv = (v - u).normalized();
          // A sample exactly at a predicted corner is as near to both edges: take the one that
          // runs along the truth, so a shared corner is not an error.
          if (d < best - 1e-9 || (d <= best + 1e-9 && std::abs(dv.dot(t)) > std::abs(direction.dot(t)))) {
            best = std::min(best, d);
            direction = dv;
          }
        }
        // Near a truth corner the nearest edge is ambiguous: a sample counts only when it is
        // farther from every truth corner than from the prediction (plus 0.5 m).
        double corner = std::numeric_limits<double>::infinity();
        for (const Vec2& c : truth_corners) corner = std::min(corner, (p - c).norm());
        if (corner < best + 0.5) continue;
        const double angle = std::acos(std::min(1.0, std::abs(direction.dot(t)))) * 180.0 / M_PI;
        worst = std::max(worst, angle);
      }
    }
  };
  scan(truth.outer);
  for (const Ring& h : truth.holes) scan(h);
  return worst;
}

std::pair<std::size_t, std::size_t> regular_corners(const PolygonWithHoles& predicted, const PolygonWithHoles& truth,
                                                    double tolerance_deg) {
  std::vector<Vec2> directions;  // unit tangents of the truth's edges of 1 m or more
  auto gather = [&](const Ring& r) {
    for (std::size_t i = 0; i < r.size(); ++i) {
      const Vec2 e = r[(i + 1) % r.size()] - r[i];
      if (e.norm() >= 1.0) directions.push_back(e.normalized());
    }
  };
  gather(truth.outer);
  for (const Ring& h : truth.holes) gather(h);
  const double cos_tolerance = std::cos(tolerance_deg * M_PI / 180.0);
  auto aligned = [&](const Vec2& e) {
    const Vec2 t = e.normalized();
    for (const Vec2& d : directions) if (std::abs(t.dot(d)) >= cos_tolerance) return true;
    return false;
  };
  std::size_t regular = 0, total = 0;
  auto corners = [&](const Ring& r) {
    for (std::size_t i = 0; i < r.size(); ++i) {
      const Vec2 before = r[i] - r[(i + r.size() - 1) % r.size()], after = r[(i + 1) % r.size()] - r[i];
      ++total;
      regular += aligned(before) && aligned(after);
    }
  };
  corners(predicted.outer);
  for (const Ring& h : predicted.holes) corners(h);
  return {regular, total};
}

std::pair<std::size_t, std::size_t> right_angle_corners(const PolygonWithHoles& polygon, double tolerance_deg,
                                                        double min_turn_deg) {
  std::size_t right = 0, total = 0;
  auto scan = [&](const Ring& r) {
    const std::size_t n = r.size();
    for (std::size_t i = 0; i < n; ++i) {
      const Vec2 before = r[i] - r[(i + n - 1) % n], after = r[(i + 1) % n] - r[i];
      if (before.norm() == 0 || after.norm() == 0) continue;
      const double turn = turn_deg(before, after);
      if (turn <= min_turn_deg) continue;
      ++total;
      right += std::abs(turn - 90.0) <= tolerance_deg || turn >= 180.0 - tolerance_deg;
    }
  };
  scan(polygon.outer);
  for (const Ring& h : polygon.holes) scan(h);
  return {right, total};
}

EvalResult evaluate(const std::vector<PolygonWithHoles>& predicted_in, const std::vector<PolygonWithHoles>& truth_in,
                    const std::optional<PolygonWithHoles>& aoi) {
  EvalResult r;
  const Geometry area = aoi ? to_ogr(*aoi) : nullptr;
  std::vector<PolygonWithHoles> predicted, truth;
  std::vector<Geometry> pred_geom, truth_geom;
  std::vector<std::size_t> pred_index, truth_index;  // (their indices among those given)
  for (std::size_t k = 0; k < truth_in.size(); ++k) {
    Geometry g = to_ogr(truth_in[k]);
    if (area && !g->Intersects(area.get())) continue;
    truth.push_back(truth_in[k]);
    truth_geom.push_back(std::move(g));
    truth_index.push_back(k);
  }
  for (std::size_t k = 0; k < predicted_in.size(); ++k) {
    Geometry g = to_ogr(predicted_in[k]);
    if (area && !g->Intersects(area.get())) continue;
    predicted.push_back(predicted_in[k]);
    pred_geom.push_back(std::move(g));
    pred_index.push_back(k);
  }
  r.predicted = predicted.size();
  r.truth = truth.size();
  auto right_angle_share = [](const std::vector<PolygonWithHoles>& polygons) {
    std::size_t right = 0, total = 0;
    for (const PolygonWithHoles& p : polygons) {
      const auto [good, all] = right_angle_corners(p);
      right += good;
      total += all;
    }
    return total ? double(right) / double(total) : 0.0;
  };
  r.right_angle_share = right_angle_share(predicted);
  r.truth_right_angle_share = right_angle_share(truth);
  // Overall IoU inside the AOI.
  Geometry pu = union_of(pred_geom), tu = union_of(truth_geom);
  if (area) {
    pu.reset(pu ? pu->Intersection(area.get()) : nullptr);
    tu.reset(tu ? tu->Intersection(area.get()) : nullptr);
  }
  if (pu && tu) r.overall_iou = iou(pu.get(), tu.get());
  // One-to-one matches (at IoU >= 0.5 a prediction overlaps at most one truth that well).
  std::vector<std::vector<double>> pair_iou(predicted.size(), std::vector<double>(truth.size(), 0));
  std::vector<double> ious, c_ious, ratios, polises, hausdorffs, blobs, tangents;
  std::size_t regular = 0, corners = 0;
  for (std::size_t i = 0; i < predicted.size(); ++i) {
    std::vector<Geometry> covered;
    int best = -1;
    double best_iou = 0.5, any_iou = 0;
    for (std::size_t j = 0; j < truth.size(); ++j) {
      if (!pred_geom[i]->Intersects(truth_geom[j].get())) continue;
      const double v = iou(pred_geom[i].get(), truth_geom[j].get());
      any_iou = std::max(any_iou, v);
      if (v >= best_iou) { best_iou = v; best = int(j); }
      const Geometry inter(pred_geom[i]->Intersection(truth_geom[j].get()));
      if (area_of(inter.get()) > 0.5 * area_of(truth_geom[j].get())) covered.push_back(Geometry(truth_geom[j]->clone()));
    }
    if (!covered.empty()) {
      const Geometry u = union_of(covered);
      blobs.push_back(iou(pred_geom[i].get(), u.get()));
    }
    PredictionScore score;
    score.predicted = pred_index[i];
    score.iou = any_iou;
    score.vertices = vertex_count(predicted[i]);
    std::tie(score.right_corners, score.corners) = right_angle_corners(predicted[i]);
    if (best < 0) {
      r.scores.push_back(score);
      continue;
    }
    ++r.matched;
    ious.push_back(best_iou);
    const double np = double(vertex_count(predicted[i])), ng = double(vertex_count(truth[best]));
    c_ious.push_back(best_iou * (1.0 - std::abs(np - ng) / (np + ng)));
    ratios.push_back(np / ng);
    polises.push_back(polis(predicted[i], truth[best]));
    hausdorffs.push_back(hausdorff(predicted[i], truth[best]));
    tangents.push_back(max_tangent_angle_deg(predicted[i], truth[best]));
    score.truth = long(truth_index[std::size_t(best)]);
    score.iou = best_iou;
    score.truth_vertices = vertex_count(truth[best]);
    score.polis = polises.back();
    score.hausdorff = hausdorffs.back();
    score.max_tangent_angle_deg = tangents.back();
    r.scores.push_back(score);
    const auto [good, all] = regular_corners(predicted[i], truth[best]);
    regular += good;
    corners += all;
  }
  auto mean = [](const std::vector<double>& v) { return v.empty() ? 0.0 : std::accumulate(v.begin(), v.end(), 0.0) / double(v.size()); };
  r.precision = r.predicted ? double(r.matched) / double(r.predicted) : 0;
  r.recall = r.truth ? double(r.matched) / double(r.truth) : 0;
  r.f1 = r.precision + r.recall > 0 ? 2 * r.precision * r.recall / (r.precision + r.recall) : 0;
  r.mean_iou = mean(ious);
  r.c_iou = mean(c_ious);
  r.n_ratio = mean(ratios);
  r.polis = mean(polises);
  r.hausdorff_mean = mean(hausdorffs);
  if (!hausdorffs.empty()) {
    std::sort(hausdorffs.begin(), hausdorffs.end());
    r.hausdorff_p95 = hausdorffs[std::min(hausdorffs.size() - 1, std::size_t(std::ceil(0.95 * double(hausdorffs.size()))) - 1)];
  }
  r.blob_iou = mean(blobs);
  r.max_tangent_angle_deg = mean(tangents);
  r.corner_share_5deg = corners ? double(regular) / double(corners) : 0;
  return r;
}

std::string eval_json(const EvalResult& r) {
  const nlohmann::ordered_json j{{"predicted", r.predicted},
                                 {"truth", r.truth},
                                 {"matched", r.matched},
                                 {"overall_iou", r.overall_iou},
                                 {"precision", r.precision},
                                 {"recall", r.recall},
                                 {"f1", r.f1},
                                 {"mean_iou", r.mean_iou},
                                 {"c_iou", r.c_iou},
                                 {"n_ratio", r.n_ratio},
                                 {"polis_m", r.polis},
                                 {"hausdorff_mean_m", r.hausdorff_mean},
                                 {"hausdorff_p95_m", r.hausdorff_p95},
                                 {"max_tangent_angle_deg", r.max_tangent_angle_deg},
                                 {"corner_share_5deg", r.corner_share_5deg},
                                 {"blob_iou", r.blob_iou},
                                 {"right_angle_share", r.right_angle_share},
                                 {"truth_right_angle_share", r.truth_right_angle_share}};
  return j.dump();  // (a non-finite number, none expected, would be written as null)
}

std::string eval_table(const EvalResult& r) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(4);
  s << "predicted / truth / matched (IoU >= 0.5): " << r.predicted << " / " << r.truth << " / " << r.matched << '\n'
    << "overall IoU              " << r.overall_iou << '\n'
    << "precision / recall / F1  " << r.precision << " / " << r.recall << " / " << r.f1 << '\n'
    << "mean matched IoU         " << r.mean_iou << '\n'
    << "C-IoU                    " << r.c_iou << '\n'
    << "N-ratio                  " << r.n_ratio << '\n'
    << "PoLiS (m)                " << r.polis << '\n'
    << "Hausdorff mean / p95 (m) " << r.hausdorff_mean << " / " << r.hausdorff_p95 << '\n'
    << "max tangent angle (deg)  " << r.max_tangent_angle_deg << '\n'
    << "corners within 5 deg     " << r.corner_share_5deg << '\n'
    << "blob IoU                 " << r.blob_iou << '\n'
    << "right angles (pred/true) " << r.right_angle_share << " / " << r.truth_right_angle_share << '\n';
  return s.str();
}

}  // namespace lodforge
