#pragma once
// What the simulated vehicle's ESCs report, as BLHeli_32, AM32 or KISS ESCs
// do: each at its own rate with its own phase, some frames lost, rpm from
// the motor's speed and current from the power its thrust takes, with
// noise. A motor whose ESC telemetry died (motor_health.hpp) reports
// nothing. Seeded, and on its own generator: it never changes what the
// controller's sensors draw.

#include "loop/input_samples.hpp"
#include "sim/motor_health.hpp"
#include "sim/noise.hpp"
#include "sim/vehicle_model.hpp"

#include <cstdint>
#include <vector>

namespace motormix::sim {

// Mechanical rpm of a rotor at full thrust; rpm grows as the square root of
// thrust. Its value does not matter to motormix's detector (it compares the
// motors with one another), only to what a reader sees.
inline constexpr double kFullThrustRpm = 12000.0;
inline constexpr int kSimMotorPoles = 14;  // eRPM = rpm * 7
// Each ESC reports at one of these rates (Hz), picked by the seed.
inline constexpr double kEscRatesHz[] = {100.0, 200.0, 500.0};
inline constexpr double kFrameLoss = 0.03;     // fraction of frames lost
inline constexpr double kRpmNoise = 0.01;      // relative, one sigma
inline constexpr double kCurrentNoise = 0.03;  // relative, one sigma
inline constexpr double kCurrentNoiseA = 0.1;  // absolute, one sigma

class EscTelemetryModel {
 public:
  EscTelemetryModel(int motors, std::uint64_t seed);
  // The readings due at t (count 0: none).
  const loop::EscTelemetrySample& sample(double t, std::int64_t utime, const VehicleModel& vehicle,
                                         const MotorHealth& health);

 private:
  double uniform();  // [0, 1)
  GaussianNoise gauss_;
  std::uint64_t uniform_state_;
  std::vector<double> period_s_, next_s_;
  loop::EscTelemetrySample sample_;
};

}  // namespace motormix::sim
