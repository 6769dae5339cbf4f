// Bring-up clients: `motormix motor-test` (one motor alone, through a running
// disarmed `motormix run`) and `motormix esc-calibrate` (the ESC range
// sequence, with no mixer on the bus). Wiring only: the clients live in the
// bring-up library (src/bringup), the rules a test must satisfy in the loop.

#include "commands.hpp"

#include "bringup/bus_clients.hpp"

#include <motormix/config/load_config.hpp>

#include <unistd.h>

#include <iostream>

namespace motormix::app {

namespace {

int exit_code(bringup::ClientOutcome outcome) {
  switch (outcome) {
    case bringup::ClientOutcome::kOk:
      return kExitOk;
    case bringup::ClientOutcome::kRefused:
      return kExitRefused;
    case bringup::ClientOutcome::kBusError:
    case bringup::ClientOutcome::kNoAnswer:
    case bringup::ClientOutcome::kAborted:
    case bringup::ClientOutcome::kInterrupted:
      return kExitRuntime;
  }
  return kExitRuntime;
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
  if (cmd.parse_only) return kExitOk;
  return exit_code(bringup::run_motor_test(*config, motors, cmd.throttle, cmd.seconds, cmd.wait_s,
                                           cmd.lcm_url, std::cout, std::cerr));
}

int esc_calibrate(const EscCalibrateCommand& cmd) {
  const auto config = load_vehicle(cmd.common, "esc-calibrate");
  if (!config) return kExitUsage;
  if (!cmd.props_off) {
    std::cerr << "motormix esc-calibrate: refused: every motor will run at full command. Take the "
                 "propellers off, then pass --props-off\n";
    return kExitUsage;
  }
  if (const std::string why = bringup::calibration_refusal(*config); !why.empty()) {
    std::cerr << "motormix esc-calibrate: refused: " << why << "\n";
    return kExitUsage;
  }
  bringup::EscCalibrationTiming timing;
  timing.listen_s = cmd.listen_s;
  timing.timeout_s = cmd.timeout_s;
  timing.min_seconds = cmd.min_seconds;
  return exit_code(bringup::run_esc_calibration(*config, timing, cmd.lcm_url, STDIN_FILENO,
                                                std::cout, std::cerr));
}

int esc_command(const EscCommandCommand& cmd) {
  const auto config = load_vehicle(cmd.common, "esc-command");
  if (!config) return kExitUsage;
  const std::optional<bringup::EscCommand> command = bringup::esc_command_named(cmd.command);
  if (!command) {
    std::cerr << "motormix esc-command: " << cmd.command << ": expected "
              << bringup::esc_command_names() << "\n";
    return kExitUsage;
  }
  if (config->hardware.protocol == config::EscProtocol::kPwm) {
    std::cerr << "motormix esc-command: refused: hardware.protocol is pwm; special commands are "
                 "DShot's (docs/wiring-it-to-motors.md)\n";
    return kExitUsage;
  }
  std::vector<int> motors;
  if (cmd.all) {
    for (int i = 0; i < config->motors(); ++i) motors.push_back(i);
  }
  for (const std::string& name : cmd.motors) {
    const int m = config->motor_index(name);
    if (m < 0) {
      std::cerr << "motormix esc-command: --motor " << name << ": expected 1.." << config->motors()
                << " or a motor name\n";
      return kExitUsage;
    }
    motors.push_back(m);
  }
  if (cmd.parse_only) return kExitOk;
  return exit_code(bringup::run_esc_command(*config, *command, motors, cmd.wait_s, cmd.lcm_url,
                                            std::cout, std::cerr));
}

}  // namespace motormix::app
