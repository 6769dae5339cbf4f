#pragma once
// The estimator's attitude, rates and velocity as a flight controller would
// publish them on the attitude channel: the true attitude, the IMU's rates
// (imu.hpp: the same gyro the built-in controller flies on) and the velocity
// with an estimator's noise. Seeded, on a generator of its own.

#include "loop/input_samples.hpp"
#include "sim/noise.hpp"
#include "sim/rigid_body.hpp"

#include <cstdint>

namespace motormix::sim {

inline constexpr double kVelocitySigmaMps = 0.05;  // an estimator's velocity noise

class AttitudeSensor {
 public:
  explicit AttitudeSensor(std::uint64_t seed) : velocity_gauss_(seed ^ 0x5E10C17EULL) {}

  loop::AttitudeSample sample(const BodyState& truth, const Eigen::Vector3d& gyro,
                              std::int64_t utime) {
    loop::AttitudeSample s;
    s.utime = utime;
    s.q = {truth.attitude.w(), truth.attitude.x(), truth.attitude.y(), truth.attitude.z()};
    for (int i = 0; i < 3; ++i) {
      s.rates[static_cast<std::size_t>(i)] = gyro[i];
      // One draw per statement: the sequence must not depend on the compiler.
      s.velocity[static_cast<std::size_t>(i)] =
          truth.velocity[i] + velocity_gauss_(kVelocitySigmaMps);
    }
    return s;
  }

 private:
  GaussianNoise velocity_gauss_;
};

}  // namespace motormix::sim
