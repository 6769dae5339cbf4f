#include "bringup/bus_clients.hpp"

#include "bringup/motor_test_client.hpp"
#include "bus/clock.hpp"
#include "bus/policy_or_error.hpp"
#include "bus/process.hpp"
#include "bus/receive.hpp"
#include "bus/sealed_publisher.hpp"
#include "bus/wire_shape.hpp"

#include <motormix/config/security.hpp>
#include <motormix/esc_command_t.hpp>
#include <motormix/mixer_status_t.hpp>
#include <motormix/motor_pwm_t.hpp>
#include <motormix/motor_test_t.hpp>
#include <motormix/output_status_t.hpp>
#include <motormix/signing_policy.hpp>

#include <lcm/lcm-cpp.hpp>

#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <optional>
#include <ostream>
#include <vector>

namespace motormix::bringup {

namespace {

using Clock = bus::MonotonicClock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The latest status seen, taken through the bus's guard inside the callback
// (nothing thrown out, refusals counted by reason). Under security: sign or
// require, only a status whose signature verifies is believed (a forged
// "test running" must not keep the client waiting).
struct StatusWatch {
  signing::Policy* policy = nullptr;
  std::optional<mixer_status_t> latest;
  int statuses = 0;
  bus::Refusals refused;
  mixer_status_t msg{};
  void on_status(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    if (bus::receive(*policy, rbuf, channel, bus::wall_us(), msg, refused) != bus::Refusal::kNone)
      return;
    latest = msg;
    ++statuses;
  }
};

// Says on the way out what the client refused to read, if anything.
struct RefusalReport {
  const bus::Refusals& refused;
  const std::string& channel;
  const char* who;
  std::ostream& err;
  ~RefusalReport() {
    if (refused.refused() > 0)
      err << "motormix " << who << ": " << channel << ": " << bus::describe(refused) << "\n";
  }
};

void send_test(bus::SealedPublisher& publisher, const std::string& channel, int motor_1based,
               double throttle, double seconds, std::int64_t utime) {
  motor_test_t msg;
  msg.utime = utime;
  msg.motor = motor_1based;
  msg.throttle = static_cast<float>(throttle);
  msg.duration_s = static_cast<float>(seconds);
  publisher.publish(channel, msg);
}

// How often a client looks again while it waits for an answer.
constexpr std::int64_t kLookEveryNs = 20'000'000;

// Enter on `fd`, polled without blocking: 1 a line, -1 end of input, 0 nothing yet.
int line_ready(int fd) {
  pollfd p{fd, POLLIN, 0};
  if (poll(&p, 1, 0) <= 0) return 0;
  char c = 0;
  while (true) {
    const ssize_t got = read(fd, &c, 1);
    if (got <= 0) return -1;
    if (c == '\n') return 1;
  }
}

}  // namespace

std::string describe_motor(const config::Config& config, int motor) {
  const auto k = static_cast<std::size_t>(motor);
  const auto& details = config.geometry.motor_details;
  const std::string name = config.motor_names()[k];
  const std::string detail = k < details.size() ? details[k] : "";
  std::string spin;
  // A sign table (the team quad) names no spin; the vehicle model's rotors do.
  const auto& rotors = config.vehicle_model.rotors;
  if (detail.find("CW") == std::string::npos && k < rotors.size()) {
    spin = rotors[k].spin == Spin::kCw ? ", CW" : ", CCW";
    spin += " (as the vehicle model has it)";
  }
  return "motor " + std::to_string(motor + 1) +
         (name != "m" + std::to_string(motor + 1) ? " (" + name + ")" : "") +
         (detail.empty() ? "" : ", " + detail) + spin;
}

ClientOutcome run_motor_test(const config::Config& config, const std::vector<int>& motors,
                             double throttle, double seconds, double wait_s,
                             const std::string& lcm_url, std::ostream& out, std::ostream& err) {
  std::optional<signing::Policy> policy = bus::policy_or_error(config, "motor-test", err);
  if (!policy) return ClientOutcome::kBusError;
  bus::Process process("motormix motor-test", lcm_url, err);
  if (!process.good()) return ClientOutcome::kBusError;
  lcm::LCM& lcm = process.lcm();
  bus::ShutdownSignals& signals = process.signals();
  bus::SealedPublisher publisher(lcm, *policy);
  StatusWatch watch;
  watch.policy = &*policy;
  const RefusalReport report{watch.refused, config.channels.status, "motor-test", err};
  lcm.subscribe(config.channels.status, &StatusWatch::on_status, &watch);
  MotorTestClient client(motors, throttle, seconds, wait_s);
  const auto start = Clock::now();
  for (;;) {
    if (signals.requested()) client.on_interrupt();
    std::optional<MotorTestAnswer> answer;
    if (watch.latest) {
      answer =
          MotorTestAnswer{watch.latest->motor_test_request_utime,
                          static_cast<loop::MotorTestResult>(watch.latest->motor_test_result),
                          watch.latest->motor_test_state == mixer_status_t::MOTOR_TEST_RUNNING};
    }
    const MotorTestClient::Action a =
        client.step(seconds_since(start), bus::wall_us(), answer ? &*answer : nullptr);
    using Kind = MotorTestClient::Action::Kind;
    switch (a.kind) {
      case Kind::kSend:
        send_test(publisher, config.channels.motor_test, a.motor, a.throttle, a.seconds, a.utime);
        break;
      case Kind::kSpinning:
        out << describe_motor(config, a.motor - 1) << ": spinning at " << throttle << " for "
            << seconds << " s" << std::endl;
        break;
      case Kind::kWait:
        process.wait_and_drain_ns(kLookEveryNs);
        break;
      case Kind::kDone:
        return ClientOutcome::kOk;
      case Kind::kNoAnswer:
        err << "motormix motor-test: no answer on " << config.channels.status << " within "
            << wait_s << " s: is motormix run running with this configuration?\n";
        return ClientOutcome::kNoAnswer;
      case Kind::kRefused:
        err << "motormix motor-test: refused: " << loop::to_string(a.refusal) << "\n";
        return ClientOutcome::kRefused;
      case Kind::kStopped:
        send_test(publisher, config.channels.motor_test, 0, 0.0, 0.0, a.utime);
        err << "motormix motor-test: interrupted, test stopped\n";
        return ClientOutcome::kInterrupted;
    }
  }
}

ClientOutcome run_esc_calibration(const config::Config& config, const EscCalibrationTiming& timing,
                                  const std::string& lcm_url, int input_fd, std::ostream& out,
                                  std::ostream& err) {
  std::optional<signing::Policy> policy = bus::policy_or_error(config, "esc-calibrate", err);
  if (!policy) return ClientOutcome::kBusError;
  bus::Process process("motormix esc-calibrate", lcm_url, err);
  if (!process.good()) return ClientOutcome::kBusError;
  lcm::LCM& lcm = process.lcm();
  bus::ShutdownSignals& signals = process.signals();
  // Nothing else may drive the outputs: any status, or any motor_pwm_t
  // heard before this process publishes its own, is a mixer.
  // Any status at all means a mixer runs, signed or not: here every one
  // counts (mode off reads them all).
  bus::SealedPublisher publisher(lcm, *policy);
  signing::Policy any_status;
  StatusWatch watch;
  watch.policy = &any_status;
  const RefusalReport report{watch.refused, config.channels.status, "esc-calibrate", err};
  int foreign_pwm = 0;
  bool publishing = false;
  struct PwmWatch {
    int* count;
    const bool* publishing;
    void on_pwm(const lcm::ReceiveBuffer*, const std::string&) {
      if (!*publishing) ++*count;
    }
  } pwm_watch{&foreign_pwm, &publishing};
  lcm.subscribe(config.channels.status, &StatusWatch::on_status, &watch);
  lcm.subscribe(config.channels.motor_pwm, &PwmWatch::on_pwm, &pwm_watch);

  EscCalibrationTiming t = timing;
  t.listen_s = std::max(timing.listen_s, 2.0 / config.status_rate_hz);
  const auto start = Clock::now();
  EscCalibration calibration(config, t, 0.0);
  motor_pwm_t msg;
  bus::WireShape<motor_pwm_t>::size(msg, config.motors());
  msg.setpoint_utime = 0;
  msg.pid_utime = 0;
  msg.failed_motors = 0;
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(1.0 / config.loop_rate_hz));
  auto next = Clock::now();
  while (calibration.outcome() == EscCalibration::Outcome::kRunning) {
    bus::drain(lcm);
    if (watch.statuses > 0 || foreign_pwm > 0) calibration.on_mixer_heard();
    if (signals.requested()) calibration.on_interrupt();
    if (calibration.phase() == EscCalibration::Phase::kMaximum) {
      const int line = line_ready(input_fd);
      if (line > 0) calibration.on_enter();
      if (line < 0) calibration.on_end_of_input();
    }
    const EscCalibration::Output o = calibration.step(seconds_since(start));
    if (calibration.phase_changed()) {
      const auto& unit = config.output_unit;
      switch (calibration.phase()) {
        case EscCalibration::Phase::kMaximum:
          out << "Every output is at its maximum (" << calibration.maximum().front() << " " << unit
              << "). Power the ESCs now; when they have beeped, press Enter (Ctrl-C "
              << "aborts). Waiting at most " << t.timeout_s << " s." << std::endl;
          break;
        case EscCalibration::Phase::kMinimum:
          out << "Minimum (" << calibration.minimum().front() << " " << unit << ") for "
              << t.min_seconds << " s: the ESCs confirm the range." << std::endl;
          break;
        default:
          break;
      }
    }
    if (o.publish) {
      publishing = true;
      msg.utime = bus::wall_us();
      for (int i = 0; i < msg.num_motors; ++i) {
        const auto k = static_cast<std::size_t>(i);
        msg.pwm[k] = static_cast<float>((*o.pwm)[k]);
        msg.command[k] = static_cast<float>(o.command);
      }
      msg.armed = o.armed;
      publisher.publish(config.channels.motor_pwm, msg);
      // Our own outputs come back on the same channel: from now on only a
      // status betrays another mixer.
      bus::drain(lcm);
      foreign_pwm = 0;
      next += period;
      // Until the next frame is due; a signal ends the wait early.
      while (!signals.requested()) {
        const auto left = next - Clock::now();
        if (left <= Clock::duration::zero()) break;
        process.wait_and_drain_ns(
            std::chrono::duration_cast<std::chrono::nanoseconds>(left).count());
      }
    } else {
      process.wait_and_drain_ns(kLookEveryNs);
      next = Clock::now();
    }
  }
  switch (calibration.outcome()) {
    case EscCalibration::Outcome::kCalibrated:
      out << "Done: outputs disarmed." << std::endl;
      return ClientOutcome::kOk;
    case EscCalibration::Outcome::kRefused:
      if (signals.requested()) {
        err << "motormix esc-calibrate: interrupted while listening; nothing was sent\n";
        return ClientOutcome::kInterrupted;
      }
      err << "motormix esc-calibrate: refused: " << calibration.reason() << " ("
          << config.channels.motor_pwm << " or " << config.channels.status << " heard within "
          << t.listen_s << " s); nothing was sent\n";
      return ClientOutcome::kRefused;
    default:
      err << "motormix esc-calibrate: " << calibration.reason() << "; outputs disarmed\n";
      return signals.requested() ? ClientOutcome::kInterrupted : ClientOutcome::kAborted;
  }
}

