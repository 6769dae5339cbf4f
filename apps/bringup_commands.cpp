// Bring-up clients: `motormix motor-test` (one motor alone, through a running
// disarmed `motormix run`) and `motormix esc-calibrate` (the ESC range
// sequence, with no mixer on the bus). Wiring and terminal dialogue only;
// the rules a test must satisfy live in the control loop.

#include "commands.hpp"

#include <motormix/config/load_config.hpp>
#include "loop/control_loop.hpp"
#include "node/wall_clock.hpp"

#include <motormix/mixer_status_t.hpp>
#include <motormix/motor_pwm_t.hpp>
#include <motormix/motor_test_t.hpp>

#include <lcm/lcm-cpp.hpp>

#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <iostream>
#include <optional>
#include <thread>

namespace motormix::app {

namespace {

using Clock = std::chrono::steady_clock;
using node::wall_us;

std::atomic<bool> g_interrupted{false};
extern "C" void on_interrupt(int) { g_interrupted = true; }

std::string where(const config::Config& config, int motor) {
  const auto& details = config.vehicle.motor_details;
  const std::string name = config.motor_names()[static_cast<std::size_t>(motor)];
  const std::string detail = static_cast<std::size_t>(motor) < details.size()
                                 ? details[static_cast<std::size_t>(motor)]
                                 : "";
  std::string spin;
  // A sign table (the team quad) names no spin; the vehicle model's rotors do.
  const auto& rotors = config.physics.rotors;
  if (detail.find("CW") == std::string::npos && static_cast<std::size_t>(motor) < rotors.size()) {
    spin = rotors[static_cast<std::size_t>(motor)].spin == Spin::kCw ? ", CW" : ", CCW";
    spin += " (as the vehicle model has it)";
  }
  return "motor " + std::to_string(motor + 1) +
         (name != "m" + std::to_string(motor + 1) ? " (" + name + ")" : "") +
         (detail.empty() ? "" : ", " + detail) + spin;
}

// The latest status seen, decoded inside the callback (nothing thrown out).
struct StatusWatch {
  std::optional<mixer_status_t> latest;
  int pwm_seen = 0;
  void on_status(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    mixer_status_t msg;
    if (msg.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) ==
        static_cast<int>(rbuf->data_size)) {
      latest = msg;
    }
  }
  void on_pwm(const lcm::ReceiveBuffer*, const std::string&) { ++pwm_seen; }
};

// Serves the bus for `seconds` or until `done` holds.
template <typename Done>
bool serve(lcm::LCM& lcm, double seconds, Done done) {
  const auto until = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                        std::chrono::duration<double>(seconds));
  while (Clock::now() < until && !g_interrupted) {
    lcm.handleTimeout(20);
    if (done()) return true;
  }
  return done();
}

void send_test(lcm::LCM& lcm, const std::string& channel, int motor_1based, double throttle,
               double seconds, std::int64_t utime) {
  motor_test_t msg;
  msg.utime = utime;
  msg.motor = motor_1based;
  msg.throttle = static_cast<float>(throttle);
  msg.duration_s = static_cast<float>(seconds);
  lcm.publish(channel, &msg);
}

}  // namespace

int motor_test(const MotorTestCommand& cmd) {
  const auto config = load_vehicle(cmd.common, "motor-test");
  if (!config) return kExitUsage;
  std::vector<int> motors;
  if (cmd.sequence) {
    for (int i = 0; i < config->motors(); ++i) motors.push_back(i);
  } else {
    const int m = config->motor_index(cmd.motor);
    if (m < 0) {
      std::cerr << "motormix motor-test: --motor " << cmd.motor << ": expected 1.."
                << config->motors() << " or a motor name\n";
      return kExitUsage;
    }
    motors.push_back(m);
  }
  lcm::LCM lcm(cmd.lcm_url);
  if (!lcm.good()) {
    std::cerr << "motormix motor-test: cannot open the LCM bus\n";
    return kExitRuntime;
  }
  StatusWatch watch;
  lcm.subscribe(config->channels.status, &StatusWatch::on_status, &watch);
  std::signal(SIGINT, on_interrupt);
  std::signal(SIGTERM, on_interrupt);
  for (std::size_t k = 0; k < motors.size() && !g_interrupted; ++k) {
    const int m = motors[k];
    const std::int64_t utime = wall_us();
    send_test(lcm, config->channels.motor_test, m + 1, cmd.throttle, cmd.seconds, utime);
    const bool answered = serve(lcm, cmd.wait_s, [&] {
      return watch.latest && watch.latest->motor_test_request_utime == utime;
    });
    if (g_interrupted) break;
    if (!answered) {
      std::cerr << "motormix motor-test: no answer on " << config->channels.status << " within "
                << cmd.wait_s << " s: is motormix run running with this configuration?\n";
      return kExitRuntime;
    }
    const auto result = static_cast<loop::MotorTestResult>(watch.latest->motor_test_result);
    if (result != loop::MotorTestResult::kOk) {
      std::cerr << "motormix motor-test: refused: " << loop::to_string(result) << "\n";
      return kExitRuntime;
    }
    std::cout << where(*config, m) << ": spinning at " << cmd.throttle << " for " << cmd.seconds
              << " s" << std::endl;
    // Until the mixer says the test is over (bounded by its duration).
    serve(lcm, cmd.seconds + 1.0, [&] {
      return watch.latest && watch.latest->motor_test_state == mixer_status_t::MOTOR_TEST_NONE;
    });
    if (cmd.sequence && k + 1 < motors.size()) serve(lcm, 1.0, [] { return false; });
  }
  if (g_interrupted) {
    send_test(lcm, config->channels.motor_test, 0, 0.0, 0.0, wall_us());
    std::cerr << "motormix motor-test: interrupted, test stopped\n";
    return kExitRuntime;
  }
  return kExitOk;
}

