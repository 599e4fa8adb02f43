// The per-triangle rigidity of paper eq. 12–14 and its derivatives with respect to the four
// entries (a, b, c, d) of the Jacobian J = [a b; c d] (row-major), in closed form.
#pragma once
#include <Eigen/Core>
#include <cmath>
#include <limits>

namespace lodforge::amips {

using Vec4 = Eigen::Matrix<double, 4, 1>;
using Mat4 = Eigen::Matrix<double, 4, 4>;

// exp(alpha * conf + (1 - alpha) * area), conf = tr(J^T J) / det J, area = det J + 1 / det J.
// Returns +infinity for det J <= 0 (a flipped or degenerate triangle). gradient and hessian may
// be null.
inline double energy(const Vec4& j, double alpha, Vec4* gradient = nullptr, Mat4* hessian = nullptr) {
  const double det = j[0] * j[3] - j[1] * j[2];
  if (!(det > 0)) return std::numeric_limits<double>::infinity();
  const double trace = j.squaredNorm();
  const double conf = trace / det;
  const double area = det + 1.0 / det;
  const double s = alpha * conf + (1.0 - alpha) * area;
  const double f = std::exp(s);
  if (!gradient && !hessian) return f;
  const Vec4 g_det(j[3], -j[2], -j[1], j[0]);
  Mat4 h_det = Mat4::Zero();
  h_det(0, 3) = h_det(3, 0) = 1.0;
  h_det(1, 2) = h_det(2, 1) = -1.0;
  const Vec4 g_conf = 2.0 * j / det - trace * g_det / (det * det);
  const Vec4 g_area = (1.0 - 1.0 / (det * det)) * g_det;
  const Vec4 g_s = alpha * g_conf + (1.0 - alpha) * g_area;
  if (gradient) *gradient = f * g_s;
  if (hessian) {
    const Mat4 h_conf = 2.0 * Mat4::Identity() / det -
                        2.0 * (j * g_det.transpose() + g_det * j.transpose()) / (det * det) -
                        trace * h_det / (det * det) +
                        2.0 * trace * g_det * g_det.transpose() / (det * det * det);
    const Mat4 h_area = 2.0 / (det * det * det) * g_det * g_det.transpose() + (1.0 - 1.0 / (det * det)) * h_det;
    const Mat4 h_s = alpha * h_conf + (1.0 - alpha) * h_area;
    *hessian = f * (g_s * g_s.transpose() + h_s);
  }
  return f;
}

}  // namespace lodforge::amips
