#pragma once
// `motormix monitor`: a live terminal view of a running motormix, read from
// its status and output channels. Plain ANSI (cursor home + clear), so it
// works over SSH and in any terminal; `--once` prints one snapshot without
// escape codes. The view itself is a pure function of the last messages,
// so it is tested without a bus.

#include "bus/receive.hpp"

#include <motormix/mixer_status_t.hpp>
#include <motormix/motor_pwm_t.hpp>
#include <motormix/output_status_t.hpp>

#include <cstdint>
#include <iosfwd>
#include <motormix/signing_policy.hpp>
#include <optional>
#include <string>

#include <memory>
#include <vector>

namespace motormix::bringup {

struct MonitorOptions {
  std::string lcm_url;  // empty: LCM_DEFAULT_URL, then LCM's default
  std::string status_channel = "MIXER_STATUS";
  std::string pwm_channel = "MOTOR_PWM";
  std::string output_status_channel = "OUTPUT_STATUS";  // motormix output's state
  // The configuration drives pins (hardware.driver): a silent output process
  // is then shown as such.
  bool expect_output = false;
  std::vector<std::string> motor_names;  // empty: m1, m2, ...
  std::string output_unit = "us";
  bool once = false;         // one snapshot, then exit 0
  double wait_s = 3.0;       // no status within this long: exit 1
  double duration_s = 0.0;   // live view: stop by itself after this long (0: until a signal)
  double refresh_hz = 10.0;  // live view redraws
  // The configuration's signing policy (security:): under sign or require,
  // a status or output that does not verify is not shown (counted, as
  // "signature"). Null: signatures are cut off unread.
  std::shared_ptr<signing::Policy> policy;
};

// What the view is drawn from: the last status and outputs, and how old
// they are (seconds, on this host's receive clock).
struct MonitorSnapshot {
  std::optional<mixer_status_t> status;
  std::optional<motor_pwm_t> pwm;
  double status_age_s = 0.0;
  double pwm_age_s = 0.0;
  // What the monitor itself refused on both channels, by reason (bus::receive;
  // a status whose num_motors is outside 1..16 counts as a bad length).
  bus::Refusals refused;
  std::optional<output_status_t> output;  // from motormix output, if one runs
  double output_age_s = 0.0;
};

// Whether the monitor draws a status: one row per motor, so a count no mixer
// has (outside 1..16) is refused (counted as a bad length).
bool monitor_shows(const mixer_status_t& status);

// Whether the monitor draws an output status (num_motors 1..16; else
// refused as a bad length).
bool monitor_shows(const output_status_t& status);

// The whole screen as text (no escape codes); `width` columns for the bars.
std::string render_monitor(const MonitorSnapshot& snapshot, const MonitorOptions& options,
                           int bar_width = 30);

// Exit codes: 0 (snapshot printed or duration reached or signal), 1 (no
// mixer on the bus within wait_s, or LCM cannot be opened).
int run_monitor(const MonitorOptions& options, std::ostream& out, std::ostream& log);

}  // namespace motormix::bringup
