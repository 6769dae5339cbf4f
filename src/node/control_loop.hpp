#pragma once
// The mixer process's decisions, with time passed in: which inputs are in
// force, whether they are stale, whether the motors may spin, and what to
// output. No LCM and no clock here, so a bus, a log replay and a test all
// drive the same logic.
//
// Safety rules (documented in the README):
// - Outputs are the disarmed values until a fresh setpoint with armed=true
//   arrives while a fresh pid is in force, and only after a setpoint with
//   armed=false has been seen: arming needs an explicit disarmed -> armed
//   transition, so a mixer (re)started mid-command never jumps the motors.
// - Arming is refused while |throttle| is above inputs.arm_max_throttle.
// - While armed, a setpoint or pid older than its timeout puts the loop in
//   failsafe. The configured action decides the outputs: disarmed values
//   (default), the last valid inputs for at most hold_last_ms and then
//   disarmed, or idle (armed, zero demand). Leaving failsafe needs fresh
//   inputs and a new disarmed -> armed transition.
// - A cycle that comes later after the previous one than the shorter input
//   timeout (the process was frozen or starved) is a failsafe too while
//   armed: for that long nobody watched the inputs, and the messages that
//   arrived meanwhile may not all have been read yet.
// - Rejected messages (non-finite, out of range, out of order) are counted
//   and otherwise ignored: the previous valid message stays in force and
//   keeps ageing toward its timeout.

#include <motormix/config/config.hpp>
#include "node/input_samples.hpp"
#include "node/message_checks.hpp"

#include <motormix/mixer.hpp>

#include <cstdint>
#include <limits>

namespace motormix::node {

enum class LoopState : std::int8_t { kDisarmed = 0, kArmed = 1, kFailsafe = 2 };
enum class FailsafeReason : std::int8_t {
  kNone = 0,
  kSetpointStale = 1,
  kPidStale = 2,
  kInvalidInput = 3,
  kLoopStalled = 4,  // the mixer itself ran no cycle for longer than an input timeout
};

const char* to_string(LoopState state);
const char* to_string(FailsafeReason reason);

struct Counters {
  std::int64_t cycles = 0;
  std::int64_t setpoint_received = 0;
  std::int64_t pid_received = 0;
  std::int64_t rejected_decode = 0;
  std::int64_t rejected_nonfinite = 0;
  std::int64_t rejected_range = 0;
  std::int64_t rejected_out_of_order = 0;
  std::int64_t rejected_future = 0;
  std::int64_t failsafe_events = 0;
  std::int64_t arming_refused = 0;  // armed requests refused by the arming check

  std::int64_t rejected() const {
    return rejected_decode + rejected_nonfinite + rejected_range + rejected_out_of_order +
           rejected_future;
  }
};

struct CycleResult {
  MixerOutput mix;
  LoopState state = LoopState::kDisarmed;
  FailsafeReason reason = FailsafeReason::kNone;
  bool state_changed = false;  // state differs from the previous cycle's
  bool setpoint_stale = true;
  bool pid_stale = true;
  std::int64_t setpoint_utime = 0;         // utime of the setpoint in force, 0 if none
  std::int64_t pid_utime = 0;              // utime of the pid in force, 0 if none
  AllocationResult last_armed_allocation;  // from the most recent armed cycle
};

class ControlLoop {
 public:
  ControlLoop(const config::Config& config, Mixer mixer);

  // now_us: a monotonic clock in microseconds (receive time, not the
  // publisher's utime, which may come from another clock). wall_us: this
  // host's wall clock, to spot messages from the future.
  Rejection on_setpoint(const SetpointSample& sample, std::int64_t now_us, std::int64_t wall_us);
  Rejection on_pid(const PidSample& pid, std::int64_t now_us, std::int64_t wall_us);
  void on_undecodable() { ++counters_.rejected_decode; }

  // One control cycle at time now_us. The returned reference stays valid
  // until the next call.
  const CycleResult& cycle(std::int64_t now_us);

  const CycleResult& last() const { return result_; }
  const Counters& counters() const { return counters_; }
  const Mixer& mixer() const { return mixer_; }

 private:
  void count(Rejection rejection);
  bool from_future(std::int64_t utime, std::int64_t wall_us);
  void enter_failsafe(FailsafeReason reason, std::int64_t now_us);
  void mix_inputs(const AxisVector& demand, std::int64_t now_us);

  Mixer mixer_;
  ThrustRange thrust_range_;
  config::YawSource yaw_source_;
  std::int64_t setpoint_timeout_us_;
  std::int64_t pid_timeout_us_;
  config::FailsafeAction failsafe_action_;
  std::int64_t hold_last_us_;
  std::int64_t max_future_us_;
  double arm_max_throttle_;
  std::int64_t failsafe_since_us_ = 0;

  static constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::min();
  SetpointSample setpoint_;
  PidSample pid_;
  std::int64_t setpoint_received_us_ = kNever;
  std::int64_t pid_received_us_ = kNever;
  std::int64_t last_setpoint_utime_ = kNever;
  std::int64_t last_pid_utime_ = kNever;
  std::int64_t last_cycle_us_ = kNever;
  bool arm_permitted_ = false;
  bool arm_refused_logged_ = false;  // a disarmed setpoint has been seen since boot or failsafe

  CycleResult result_;
  Counters counters_;
};

}  // namespace motormix::node
