#include "deformation/deform.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
#include <cmath>
#include <limits>

#include "deformation/amips.hpp"
#include "geometry/polygon.hpp"

namespace lodforge {

namespace {

using Matrix46 = Eigen::Matrix<double, 4, 6>;

// d vec(J) / d (vp, vq, vr) for J = [vp - vq, vp - vr] * B, vec row-major (a, b, c, d).
Matrix46 jacobian_map(const Eigen::Matrix2d& b) {
  Matrix46 a = Matrix46::Zero();
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 2; ++j) {
      const int row = 2 * i + j;
      a(row, 0 + i) = b(0, j) + b(1, j);
      a(row, 2 + i) = -b(0, j);
      a(row, 4 + i) = -b(1, j);
    }
  }
  return a;
}

Eigen::Matrix<double, 6, 1> corners(const Eigen::VectorXd& x, const std::array<int, 3>& t) {
  Eigen::Matrix<double, 6, 1> v;
  for (int k = 0; k < 3; ++k) v.segment<2>(2 * k) = x.segment<2>(2 * t[k]);
  return v;
}

amips::Vec4 jacobian(const Eigen::Matrix<double, 6, 1>& v, const Eigen::Matrix2d& b) {
  Eigen::Matrix2d d;
  d.col(0) = v.segment<2>(0) - v.segment<2>(2);
  d.col(1) = v.segment<2>(0) - v.segment<2>(4);
  const Eigen::Matrix2d j = d * b;
  return {j(0, 0), j(0, 1), j(1, 0), j(1, 1)};
}

amips::Mat4 project_psd(const amips::Mat4& h) {
  Eigen::SelfAdjointEigenSolver<amips::Mat4> eig(h);
  amips::Vec4 values = eig.eigenvalues().cwiseMax(0.0);
  return eig.eigenvectors() * values.asDiagonal() * eig.eigenvectors().transpose();
}

// Smallest t > 0 with det(u + t du, w + t dw) = 0, or +infinity.
double first_flip(const Eigen::Vector2d& u, const Eigen::Vector2d& w, const Eigen::Vector2d& du,
                  const Eigen::Vector2d& dw) {
  const double c = cross(u, w);
  const double b = cross(u, dw) + cross(du, w);
  const double a = cross(du, dw);
  double best = std::numeric_limits<double>::infinity();
  auto consider = [&best](double t) { if (t > 0 && t < best) best = t; };
  if (std::abs(a) < 1e-14 * (std::abs(b) + std::abs(c))) {
    if (b != 0) consider(-c / b);
    return best;
  }
  const double disc = b * b - 4 * a * c;
  if (disc < 0) return best;
  const double sq = std::sqrt(disc);
  const double q = -0.5 * (b + (b >= 0 ? sq : -sq));
  if (q != 0) consider(c / q);
  consider(q / a);
  return best;
}

}  // namespace

DeformationEnergy::DeformationEnergy(const TriangleMesh& mesh, const std::vector<Eigen::Vector2d>& rest,
                                     const std::vector<Vec2>& targets, const DeformationOptions& options)
    : mesh_(mesh), targets_(targets), options_(options) {
  rest_inverse_.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles) {
    Eigen::Matrix2d d;
    d.col(0) = rest[t[0]] - rest[t[1]];
    d.col(1) = rest[t[0]] - rest[t[2]];
    rest_inverse_.push_back(d.inverse());
  }
  anchor_.resize(2 * mesh.vertices.size());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) anchor_.segment<2>(2 * i) = mesh.vertices[i];
}