namespace {

struct NamedCommand {
  const char* name;
  int number;
};
// The ESCs' numbering (BLHeli_32, AM32, Bluejay).
constexpr NamedCommand kEscCommands[] = {{"beep1", 1},
                                         {"beep2", 2},
                                         {"beep3", 3},
                                         {"beep4", 4},
                                         {"beep5", 5},
                                         {"esc-info", 6},
                                         {"spin-direction-1", 7},
                                         {"spin-direction-2", 8},
                                         {"3d-off", 9},
                                         {"3d-on", 10},
                                         {"save", 12},
                                         {"spin-normal", 20},
                                         {"spin-reversed", 21}};
constexpr int kBeepRepeat = 1;
constexpr int kSettingRepeat = 10;  // ESCs act on a setting after 6 frames of it
constexpr int kLastBeep = 5;

// The latest output_status_t, through the bus's guard (signed ones only
// under security: sign or require).
struct OutputStatusWatch {
  signing::Policy* policy = nullptr;
  std::optional<output_status_t> latest;
  bus::Refusals refused;
  output_status_t msg{};
  void on_status(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    if (bus::receive(*policy, rbuf, channel, bus::wall_us(), msg, refused) != bus::Refusal::kNone)
      return;
    latest = msg;
  }
};

}  // namespace

