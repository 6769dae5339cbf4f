#include "commands.hpp"

#include <motormix/config/build_mixer.hpp>
#include <motormix/config/load_config.hpp>
#include <motormix/config/matrix_export.hpp>
#include <motormix/config/px4_import.hpp>
#include <motormix/config/security.hpp>
#include "bringup/monitor.hpp"
#include "log/log_replay.hpp"
#include "log/log_signing.hpp"
#include "log/ulog_import.hpp"
#include "node/describe.hpp"
#include "node/lcm_node.hpp"
#include "output/output_process.hpp"

#include <motormix/signing.hpp>

#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>

namespace motormix::app {

std::optional<config::Config> load_vehicle(const CommonOptions& common, const char* command) {
  try {
    if (common.preset.empty())
      return config::load_config_file(common.config_path, common.overrides);
    return config::load_config_text("geometry: {preset: " + common.preset + "}\n",
                                    "preset " + common.preset, common.overrides);
  } catch (const config::ConfigError& e) {
    std::cerr << "motormix " << command << ": " << e.what() << "\n";
    return std::nullopt;
  }
}

// --check: the security line, and the key read as the process would read it
// (a key file that is missing or open to others fails the check).
bool check_security(const config::Config& config, const char* command) {
  try {
    config::signing_policy(config);
    return true;
  } catch (const config::ConfigError& e) {
    std::cerr << "motormix " << command << ": " << e.what() << "\n";
    return false;
  }
}

int run(const RunCommand& cmd) {
  const auto config = load_vehicle(cmd.common, "run");
  if (!config) return kExitUsage;
  if (cmd.check_only) {
    // The key first: a configuration whose key cannot be read is not valid.
    if (!check_security(*config, "run")) return kExitUsage;
    std::cout << "config "
              << (cmd.common.preset.empty() ? cmd.common.config_path
                                            : "of preset " + cmd.common.preset)
              << " is valid: " << config->motors() << " motors, strategy "
              << config::to_string(config->strategy) << "\n";
    const loop::ControlLoop loop(*config, config::build_mixer(*config));
    for (const std::string& line : node::describe_run(*config, loop)) std::cout << line << "\n";
    std::cout << "\n" << config::export_matrix(*config, config::MatrixFormat::kTable);
    return kExitOk;
  }
  node::RunOptions options;
  options.lcm_url = cmd.lcm_url;
  options.max_cycles = cmd.max_cycles;
  options.lockstep = cmd.lockstep;
  options.lockstep_idle_s = cmd.lockstep_idle_s;
  options.timing_report_path = cmd.timing_report;
  return node::run_node(*config, options, std::cerr);
}

int output(const OutputCommand& cmd) {
  const auto config = load_vehicle(cmd.common, "output");
  if (!config) return kExitUsage;
  if (config->hardware.driver == config::HardwareDriver::kNone) {
    std::cerr << "motormix output: the configuration has no hardware driver (set hardware.driver: "
                 "serial or sysfs; docs/wiring-it-to-motors.md)\n";
    return kExitUsage;
  }
  if (cmd.check_only) {
    // The key first: a configuration whose key cannot be read is not valid.
    if (!check_security(*config, "output")) return kExitUsage;
    const config::Hardware& hw = config->hardware;
    std::cout << "hardware: " << config::to_string(hw.driver) << ", "
              << config::to_string(hw.protocol) << (hw.bidirectional ? " bidirectional" : "")
              << ", " << config->motors() << " motors at " << hw.pulse_rate_hz
              << " Hz, disarmed when motor_pwm_t is older than " << hw.motor_pwm_timeout_s * 1e3
              << " ms";
    if (hw.driver == config::HardwareDriver::kSerial) {
      std::cout << "; " << hw.serial.device << " at " << hw.serial.baud
                << " baud, the firmware disarms on its own after " << hw.serial.link_timeout_s * 1e3
                << " ms without a frame";
    } else {
      std::cout << "; " << hw.sysfs.root << "/pwmchip" << hw.sysfs.chip;
    }
    std::cout << "; " << hw.telemetry.size() << " ESC telemetry wire(s)\n";
    std::cout << config::describe(config->security) << "\n";
    return kExitOk;
  }
  output::OutputOptions options;
  options.lcm_url = cmd.lcm_url;
  options.disarm_only = cmd.disarm_only;
  options.max_run_s = cmd.max_run_s;
  return output::run_output(*config, options, std::cerr);
}

int keygen(const KeygenCommand& cmd) {
  try {
    signing::write_new_key(cmd.path);
  } catch (const signing::KeyError& e) {
    std::cerr << "motormix keygen: " << e.what() << "\n";
    return kExitRuntime;
  }
  std::cout << "wrote a new signing key to " << cmd.path
            << " (readable by its owner only); copy it to the other hosts of the bus over a "
               "channel you trust\n";
  return kExitOk;
}

int import_px4(const ImportPx4Command& cmd) {
  config::Px4Import imported;
  try {
    const config::Px4Parameters params = config::read_px4_parameters(cmd.path);
    imported = config::import_px4(params, cmd.path);
    // What it wrote must load: a mapping error is found here, not at start-up.
    config::load_config_text(imported.yaml, "the imported configuration");
  } catch (const std::exception& e) {
    std::cerr << "motormix import px4-params: " << e.what() << "\n";
    return kExitUsage;
  }
  for (const std::string& n : imported.not_mapped)
    std::cerr << "motormix import px4-params: not mapped: " << n << "\n";
  for (const std::string& n : imported.notes)
    std::cerr << "motormix import px4-params: note: " << n << "\n";
  if (cmd.out.empty()) {
    std::cout << imported.yaml;
    return kExitOk;
  }
  if (!cmd.force && std::ifstream(cmd.out).good()) {
    std::cerr << "motormix import px4-params: " << cmd.out << " exists; --force to overwrite it\n";
    return kExitUsage;
  }
  std::ofstream file(cmd.out);
  file << imported.yaml;
  if (!file) {
    std::cerr << "motormix import px4-params: cannot write " << cmd.out << "\n";
    return kExitRuntime;
  }
  std::cerr << "motormix import px4-params: wrote " << cmd.out << "\n";
  return kExitOk;
}

int import_ulog(const ImportUlogCommand& cmd) {
  lcmlog::UlogImportOptions options;
  options.reference = cmd.reference;
  if (!cmd.config_path.empty()) {
    CommonOptions common;
    common.config_path = cmd.config_path;
    const auto config = load_vehicle(common, "import ulog");
    if (!config) return kExitUsage;
    options.channels = config->channels;
    options.motors = config->motors();
  }
  if (!cmd.force && std::ifstream(cmd.out).good()) {
    std::cerr << "motormix import ulog: " << cmd.out << " exists; --force to overwrite it\n";
    return kExitUsage;
  }
  lcmlog::UlogImportSummary s;
  if (!lcmlog::import_ulog(cmd.ulog, cmd.out, options, s, std::cerr)) return kExitRuntime;
  for (const std::string& n : s.notes) std::cerr << "motormix import ulog: note: " << n << "\n";
  std::cout << std::fixed << std::setprecision(2) << "imported " << cmd.ulog << " -> " << cmd.out
            << " (" << s.duration_s << " s of flight)\n";
  for (const auto& [channel, count] : s.events)
    std::cout << "  " << channel << ": " << count << "\n";
  std::cout << "inputs clamped into motormix's ranges: " << s.clamped
            << "; samples skipped (not finite): " << s.skipped << "\n";
  return kExitOk;
}

namespace {

// The replay against the log's reference mixer (PX4's commands, imported).
void print_comparison(const lcmlog::ReferenceComparison& c) {
  std::cout << "compared with   " << c.channel << ": " << c.compared << " of " << c.references
            << " commands (" << c.reference_disarmed << " stopped there, " << c.motormix_disarmed
            << " with motormix disarmed, " << c.unpaired
            << " without motormix's answer to the same "
            << "inputs)\n";
  if (c.compared == 0) return;
  std::cout << std::scientific << std::setprecision(2);
  std::cout << "  largest difference per motor:";
  for (double d : c.max_difference) std::cout << " " << d;
  std::cout << "\n  p99 difference per motor:    ";
  for (double d : c.p99_difference) std::cout << " " << d;
  std::cout << "\n  largest " << c.worst << " (motor " << c.worst_motor << ", " << std::fixed
            << std::setprecision(3) << c.worst_at_s << " s into the log)\n"
            << "  commands differing by more than " << std::scientific << std::setprecision(0)
            << lcmlog::ReferenceComparison::kSameCommand << ": " << c.differing_spool_up
            << " while motormix spooled up after arming (output.spool_up_s), "
            << c.differing_saturated << " with a motor at 0 or 1 (saturation), "
            << c.differing_limited
            << " with an axis motormix could not deliver (airmode, priorities), "
            << c.differing_other << " elsewhere\n"
            << std::fixed << std::setprecision(2);
}

}  // namespace

int replay(const ReplayCommand& cmd) {
  const auto config = load_vehicle(cmd.common, "replay");
  if (!config) return kExitUsage;
  lcmlog::ReplayOptions options;
  options.progress = isatty(STDERR_FILENO) != 0;
  options.cycle_on_every_input = cmd.every_input;
  options.max_gap_s = cmd.max_gap_s;
  options.verify = cmd.verify;
  options.reference_channel = cmd.reference;
  if (cmd.verify) {
    // The key is configuration: without it, or unreadable, a usage error
    // (exit 2) before anything is read, as every other command says it.
    if (config->security.key_file.empty()) {
      std::cerr << "motormix replay: --verify needs the key: set security.key_file (the log "
                   "must also be signed: motormix sign-log)\n";
      return kExitUsage;
    }
    try {
      (void)signing::load_key(config->security.key_file);
    } catch (const signing::KeyError& e) {
      std::cerr << "motormix replay: security.key_file: " << e.what() << "\n";
      return kExitUsage;
    }
  }
  lcmlog::ReplaySummary s;
  if (!lcmlog::replay_log(*config, cmd.in_log, cmd.out_log, options, s, std::cerr)) {
    return kExitRuntime;
  }
  std::cout << std::fixed << std::setprecision(2) << "replayed " << cmd.in_log << " -> "
            << cmd.out_log << "\n"
            << "duration        " << s.duration_s << " s (loop " << config->loop_rate_hz
            << " Hz, strategy " << config::to_string(config->strategy) << ")\n"
            << "messages        " << s.input_events << " inputs, " << s.other_events
            << " other events copied, " << s.outputs << " outputs written\n"
            << "armed           " << s.armed_s << " s\n"
            << "not delivered   roll " << s.limited_s[0] << " s, pitch " << s.limited_s[1]
            << " s, yaw " << s.limited_s[2] << " s, thrust " << s.limited_s[3]
            << " s (armed time with that axis limited)\n"
            << "failsafe events " << s.failsafe_events << "; rejected inputs " << s.rejected << "\n"
            << "motor failures  " << s.failed_s << " s armed with failed motors, "
            << s.failure_changes << " changes of the failure set, " << s.detections
            << " declared by the failure detector\n"
            << "battery         " << s.compensated_s << " s compensated, largest thrust gain "
            << std::setprecision(3) << s.max_thrust_gain << std::setprecision(2) << "\n"
            << "log damage      " << s.discontinuities << " time discontinuities ("
            << s.skipped_events << " events skipped), " << s.skipped.size()
            << " damaged stretches skipped\n";
  if (cmd.verify) {
    // Freshness: per link and channel, timestamps must rise through the log,
    // and a link's first message must be stamped near the time the log
    // received it; how old the log is, it cannot say.
    std::cout << "signatures      checked with " << config->security.key_file
              << " (log receive time as the clock)\n";
    for (const lcmlog::ChannelVerification& v : s.verification) {
      const auto& c = v.counts;
      std::cout << "  " << v.channel << ": " << c.signed_accepted << " verified";
      if (c.rejected() > 0) {
        std::cout << "; refused " << c.rejected_unsigned << " unsigned, "
                  << c.rejected_bad_signature << " bad signature, " << c.rejected_replayed
                  << " replayed, " << c.rejected_stale + c.rejected_other << " stale";
      }
      std::cout << "\n";
    }
    std::cout << (s.unverified == 0 ? "every event verified\n"
                                    : std::to_string(s.unverified) + " events refused\n");
  }
  if (s.reference.present()) print_comparison(s.reference);
  if (s.damaged()) return kExitDamagedLog;
  return cmd.verify && s.unverified > 0 ? kExitRefused : kExitOk;
}

int sign_log(const SignLogCommand& cmd) {
  const auto config = load_vehicle(cmd.common, "sign-log");
  if (!config) return kExitUsage;
  lcmlog::SignLogOptions options;
  options.from_now = cmd.now;
  lcmlog::SignLogSummary s;
  if (!lcmlog::sign_log(*config, cmd.in_log, cmd.out_log, options, s, std::cerr)) {
    return kExitRuntime;
  }
  std::cout << "signed " << cmd.in_log << " -> " << cmd.out_log << ": " << s.signed_events
            << " events signed (link id " << config->security.link_id << ", stamped "
            << (cmd.now ? "from now" : "at the log's times") << "), " << s.already_signed
            << " already signed, copied\n";
  return s.skipped.empty() ? kExitOk : kExitDamagedLog;
}

int monitor(const MonitorCommand& cmd) {
  bringup::MonitorOptions o;
  if (!cmd.common.config_path.empty() || !cmd.common.preset.empty()) {
    const auto config = load_vehicle(cmd.common, "monitor");
    if (!config) return kExitUsage;
    o.status_channel = config->channels.status;
    o.pwm_channel = config->channels.motor_pwm;
    o.output_status_channel = config->channels.output_status;
    o.expect_output = config->hardware.driver != config::HardwareDriver::kNone;
    o.motor_names = config->motor_names();
    o.output_unit = config->output_unit;
    try {
      o.policy = std::make_shared<signing::Policy>(config::signing_policy(*config));
    } catch (const config::ConfigError& e) {
      std::cerr << "motormix monitor: " << e.what() << "\n";
      return kExitUsage;
    }
  }
  if (!cmd.status_channel.empty()) o.status_channel = cmd.status_channel;
  if (!cmd.pwm_channel.empty()) o.pwm_channel = cmd.pwm_channel;
  o.lcm_url = cmd.lcm_url;
  o.once = cmd.once;
  o.wait_s = cmd.wait_s;
  o.duration_s = cmd.duration_s;
  return bringup::run_monitor(o, std::cout, std::cerr);
}

int matrix(const MatrixCommand& cmd) {
  const auto config = load_vehicle(cmd.common, "matrix");
  if (!config) return kExitUsage;
  try {
    std::cout << config::export_matrix(
        *config,
        parse_in(config::kMatrixFormatNames, cmd.format).value_or(config::MatrixFormat::kTable));
    return kExitOk;
  } catch (const config::ConfigError& e) {  // a format the geometry cannot give
    std::cerr << "motormix matrix: " << e.what() << "\n";
    return kExitUsage;
  }
}

}  // namespace motormix::app
