#pragma once
// Arming and failsafe: whether the motors may spin, decided once per cycle
// from the freshness of the inputs and the setpoint in force.
//
// - Arming needs a fresh setpoint with armed=true while a fresh pid is in
//   force, and only after a setpoint with armed=false has been seen since
//   start or since the last failsafe: a mixer (re)started mid-command never
//   jumps the motors.
// - Arming is refused while |throttle| is above inputs.arm_max_throttle,
//   counted once per request (not once per cycle).
// - While armed: a stalled loop, then a stale setpoint, then a stale pid
//   (in that order of precedence) is a failsafe; a setpoint with
//   armed=false disarms.
// - Leaving failsafe needs a fresh setpoint with armed=false, and then a new
//   disarmed -> armed transition.

#include "loop/loop_state.hpp"

#include <motormix/enum_names.hpp>

#include <cstdint>

namespace motormix::loop {

class Arming {
 public:
  explicit Arming(double arm_max_throttle) : arm_max_throttle_(arm_max_throttle) {}

  // A setpoint was accepted: armed=false permits the next arming.
  void on_setpoint(bool armed) {
    if (!armed) arm_permitted_ = true;
  }

  // What one cycle sees of its inputs.
  struct Inputs {
    bool stalled = false;  // the previous cycle is longer ago than an input timeout
    bool setpoint_fresh = false;
    bool pid_fresh = false;
    bool setpoint_armed = false;
    double throttle = 0.0;
  };
  // Why a setpoint that says armed did not arm (once per request).
  enum class Refusal : std::uint8_t {
    kNone,
    kThrottleHigh,      // throttle above inputs.arm_max_throttle
    kNotDisarmedFirst,  // no armed=false setpoint since start, disarming or failsafe
  };
  // What the node logs for each (docs/running.md quotes them).
  static constexpr EnumName<Refusal> kRefusalNames[] = {
      {Refusal::kNone, "none"},
      {Refusal::kThrottleHigh, "throttle above inputs.arm_max_throttle: lower it, then ask again"},
      {Refusal::kNotDisarmedFirst,
       "no setpoint with armed false came before this one (since start, a landing or a "
       "failsafe): send armed false, then true"},
  };
  static const char* to_string(Refusal value) { return name_in(kRefusalNames, value); }
  // What happened in this cycle, for the loop's counters.
  struct Events {
    bool failsafe_entered = false;
    bool arming_refused = false;
    Refusal refusal = Refusal::kNone;
  };
  Events update(const Inputs& in, std::int64_t now_us);

  // Disarms at once (the spin landing touched down); arming again needs a
  // setpoint with armed false first.
  void disarm() {
    state_ = LoopState::kDisarmed;
    reason_ = FailsafeReason::kNone;
    arm_permitted_ = false;
  }
  // A failsafe for a reason found outside update() (an invalid demand).
  void enter_failsafe(FailsafeReason reason, std::int64_t now_us);

  LoopState state() const { return state_; }
  FailsafeReason reason() const { return reason_; }
  std::int64_t armed_since_us() const { return armed_since_us_; }
  std::int64_t failsafe_since_us() const { return failsafe_since_us_; }

 private:
  double arm_max_throttle_;
  LoopState state_ = LoopState::kDisarmed;
  FailsafeReason reason_ = FailsafeReason::kNone;
  bool arm_permitted_ = false;
  bool arm_refused_logged_ = false;
  std::int64_t armed_since_us_ = 0;
  std::int64_t failsafe_since_us_ = 0;
};

}  // namespace motormix::loop