double DeformationEnergy::value(const Eigen::VectorXd& x, Eigen::VectorXd* gradient) const {
  std::vector<Eigen::Triplet<double>> unused;
  if (!gradient) {
    double e = 0;
    for (std::size_t t = 0; t < mesh_.triangles.size(); ++t) {
      e += amips::energy(jacobian(corners(x, mesh_.triangles[t]), rest_inverse_[t]), options_.alpha);
      if (!std::isfinite(e)) return e;
    }
    for (std::size_t k = 0; k < mesh_.boundary.size(); ++k) {
      const BoundaryEdge& b = mesh_.boundary[k];
      const double r = (x.segment<2>(2 * b.b) - x.segment<2>(2 * b.a)).dot(targets_[k]);
      e += options_.lambda_px * r * r;
    }
    return e + options_.anchor_px * (x - anchor_).squaredNorm();
  }
  gradient->setZero(x.size());
  double e = 0;
  for (std::size_t t = 0; t < mesh_.triangles.size(); ++t) {
    amips::Vec4 g = amips::Vec4::Zero();  // (set by energy where it is finite; zero keeps the compiler sure of it)
    const auto& tri = mesh_.triangles[t];
    e += amips::energy(jacobian(corners(x, tri), rest_inverse_[t]), options_.alpha, &g);
    if (!std::isfinite(e)) return e;
    const Eigen::Matrix<double, 6, 1> gv = jacobian_map(rest_inverse_[t]).transpose() * g;
    for (int k = 0; k < 3; ++k) gradient->segment<2>(2 * tri[k]) += gv.segment<2>(2 * k);
  }
  for (std::size_t k = 0; k < mesh_.boundary.size(); ++k) {
    const BoundaryEdge& b = mesh_.boundary[k];
    const double r = (x.segment<2>(2 * b.b) - x.segment<2>(2 * b.a)).dot(targets_[k]);
    e += options_.lambda_px * r * r;
    gradient->segment<2>(2 * b.b) += 2 * options_.lambda_px * r * targets_[k];
    gradient->segment<2>(2 * b.a) -= 2 * options_.lambda_px * r * targets_[k];
  }
  e += options_.anchor_px * (x - anchor_).squaredNorm();
  *gradient += 2 * options_.anchor_px * (x - anchor_);
  return e;
}

double DeformationEnergy::value(const Eigen::VectorXd& x, Eigen::VectorXd& gradient,
                                std::vector<Eigen::Triplet<double>>& exact, std::vector<Eigen::Triplet<double>>* projected) const {
  gradient.setZero(x.size());
  exact.clear();
  if (projected) projected->clear();
  double e = 0;
  for (std::size_t t = 0; t < mesh_.triangles.size(); ++t) {
    amips::Vec4 g;
    amips::Mat4 h;
    const auto& tri = mesh_.triangles[t];
    e += amips::energy(jacobian(corners(x, tri), rest_inverse_[t]), options_.alpha, &g, &h);
    if (!std::isfinite(e)) return e;
    const Matrix46 a = jacobian_map(rest_inverse_[t]);
    const Eigen::Matrix<double, 6, 1> gv = a.transpose() * g;
    const Eigen::Matrix<double, 6, 6> hx = a.transpose() * h * a;
    Eigen::Matrix<double, 6, 6> hv;
    if (projected) hv = a.transpose() * project_psd(h) * a;
    for (int k = 0; k < 3; ++k) {
      gradient.segment<2>(2 * tri[k]) += gv.segment<2>(2 * k);
      for (int l = 0; l < 3; ++l)
        for (int i = 0; i < 2; ++i)
          for (int j = 0; j < 2; ++j) {
            exact.emplace_back(2 * tri[k] + i, 2 * tri[l] + j, hx(2 * k + i, 2 * l + j));
            if (projected) projected->emplace_back(2 * tri[k] + i, 2 * tri[l] + j, hv(2 * k + i, 2 * l + j));
          }
    }
  }
  const std::size_t triangle_terms = exact.size();
  for (std::size_t k = 0; k < mesh_.boundary.size(); ++k) {
    const BoundaryEdge& b = mesh_.boundary[k];
    const Vec2& d = targets_[k];
    const double r = (x.segment<2>(2 * b.b) - x.segment<2>(2 * b.a)).dot(d);
    e += options_.lambda_px * r * r;
    gradient.segment<2>(2 * b.b) += 2 * options_.lambda_px * r * d;
    gradient.segment<2>(2 * b.a) -= 2 * options_.lambda_px * r * d;
    const Eigen::Matrix2d block = 2 * options_.lambda_px * d * d.transpose();
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j) {
        exact.emplace_back(2 * b.a + i, 2 * b.a + j, block(i, j));
        exact.emplace_back(2 * b.b + i, 2 * b.b + j, block(i, j));
        exact.emplace_back(2 * b.a + i, 2 * b.b + j, -block(i, j));
        exact.emplace_back(2 * b.b + i, 2 * b.a + j, -block(i, j));
      }
  }
  e += options_.anchor_px * (x - anchor_).squaredNorm();
  gradient += 2 * options_.anchor_px * (x - anchor_);
  for (int i = 0; i < int(x.size()); ++i) exact.emplace_back(i, i, 2 * options_.anchor_px);
  // The alignment and anchor terms are convex quadratics: identical in both.
  if (projected) projected->insert(projected->end(), exact.begin() + std::ptrdiff_t(triangle_terms), exact.end());
  return e;
}

