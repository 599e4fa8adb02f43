// Footprint quality against ground truth, in metres: overall IoU, one-to-one matching at IoU >= 0.5
// (precision, recall, F1, mean matched IoU), C-IoU, N-ratio, PoLiS, Hausdorff, and blob-level IoU
// (a predicted blob against the union of the truth footprints it covers, since a segmentation
// merges houses that share walls).
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "geometry/types.hpp"

namespace lodforge {

// One prediction (inside the AOI) and the truth footprint it matched (IoU >= 0.5), if any.
struct PredictionScore {
  std::size_t predicted = 0;   // its index among the predictions given
  long truth = -1;             // the matched truth's index among those given; -1: none
  double iou = 0;              // with the matched truth; unmatched: the best IoU with any
  std::size_t vertices = 0, truth_vertices = 0;
  double polis = 0, hausdorff = 0, max_tangent_angle_deg = 0;  // matched only
  std::size_t corners = 0, right_corners = 0;  // its corners (turn over 5°), and those within 5° of 90° or 180°
};

struct EvalResult {
  std::size_t predicted = 0, truth = 0, matched = 0;
  double overall_iou = 0;
  double precision = 0, recall = 0, f1 = 0;
  double mean_iou = 0;             // over matched pairs
  double c_iou = 0;                // mean IoU x (1 - |Np - Ng| / (Np + Ng)) over matched pairs
  double n_ratio = 0;              // mean vertex count ratio predicted / truth over matched pairs
  double polis = 0;                // mean PoLiS distance over matched pairs (m)
  double hausdorff_mean = 0, hausdorff_p95 = 0;  // over matched pairs (m)
  double max_tangent_angle_deg = 0;  // mean over matched pairs of the largest tangent orientation error
  double corner_share_5deg = 0;      // share of predicted corners whose two edges are within 5° of the
                                     // truth building's edge orientations (over matched pairs)
  double blob_iou = 0;             // mean over predictions of IoU with the union of the truth they cover
  // Right angles: the share of corners (turn over 5°) whose turn is within 5° of 90° or 180°,
  // over every prediction and, for comparison, every truth footprint (inside the AOI). A pixel
  // staircase scores 1: read it with the N-ratio.
  double right_angle_share = 0, truth_right_angle_share = 0;
  std::vector<PredictionScore> scores;  // per prediction inside the AOI, in the order given
};

// aoi (optional): only what lies inside counts; truth outside it is dropped, predictions clipped.
EvalResult evaluate(const std::vector<PolygonWithHoles>& predicted, const std::vector<PolygonWithHoles>& truth,
                    const std::optional<PolygonWithHoles>& aoi = std::nullopt);

// Intersection over union of two polygons.
double polygon_iou(const PolygonWithHoles& a, const PolygonWithHoles& b);

// Symmetric PoLiS distance (Avbelj et al. 2015) and Hausdorff distance between two polygons' boundaries.
double polis(const PolygonWithHoles& a, const PolygonWithHoles& b);
double hausdorff(const PolygonWithHoles& a, const PolygonWithHoles& b);
// The largest angle (degrees, orientation modulo 180°) between the truth boundary's tangent at a
// sample point (every 0.25 m) and the predicted boundary's tangent at its nearest point. Samples
// near corners, where the nearest edge is ambiguous, are left out (see metrics.cpp).
double max_tangent_angle_deg(const PolygonWithHoles& predicted, const PolygonWithHoles& truth);

// Corners of predicted whose two edges both lie within tolerance_deg of an orientation (mod 180°)
// of one of truth's edges at least 1 m long: (regular corners, corners).
std::pair<std::size_t, std::size_t> regular_corners(const PolygonWithHoles& predicted, const PolygonWithHoles& truth,
                                                    double tolerance_deg = 5.0);

// Corners of a polygon (vertices where the boundary turns by more than min_turn_deg) whose turn
// is within tolerance_deg of 90° or 180°: (right-angled corners, corners).
std::pair<std::size_t, std::size_t> right_angle_corners(const PolygonWithHoles& polygon, double tolerance_deg = 5.0,
                                                        double min_turn_deg = 5.0);

std::string eval_json(const EvalResult& r);
std::string eval_table(const EvalResult& r);

}  // namespace lodforge
