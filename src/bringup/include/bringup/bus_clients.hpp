#pragma once
// The bring-up clients on the bus: the motor test through a running
// `motormix run`, and the ESC calibration with no mixer running. Their
// decisions are in motor_test_client.hpp and esc_calibration.hpp (time
// passed in, tested on their own); this is the bus, the terminal and the
// clock around them.

#include "bringup/esc_calibration.hpp"

#include <motormix/config/config.hpp>

#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

namespace motormix::bringup {

enum class ClientOutcome {
  kOk = 0,
  kBusError,     // the LCM bus could not be opened, the signals held, or the key file read
  kNoAnswer,     // motor test: no mixer answered
  kRefused,      // the mixer refused the test, or calibration found a mixer running
  kAborted,      // calibration ended before the range was taught (outputs disarmed)
  kInterrupted,  // Ctrl-C or SIGTERM (motor test stopped, outputs disarmed)
};

// "motor 2 (front_left), front left, CW": where a motor is and how it spins.
std::string describe_motor(const config::Config& config, int motor);

// Each client is a bus::Process of its own: its shutdown signals are held
// from before the bus opens, and a signal ends it safely (the motor test
// sends the stop, calibration disarms, a command stops waiting).

// Spins each of `motors` (0-based) in turn.
ClientOutcome run_motor_test(const config::Config& config, const std::vector<int>& motors,
                             double throttle, double seconds, double wait_s,
                             const std::string& lcm_url, std::ostream& out, std::ostream& err);

// The calibration sequence; the user's Enter is read from `input_fd`.
ClientOutcome run_esc_calibration(const config::Config& config, const EscCalibrationTiming& timing,
                                  const std::string& lcm_url, int input_fd, std::ostream& out,
                                  std::ostream& err);

// A DShot special command by name ("beep1".."beep5", "esc-info",
// "spin-direction-1", "spin-direction-2", "3d-off", "3d-on", "save",
// "spin-normal", "spin-reversed") or number (1..47): its number and the
// frames it goes in (10 for a setting, as ESCs act on one after 6; 1 for a
// beep); nullopt for anything else.
struct EscCommand {
  int number = 0;
  int repeat = 1;
};
std::optional<EscCommand> esc_command_named(const std::string& name);
// The names, for the help text.
std::string esc_command_names();

// Publishes one esc_command_t for `motors` (0-based) and waits up to
// `wait_s` for `motormix output`'s status to count it sent or refused.
ClientOutcome run_esc_command(const config::Config& config, const EscCommand& command,
                              const std::vector<int>& motors, double wait_s,
                              const std::string& lcm_url, std::ostream& out, std::ostream& err);

}  // namespace motormix::bringup
