#pragma once
// `motormix output`: motor_pwm_t from the bus to the ESC pins through the
// driver the `hardware:` section names, behind the output gate's failsafe
// (output_gate.hpp), and KISS / BLHeli_32 telemetry wires read back onto
// the bus as esc_telemetry_t. Single-threaded: one poll over the LCM
// socket, a 5 ms timer, the serial ports and a signal descriptor.

#include <motormix/config/config.hpp>

#include <ostream>
#include <string>

namespace motormix::output {

struct OutputOptions {
  std::string lcm_url;       // empty: LCM's default (LCM_DEFAULT_URL)
  bool disarm_only = false;  // write the disarmed pulses once and exit (a supervisor's stop hook)
  double max_run_s = 0.0;    // stop after this long (tests, demos); 0: until a signal
};

// The process's exit code: 0 after a signal (disarmed pulses written), 1 on
// a start-up error (said on log).
int run_output(const config::Config& config, const OutputOptions& options, std::ostream& log);

}  // namespace motormix::output
