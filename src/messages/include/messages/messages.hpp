#pragma once
// Control-loop results as LCM messages, shared by the live node and the
// offline replay so both publish exactly the same thing. Filling reuses the
// messages' storage (sized once at set-up): no allocation per cycle.

#include <motormix/config/config.hpp>
#include <motormix/signing_policy.hpp>
#include "bus/receive.hpp"
#include "loop/control_loop.hpp"

#include <motormix/attitude_t.hpp>
#include <motormix/battery_t.hpp>
#include <motormix/esc_telemetry_t.hpp>
#include <motormix/mixer_status_t.hpp>
#include <motormix/motor_pwm_t.hpp>
#include <motormix/motor_status_t.hpp>
#include <motormix/motor_test_t.hpp>
#include <motormix/pid_t.hpp>
#include <motormix/setpoint_t.hpp>

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace motormix::messages {

struct LoopTiming {
  std::array<float, 4> period_us{};        // min, mean, max, p99
  std::array<float, 4> compute_us{};       // min, mean, max, p99
  std::array<float, 4> wake_latency_us{};  // min, mean, max, p99
  std::int64_t overruns = 0;
  std::int64_t kernel_drops = -1;  // own_udp_socket_drops(); -1: unknown
  // This host's wall clock minus the clock the loop was cycled on (the node
  // cycles on the monotonic clock; replay and simulation on utimes: 0), so
  // times the loop recorded (a detection's) are reported as utimes.
  std::int64_t wall_minus_loop_clock_us = 0;
};

// Sizes the variable-length fields for `motors` outputs.
void size_pwm_message(motor_pwm_t& msg, int motors);

void fill_pwm_message(motor_pwm_t& msg, const loop::CycleResult& r, std::int64_t utime);
// What the bus decided about the input messages before the loop saw them:
// the signing policy's mode and counts (security:), and every refusal by
// its reason (bus::receive), the signature's included.
struct InputAccounting {
  signing::Mode mode = signing::Mode::kOff;
  signing::PolicyCounts security;
  bus::Refusals refused;
};

void fill_status_message(mixer_status_t& msg, const loop::CycleResult& r, const loop::Counters& c,
                         const LoopTiming& timing, std::uint64_t config_hash, int motors,
                         std::int64_t utime, const InputAccounting& inputs = InputAccounting{});

// Decoded input messages as the loop's samples (InputReader decodes them
// through the bus's guard first, so every array holds what its count says).
loop::SetpointSample to_sample(const setpoint_t& msg);
loop::PidSample to_sample(const pid_t& msg);
loop::MotorStatusSample to_sample(const motor_status_t& msg);
loop::BatterySample to_sample(const battery_t& msg);
loop::MotorTestSample to_sample(const motor_test_t& msg);
loop::EscTelemetrySample to_sample(const esc_telemetry_t& msg);
loop::AttitudeSample to_sample(const attitude_t& msg);

// The samples as messages, for publishers (the simulator's vehicle).
void fill_esc_telemetry_message(esc_telemetry_t& msg, const loop::EscTelemetrySample& s);
void fill_attitude_message(attitude_t& msg, const loop::AttitudeSample& s);

// What the detector found, as motor_status_t: every motor in force as
// failed (configured, reported and detected), so a reader sees one set.
void fill_motor_status_message(motor_status_t& msg, MotorMask failed, int motors,
                               std::int64_t utime);

// The input channels a mixer reads.
enum class InputKind : std::uint8_t {
  kSetpoint,
  kPid,
  kMotorStatus,
  kBattery,
  kMotorTest,
  kEscTelemetry,
  kAttitude
};

// Which input each channel carries for this loop: the one routing the node
// (what it subscribes to, how it hands a message over) and the offline
// replay (what it delivers) share. Battery only when configured; ESC
// telemetry and attitude only when the loop reads them (failure detection's
// sources, the spin landing); motor tests always (a refused request is
// still answered). Built once; kind() allocates nothing.
class InputRoutes {
 public:
  explicit InputRoutes(const config::Config& config);
  std::optional<InputKind> kind(const std::string& channel) const;
  const std::vector<std::pair<std::string, InputKind>>& channels() const { return channels_; }

 private:
  std::vector<std::pair<std::string, InputKind>> channels_;
};

}  // namespace motormix::messages
