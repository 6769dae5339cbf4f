#pragma once
// The states of the mixer process and the reasons for a failsafe, as the
// status message reports them (mixer_status_t STATE_* and REASON_*).

#include <cstdint>
#include <motormix/enum_names.hpp>

namespace motormix::loop {

enum class LoopState : std::int8_t { kDisarmed = 0, kArmed = 1, kFailsafe = 2 };
enum class FailsafeReason : std::int8_t {
  kNone = 0,
  kSetpointStale = 1,
  kPidStale = 2,
  kInvalidInput = 3,
  kLoopStalled = 4,  // the mixer itself ran no cycle for longer than an input timeout
};

inline constexpr EnumName<LoopState> kLoopStateNames[] = {
    {LoopState::kDisarmed, "disarmed"},
    {LoopState::kArmed, "armed"},
    {LoopState::kFailsafe, "failsafe"},
};
inline const char* to_string(LoopState value) { return name_in(kLoopStateNames, value); }
inline constexpr EnumName<FailsafeReason> kFailsafeReasonNames[] = {
    {FailsafeReason::kNone, "none"},
    {FailsafeReason::kSetpointStale, "setpoint stale"},
    {FailsafeReason::kPidStale, "pid stale"},
    {FailsafeReason::kLoopStalled, "loop stalled"},
    {FailsafeReason::kInvalidInput, "invalid input"},
};
inline const char* to_string(FailsafeReason value) { return name_in(kFailsafeReasonNames, value); }

}  // namespace motormix::loop