std::optional<EscCommand> esc_command_named(const std::string& name) {
  int number = 0;
  for (const NamedCommand& c : kEscCommands)
    if (name == c.name) number = c.number;
  if (number == 0) {
    if (name.empty() || name.size() > 2 ||
        !std::all_of(name.begin(), name.end(), [](char ch) { return ch >= '0' && ch <= '9'; }))
      return std::nullopt;
    number = std::stoi(name);
    if (number < 1 || number > 47) return std::nullopt;
  }
  return EscCommand{number, number <= kLastBeep ? kBeepRepeat : kSettingRepeat};
}

std::string esc_command_names() {
  std::string s;
  for (const NamedCommand& c : kEscCommands) s += (s.empty() ? "" : ", ") + std::string(c.name);
  return s + " or a number 1..47";
}

ClientOutcome run_esc_command(const config::Config& config, const EscCommand& command,
                              const std::vector<int>& motors, double wait_s,
                              const std::string& lcm_url, std::ostream& out, std::ostream& err) {
  std::optional<signing::Policy> policy = bus::policy_or_error(config, "esc-command", err);
  if (!policy) return ClientOutcome::kBusError;
  bus::Process process("motormix esc-command", lcm_url, err);
  if (!process.good()) return ClientOutcome::kBusError;
  lcm::LCM& lcm = process.lcm();
  const auto interrupted = [&] {
    if (!process.signals().requested()) return false;
    err << "motormix esc-command: interrupted\n";
    return true;
  };
  bus::SealedPublisher publisher(lcm, *policy);
  OutputStatusWatch watch;
  watch.policy = &*policy;
  const RefusalReport report{watch.refused, config.channels.output_status, "esc-command", err};
  lcm.subscribe(config.channels.output_status, &OutputStatusWatch::on_status, &watch);
  // The output's counts before: what changes after the command is its answer.
  const auto start = Clock::now();
  while (!watch.latest && seconds_since(start) < wait_s && !interrupted())
    process.wait_and_drain_ns(kLookEveryNs);
  if (process.signals().requested()) return ClientOutcome::kInterrupted;
  if (!watch.latest) {
    err << "motormix esc-command: no motormix output on " << config.channels.output_status
        << " within " << wait_s << " s\n";
    return ClientOutcome::kNoAnswer;
  }
  const std::int64_t sent_before = watch.latest->esc_commands_sent;
  const std::int64_t refused_before = watch.latest->esc_commands_refused;
  esc_command_t msg{};
  msg.utime = bus::wall_us();
  msg.command = static_cast<std::int8_t>(command.number);
  msg.repeat = static_cast<std::int8_t>(command.repeat);
  for (int m : motors) msg.motors |= static_cast<std::int32_t>(1U << m);
  publisher.publish(config.channels.esc_command, msg);
  while (seconds_since(start) < 2 * wait_s) {
    if (interrupted()) return ClientOutcome::kInterrupted;
    process.wait_and_drain_ns(kLookEveryNs);
    if (watch.latest->esc_commands_sent > sent_before) {
      out << "ESC command " << command.number << " sent to " << motors.size() << " motor"
          << (motors.size() == 1 ? "" : "s") << " in " << command.repeat << " frame"
          << (command.repeat == 1 ? "" : "s") << std::endl;
      return ClientOutcome::kOk;
    }
    if (watch.latest->esc_commands_refused > refused_before) {
      err << "motormix esc-command: refused by motormix output (its log says why: an output "
             "armed, hardware.protocol not DShot, or no firmware report yet)\n";
      return ClientOutcome::kRefused;
    }
  }
  err << "motormix esc-command: motormix output did not count the command within " << wait_s
      << " s\n";
  return ClientOutcome::kNoAnswer;
}

}  // namespace motormix::bringup
