#pragma once
// What the three-rotor (spinning_descent.cpp) and the two-rotor
// (two_rotor_descent.cpp) landings share: the collective thrust (the
// vertical speed flown down by a proportional-integral loop on the measured
// velocity, or, without one, the setpoint's throttle) and where the thrust
// should point (up, tilted against the drift). Internal to the core.

#include <motormix/angles.hpp>
#include <motormix/safety/spinning_descent.hpp>

#include <algorithm>
#include <array>
#include <cmath>

namespace motormix::detail {

// Far from upright more thrust buys little and takes the differential the
// rotors need to right the vehicle: the tilt compensation stops here.
inline constexpr double kMinTiltCompensationCos = 0.85;  // 32 degrees
inline constexpr double kMaxSpeedMps = 200.0;            // beyond: taken as unknown
inline constexpr double kMaxRateRadS = 100.0;            // rates beyond any gyro: clipped
inline constexpr double kMaxDtS = 0.05;  // a longer gap is taken as this (a stalled process)

struct CollectiveState {
  double velocity_integral = 0.0;
  double up_force = 0.0;  // the vertical force asked for last (N)
};

// The thrust along the body's -z axis (N) that gives the vertical force the
// descent asks for; `up_body`: the world's up in body axes.
inline double descent_collective(const SpinningDescentModel& m, const SpinningDescentSettings& s,
                                 const DescentInput& in, const Eigen::Vector3d& up_body, double dt,
                                 CollectiveState& state) {
  const double weight = m.mass_kg * kStandardGravity;
  double up_force = 0.0;
  if (std::isfinite(in.velocity.z()) && std::abs(in.velocity.z()) < kMaxSpeedMps) {
    const double error = in.velocity.z() - s.descent_rate_mps;  // NED: positive is too fast down
    // The integral learns the thrust model's error while upright only.
    if (-up_body.z() > kMinTiltCompensationCos) {
      state.velocity_integral =
          std::clamp(state.velocity_integral + s.velocity_integral * error * dt,
                     -0.4 * kStandardGravity, 0.4 * kStandardGravity);
    }
    up_force = m.mass_kg * (kStandardGravity + s.velocity_gain * error + state.velocity_integral);
    up_force = std::clamp(up_force, 0.3 * weight, 1.6 * weight);
  } else {
    double full = 0.0;
    for (double t : m.max_thrust_n) full += t;
    up_force = (std::isfinite(in.throttle) ? std::clamp(in.throttle, 0.0, 1.0) : 0.0) * full;
  }
  state.up_force = up_force;
  // The thrust axis is body -z; only its upward part carries the weight.
  const double cos_tilt = std::max(-up_body.z(), kMinTiltCompensationCos);
  return up_force / cos_tilt;
}

// The world's up as the thrust should point it, seen from the body: tilted
// against the horizontal velocity (drift_gain, at most max_tilt_deg), plain
// up without a velocity. `body_to_world`: the attitude's rotation.
inline Eigen::Vector3d wanted_up_body(const SpinningDescentSettings& s, const DescentInput& in,
                                      const Eigen::Matrix3d& body_to_world) {
  Eigen::Vector3d thrust_world(0.0, 0.0, -kStandardGravity);
  if (in.velocity.allFinite() && in.velocity.cwiseAbs().maxCoeff() < kMaxSpeedMps) {
    Eigen::Vector2d brake = -s.drift_gain * Eigen::Vector2d(in.velocity.x(), in.velocity.y());
    const double most = kStandardGravity * std::tan(s.max_tilt_deg / kDegPerRad);
    if (brake.norm() > most) brake *= most / brake.norm();
    thrust_world.head<2>() = brake;
  }
  return body_to_world.transpose() * thrust_world.normalized();
}

// The working motors' thrusts as the descent commands them (N, in place):
// none once landed or when not finite, else within what each motor gives;
// each one's share of its maximum goes to `fraction` (the others' stay as
// they are). Then the lag: `lagged` is what the motors give next cycle.
// Returns the lag's step (the share of the way `lagged` moved), for what
// else follows the motors.
template <int N>
double command_working(const SpinningDescentModel& m, const std::array<int, N>& working,
                       bool landed, double dt, Eigen::Matrix<double, N, 1>& f,
                       MotorVector& fraction, Eigen::Matrix<double, N, 1>& lagged) {
  for (Eigen::Index j = 0; j < N; ++j) {
    const auto k = static_cast<std::size_t>(working[static_cast<std::size_t>(j)]);
    f[j] = landed || !std::isfinite(f[j]) ? 0.0
                                          : std::clamp(f[j], m.min_thrust_n[k], m.max_thrust_n[k]);
    fraction[static_cast<Eigen::Index>(k)] = f[j] / m.max_thrust_n[k];
  }
  const double alpha = 1.0 - std::exp(-dt / std::max(m.time_constant_s, 1e-3));
  lagged += alpha * (f - lagged);
  return alpha;
}

}  // namespace motormix::detail
