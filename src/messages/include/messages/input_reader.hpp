#pragma once
// How the node and the replay take an input message off the bus: through
// bus::receive (the signing policy, the wire checks, LCM's decoder), every
// refusal counted by its reason, then converted to the loop's sample. The
// messages decoded into are kept and reused, so a reading allocates
// nothing once each type has held its largest array.

#include "bus/receive.hpp"
#include "loop/control_loop.hpp"
#include "loop/input_samples.hpp"
#include "messages/messages.hpp"

#include <motormix/signing_policy.hpp>

#include <cstddef>
#include <cstdint>
#include <string>
#include <variant>

namespace motormix::messages {

// One input, converted: which alternative is held follows its InputKind.
using InputSample = std::variant<loop::SetpointSample, loop::PidSample, loop::MotorStatusSample,
                                 loop::BatterySample, loop::MotorTestSample,
                                 loop::EscTelemetrySample, loop::AttitudeSample>;

class InputReader {
 public:
  // The bus's verdict on `data` as an input of `kind` on `channel` (counted
  // in refusals()); with Refusal::kNone, `out` holds it. `wall_us` is this
  // host's wall clock (the replay's: the log's time), for the signature's
  // freshness. Never throws.
  bus::Refusal read(InputKind kind, signing::Policy& policy, const std::string& channel,
                    const void* data, std::size_t size, std::int64_t wall_us,
                    InputSample& out) noexcept;
  const bus::Refusals& refusals() const { return refusals_; }

 private:
  template <typename Message>
  bus::Refusal take(Message& msg, signing::Policy& policy, const std::string& channel,
                    const void* data, std::size_t size, std::int64_t wall_us,
                    InputSample& out) noexcept;

  setpoint_t setpoint_{};
  pid_t pid_{};
  motor_status_t motor_status_{};
  battery_t battery_{};
  motor_test_t motor_test_{};
  esc_telemetry_t esc_telemetry_{};
  attitude_t attitude_{};
  bus::Refusals refusals_;
};

// Hands a sample to the loop; true when the loop took it (it counts what it
// rejects, by its own reasons: non-finite, out of range, out of order...).
bool hand_over(loop::ControlLoop& loop, const InputSample& sample, std::int64_t now_us,
               std::int64_t wall_us);

}  // namespace motormix::messages
