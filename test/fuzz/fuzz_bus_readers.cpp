// What each process that reads the bus decodes, on arbitrary bytes, through
// the bus's one guard (bus::receive) and then that process's own use of the
// message. Built four times:
//   fuzz_output_reader   motor_pwm_t into motormix output's gate; the pins'
//                        values stay finite and in each motor's range, or
//                        disarmed.
//   fuzz_monitor_reader  mixer_status_t and motor_pwm_t into the monitor's
//                        screen (rendered every message).
//   fuzz_sim_reader      motor_pwm_t and mixer_status_t as sim --lcm takes them.
//   fuzz_bringup_reader  mixer_status_t as the motor-test client's answer.
// Input: chunks of a 2-byte big-endian length and that many bytes; chunk k
// goes to the process's channel k mod (its channel count). Whatever
// bus::receive takes must be a whole, consistent message: exactly the bytes
// it came from (less a signature trailer, which mode off cuts off), arrays
// the length they say, within the type's largest.

#include "bringup/monitor.hpp"
#include "bringup/motor_test_client.hpp"
#include "bus/receive.hpp"
#include "output/output_gate.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

namespace {

using namespace motormix;

[[noreturn]] void violation(const char* what) {
  std::fprintf(stderr, "fuzz invariant violated: %s\n", what);
  std::abort();
}

template <typename Message>
bool take(const std::uint8_t* data, std::size_t size, Message& out, bus::Refusals& counts) {
  static signing::Policy off;
  const bus::Refusal r = bus::receive(off, "FUZZ", data, size, 0, out, counts);
  if (r != bus::Refusal::kNone) return false;
  // Exactly the bytes, or the bytes less a signature trailer (mode off cuts
  // one off unread).
  const auto whole = static_cast<std::size_t>(out.getEncodedSize());
  if (whole != size && whole + signing::kTrailerBytes != size) violation("taken, not whole");
  return true;
}

[[maybe_unused]] void consistent(const motor_pwm_t& m) {
  const auto n = static_cast<std::size_t>(m.num_motors);
  if (m.num_motors < 0 || m.num_motors > kMaxMotors) violation("motor_pwm_t count");
  if (m.pwm.size() != n || m.command.size() != n || m.direction.size() != n)
    violation("motor_pwm_t arrays");
}

#if defined(MOTORMIX_FUZZ_OUTPUT)
constexpr int kChannels = 1;
#elif defined(MOTORMIX_FUZZ_BRINGUP)
constexpr int kChannels = 1;
#elif defined(MOTORMIX_FUZZ_MONITOR)
constexpr int kChannels = 3;  // status, outputs, output_status
#else
constexpr int kChannels = 2;
#endif

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  bus::Refusals counts;
  std::size_t at = 0;
  int chunk = 0;
  std::size_t chunks = 0;
#if defined(MOTORMIX_FUZZ_OUTPUT)
  output::OutputGate gate(
      {{1000, 2000, 900}, {1000, 2000, 900}, {1100, 1900, 1000}, {1000, 2000, 900}}, 0.05);
  motor_pwm_t pwm{};
  double now = 0.0;
#elif defined(MOTORMIX_FUZZ_MONITOR)
  bringup::MonitorSnapshot snap;
  bringup::MonitorOptions options;
  mixer_status_t status{};
  motor_pwm_t pwm{};
  output_status_t output{};
#elif defined(MOTORMIX_FUZZ_SIM)
  motor_pwm_t pwm{};
  mixer_status_t status{};
#else
  bringup::MotorTestClient client({0, 1}, 0.1, 1.0, 3.0);
  mixer_status_t status{};
  double now = 0.0;
#endif
  while (at + 2 <= size) {
    const std::size_t len =
        std::min<std::size_t>((std::size_t{data[at]} << 8) | data[at + 1], size - at - 2);
    const std::uint8_t* msg = data + at + 2;
    at += 2 + len;
    ++chunks;
    const int channel = chunk++ % kChannels;
#if defined(MOTORMIX_FUZZ_OUTPUT)
    now += 0.0025;
    if (take(msg, len, pwm, counts)) {
      consistent(pwm);
      gate.accept(pwm.pwm.data(), pwm.num_motors, pwm.armed,
                  static_cast<std::uint32_t>(pwm.bringup_motors), now);
    }
    double out[4];
    const output::GateState state = gate.decide(now, out);
    for (int i = 0; i < gate.outputs(); ++i) {
      const output::PulseRange& r = gate.range(i);
      if (!std::isfinite(out[i])) violation("pin value not finite");
      const bool tested = state == output::GateState::kMotorTest && ((gate.bringup() >> i) & 1U);
      // A motor test: within the default max_throttle (0.15) of the range
      // from its stopped end.
      const double reach = output::BringupLimits{}.max_share * (r.high - r.low) + 1e-9;
      if (state == output::GateState::kArmed ? (out[i] < r.low || out[i] > r.high)
          : tested                           ? (out[i] < r.low || out[i] > r.low + reach)
                                             : out[i] != r.disarmed)
        violation("pin value outside its range, or not disarmed");
    }
    if (state == output::GateState::kMotorTest &&
        (gate.bringup() == 0 || (gate.bringup() & (gate.bringup() - 1U)) != 0))
      violation("a motor test on no motor or on several");
#elif defined(MOTORMIX_FUZZ_MONITOR)
    if (channel == 0 && take(msg, len, status, counts) && bringup::monitor_shows(status))
      snap.status = status;
    if (channel == 1 && take(msg, len, pwm, counts)) {
      consistent(pwm);
      snap.pwm = pwm;
    }
    if (channel == 2 && take(msg, len, output, counts) && bringup::monitor_shows(output))
      snap.output = output;
    snap.refused = counts;
    const std::string screen = bringup::render_monitor(snap, options);
    if (screen.empty()) violation("empty screen");
#elif defined(MOTORMIX_FUZZ_SIM)
    if (channel == 0 && take(msg, len, pwm, counts)) consistent(pwm);
    if (channel == 1) take(msg, len, status, counts);
#else
    now += 0.02;
    std::optional<bringup::MotorTestAnswer> answer;
    if (take(msg, len, status, counts)) {
      answer =
          bringup::MotorTestAnswer{status.motor_test_request_utime,
                                   static_cast<loop::MotorTestResult>(status.motor_test_result),
                                   status.motor_test_state == mixer_status_t::MOTOR_TEST_RUNNING};
    }
    const auto action = client.step(now, 1'000'000 + static_cast<std::int64_t>(now * 1e6),
                                    answer ? &*answer : nullptr);
    if (action.kind == bringup::MotorTestClient::Action::Kind::kSend &&
        (action.motor < 0 || action.motor > 2))
      violation("motor test request for a motor not asked for");
#endif
    (void)channel;
  }
  if (counts.taken + counts.refused() != chunks) violation("a message neither taken nor refused");
  return 0;
}
