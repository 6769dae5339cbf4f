#include "sim/esc_telemetry_model.hpp"

#include "sim/period.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>

namespace motormix::sim {

namespace {
// Apart from the sensors' seed, so the two never share a sequence.
constexpr std::uint64_t kSeedOffset = 0x7E1E3E7E1E3E7ULL;
}  // namespace

EscTelemetryModel::EscTelemetryModel(int motors, std::uint64_t seed, bool latency)
    : gauss_(seed ^ kSeedOffset),
      uniform_state_(seed * 0x9E3779B97F4A7C15ULL + kSeedOffset),
      latency_(latency) {
  for (int i = 0; i < motors; ++i) {
    Esc esc;
    const auto pick = static_cast<std::size_t>(uniform() * std::size(kEscRatesHz));
    esc.period_s = 1.0 / kEscRatesHz[pick];
    esc.next_s = uniform() * esc.period_s;  // its own phase
    escs_.push_back(esc);
  }
}

double EscTelemetryModel::uniform() {
  // splitmix64: a uniform draw without touching the Gaussian's sequence.
  std::uint64_t z = (uniform_state_ += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * 0x1.0p-53;
}

loop::EscReading EscTelemetryModel::measure(int i, const VehicleModel& vehicle) {
  loop::EscReading r;
  r.motor = i + 1;
  // An ESC counts the commutations it drives: an unpowered motor reads 0
  // rpm and draws nothing, however fast its rotor still freewheels.
  const bool driven = !vehicle.freewheeling(i);
  const double speed = driven ? std::max(vehicle.motor_speed(i), 0.0) : 0.0;
  r.rpm = std::max(0.0, kFullThrustRpm * std::sqrt(speed) * (1.0 + gauss_(kRpmNoise)));
  r.erpm = r.rpm * (kSimMotorPoles / 2);
  const double thrust = driven ? std::max(vehicle.thrust_fraction(i), 0.0) : 0.0;
  const double full_a = vehicle.physics().battery.full_throttle_current_a;
  r.current_a =
      full_a * thrust * std::sqrt(thrust) * (1.0 + gauss_(kCurrentNoise)) + gauss_(kCurrentNoiseA);
  r.voltage_v = vehicle.battery().terminal_v();
  r.temperature_c = 40.0;
  r.consumption_mah = std::numeric_limits<double>::quiet_NaN();
  return r;
}

const loop::EscTelemetrySample& EscTelemetryModel::sample(double t, std::int64_t utime,
                                                          const VehicleModel& vehicle,
                                                          const MotorHealth& health) {
  sample_.utime = utime;
  sample_.count = 0;
  for (std::size_t k = 0; k < escs_.size(); ++k) {
    Esc& esc = escs_[k];
    const int i = static_cast<int>(k);
    // What the ESC measures now goes on its way...
    if (due(t, esc.next_s)) {
      while (due(t, esc.next_s)) esc.next_s += esc.period_s;
      if (((health.telemetry_dead >> i) & 1U) == 0 && uniform() >= kFrameLoss &&
          esc.size < kInFlight) {
        double arrives = t;
        if (latency_) {
          arrives += kEscLatencyS + kEscJitterS * uniform();
          if (esc.size > 0) {
            const InFlight& last = esc.queue[(esc.head + esc.size - 1) % kInFlight];
            arrives = std::max(arrives, last.arrives_s);
          }
        }
        esc.queue[(esc.head + esc.size) % kInFlight] = {arrives, measure(i, vehicle)};
        ++esc.size;
      }
    }
    // ...and what has arrived by now is read. Each reading is published as
    // it comes, as motormix output does (one message per KISS frame, one
    // reading per motor per bidirectional DShot frame): within one step a
    // newer reading of the same ESC supersedes the older, so no message
    // names a motor twice.
    int slot = -1;
    while (esc.size > 0 && due(t, esc.queue[esc.head].arrives_s)) {
      if (slot < 0) {
        if (sample_.count >= loop::kMaxEscReadings) break;
        slot = sample_.count++;
      }
      sample_.readings[static_cast<std::size_t>(slot)] = esc.queue[esc.head].reading;
      esc.head = (esc.head + 1) % kInFlight;
      --esc.size;
    }
  }
  return sample_;
}

}  // namespace motormix::sim
