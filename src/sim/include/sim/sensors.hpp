#pragma once
// What the built-in controller sees of the simulated vehicle: the IMU's
// rates (imu.hpp) and the rest of its true state with the scenario's sensor
// noise, from one seeded generator.

#include "sim/noise.hpp"
#include "sim/rigid_body.hpp"
#include "sim/scenario.hpp"

#include <motormix/angles.hpp>

#include <cstdint>

namespace motormix::sim {

// The range of the simulated gyros (the common +-2000 deg/s).
inline constexpr double kGyroRangeRadS = 2000.0 * kRadPerDeg;

// What the controller sees: the state with the scenario's sensor noise.
class Sensors {
 public:
  Sensors(const SensorNoise& noise, std::uint64_t seed) : noise_(noise), gauss_(seed) {}
  BodyState measure(const BodyState& truth, const Eigen::Vector3d& gyro) {
    BodyState m = truth;
    // One draw per statement: the order of a constructor's arguments is
    // unspecified, and the sequence must not depend on the compiler.
    const Eigen::Vector3d tilt_noise = draws(noise_.attitude_deg * kRadPerDeg);
    if (tilt_noise.squaredNorm() > 0) {
      // A small rotation: (1, v/2) normalized is exp(v) to second order.
      m.attitude = (truth.attitude * Eigen::Quaterniond(1.0, tilt_noise.x() / 2, tilt_noise.y() / 2,
                                                        tilt_noise.z() / 2))
                       .normalized();
    }
    m.rates = gyro;
    m.position.z() += gauss_(noise_.altitude_m);
    m.velocity.z() += gauss_(noise_.altitude_m);
    return m;
  }
  double speed(double truth) { return truth + gauss_(noise_.speed_mps); }

 private:
  Eigen::Vector3d draws(double sigma) {
    Eigen::Vector3d v;
    v.x() = gauss_(sigma);
    v.y() = gauss_(sigma);
    v.z() = gauss_(sigma);
    return v;
  }
  SensorNoise noise_;
  GaussianNoise gauss_;
};

}  // namespace motormix::sim
