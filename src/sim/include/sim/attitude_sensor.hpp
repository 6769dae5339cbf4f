#pragma once
// The estimator's attitude, rates and velocity as a flight controller would
// publish them on the attitude channel: the true state with gyro noise, a
// constant gyro bias per axis and the gyro's range (rates beyond it read as
// the range's end), and the velocity with an estimator's noise. Seeded, on
// generators of its own (the velocity's apart, so adding it left the rates'
// sequence as it was), apart from the controller's sensors.

#include "loop/input_samples.hpp"
#include "sim/noise.hpp"
#include "sim/rigid_body.hpp"
#include "sim/sensors.hpp"

#include <algorithm>
#include <cstdint>

namespace motormix::sim {

inline constexpr double kGyroBiasSigmaRadS = 0.005;  // per axis, drawn once per run
inline constexpr double kVelocitySigmaMps = 0.05;     // an estimator's velocity noise

class AttitudeSensor {
 public:
  AttitudeSensor(double gyro_noise_rad_s, std::uint64_t seed)
      : noise_(gyro_noise_rad_s), gauss_(seed ^ 0xA771DE5E5ULL), velocity_gauss_(seed ^ 0x5E10C17EULL) {
    for (double& b : bias_) b = gauss_(kGyroBiasSigmaRadS);
  }

  loop::AttitudeSample sample(const BodyState& truth, std::int64_t utime) {
    loop::AttitudeSample s;
    s.utime = utime;
    s.q = {truth.attitude.w(), truth.attitude.x(), truth.attitude.y(), truth.attitude.z()};
    for (int i = 0; i < 3; ++i) {
      const double w = truth.rates[i] + bias_[static_cast<std::size_t>(i)] + gauss_(noise_);
      s.rates[static_cast<std::size_t>(i)] = std::clamp(w, -kGyroRangeRadS, kGyroRangeRadS);
    }
    for (int i = 0; i < 3; ++i) {
      s.velocity[static_cast<std::size_t>(i)] = truth.velocity[i] + velocity_gauss_(kVelocitySigmaMps);
    }
    return s;
  }

 private:
  double noise_;
  GaussianNoise gauss_;
  GaussianNoise velocity_gauss_;
  double bias_[3] = {0, 0, 0};
};

}  // namespace motormix::sim
