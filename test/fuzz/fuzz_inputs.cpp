// One channel's message decoder and input checks on arbitrary bytes, driving
// the control loop. Built three times: MOTORMIX_FUZZ_SETPOINT decodes every
// chunk as a setpoint_t (pid messages are well-formed, from the input too),
// MOTORMIX_FUZZ_FAILURES decodes chunks in turn as a motor_status_t, a
// battery_t, an esc_telemetry_t and an attitude_t (with well-formed setpoint
// and pid from the input, so the loop arms and mixes with failure sets,
// compensation and the failure detector judging), otherwise as a pid_t.
// Chunks: one length byte, then that many bytes. After every chunk a control
// cycle runs 2.5 ms later, and its outputs must be in range.
//
// These are robustness fuzzers: they check that no input crashes the loop
// or drives an output out of its range, not that the detector finds the
// right motor (detection_sim_tests and the unit tests judge that).
// fuzz_failures starts from seeds of valid sequences (seeds/failures).

#include "fuzz_checks.hpp"
#include "loop/control_loop.hpp"
#include "messages/input_reader.hpp"
#include "messages/messages.hpp"

#include <motormix/config/build_mixer.hpp>
#include <motormix/config/load_config.hpp>

#include <cstdint>
#include <cstring>

namespace {

const motormix::config::Config& fuzz_config() {
  // Real-time limits loose enough that the fuzzer reaches the armed state.
  static const motormix::config::Config c = motormix::config::load_config_text(
      "geometry: {preset: hexa_x}\nmixer: {strategy: prioritized}\n"
      "output: {min: 1000, max: 2000, disarmed: 900, idle: 0.05, slew_per_s: 40000}\n"
      "inputs: {yaw_source: pid, failsafe: hold_last}\n"
      "battery: {nominal_v: 16.8, max_gain: 2}\n"
      "failure_detection: {sources: [telemetry, rates, outputs]}\n",
      "fuzz");
  return c;
}

#ifndef MOTORMIX_FUZZ_SETPOINT
// Well-formed inputs the other channels get, made from the chunk's bytes so
// the fuzzer also steers arming, throttle, roll and pitch.
motormix::loop::SetpointSample setpoint_from(const std::uint8_t* msg, std::size_t len,
                                             std::int64_t utime) {
  motormix::loop::SetpointSample s;
  s.utime = utime;
  s.armed = len > 0 && (msg[0] & 1U);
  s.throttle = len > 1 ? msg[1] / 255.0 : 0.0;
  return s;
}
#endif

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace motormix;
  loop::ControlLoop loop(fuzz_config(), config::build_mixer(fuzz_config()));
  std::int64_t now = 1'000'000;
  const std::int64_t wall_offset = 1'764'000'000'000'000;
  // Every message the node's way: bus::receive, then the loop.
  signing::Policy policy;
  messages::InputReader reader;
  messages::InputSample sample;
  std::uint64_t reads = 0;
  const auto deliver = [&](messages::InputKind kind, const std::uint8_t* bytes, std::size_t n) {
    ++reads;
    if (reader.read(kind, policy, "FUZZ", bytes, n, now + wall_offset, sample) ==
        bus::Refusal::kNone) {
      messages::hand_over(loop, sample, now, now + wall_offset);
    }
  };
  std::size_t at = 0;
  while (at < size) {
    const std::size_t len = std::min<std::size_t>(data[at], size - at - 1);
    const std::uint8_t* msg = data + at + 1;
    at += 1 + len;
#ifdef MOTORMIX_FUZZ_SETPOINT
    deliver(messages::InputKind::kSetpoint, msg, len);
    loop::PidSample p;
    p.utime = now + wall_offset;
    p.roll = len > 0 ? (msg[0] - 128) / 128.0 : 0.0;
    loop.on_pid(p, now, now + wall_offset);
#elif defined(MOTORMIX_FUZZ_FAILURES)
    constexpr messages::InputKind kKinds[] = {
        messages::InputKind::kMotorStatus, messages::InputKind::kBattery,
        messages::InputKind::kEscTelemetry, messages::InputKind::kAttitude};
    deliver(kKinds[at % 4], msg, len);
    loop.on_setpoint(setpoint_from(msg, len, now + wall_offset), now, now + wall_offset);
    loop::PidSample p;
    p.utime = now + wall_offset;
    p.roll = len > 3 ? (msg[3] - 128) / 128.0 : 0.0;
    p.pitch = len > 4 ? (msg[4] - 128) / 128.0 : 0.0;
    loop.on_pid(p, now, now + wall_offset);
#else
    deliver(messages::InputKind::kPid, msg, len);
    loop.on_setpoint(setpoint_from(msg, len, now + wall_offset), now, now + wall_offset);
#endif
    now += len > 2 && msg[2] == 0xFF ? 200'000 : 2'500;  // sometimes long enough to go stale
    const loop::CycleResult& r = loop.cycle(now);
    motormix::fuzz::check_outputs(loop.mixer(), r.mix);
    const loop::Counters& c = loop.counters();
    if (c.rejected() < 0 || c.cycles <= 0) std::abort();
    const bus::Refusals& refused = reader.refusals();
    if (refused.taken + refused.refused() != reads) std::abort();  // each read counted once
  }
  return 0;
}
