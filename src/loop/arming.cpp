#include "loop/arming.hpp"

#include <cmath>

namespace motormix::loop {

void Arming::enter_failsafe(FailsafeReason reason, std::int64_t now_us) {
  state_ = LoopState::kFailsafe;
  reason_ = reason;
  arm_permitted_ = false;
  failsafe_since_us_ = now_us;
}

Arming::Events Arming::update(const Inputs& in, std::int64_t now_us) {
  Events events;
  switch (state_) {
    case LoopState::kArmed: {
      FailsafeReason reason = FailsafeReason::kNone;
      if (in.stalled) {
        reason = FailsafeReason::kLoopStalled;
      } else if (!in.setpoint_fresh) {
        reason = FailsafeReason::kSetpointStale;
      } else if (!in.pid_fresh) {
        reason = FailsafeReason::kPidStale;
      } else if (!in.setpoint_armed) {
        state_ = LoopState::kDisarmed;
      }
      if (reason != FailsafeReason::kNone) {
        enter_failsafe(reason, now_us);
        events.failsafe_entered = true;
      }
      break;
    }
    case LoopState::kFailsafe:
      if (in.setpoint_fresh && !in.setpoint_armed) {
        state_ = LoopState::kDisarmed;
        reason_ = FailsafeReason::kNone;
      }
      break;
    case LoopState::kDisarmed:
      if (in.setpoint_fresh && in.pid_fresh && in.setpoint_armed) {
        Refusal refusal = Refusal::kNone;
        if (!arm_permitted_) {
          refusal = Refusal::kNotDisarmedFirst;
        } else if (std::abs(in.throttle) <= arm_max_throttle_) {
          state_ = LoopState::kArmed;
          armed_since_us_ = now_us;
        } else {
          refusal = Refusal::kThrottleHigh;
        }
        if (refusal != Refusal::kNone && !arm_refused_logged_) {
          events.arming_refused = true;
          events.refusal = refusal;
          arm_refused_logged_ = true;  // once per request, not once per cycle
        }
      }
      if (!in.setpoint_armed) arm_refused_logged_ = false;
      break;
  }
  return events;
}

}  // namespace motormix::loop
