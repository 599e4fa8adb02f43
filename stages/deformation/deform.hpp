// Stage 6: the contour deformation of paper eq. 10–15. AMIPS rigidity of the refined
// triangulation plus alignment of the boundary edges to their target directions, minimized by a
// projected Newton method with the analytic per-triangle Hessian, a flip-free step bound and
// Armijo backtracking, so no triangle ever flips (det J > 0 throughout).
#pragma once
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <functional>
#include <vector>

#include "common/option.hpp"
#include "geometry/types.hpp"
#include "triangulation/triangulate.hpp"

namespace lodforge {

struct DeformationOptions {
  double alpha = 0.5;          // conformal vs area balance of eq. 14
  double lambda_px = 1e5;      // alignment weight of eq. 15, per pixel^2 (GSD-independent)
  double anchor_px = 1e-2;     // weak pull of every vertex to its input position, pins the pose
  int max_iterations = 100;    // Newton iterations per round
  int max_rounds = 10;         // rounds; each re-solves from the current shape as rest shape
  double target_rms_deg = 0.3; // rounds stop once the boundary is aligned this well
  double min_round_gain = 0.01; // ... or once a round lowers the RMS deviation by less than this share
  double relative_tolerance = 1e-12;
  double simplify_px = 0.0;    // each labeled run simplified to this before meshing (0 = full staircase)
  bool keep_boundary_simple = true;  // reject steps that fold the boundary over itself  // Newton stops when the decrement is below this * energy

  template <class V>
  void visit(V& v) {
    v("alpha", alpha, "conformal vs area distortion balance of eq. 14", Check::between(0, 1));
    v("lambda_px", lambda_px, "alignment weight lambda of eq. 15 per pixel^2", Check::above(0));
    v("anchor_px", anchor_px, "weight pulling each vertex to its input position (pins rotation and drift)", Check::at_least(0));
    v("max_iterations", max_iterations, "Newton iterations per round at most", Check::at_least(1));
    v("max_rounds", max_rounds, "rounds with an updated rest shape at most (1 = the paper's single solve)", Check::at_least(1));
    v("target_rms_deg", target_rms_deg, "rounds stop when the boundary's RMS deviation from its targets is below this (degrees)", Check::at_least(0));
    v("min_round_gain", min_round_gain, "rounds also stop when one lowers that RMS deviation by less than this share of it (0 = only target_rms_deg and max_rounds stop them)", Check::between(0, 1));
    v("simplify_px", simplify_px, "before meshing, each run of one label is simplified by Douglas-Peucker to this (pixels; run ends kept, removed vertices follow their simplified edge); 0 = mesh the full staircase (the paper)", Check::at_least(0));
    v("keep_boundary_simple", keep_boundary_simple, "reject Newton steps that fold the boundary over itself (off: the paper's unconstrained energy)");
    v("relative_tolerance", relative_tolerance, "Newton stops when the decrement falls below this share of the energy", Check::above(0));
  }
};

// The energy of eq. 15 on a fixed mesh and rest shape, with the pose anchor. x packs the
// vertices as (x0, y0, x1, y1, ...).
class DeformationEnergy {
 public:
  DeformationEnergy(const TriangleMesh& mesh, const std::vector<Eigen::Vector2d>& rest,
                    const std::vector<Vec2>& boundary_targets, const DeformationOptions& options);
  // Energy and (optionally) gradient; +infinity if any triangle is flipped.
  double value(const Eigen::VectorXd& x, Eigen::VectorXd* gradient = nullptr) const;
  // Energy, gradient, the exact Hessian and, when asked for, the one with every triangle's block
  // projected to positive semi-definite, as triplets (same pattern in both).
  double value(const Eigen::VectorXd& x, Eigen::VectorXd& gradient, std::vector<Eigen::Triplet<double>>& exact_hessian,
               std::vector<Eigen::Triplet<double>>* projected_hessian) const;
  // Largest step t in (0, 1] along p that keeps every triangle unflipped, times a margin.
  double max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& p) const;
  // Unflipped triangles do not keep the boundary from folding over itself at a boundary vertex
  // (local injectivity only holds inside): the line search also requires simple rings, once
  // edges shorter than 0.1 px (collapsed staircase risers) are merged.
  bool boundary_is_simple(const Eigen::VectorXd& x) const;
  int size() const { return int(2 * mesh_.vertices.size()); }

 private:
  const TriangleMesh& mesh_;
  std::vector<Eigen::Matrix2d> rest_inverse_;  // [vp - vq, vp - vr]^-1 of the rest triangle
  std::vector<Vec2> targets_;
  Eigen::VectorXd anchor_;
  DeformationOptions options_;
};

struct DeformationResult {
  std::vector<Vec2> vertices;  // deformed mesh vertices
  int iterations = 0;          // Newton iterations over all rounds
  int rounds = 0;
  double energy = 0;           // final energy of the last round
  double gradient_norm = 0;    // its gradient norm at the end
  double rms_deg = 0, max_deg = 0;  // boundary deviation from the targets
  bool stopped = false;        // the stop callback ended the solve early
};

// Boundary deviation from targets in degrees: the length-weighted RMS over all boundary edges,
// and the maximum over the edges still longer than a tenth of a pixel (a staircase riser that
// the alignment collapsed to a point has no direction left; its offset is below 0.1 px).
std::pair<double, double> alignment_error_deg(const TriangleMesh& mesh, const std::vector<Vec2>& vertices,
                                              const std::vector<Vec2>& boundary_targets);

// mesh in pixel units; boundary_targets: a unit normal per mesh.boundary edge.
DeformationResult deform(const TriangleMesh& mesh, const std::vector<Vec2>& boundary_targets,
                         const DeformationOptions& options, const std::function<bool()>& should_stop = {});

}  // namespace lodforge
