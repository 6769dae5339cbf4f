#include "messages/input_reader.hpp"

#include <type_traits>

namespace motormix::messages {

template <typename Message>
bus::Refusal InputReader::take(Message& msg, signing::Policy& policy, const std::string& channel,
                               const void* data, std::size_t size, std::int64_t wall_us,
                               InputSample& out) noexcept {
  const bus::Refusal r = bus::receive(policy, channel, data, size, wall_us, msg, refusals_);
  if (r == bus::Refusal::kNone) out = to_sample(msg);  // the sample type follows the message
  return r;
}

bus::Refusal InputReader::read(InputKind kind, signing::Policy& policy, const std::string& channel,
                               const void* data, std::size_t size, std::int64_t wall_us,
                               InputSample& out) noexcept {
  switch (kind) {
    case InputKind::kSetpoint:
      return take(setpoint_, policy, channel, data, size, wall_us, out);
    case InputKind::kPid:
      return take(pid_, policy, channel, data, size, wall_us, out);
    case InputKind::kMotorStatus:
      return take(motor_status_, policy, channel, data, size, wall_us, out);
    case InputKind::kBattery:
      return take(battery_, policy, channel, data, size, wall_us, out);
    case InputKind::kMotorTest:
      return take(motor_test_, policy, channel, data, size, wall_us, out);
    case InputKind::kEscTelemetry:
      return take(esc_telemetry_, policy, channel, data, size, wall_us, out);
    case InputKind::kAttitude:
      return take(attitude_, policy, channel, data, size, wall_us, out);
  }
  refusals_.count(bus::Refusal::kWrongType);  // no such input: not reached
  return bus::Refusal::kWrongType;
}

bool hand_over(loop::ControlLoop& loop, const InputSample& sample, std::int64_t now_us,
               std::int64_t wall_us) {
  return std::visit(
      [&](const auto& s) {
        using Sample = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<Sample, loop::SetpointSample>) {
          return loop.on_setpoint(s, now_us, wall_us) == loop::Rejection::kNone;
        } else if constexpr (std::is_same_v<Sample, loop::PidSample>) {
          return loop.on_pid(s, now_us, wall_us) == loop::Rejection::kNone;
        } else if constexpr (std::is_same_v<Sample, loop::MotorStatusSample>) {
          return loop.on_motor_status(s, now_us, wall_us) == loop::Rejection::kNone;
        } else if constexpr (std::is_same_v<Sample, loop::BatterySample>) {
          return loop.on_battery(s, now_us, wall_us) == loop::Rejection::kNone;
        } else if constexpr (std::is_same_v<Sample, loop::MotorTestSample>) {
          return loop.on_motor_test(s, now_us, wall_us) == loop::MotorTestResult::kOk;
        } else if constexpr (std::is_same_v<Sample, loop::EscTelemetrySample>) {
          return loop.on_esc_telemetry(s, now_us, wall_us) == loop::Rejection::kNone;
        } else {
          static_assert(std::is_same_v<Sample, loop::AttitudeSample>);
          return loop.on_attitude(s, now_us, wall_us) == loop::Rejection::kNone;
        }
      },
      sample);
}

}  // namespace motormix::messages