namespace {

// Publishes every output at one value per channel, at the loop rate, until
// `until` returns true or `seconds` pass; false if interrupted.
template <typename Until>
bool hold_outputs(lcm::LCM& lcm, const config::Config& config, const std::vector<double>& pwm,
                  double command, bool armed, double seconds, Until until) {
  motor_pwm_t msg;
  msg.num_motors = config.motors();
  msg.command.assign(static_cast<std::size_t>(msg.num_motors), static_cast<float>(command));
  msg.direction.assign(static_cast<std::size_t>(msg.num_motors), 0);
  msg.pwm.resize(static_cast<std::size_t>(msg.num_motors));
  for (std::size_t i = 0; i < pwm.size(); ++i) msg.pwm[i] = static_cast<float>(pwm[i]);
  msg.armed = armed;
  msg.setpoint_utime = 0;
  msg.pid_utime = 0;
  msg.failed_motors = 0;
  const auto period = std::chrono::duration<double>(1.0 / config.loop_rate_hz);
  const auto end = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                      std::chrono::duration<double>(seconds));
  auto next = Clock::now();
  while (Clock::now() < end) {
    if (g_interrupted) return false;
    msg.utime = wall_us();
    lcm.publish(config.channels.motor_pwm, &msg);
    if (until()) return true;
    next += std::chrono::duration_cast<Clock::duration>(period);
    std::this_thread::sleep_until(next);
  }
  return !g_interrupted;
}

// A line on standard input (Enter), polled without blocking; -1 at end of input.
int line_ready() {
  pollfd p{STDIN_FILENO, POLLIN, 0};
  if (poll(&p, 1, 0) <= 0) return 0;
  char c = 0;
  while (true) {
    const ssize_t got = read(STDIN_FILENO, &c, 1);
    if (got <= 0) return -1;
    if (c == '\n') return 1;
  }
}

}  // namespace

int esc_calibrate(const EscCalibrateCommand& cmd) {
  const auto config = load_vehicle(cmd.common, "esc-calibrate");
  if (!config) return kExitUsage;
  if (!cmd.props_off) {
    std::cerr << "motormix esc-calibrate: refused: every motor will run at full command. Take the "
                 "propellers off, then pass --props-off\n";
    return kExitUsage;
  }
  for (const OutputChannel& ch : config->outputs) {
    if (ch.mode != OutputMode::kUnipolar) {
      std::cerr << "motormix esc-calibrate: refused: the outputs are "
                << (ch.mode == OutputMode::kCentered ? "centered (reversible drives)"
                                                     : "duty plus direction pin (H-bridges)")
                << "; calibration is for PWM ESCs that learn their throttle range (output.mode "
                   "unipolar)\n";
      return kExitUsage;
    }
  }
  lcm::LCM lcm(cmd.lcm_url);
  if (!lcm.good()) {
    std::cerr << "motormix esc-calibrate: cannot open the LCM bus\n";
    return kExitRuntime;
  }
  // Nothing else may drive the outputs: listen for a mixer first.
  StatusWatch watch;
  lcm.subscribe(config->channels.status, &StatusWatch::on_status, &watch);
  lcm.subscribe(config->channels.motor_pwm, &StatusWatch::on_pwm, &watch);
  const double listen = std::max(cmd.listen_s, 2.0 / config->status_rate_hz);
  serve(lcm, listen, [] { return false; });
  if (watch.latest || watch.pwm_seen > 0) {
    std::cerr << "motormix esc-calibrate: refused: a mixer is running on the bus ("
              << config->channels.motor_pwm << " or " << config->channels.status << " heard within "
              << listen << " s): stop it first\n";
    return kExitRuntime;
  }
  std::signal(SIGINT, on_interrupt);
  std::signal(SIGTERM, on_interrupt);
  std::vector<double> high, low, disarmed;
  for (const OutputChannel& ch : config->outputs) {
    high.push_back(ch.reversed ? ch.min : ch.max);
    low.push_back(ch.reversed ? ch.max : ch.min);
    disarmed.push_back(ch.disarmed);
  }
  const auto finish = [&](int code, const char* why) {
    hold_outputs(lcm, *config, disarmed, 0.0, false, 0.5, [] { return false; });
    if (why != nullptr) std::cerr << "motormix esc-calibrate: " << why << "; outputs disarmed\n";
    return code;
  };
  std::cout << "Every output is at its maximum (" << high.front() << " " << config->output_unit
            << "). Power the ESCs now; when they have beeped, press Enter (Ctrl-C aborts). "
            << "Waiting at most " << cmd.timeout_s << " s." << std::endl;
  int confirmed = 0;
  if (!hold_outputs(lcm, *config, high, 1.0, true, cmd.timeout_s, [&] {
        confirmed = line_ready();
        return confirmed != 0;
      })) {
    g_interrupted = false;  // publish the disarmed values all the same
    return finish(kExitRuntime, "interrupted");
  }
  if (confirmed != 1) {
    return finish(kExitRuntime, confirmed < 0 ? "no confirmation (end of input)"
                                              : "no confirmation within the timeout");
  }
  std::cout << "Minimum (" << low.front() << " " << config->output_unit << ") for "
            << cmd.min_seconds << " s: the ESCs confirm the range." << std::endl;
  if (!hold_outputs(lcm, *config, low, 0.0, true, cmd.min_seconds, [] { return false; })) {
    g_interrupted = false;
    return finish(kExitRuntime, "interrupted");
  }
  finish(kExitOk, nullptr);
  std::cout << "Done: outputs disarmed." << std::endl;
  return kExitOk;
}

}  // namespace motormix::app
