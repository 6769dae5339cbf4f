#pragma once
// What the spin equilibrium (spin_equilibrium.cpp), the spinning descent
// (spinning_descent.cpp) and the two-rotor descent share: the rotors' own
// angular momentum, the torque that holds body rates, a vector's part in
// the rotor plane, the degree. Internal to the core.

#include <motormix/angles.hpp>
#include <motormix/safety/spinning_descent.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>

namespace motormix::detail {

using motormix::kDegPerRad;

inline Eigen::Vector2d planar(const Eigen::Vector3d& v) { return {v.x(), v.y()}; }

// The rotors' angular momentum with the working motors at thrusts f.
inline Eigen::Vector3d rotor_momentum(const SpinningDescentModel& m,
                                      const std::array<int, 3>& working, const Eigen::Vector3d& f) {
  Eigen::Vector3d h = Eigen::Vector3d::Zero();
  if (m.rotor_inertia_kgm2 <= 0.0) return h;
  for (std::size_t j = 0; j < 3; ++j) {
    const auto k = static_cast<std::size_t>(working[j]);
    const double share = std::max(f[static_cast<Eigen::Index>(j)], 0.0) / m.max_thrust_n[k];
    h += m.spin[k] * m.rotor_inertia_kgm2 * m.max_rotor_speed_rad_s * std::sqrt(share) * m.axis[k];
  }
  return h;
}

// What the rotors must supply to hold body rates w: w x (Iw + h) + drag.
inline Eigen::Vector3d holding_torque(const SpinningDescentModel& m, const Eigen::Vector3d& w,
                                      const Eigen::Vector3d& h) {
  return w.cross(m.inertia_kgm2.cwiseProduct(w) + h) + m.rotational_drag * w;
}

}  // namespace motormix::detail
