#include "sim/imu.hpp"

#include "sim/sensors.hpp"

#include <motormix/angles.hpp>

#include <algorithm>
#include <cmath>

namespace motormix::sim {

namespace {

constexpr std::uint64_t kSeedOffset = 0x1A4B5C6D7E8F9ULL;  // apart from every other generator
constexpr double kSecondHarmonicShare = 0.5;  // the blade pass, against the once-per-revolution
constexpr double kYawShare = 0.5;             // a frame shakes less about its vertical axis

}  // namespace

void GyroLowPass::design(double dt) {
  dt_ = dt;
  // Bilinear transform of 1 / (s^2/w^2 + sqrt(2) s/w + 1), prewarped so the
  // cutoff lands where asked.
  const double k = std::tan(kPi * cutoff_hz_ * dt);
  const double norm = 1.0 / (1.0 + std::sqrt(2.0) * k + k * k);
  b0_ = k * k * norm;
  b1_ = 2.0 * b0_;
  b2_ = b0_;
  a1_ = 2.0 * (k * k - 1.0) * norm;
  a2_ = (1.0 - std::sqrt(2.0) * k + k * k) * norm;
}

Eigen::Vector3d GyroLowPass::filter(const Eigen::Vector3d& x, double dt) {
  if (dt != dt_) design(dt);
  if (!primed_) {
    // Settled on the first sample (no step through the filter): the
    // states a constant input leaves, the output equal to it (unit DC gain).
    state_[1] = (b2_ - a2_) * x;
    state_[0] = (b1_ - a1_) * x + state_[1];
    primed_ = true;
  }
  // Transposed direct form II.
  const Eigen::Vector3d y = b0_ * x + state_[0];
  state_[0] = b1_ * x - a1_ * y + state_[1];
  state_[1] = b2_ * x - a2_ * y;
  return y;
}

Imu::Imu(const config::VehiclePhysics& vehicle, double white_noise_rad_s, bool realistic,
         std::uint64_t seed)
    : p_(vehicle.imu),
      max_rotor_speed_(vehicle.max_rotor_speed_rad_s),
      white_(white_noise_rad_s),
      realistic_(realistic && !vehicle.wheeled),
      gauss_(seed ^ kSeedOffset),
      lowpass_(vehicle.imu.lowpass_hz) {
  bias_ = draw3(kGyroBiasSigmaRadS);
  for (std::size_t i = 0; i < vehicle.rotors.size() && i < phase_.size(); ++i) {
    phase_[i] = gauss_(kPi);
    for (Eigen::Vector3d& d : shake_[i]) {
      d = draw3(1.0);
      d.z() *= kYawShare;
      d.normalize();
    }
  }
}

Eigen::Vector3d Imu::draw3(double sigma) {
  // One draw per statement: the order must not depend on the compiler.
  Eigen::Vector3d v;
  v.x() = gauss_(sigma);
  v.y() = gauss_(sigma);
  v.z() = gauss_(sigma);
  return v;
}

void Imu::sample(const VehicleModel& vehicle, double dt) {
  Eigen::Vector3d w = vehicle.body().rates + bias_ + draw3(white_);
  if (!realistic_) {
    rates_ = w.cwiseMax(-kGyroRangeRadS).cwiseMin(kGyroRangeRadS);
    return;
  }
  const double amplitude = p_.vibration_dps * kRadPerDeg;
  for (int i = 0; i < vehicle.motors() && i < static_cast<int>(phase_.size()); ++i) {
    const auto k = static_cast<std::size_t>(i);
    // A rotor's speed grows as the square root of its thrust fraction; the
    // shaking force of an imbalance as the square of its speed.
    const double fraction = std::max(vehicle.motor_speed(i), 0.0);
    phase_[k] = std::fmod(phase_[k] + max_rotor_speed_ * std::sqrt(fraction) * dt, 2.0 * kPi);
    const double a = amplitude * fraction;
    w += a * (std::sin(phase_[k]) * shake_[k][0] +
              kSecondHarmonicShare * std::sin(2.0 * phase_[k]) * shake_[k][1]);
  }
  bias_ += draw3(p_.bias_drift_dps * kRadPerDeg * std::sqrt(dt));
  w = w.cwiseMax(-kGyroRangeRadS).cwiseMin(kGyroRangeRadS);
  rates_ = lowpass_.filter(w, dt);
}

}  // namespace motormix::sim
