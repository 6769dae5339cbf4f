#pragma once
// The states of the mixer process and the reasons for a failsafe, as the
// status message reports them (mixer_status_t STATE_* and REASON_*).

#include <cstdint>

namespace motormix::loop {

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

}  // namespace motormix::loop
