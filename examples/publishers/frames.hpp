#pragma once
// motormix reads attitude in body FRD (x front, y right, z down) relative to
// NED (north, east, down). Estimators built for ROS and many SLAM stacks give
// body FLU (x front, y left, z up) relative to ENU (east, north, up). These
// are the conversions, in one place; take them if your estimator is FLU/ENU.

#include <array>
#include <cmath>

namespace frames {

using Quaternion = std::array<double, 4>;  // w, x, y, z
using Vector3 = std::array<double, 3>;

inline Quaternion multiply(const Quaternion& a, const Quaternion& b) {
  return {a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
          a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
          a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
          a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]};
}

// q rotating body FLU into ENU -> q rotating body FRD into NED:
// q_ned_enu * q * q_flu_frd, where ENU -> NED swaps the first two axes and
// negates the third (180 degrees about (1, 1, 0)/sqrt 2) and FRD -> FLU
// negates y and z (180 degrees about x).
inline Quaternion frd_ned_from_flu_enu(const Quaternion& q_enu_flu) {
  const double h = std::sqrt(0.5);
  const Quaternion q_ned_enu{0.0, h, h, 0.0};
  const Quaternion q_flu_frd{0.0, 1.0, 0.0, 0.0};
  return multiply(multiply(q_ned_enu, q_enu_flu), q_flu_frd);
}

// Body rates FLU -> FRD: y and z change sign.
inline Vector3 frd_from_flu(const Vector3& v) { return {v[0], -v[1], -v[2]}; }

// Velocity ENU -> NED: north is ENU's y, east its x, down minus its z.
inline Vector3 ned_from_enu(const Vector3& v) { return {v[1], v[0], -v[2]}; }

}  // namespace frames
