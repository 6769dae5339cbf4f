#pragma once
// The subcommands of the motormix binary. Each returns the process exit code:
// 0 ok, 1 runtime error, 2 usage or configuration error, 3 (replay) damaged
// input log, 4 (sim) crashed, 5 (bring-up) refused.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace motormix::config {
struct Config;
}

namespace motormix::app {

inline constexpr int kExitOk = 0;
inline constexpr int kExitRuntime = 1;
inline constexpr int kExitUsage = 2;
// replay: the output was written from every valid event, but the input log
// had damaged stretches that were skipped (listed on stderr).
inline constexpr int kExitDamagedLog = 3;
// sim: the run ended in a crash (the JSON result says how and when).
inline constexpr int kExitCrashed = 4;
// motor-test, esc-calibrate: refused, nothing spun (the mixer refused the
// test; a mixer runs on the bus while calibrating). stderr says why.
inline constexpr int kExitRefused = 5;

// A vehicle: exactly one of a configuration file and a preset (checked
// after parsing; `monitor` takes at most one), and --set overrides.
struct CommonOptions {
  std::string config_path;
  std::string preset;
  std::vector<std::string> overrides;  // --set key.path=value
};

struct RunCommand {
  CommonOptions common;
  std::string lcm_url;
  bool check_only = false;
  long long max_cycles = 0;
  std::string timing_report;
  bool lockstep = false;
  double lockstep_idle_s = 30.0;
};
int run(const RunCommand& cmd);

struct OutputCommand {
  CommonOptions common;
  std::string lcm_url;
  bool check_only = false;
  bool disarm_only = false;
  double max_run_s = 0.0;
};
int output(const OutputCommand& cmd);

struct KeygenCommand {
  std::string path;
};
// A new signing key (64 hex digits, mode 0600); never overwrites a file.
int keygen(const KeygenCommand& cmd);

// The configuration `common` names (the file, or the preset's defaults),
// with its overrides; on error, says so on stderr as "motormix COMMAND: ..."
// and returns nothing.
std::optional<config::Config> load_vehicle(const CommonOptions& common, const char* command);

struct ImportPx4Command {
  std::string path;  // .params or .ulg
  std::string out;   // empty: standard output
  bool force = false;
};
// A PX4 airframe's parameters as a configuration; what is not mapped is
// listed on stderr.
int import_px4(const ImportPx4Command& cmd);

struct ImportUlogCommand {
  std::string ulog;
  std::string out;
  std::string config_path;  // optional: its channels and motor count
  std::string reference = "PX4_MOTORS";
  bool force = false;
};
// A PX4 flight log as an LCM event log for `motormix replay`.
int import_ulog(const ImportUlogCommand& cmd);

struct MixCommand {
  CommonOptions common;
  double throttle = 0.0;
  double roll = 0.0;
  double pitch = 0.0;
  double yaw = 0.0;
  bool json = false;
  bool batch = false;                     // demands from stdin, one JSON line out per demand
  std::optional<double> battery_voltage;  // applied unfiltered, needs a battery section
  std::vector<std::string> failed;        // motor numbers or names, added to mixer.failed_motors
  bool parse_only = false;                // validate everything, then exit 0 without mixing
};
int mix(const MixCommand& cmd);

struct MatrixCommand {
  CommonOptions common;
  std::string format = "table";
};
int matrix(const MatrixCommand& cmd);

struct MonitorCommand {
  CommonOptions common;  // optional: channels, motor names, unit
  std::string lcm_url;
  std::string status_channel;  // empty: from the config, else MIXER_STATUS
  std::string pwm_channel;     // empty: from the config, else MOTOR_PWM
  bool once = false;
  double wait_s = 3.0;
  double duration_s = 0.0;
};
int monitor(const MonitorCommand& cmd);

struct ReplayCommand {
  CommonOptions common;
  std::string in_log;
  std::string out_log;
  bool every_input = false;
  double max_gap_s = 10.0;
  bool verify = false;
  std::string reference = "PX4_MOTORS";
};
int replay(const ReplayCommand& cmd);

struct SignLogCommand {
  CommonOptions common;
  std::string in_log;
  std::string out_log;
  bool now = false;
};
int sign_log(const SignLogCommand& cmd);

struct SimCommand {
  CommonOptions common;
  std::string scenario = "hover";
  std::vector<std::string> fail;      // MOTOR@SECONDS
  bool no_scenario_failures = false;  // drop the scenario's own failure events
  bool undetected = false;
  std::uint64_t seed = 1;
  bool json = false;
  std::string log_path;
  bool lcm = false;
  bool lockstep = false;  // with --lcm: drive motormix run --lockstep, tick by tick
  std::string lcm_url;
  bool controller = true;
  double duration_s = 0.0;
  bool parse_only = false;  // resolve the scenario and every --fail, then exit 0 without flying
  bool ideal = false;       // every piece of realism off (sim/realism.hpp)
  std::string realism;      // PIECE=on|off,...
  std::string truth;        // model error, FACTOR=x,...
};
int sim(const SimCommand& cmd);

struct MotorTestCommand {
  CommonOptions common;
  std::string lcm_url;
  std::string motor;  // number as motormix matrix prints it, or name
  double throttle = 0.1;
  double seconds = 2.0;
  bool sequence = false;    // every motor in turn, in the diagram's numbering
  double wait_s = 3.0;      // for the mixer's answer
  bool parse_only = false;  // resolve the motor, then exit 0 without the bus
};
int motor_test(const MotorTestCommand& cmd);

struct EscCalibrateCommand {
  CommonOptions common;
  std::string lcm_url;
  bool props_off = false;    // required: the user says the propellers are off
  double timeout_s = 30.0;   // at the maximum, waiting for the user's Enter
  double min_seconds = 4.0;  // at the minimum before disarming
  double listen_s = 1.0;     // listening for a running mixer first
};
int esc_calibrate(const EscCalibrateCommand& cmd);

struct EscCommandCommand {
  CommonOptions common;
  std::string lcm_url;
  std::string command;              // a name or 1..47 (bringup::esc_command_named)
  std::vector<std::string> motors;  // numbers or names; empty with all
  bool all = false;
  double wait_s = 2.0;      // for motormix output's status
  bool parse_only = false;  // resolve the command and motors, then exit 0 without the bus
};
int esc_command(const EscCommandCommand& cmd);

}  // namespace motormix::app
