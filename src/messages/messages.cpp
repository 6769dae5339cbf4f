#include "messages/messages.hpp"

#include "messages/esc_telemetry.hpp"

#include "bus/receive.hpp"
#include "bus/wire_shape.hpp"

#include <algorithm>

namespace motormix::messages {

void size_pwm_message(motor_pwm_t& msg, int motors) {
  // The wire's own sizing: what the bus checks on receipt is what is built.
  bus::WireShape<motor_pwm_t>::size(msg, motors);
}

void fill_pwm_message(motor_pwm_t& msg, const loop::CycleResult& r, std::int64_t utime) {
  msg.utime = utime;
  for (int i = 0; i < msg.num_motors; ++i) {
    const auto k = static_cast<std::size_t>(i);
    msg.command[k] = static_cast<float>(r.mix.command[i]);
    msg.pwm[k] = static_cast<float>(r.mix.output[i]);
    msg.direction[k] = r.mix.direction[k];
  }
  msg.armed = r.mix.armed;
  msg.setpoint_utime = r.setpoint_utime;
  msg.pid_utime = r.pid_utime;
  msg.failed_motors = static_cast<int32_t>(r.mix.armed ? r.mix.failed : r.failed);
  msg.bringup_motors =
      !r.mix.armed && r.motor_test >= 0 ? static_cast<int32_t>(1U << r.motor_test) : 0;
}

static_assert(mixer_status_t::DETECTOR_TELEMETRY == static_cast<int>(DetectorSources::kTelemetry) &&
                  mixer_status_t::DETECTOR_RATES == static_cast<int>(DetectorSources::kRates) &&
                  mixer_status_t::DETECTOR_OUTPUTS == static_cast<int>(DetectorSources::kOutputs),
              "the status' DETECTOR_* bits are the detector's source bits");

void fill_status_message(mixer_status_t& s, const loop::CycleResult& r, const loop::Counters& c,
                         const LoopTiming& timing, std::uint64_t config_hash, int motors,
                         std::int64_t utime, const InputAccounting& inputs) {
  s.utime = utime;
  s.state = static_cast<int8_t>(r.state);
  s.failsafe_reason = static_cast<int8_t>(r.reason);
  s.setpoint_stale = r.setpoint_stale;
  s.pid_stale = r.pid_stale;
  s.num_motors = motors;
  // What is true in this cycle: a cycle that did not mix reports nothing
  // saturated and nothing unallocated.
  const AllocationResult& a = r.mix.allocation;
  s.saturated_upper = static_cast<int32_t>(a.saturated_upper);
  s.saturated_lower = static_cast<int32_t>(a.saturated_lower);
  for (int i = 0; i < kNumAxes; ++i) {
    s.axis_limited[i] = (a.axis_limited >> i) & 1U;
    s.unallocated[i] = static_cast<float>(a.unallocated[i]);
  }
  s.failed_motors = static_cast<int32_t>(r.failed);
  s.failure_handling = static_cast<int8_t>(r.failure);
  for (int i = 0; i < kNumAxes; ++i) {
    s.axis_held[i] = (r.held >> i) & 1U;
    s.authority[i] = static_cast<float>(r.authority[i]);
  }
  s.battery_state = static_cast<int8_t>(r.battery);
  s.battery_voltage = static_cast<float>(r.battery_v);
  s.thrust_gain = static_cast<float>(r.thrust_gain);
  for (std::size_t i = 0; i < 4; ++i) s.input_age_ms[i] = static_cast<float>(r.input_age_ms[i]);
  s.cycles = c.cycles;
  s.setpoint_received = c.setpoint_received;
  s.pid_received = c.pid_received;
  s.rejected_nonfinite = c.rejected_nonfinite;
  s.rejected_range = c.rejected_range;
  s.rejected_stale_order = c.rejected_out_of_order;
  s.rejected_future = c.rejected_future;
  s.failsafe_events = c.failsafe_events;
  s.arming_refused = c.arming_refused;
  s.arming_refused_throttle = c.arming_refused_throttle;
  s.arming_refused_not_disarmed_first = c.arming_refused_not_disarmed_first;
  static_assert(static_cast<int>(loop::Arming::Refusal::kThrottleHigh) ==
                        mixer_status_t::ARMING_REFUSAL_THROTTLE &&
                    static_cast<int>(loop::Arming::Refusal::kNotDisarmedFirst) ==
                        mixer_status_t::ARMING_REFUSAL_NOT_DISARMED_FIRST,
                "the status' ARMING_REFUSAL_* are the loop's refusals");
  s.arming_refusal = static_cast<int8_t>(r.last_arming_refusal);
  s.motor_status_received = c.motor_status_received;
  s.battery_received = c.battery_received;
  s.rejected_size = c.rejected_size;
  const auto count = [](std::uint64_t n) { return static_cast<int64_t>(n); };
  const bus::Refusals& refused = inputs.refused;
  s.rejected_decode = count(refused.malformed());
  s.rejected_truncated = count(refused.truncated);
  s.rejected_trailing = count(refused.trailing);
  s.rejected_wrong_type = count(refused.wrong_type);
  s.rejected_bad_length = count(refused.bad_length);
  s.rejected_undecodable = count(refused.undecodable);
  static_assert(static_cast<int>(signing::Mode::kRequire) == mixer_status_t::SECURITY_REQUIRE &&
                static_cast<int>(signing::Mode::kSign) == mixer_status_t::SECURITY_SIGN);
  s.security_mode = static_cast<int8_t>(inputs.mode);
  s.signed_received = count(inputs.security.signed_accepted);
  s.unsigned_received = count(inputs.security.unsigned_accepted);
  s.rejected_unsigned = count(inputs.security.rejected_unsigned);
  s.rejected_bad_signature = count(inputs.security.rejected_bad_signature);
  s.rejected_replayed = count(inputs.security.rejected_replayed);
  // "other" (more signed channels than a verifier keeps) cannot happen in a
  // mixer, which reads fewer channels than that; counted here all the same.
  s.rejected_stale_signature =
      count(inputs.security.rejected_stale + inputs.security.rejected_other);
  for (std::size_t i = 0; i < 4; ++i) {
    s.period_us[i] = timing.period_us[i];
    s.compute_us[i] = timing.compute_us[i];
    s.wake_latency_us[i] = timing.wake_latency_us[i];
  }
  s.overruns = timing.overruns;
  s.kernel_drops = timing.kernel_drops;
  s.config_hash = static_cast<int64_t>(config_hash);
  s.motor_test_state =
      r.motor_test >= 0 ? mixer_status_t::MOTOR_TEST_RUNNING : mixer_status_t::MOTOR_TEST_NONE;
  s.motor_test_motor = static_cast<int8_t>(r.motor_test + 1);
  s.motor_test_throttle = static_cast<float>(r.motor_test_throttle);
  s.motor_test_request_utime = r.motor_test_request_utime;
  s.motor_test_result = static_cast<int8_t>(r.motor_test_result);
  s.motor_tests_started = c.motor_tests_started;
  s.motor_tests_refused = c.motor_tests_refused;
  s.spooling_up = r.spooling_up;
  s.spool_up = static_cast<float>(r.spool_up);
  s.detected_motors = static_cast<int32_t>(r.detection.failed);
  s.detected_by = static_cast<int8_t>(r.detection.source);
  s.detected_motor = static_cast<int8_t>(r.detection.motor + 1);
  s.detected_utime = r.detection.source == DetectionSource::kNone
                         ? 0
                         : r.detection.at_us + timing.wall_minus_loop_clock_us;
  s.telemetry_silent = static_cast<int32_t>(r.detection.telemetry_silent);
  s.esc_telemetry_received = c.esc_telemetry_received;
  s.attitude_received = c.attitude_received;
  s.attitude_age_ms = static_cast<float>(r.attitude_age_ms);
  s.detector_sources = static_cast<int8_t>(r.detector_sources);
  s.esc_telemetry_age_ms = static_cast<float>(r.esc_telemetry_age_ms);
  s.motor_loss_on = r.motor_loss_on;
  s.landing_state = static_cast<int8_t>(r.landing.state);
  s.landing_motor = static_cast<int8_t>(r.landing.motor + 1);
  s.spin_rate = static_cast<float>(r.landing.measured_rate_rad_s);
  s.spin_axis_error_deg = static_cast<float>(r.landing.axis_error_deg);
}

void fill_esc_telemetry_message(esc_telemetry_t& msg, const loop::EscTelemetrySample& s) {
  start_esc_telemetry(msg, s.utime);
  for (int i = 0; i < std::min(s.count, loop::kMaxEscReadings); ++i)
    add_esc_reading(msg, s.readings[static_cast<std::size_t>(i)]);
}

void fill_attitude_message(attitude_t& msg, const loop::AttitudeSample& s) {
  msg.utime = s.utime;
  for (std::size_t i = 0; i < 4; ++i) msg.q[i] = static_cast<float>(s.q[i]);
  for (std::size_t i = 0; i < 3; ++i) msg.rates[i] = static_cast<float>(s.rates[i]);
  for (std::size_t i = 0; i < 3; ++i) msg.velocity[i] = static_cast<float>(s.velocity[i]);
}

void fill_motor_status_message(motor_status_t& msg, MotorMask failed, int motors,
                               std::int64_t utime) {
  msg.utime = utime;
  msg.num_motors = motors;
  msg.failed.assign(static_cast<std::size_t>(motors), 0);
  for (int i = 0; i < motors; ++i) msg.failed[static_cast<std::size_t>(i)] = (failed >> i) & 1U;
}

loop::SetpointSample to_sample(const setpoint_t& msg) {
  return loop::SetpointSample{msg.utime, msg.throttle, msg.yaw, msg.armed != 0};
}

loop::MotorStatusSample to_sample(const motor_status_t& msg) {
  loop::MotorStatusSample out{msg.utime, msg.num_motors, 0};
  const int n = std::min(msg.num_motors, static_cast<int>(msg.failed.size()));
  for (int i = 0; i < n && i < 32; ++i) {
    if (msg.failed[static_cast<std::size_t>(i)] != 0) out.failed |= std::uint32_t{1} << i;
  }
  return out;
}

loop::BatterySample to_sample(const battery_t& msg) {
  return loop::BatterySample{msg.utime, msg.voltage};
}

loop::PidSample to_sample(const pid_t& msg) {
  return loop::PidSample{msg.utime, msg.roll, msg.pitch, msg.yaw};
}

loop::EscTelemetrySample to_sample(const esc_telemetry_t& msg) {
  static_assert(bus::WireShape<esc_telemetry_t>::kMaxLength <= loop::kMaxEscReadings);
  loop::EscTelemetrySample out;
  out.utime = msg.utime;
  out.count = msg.count;
  const int n = std::min(msg.count, static_cast<int>(msg.motor.size()));
  for (int i = 0; i < n && i < loop::kMaxEscReadings; ++i) {
    const auto k = static_cast<std::size_t>(i);
    out.readings[k] = loop::EscReading{
        msg.motor[k],     msg.rpm[k],           msg.erpm[k],           msg.current_a[k],
        msg.voltage_v[k], msg.temperature_c[k], msg.consumption_mah[k]};
  }
  return out;
}

loop::AttitudeSample to_sample(const attitude_t& msg) {
  loop::AttitudeSample out;
  out.utime = msg.utime;
  for (std::size_t i = 0; i < 4; ++i) out.q[i] = msg.q[i];
  for (std::size_t i = 0; i < 3; ++i) out.rates[i] = msg.rates[i];
  for (std::size_t i = 0; i < 3; ++i) out.velocity[i] = msg.velocity[i];
  return out;
}

loop::MotorTestSample to_sample(const motor_test_t& msg) {
  return loop::MotorTestSample{msg.utime, msg.motor, msg.throttle, msg.duration_s};
}

InputRoutes::InputRoutes(const config::Config& config) {
  const config::Channels& c = config.channels;
  channels_ = {{c.setpoint, InputKind::kSetpoint},
               {c.pid, InputKind::kPid},
               {c.motor_status, InputKind::kMotorStatus}};
  if (config.battery) channels_.emplace_back(c.battery, InputKind::kBattery);
  if (loop::ControlLoop::reads_esc_telemetry(config))
    channels_.emplace_back(c.esc_telemetry, InputKind::kEscTelemetry);
  if (loop::ControlLoop::reads_attitude(config))
    channels_.emplace_back(c.attitude, InputKind::kAttitude);
  channels_.emplace_back(c.motor_test, InputKind::kMotorTest);
}

std::optional<InputKind> InputRoutes::kind(const std::string& channel) const {
  for (const auto& [name, kind] : channels_) {
    if (name == channel) return kind;
  }
  return std::nullopt;
}

}  // namespace motormix::messages
