#pragma once
// What the simulated vehicle's ESCs report, as BLHeli_32, AM32 or KISS ESCs
// do: each at its own rate with its own phase, some frames lost, rpm from
// the motor's speed and current from the power its thrust takes, with
// noise, late (kEscLatencyS). A motor whose ESC telemetry died (motor_health.hpp) reports
// nothing. Seeded, and on its own generator: it never changes what the
// controller's sensors draw.

#include "loop/input_samples.hpp"
#include "sim/motor_health.hpp"
#include "sim/noise.hpp"
#include "sim/vehicle_model.hpp"

#include <array>
#include <cstddef>
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
// With realism's esc_latency: each reading arrives this long after the ESC
// measured it (a 10-byte frame at 115200 baud takes 0.87 ms, and the ESC
// averages its rpm over a commutation cycle), plus a jitter drawn uniformly
// up to kEscJitterS (the request round-robin and the host's serial read);
// one ESC's readings arrive in order.
inline constexpr double kEscLatencyS = 0.002;
inline constexpr double kEscJitterS = 0.004;

class EscTelemetryModel {
 public:
  EscTelemetryModel(int motors, std::uint64_t seed, bool latency = true);
  // The readings arriving by t (count 0: none), stamped utime.
  const loop::EscTelemetrySample& sample(double t, std::int64_t utime, const VehicleModel& vehicle,
                                         const MotorHealth& health);

 private:
  // Readings on their way: enough for a 500 Hz ESC's kEscLatencyS +
  // kEscJitterS (a fuller queue drops the newest, as a full serial buffer).
  static constexpr std::size_t kInFlight = 8;
  struct InFlight {
    double arrives_s = 0.0;
    loop::EscReading reading;
  };
  struct Esc {
    double period_s = 0.0, next_s = 0.0;
    std::array<InFlight, kInFlight> queue{};
    std::size_t head = 0, size = 0;
  };
  double uniform();  // [0, 1)
  loop::EscReading measure(int motor, const VehicleModel& vehicle);
  GaussianNoise gauss_;
  std::uint64_t uniform_state_;
  bool latency_;
  std::vector<Esc> escs_;
  loop::EscTelemetrySample sample_;
};

}  // namespace motormix::sim
