#pragma once
// The estimator's attitude and rates as a flight controller would publish
// them on the attitude channel: the true state with gyro noise, a constant
// gyro bias per axis and the gyro's range (rates beyond it read as the
// range's end). Seeded, on its own generator, apart from the controller's
// sensors.

#include "loop/input_samples.hpp"
#include "sim/noise.hpp"
#include "sim/rigid_body.hpp"

#include <algorithm>
#include <cstdint>

namespace motormix::sim {

inline constexpr double kGyroRangeRadS = 2000.0 * 3.14159265358979323846 / 180.0;
inline constexpr double kGyroBiasSigmaRadS = 0.005;  // per axis, drawn once per run

class AttitudeSensor {
 public:
  AttitudeSensor(double gyro_noise_rad_s, std::uint64_t seed)
      : noise_(gyro_noise_rad_s), gauss_(seed ^ 0xA771DE5E5ULL) {
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
    return s;
  }

 private:
  double noise_;
  GaussianNoise gauss_;
  double bias_[3] = {0, 0, 0};
};

}  // namespace motormix::sim
