#pragma once
// Solving the 4 x 4 symmetric positive definite system of `optimal`'s Newton
// step (its dual, B_f B_f^T + I / gamma) by a square-root-free Cholesky
// factorization (L D L^T) written out in full. Eigen's LDLT at this size runs
// its general loops with pivoting, and took 40 % of an octo's solve; the
// system is positive definite by construction (I / gamma on the diagonal),
// so it needs no pivoting, and at a fixed size of 4 every step is a few
// scalar operations.

#include <Eigen/Core>

#include <cmath>

namespace motormix::detail {

// x = a^-1 b from the lower triangle of `a`, by a = L D L^T with L unit
// lower triangular (no square roots: four divisions are the whole serial
// cost). Returns false, leaving x unspecified, when a pivot is not positive
// (or not finite): `a` is then not positive definite to working precision,
// and the caller solves another way.
inline bool solve_spd4(const Eigen::Matrix4d& a, const Eigen::Vector4d& b, Eigen::Vector4d& x) {
  // Column 0.
  const double d0 = a(0, 0);
  if (!(d0 > 0.0)) return false;
  const double i0 = 1.0 / d0;
  const double l10 = a(1, 0) * i0;
  const double l20 = a(2, 0) * i0;
  const double l30 = a(3, 0) * i0;
  // Column 1; t = the column before its division by the pivot (L D).
  const double d1 = a(1, 1) - l10 * a(1, 0);
  if (!(d1 > 0.0)) return false;
  const double i1 = 1.0 / d1;
  const double t21 = a(2, 1) - l20 * a(1, 0);
  const double t31 = a(3, 1) - l30 * a(1, 0);
  const double l21 = t21 * i1;
  const double l31 = t31 * i1;
  // Column 2.
  const double d2 = a(2, 2) - l20 * a(2, 0) - l21 * t21;
  if (!(d2 > 0.0)) return false;
  const double i2 = 1.0 / d2;
  const double t32 = a(3, 2) - l30 * a(2, 0) - l31 * t21;
  const double l32 = t32 * i2;
  // Column 3.
  const double d3 = a(3, 3) - l30 * a(3, 0) - l31 * t31 - l32 * t32;
  if (!(d3 > 0.0) || !std::isfinite(d3)) return false;
  const double i3 = 1.0 / d3;

  // L y = b, then L^T x = D^-1 y.
  const double y0 = b[0];
  const double y1 = b[1] - l10 * y0;
  const double y2 = b[2] - l20 * y0 - l21 * y1;
  const double y3 = b[3] - l30 * y0 - l31 * y1 - l32 * y2;
  x[3] = y3 * i3;
  x[2] = y2 * i2 - l32 * x[3];
  x[1] = y1 * i1 - l21 * x[2] - l31 * x[3];
  x[0] = y0 * i0 - l10 * x[1] - l20 * x[2] - l30 * x[3];
  return std::isfinite(x[0]) && std::isfinite(x[1]) && std::isfinite(x[2]) && std::isfinite(x[3]);
}

}  // namespace motormix::detail