double DeformationEnergy::max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& p) const {
  double t_max = std::numeric_limits<double>::infinity();
  for (const auto& t : mesh_.triangles) {
    const Eigen::Vector2d u = x.segment<2>(2 * t[0]) - x.segment<2>(2 * t[1]);
    const Eigen::Vector2d w = x.segment<2>(2 * t[0]) - x.segment<2>(2 * t[2]);
    const Eigen::Vector2d du = p.segment<2>(2 * t[0]) - p.segment<2>(2 * t[1]);
    const Eigen::Vector2d dw = p.segment<2>(2 * t[0]) - p.segment<2>(2 * t[2]);
    t_max = std::min(t_max, first_flip(u, w, du, dw));
  }
  return std::min(1.0, 0.9 * t_max);
}

bool DeformationEnergy::boundary_is_simple(const Eigen::VectorXd& x) const {
  PolygonWithHoles rings;
  for (std::size_t r = 0; r < mesh_.ring_vertex.size(); ++r) {
    Ring ring;
    for (int v : mesh_.ring_vertex[r]) ring.push_back(x.segment<2>(2 * v));
    ring = remove_degenerate_vertices(ring, 0.1);  // collapsed risers (< 0.1 px) are points now
    if (r == 0) rings.outer = std::move(ring);
    else rings.holes.push_back(std::move(ring));
  }
  return polygon_problem(rings).empty();
}

std::pair<double, double> alignment_error_deg(const TriangleMesh& mesh, const std::vector<Vec2>& v,
                                              const std::vector<Vec2>& targets) {
  double sum = 0, weight = 0, worst = 0;
  for (std::size_t k = 0; k < mesh.boundary.size(); ++k) {
    const Vec2 e = v[mesh.boundary[k].b] - v[mesh.boundary[k].a];
    const double len = e.norm();
    if (len <= 0) continue;
    const double angle = std::asin(std::min(1.0, std::abs(e.dot(targets[k])) / len)) * 180.0 / M_PI;
    sum += len * angle * angle;
    weight += len;
    if (len >= 0.1) worst = std::max(worst, angle);
  }
  return {weight > 0 ? std::sqrt(sum / weight) : 0.0, worst};
}

