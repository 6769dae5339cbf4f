#pragma once
// `motormix import ulog`: a PX4 flight log (ULog) as an LCM event log that
// `motormix replay` and lcm-logplayer take. What PX4 mixed becomes what
// motormix mixes, on the configuration's channels:
//
// - vehicle_torque_setpoint -> pid_t (roll, pitch, yaw), and
//   vehicle_thrust_setpoint -> setpoint_t (throttle = -z, yaw from the torque
//   of the same sample), both stamped with PX4's sample time; older logs'
//   actuator_controls_0 (control[0..3]) stand for both. `armed` follows
//   actuator_armed (or vehicle_status.arming_state).
// - vehicle_angular_velocity with the latest vehicle_attitude.q and
//   vehicle_local_position's velocity -> attitude_t.
// - esc_status -> esc_telemetry_t (rpm, current, voltage, temperature; the
//   motor from each report's actuator_function where logged).
// - PX4's own outputs, actuator_motors (with actuator_outputs as pwm), ->
//   motor_pwm_t on a channel of its own (`reference`), its setpoint_utime
//   and pid_utime the sample time of the inputs PX4 mixed them from: the
//   replay pairs them with motormix's answer to the same inputs.
//
// Event times and utimes are PX4's: microseconds since the flight
// controller booted. Values motormix's inputs refuse (non-finite, out of
// range) are clamped or skipped and counted, never written.

#include <motormix/config/config.hpp>
#include <motormix/config/ulog.hpp>

#include <cstdint>
#include <iosfwd>
#include <map>
#include <string>
#include <vector>

namespace motormix::lcmlog {

// Where PX4's own motor commands go, unless told otherwise.
inline constexpr const char* kPx4ReferenceChannel = "PX4_MOTORS";

struct UlogImportOptions {
  config::Channels channels;  // setpoint, pid, attitude, esc_telemetry
  std::string reference = kPx4ReferenceChannel;
  int motors = 0;  // PX4 outputs per reference message; 0: CA_ROTOR_COUNT, else 4
};

struct UlogImportSummary {
  std::map<std::string, std::int64_t> events;  // written, by channel
  std::int64_t clamped = 0;                    // input values brought into range
  std::int64_t skipped = 0;                    // samples with non-finite inputs
  double duration_s = 0.0;
  std::vector<std::string> notes;  // what the log did not have, and what stood in
};

// One LCM event of the import, encoded.
struct ImportedEvent {
  std::int64_t t = 0;  // microseconds, PX4's clock
  int order = 0;       // among events at the same time: inputs first
  std::string channel;
  std::vector<std::uint8_t> bytes;
};

// The events of a parsed ULog in time order (what import_ulog writes).
// Throws std::runtime_error if it holds no mixing inputs.
std::vector<ImportedEvent> ulog_events(const config::Ulog& ulog, const UlogImportOptions& options,
                                       UlogImportSummary& summary);

// Returns false (with a message on `log`) if the ULog cannot be read, holds
// no mixing inputs, or the output cannot be written.
bool import_ulog(const std::string& ulog_path, const std::string& out_path,
                 const UlogImportOptions& options, UlogImportSummary& summary, std::ostream& log);

}  // namespace motormix::lcmlog
