#pragma once
// The flight controller's gyro: what both the built-in controller and the
// attitude_t motormix reads see of the body rates. Sampled at every physics
// step (at least vehicle.imu.rate_hz), each sample is the true rate plus
//   - vibration: each rotor shakes the frame once per revolution (an
//     unbalanced prop) and twice (the blades passing the arm), with an
//     amplitude growing as the square of its speed and a direction per rotor
//     and harmonic drawn from the seed;
//   - white noise (the scenario's gyro_rad_s);
//   - a bias: drawn once per run, then drifting as a random walk;
// clipped to the gyro's range (the sensor saturates before any filter), and
// then low-passed as the controller does (second-order Butterworth at
// vehicle.imu.lowpass_hz; it delays the rates by about 0.23 / lowpass_hz s).
// With realism's imu off: the true rates with white noise and the constant
// bias, unfiltered. Seeded, on generators of its own.

#include "sim/noise.hpp"
#include "sim/vehicle_model.hpp"

#include <motormix/config/vehicle_physics.hpp>

#include <array>
#include <cstdint>

namespace motormix::sim {

inline constexpr double kGyroBiasSigmaRadS = 0.005;  // per axis, drawn once per run

// A second-order Butterworth low-pass (bilinear transform, prewarped), one
// per axis; the coefficients follow the sample period.
class GyroLowPass {
 public:
  explicit GyroLowPass(double cutoff_hz) : cutoff_hz_(cutoff_hz) {}
  Eigen::Vector3d filter(const Eigen::Vector3d& x, double dt);

 private:
  void design(double dt);
  double cutoff_hz_;
  double dt_ = 0.0;
  double b0_ = 1, b1_ = 0, b2_ = 0, a1_ = 0, a2_ = 0;
  std::array<Eigen::Vector3d, 2> state_{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  bool primed_ = false;
};

class Imu {
 public:
  Imu(const config::VehiclePhysics& vehicle, double white_noise_rad_s, bool realistic,
      std::uint64_t seed);
  // One gyro sample after a physics step of dt.
  void sample(const VehicleModel& vehicle, double dt);
  // The latest filtered rates (rad/s, body FRD).
  const Eigen::Vector3d& rates() const { return rates_; }
  // The current bias (for tests).
  const Eigen::Vector3d& bias() const { return bias_; }

 private:
  Eigen::Vector3d draw3(double sigma);
  config::ImuPhysics p_;
  double max_rotor_speed_ = 0.0;
  double white_;
  bool realistic_;
  GaussianNoise gauss_;
  Eigen::Vector3d bias_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d rates_ = Eigen::Vector3d::Zero();
  GyroLowPass lowpass_;
  // Per rotor: its phase (rad) and the direction of its two harmonics.
  std::array<double, kMaxMotors> phase_{};
  std::array<std::array<Eigen::Vector3d, 2>, kMaxMotors> shake_{};
};

}  // namespace motormix::sim