namespace {

struct NewtonOutcome {
  double energy, gradient_norm;
  int iterations;
  bool stopped;
};

// Newton's method: the exact Hessian where it is positive definite (quadratic convergence near
// the minimum), else the per-triangle projected one (always a descent direction); a flip-free
// step bound and Armijo backtracking.
NewtonOutcome newton(const DeformationEnergy& energy, Eigen::VectorXd& x, const DeformationOptions& o,
                     const std::function<bool()>& should_stop) {
  Eigen::VectorXd g, p;
  std::vector<Eigen::Triplet<double>> exact, projected;
  Eigen::SparseMatrix<double> h(x.size(), x.size()), assembled(x.size(), x.size());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver;
  bool analyzed = false;
  double e = energy.value(x, g, exact, nullptr);
  int iteration = 0;
  double shift = 0;  // multiple of the identity added to the exact Hessian, adapted per iteration
  // The sparsity pattern never changes (same mesh, same triplet order in the exact and projected
  // Hessians): the matrix is built once, then only its values are summed in place.
  std::vector<int> slot, diagonal;
  const std::vector<Eigen::Triplet<double>>* assembled_from = nullptr;
  auto assemble = [&](const std::vector<Eigen::Triplet<double>>& triplets) {
    if (slot.size() != triplets.size()) {  // a new pattern: built, and analysed again below
      analyzed = false;
      assembled.setFromTriplets(triplets.begin(), triplets.end());
      assembled.makeCompressed();
      slot.resize(triplets.size());
      for (std::size_t k = 0; k < triplets.size(); ++k)
        slot[k] = int(&assembled.coeffRef(triplets[k].row(), triplets[k].col()) - assembled.valuePtr());
      diagonal.resize(x.size());
      for (int i = 0; i < int(x.size()); ++i) diagonal[i] = int(&assembled.coeffRef(i, i) - assembled.valuePtr());
    } else {
      double* values = assembled.valuePtr();
      std::fill(values, values + assembled.nonZeros(), 0.0);
      for (std::size_t k = 0; k < triplets.size(); ++k) values[slot[k]] += triplets[k].value();
    }
    assembled_from = &triplets;
  };
  auto factorize = [&](const std::vector<Eigen::Triplet<double>>& triplets, double tau) {
    if (assembled_from != &triplets) assemble(triplets);
    h = assembled;
    if (tau > 0) for (int i : diagonal) h.valuePtr()[i] += tau;
    if (!analyzed) { solver.analyzePattern(h); analyzed = true; }
    solver.factorize(h);
    return solver.info() == Eigen::Success && (solver.vectorD().array() > 0).all();
  };
  // The smallest shift (0, or growing by 4x from a tenth of the last one) that makes the exact
  // Hessian positive definite; the projected Hessian if none does within a few tries.
  auto choose_step_matrix = [&]() {
    double tau = shift > 0 ? shift / 10 : 0;
    for (int attempt = 0; attempt < 40; ++attempt) {
      if (factorize(exact, tau)) { shift = tau; return true; }
      tau = tau > 0 ? 4 * tau : 1e-6 * (1 + g.norm());
    }
    shift = 0;
    energy.value(x, g, exact, &projected);  // the projected Hessian, only when it is needed
    assembled_from = nullptr;
    return factorize(projected, 0);
  };
  for (; iteration < o.max_iterations; ++iteration) {
    if (should_stop && should_stop()) return {e, g.norm(), iteration, true};
    if (!choose_step_matrix()) break;
    p = solver.solve(-g);
    const double slope = g.dot(p);
    if (!(slope < 0)) break;
    if (-slope < 2 * o.relative_tolerance * std::abs(e)) break;  // Newton decrement
    double t = energy.max_step(x, p);
    auto acceptable = [&](double step, double& value) {
      value = energy.value(x + step * p);
      return value <= e + 1e-4 * step * slope && (!o.keep_boundary_simple || energy.boundary_is_simple(x + step * p));
    };
    double trial = e;
    bool accepted = false;
    for (int k = 0; k < 60 && !accepted; ++k) {
      accepted = acceptable(t, trial);
      if (!accepted) t *= 0.5;
    }
    if (!accepted) break;
    x += t * p;
    const double previous = e;
    e = energy.value(x, g, exact, nullptr);
    assembled_from = nullptr;
    if (previous - e <= 1e-15 * std::abs(previous)) { ++iteration; break; }
  }
  return {e, g.norm(), iteration, false};
}

}  // namespace

DeformationResult deform(const TriangleMesh& mesh, const std::vector<Vec2>& targets,
                         const DeformationOptions& o, const std::function<bool()>& should_stop) {
  DeformationResult result;
  std::vector<Eigen::Vector2d> rest(mesh.vertices.begin(), mesh.vertices.end());
  Eigen::VectorXd x(2 * mesh.vertices.size());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) x.segment<2>(2 * i) = mesh.vertices[i];
  double previous_rms = std::numeric_limits<double>::infinity();
  for (int round = 0; round < o.max_rounds; ++round) {
    const DeformationEnergy energy(mesh, rest, targets, o);
    const NewtonOutcome outcome = newton(energy, x, o, should_stop);
    result.iterations += outcome.iterations;
    result.rounds = round + 1;
    result.energy = outcome.energy;
    result.gradient_norm = outcome.gradient_norm;
    for (std::size_t i = 0; i < rest.size(); ++i) rest[i] = x.segment<2>(2 * i);
    std::tie(result.rms_deg, result.max_deg) = alignment_error_deg(mesh, rest, targets);
    if (outcome.stopped) { result.stopped = true; break; }
    if (result.rms_deg <= o.target_rms_deg) break;
    // Stalled: the boundary cannot align further (a fold the simplicity check blocks, targets
    // that contradict each other); more rounds would only repeat the same iterations.
    if (result.rms_deg > (1 - o.min_round_gain) * previous_rms) break;
    previous_rms = result.rms_deg;
  }
  result.vertices.assign(rest.begin(), rest.end());
  return result;
}

}  // namespace lodforge
