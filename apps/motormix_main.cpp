// motormix: one binary, one subcommand per job. Wiring only.

#include "commands.hpp"

#include <motormix/config/matrix_export.hpp>
#include <motormix/version.hpp>

#include <CLI/CLI.hpp>

#include <iostream>

int main(int argc, char** argv) {
  using namespace motormix::app;
  CLI::App app{"motormix: attitude/thrust commands in, one command per motor out, over LCM"};
  app.set_version_flag("--version", std::string("motormix ") + motormix::kVersion);
  app.require_subcommand(1);
  // Parse and validate everything (options, files, one of --config and
  // --preset), then stop: the documentation's commands are checked this way.
  bool parse_only = false;
  app.add_flag("--parse-only", parse_only,
               "check the command line (options, values, files) and exit without running")
      ->group("");

  // A vehicle by configuration file or by preset, and --set overrides, the
  // same way in every subcommand. Exactly one of the two (checked after
  // parsing, for the subcommands listed in `vehicles`).
  std::vector<std::pair<CLI::App*, const CommonOptions*>> vehicles;
  const auto add_vehicle = [&vehicles](CLI::App* sub, CommonOptions& common,
                                       const char* config_help = "YAML configuration file",
                                       bool required = true) {
    auto* config =
        sub->add_option("--config", common.config_path, config_help)->check(CLI::ExistingFile);
    config->excludes(sub->add_option(
        "--preset", common.preset, "a preset vehicle (its defaults; motormix matrix lists them)"));
    sub->add_option("--set", common.overrides, "override a config value: key.path=value");
    if (required) vehicles.emplace_back(sub, &common);
  };

  // The bus, the same way in every subcommand that uses it: --lcm-url, else
  // $LCM_DEFAULT_URL, else LCM's own default. Taking the variable here
  // (rather than leaving it to LCM) lets messages name the URL in use.
  const auto add_lcm_url = [](CLI::App* sub, std::string& url, const char* when = "") {
    sub->add_option(
           "--lcm-url", url,
           std::string("LCM URL") + when + " (default: $LCM_DEFAULT_URL, then LCM's default)")
        ->envname("LCM_DEFAULT_URL");
  };

  RunCommand run_cmd;
  CLI::App* run_app = app.add_subcommand("run", "run the mixer process on the LCM bus");
  add_vehicle(run_app, run_cmd.common);
  add_lcm_url(run_app, run_cmd.lcm_url);
  run_app->add_flag("--check", run_cmd.check_only,
                    "validate the configuration and exit without touching the bus");
  run_app
      ->add_option("--max-cycles", run_cmd.max_cycles,
                   "stop by itself after this many loop cycles (0: until a signal)")
      ->check(CLI::NonNegativeNumber);
  run_app->add_flag("--lockstep", run_cmd.lockstep,
                    "one cycle per lockstep_t a simulator publishes on channels.lockstep, at its "
                    "time, instead of the timer (docs/lockstep.md)");
  run_app
      ->add_option("--lockstep-idle-s", run_cmd.lockstep_idle_s,
                   "with --lockstep: exit (status 3) once no tick has come for this many seconds "
                   "of wall time, the simulator gone (0: wait for ever)")
      ->check(CLI::Range(0.0, 86400.0))
      ->capture_default_str();
  run_app->add_option("--timing-report", run_cmd.timing_report,
                      "at the end of the run, write its loop timing to this file as JSON "
                      "(wake-up lateness and period percentiles, the largest and when, "
                      "overruns, kernel drops, the scheduling granted)");

  OutputCommand output_cmd;
  CLI::App* output_app = app.add_subcommand(
      "output", "drive the ESC pins from motor_pwm_t (the hardware: section), with its failsafe");
  add_vehicle(output_app, output_cmd.common);
  add_lcm_url(output_app, output_cmd.lcm_url);
  output_app->add_flag("--check", output_cmd.check_only,
                       "validate the configuration and its hardware section and exit");
  output_app->add_flag("--disarm", output_cmd.disarm_only,
                       "write the disarmed pulses once and exit (for a supervisor's stop hook)");
  output_app
      ->add_option("--max-seconds", output_cmd.max_run_s,
                   "stop by itself after this long, disarmed (0: until a signal)")
      ->check(CLI::NonNegativeNumber);

  KeygenCommand keygen_cmd;
  CLI::App* keygen_app = app.add_subcommand(
      "keygen", "write a new key for signed messages (mode 0600; never overwrites)");
  keygen_app->add_option("file", keygen_cmd.path, "where to write it")->required();

  ImportPx4Command import_cmd;
  CLI::App* import_app = app.add_subcommand(
      "import", "turn another stack's description of a vehicle into a motormix configuration");
  import_app->require_subcommand(1);
  CLI::App* import_px4_app = import_app->add_subcommand(
      "px4-params",
      "a PX4 airframe's parameters (QGroundControl .params, or a flight log .ulg) as a "
      "configuration; what is not mapped is listed on stderr");
  import_px4_app->add_option("file", import_cmd.path, ".params or .ulg")
      ->required()
      ->check(CLI::ExistingFile);
  import_px4_app->add_option("-o,--out", import_cmd.out,
                             "write the configuration here (default: standard output)");
  import_px4_app->add_flag("--force", import_cmd.force, "overwrite --out if it exists");
  ImportUlogCommand import_ulog_cmd;
  CLI::App* import_ulog_app = import_app->add_subcommand(
      "ulog",
      "a PX4 flight log (.ulg) as an LCM log for motormix replay and lcm-logplayer: PX4's "
      "torque and thrust setpoints as setpoint and pid, rates and attitude, ESC reports, and "
      "PX4's own motor commands on a channel of their own for comparison");
  import_ulog_app->add_option("flight", import_ulog_cmd.ulog, "the PX4 flight log (.ulg)")
      ->required()
      ->check(CLI::ExistingFile);
  import_ulog_app->add_option("out", import_ulog_cmd.out, "the LCM log to write")->required();
  import_ulog_app->add_option("--config", import_ulog_cmd.config_path,
                              "take channel names and the motor count from this configuration "
                              "(default: motormix's channels, CA_ROTOR_COUNT motors)");
  import_ulog_app
      ->add_option("--reference", import_ulog_cmd.reference,
                   "the channel for PX4's own motor commands")
      ->capture_default_str();
  import_ulog_app->add_flag("--force", import_ulog_cmd.force, "overwrite the output if it exists");

  MixCommand mix_cmd;
  CLI::App* mix_app = app.add_subcommand(
      "mix", "evaluate the configured mixer once, as if armed with fresh inputs");
  add_vehicle(mix_app, mix_cmd.common);
  mix_app->add_option("--throttle", mix_cmd.throttle, "collective thrust 0..1 (ground: -1..1)");
  mix_app->add_option("--roll", mix_cmd.roll, "roll demand -1..1");
  mix_app->add_option("--pitch", mix_cmd.pitch, "pitch demand -1..1");
  mix_app->add_option("--yaw", mix_cmd.yaw, "yaw demand -1..1");
  mix_app->add_flag("--json", mix_cmd.json, "print one JSON object");
  mix_app->add_flag("--batch", mix_cmd.batch,
                    "read demands from standard input, one 'roll pitch yaw throttle' per line, and "
                    "print one JSON object per line");
  mix_app->add_option("--battery-voltage", mix_cmd.battery_voltage,
                      "apply battery compensation for this pack voltage (unfiltered)");
  mix_app
      ->add_option("--failed", mix_cmd.failed,
                   "treat these motors as failed: numbers as motormix matrix prints them, or "
                   "names (added to mixer.failed_motors)")
      ->delimiter(',');

  MatrixCommand matrix_cmd;
  CLI::App* matrix_app =
      app.add_subcommand("matrix", "print the mixing matrix of a configuration or a preset");
  add_vehicle(matrix_app, matrix_cmd.common);
  matrix_app->add_option("--format", matrix_cmd.format, "output format")
      ->check(CLI::IsMember(motormix::names_in(motormix::config::kMatrixFormatNames)));

  ReplayCommand replay_cmd;
  CLI::App* replay_app = app.add_subcommand(
      "replay", "run the mixer offline over a flight log (log time as the clock)");
  add_vehicle(replay_app, replay_cmd.common);
  replay_app->add_option("in", replay_cmd.in_log, "input LCM event log")
      ->required()
      ->check(CLI::ExistingFile);
  replay_app->add_option("out", replay_cmd.out_log, "output LCM event log (inputs + outputs)")
      ->required();
  replay_app->add_flag("--every-input", replay_cmd.every_input,
                       "also run a cycle right after every input event (golden files)");
  replay_app
      ->add_option("--max-gap", replay_cmd.max_gap_s,
                   "seconds between consecutive events beyond which time is discontinuous "
                   "(no cycles are run across; default 10)")
      ->check(CLI::Range(0.001, 86400.0));
  replay_app->add_flag("--verify", replay_cmd.verify,
                       "check every event's signature with security.key_file (per-channel "
                       "report; exit 5 if any is refused) and mix as under security.mode require");
  replay_app
      ->add_option("--reference", replay_cmd.reference,
                   "a channel of another mixer's motor_pwm_t to compare with, when the log holds "
                   "it (motormix import ulog puts PX4's there); empty: none")
      ->capture_default_str();

  SignLogCommand sign_log_cmd;
  CLI::App* sign_log_app = app.add_subcommand(
      "sign-log", "copy a flight log with every event signed with security.key_file");
  add_vehicle(sign_log_app, sign_log_cmd.common);
  sign_log_app->add_option("in", sign_log_cmd.in_log, "input LCM event log")
      ->required()
      ->check(CLI::ExistingFile);
  sign_log_app->add_option("out", sign_log_cmd.out_log, "signed copy")->required();
  sign_log_app->add_flag("--now", sign_log_cmd.now,
                         "stamp the signatures from now (keeping the spacing), so that a live "
                         "mixer takes the copy once when lcm-logplayer plays it");

  MonitorCommand monitor_cmd;
  CLI::App* monitor_app =
      app.add_subcommand("monitor", "live terminal view of a running motormix on the bus");
  add_vehicle(monitor_app, monitor_cmd.common,
              "configuration of the running mixer (channels, motor names, unit)",
              /*required=*/false);
  add_lcm_url(monitor_app, monitor_cmd.lcm_url);
  monitor_app->add_option("--status-channel", monitor_cmd.status_channel,
                          "mixer_status_t channel (default: from --config, else MIXER_STATUS)");
  monitor_app->add_option("--pwm-channel", monitor_cmd.pwm_channel,
                          "motor_pwm_t channel (default: from --config, else MOTOR_PWM)");
  monitor_app->add_flag("--once", monitor_cmd.once, "print one snapshot and exit");
  monitor_app
      ->add_option("--wait", monitor_cmd.wait_s,
                   "seconds to wait for a status before giving up (default 3)")
      ->check(CLI::Range(0.1, 600.0));
  monitor_app
      ->add_option("--duration", monitor_cmd.duration_s,
                   "stop the live view by itself after this many seconds (default: until Ctrl-C)")
      ->check(CLI::Range(0.0, 1e6));

  SimCommand sim_cmd;
  CLI::App* sim_app = app.add_subcommand(
      "sim",
      "fly the configuration in closed loop: lockstep (default) or live beside motormix run");
  add_vehicle(sim_app, sim_cmd.common);
  sim_app->add_option("--scenario", sim_cmd.scenario,
                      "a shipped scenario (hover, steps, flips, motor_out, battery_sag, gusts, "
                      "drive, spin_landing, spin_landing_gusts, two_motor_landing, "
                      "two_motor_landing_gusts) or a YAML file (default hover)");
  sim_app->add_option("--fail", sim_cmd.fail,
                      "fail a motor: MOTOR@SECONDS[:KIND], motor numbered as motormix matrix "
                      "prints it or named; KIND stop (default), half_thrust, intermittent, "
                      "desync, telemetry, prop_lost or prop_damaged (repeatable)");
  sim_app->add_flag("--no-scenario-failures", sim_cmd.no_scenario_failures,
                    "drop the scenario's own motor failures (motor_out, spin_landing): with "
                    "--fail, another motor fails instead");
  sim_app->add_flag("--undetected", sim_cmd.undetected,
                    "nothing outside motormix reports failed motors on motor_status: only "
                    "motormix's own detector (failure_detection:) can find them");
  sim_app->add_option("--seed", sim_cmd.seed, "seed of the sensor noise (default 1)");
  sim_app->add_flag("--json", sim_cmd.json, "print only the JSON result");
  sim_app->add_option("--log", sim_cmd.log_path, "write the run as an LCM event log (lockstep)");
  sim_app->add_flag("--lcm", sim_cmd.lcm,
                    "run in real time on the bus against a separate motormix run");
  add_lcm_url(sim_app, sim_cmd.lcm_url, " with --lcm");
  sim_app->add_flag("--lockstep", sim_cmd.lockstep,
                    "with --lcm: drive a `motormix run --lockstep` tick by tick, as fast as both "
                    "go, whatever the machine's load (docs/lockstep.md)");
  sim_app->add_flag("!--no-controller", sim_cmd.controller,
                    "with --lcm: publish no setpoint or pid (your controller flies from "
                    "VEHICLE_STATE)");
  sim_app->add_option("--duration", sim_cmd.duration_s, "seconds to run instead of the scenario's")
      ->check(CLI::Range(0.01, 86400.0));
  sim_app->add_flag("--ideal", sim_cmd.ideal,
                    "switch every piece of realism off: rotors without momentum, equal spin-up "
                    "and spin-down, an unfiltered gyro without vibration, instant ESC telemetry, "
                    "no ground effect (the simulator before 0.10)");
  sim_app->add_option("--realism", sim_cmd.realism,
                      "switch pieces on or off, after --ideal: PIECE=on|off,... with PIECE "
                      "rotor_momentum, spin_down, imu, esc_latency or ground_effect");
  sim_app->add_option("--truth", sim_cmd.truth,
                      "model error: the simulated vehicle's FACTOR=x,... against its "
                      "configuration, FACTOR mass, inertia, drag, time_constant or rotor_inertia "
                      "(0.1..10)");

  MotorTestCommand test_cmd;
  CLI::App* test_app = app.add_subcommand(
      "motor-test", "spin one motor alone through a running, disarmed motormix run");
  add_vehicle(test_app, test_cmd.common);
  add_lcm_url(test_app, test_cmd.lcm_url);
  auto* test_motor = test_app->add_option(
      "--motor", test_cmd.motor, "the motor: number as motormix matrix prints it, or name");
  auto* test_sequence = test_app->add_flag("--sequence", test_cmd.sequence,
                                           "every motor in turn, saying where it is and its spin");
  test_motor->excludes(test_sequence);
  test_app
      ->add_option("--throttle", test_cmd.throttle,
                   "command 0..motor_test.max_throttle (default 0.1)")
      ->check(CLI::Range(0.0, 1.0));
  test_app->add_option("--seconds", test_cmd.seconds, "how long (default 2)")
      ->check(CLI::Range(0.0, 60.0));
  test_app
      ->add_option("--wait", test_cmd.wait_s, "seconds to wait for the mixer's answer (default 3)")
      ->check(CLI::Range(0.1, 60.0));

  EscCalibrateCommand esc_cmd;
  CLI::App* esc_app = app.add_subcommand(
      "esc-calibrate", "teach PWM ESCs their range: maximum, your Enter, minimum, disarmed");
  add_vehicle(esc_app, esc_cmd.common);
  add_lcm_url(esc_app, esc_cmd.lcm_url);
  esc_app->add_flag("--props-off", esc_cmd.props_off,
                    "required: the propellers are off (every motor runs at full command)");
  esc_app
      ->add_option("--timeout", esc_cmd.timeout_s,
                   "seconds at the maximum waiting for Enter before aborting (default 30)")
      ->check(CLI::Range(0.1, 600.0));
  esc_app
      ->add_option("--min-seconds", esc_cmd.min_seconds,
                   "seconds at the minimum before disarming (default 4)")
      ->check(CLI::Range(0.1, 60.0));

  EscCommandCommand escc_cmd;
  CLI::App* escc_app = app.add_subcommand(
      "esc-command",
      "send a DShot special command (beep, spin direction, 3D, save) to ESCs through a running "
      "motormix output, only while every output is disarmed");
  add_vehicle(escc_app, escc_cmd.common);
  add_lcm_url(escc_app, escc_cmd.lcm_url);
  escc_app
      ->add_option("command", escc_cmd.command,
                   "beep1..beep5, esc-info, spin-direction-1, spin-direction-2, 3d-off, 3d-on, "
                   "save, spin-normal, spin-reversed, or a number 1..47")
      ->required();
  auto* escc_motor =
      escc_app->add_option("--motor", escc_cmd.motors,
                           "a motor: number as motormix matrix prints it, or name (repeatable)");
  auto* escc_all = escc_app->add_flag("--all", escc_cmd.all, "every motor");
  escc_motor->excludes(escc_all);
  escc_app
      ->add_option("--wait", escc_cmd.wait_s,
                   "seconds to wait for motormix output's status (default 2)")
      ->check(CLI::Range(0.1, 60.0));

  try {
    app.parse(argc, argv);
    for (const auto& [sub, common] : vehicles) {
      if (sub->parsed() && common->config_path.empty() == common->preset.empty()) {
        throw CLI::RequiredError(sub->get_name() + ": exactly one of --config and --preset");
      }
    }
    if (test_app->parsed() && test_cmd.motor.empty() && !test_cmd.sequence) {
      throw CLI::RequiredError("--motor or --sequence");
    }
    if (escc_app->parsed() && escc_cmd.motors.empty() && !escc_cmd.all) {
      throw CLI::RequiredError("--motor or --all");
    }
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return kExitUsage;
  }
  if (parse_only) {
    // The vehicle named must load too: a configuration shown in the guide
    // is checked with the command that uses it. The subcommands that name
    // more (a scenario, motors to fail, a motor to test, a battery voltage)
    // resolve it all and stop before doing anything.
    mix_cmd.parse_only = sim_cmd.parse_only = test_cmd.parse_only = escc_cmd.parse_only = true;
    if (mix_app->parsed()) return mix(mix_cmd);
    if (sim_app->parsed()) return sim(sim_cmd);
    if (test_app->parsed()) return motor_test(test_cmd);
    if (escc_app->parsed()) return esc_command(escc_cmd);
    for (const auto& [sub, common] : vehicles) {
      if (sub->parsed() && !load_vehicle(*common, sub->get_name().c_str())) return kExitUsage;
    }
    return kExitOk;
  }
  if (run_app->parsed()) return run(run_cmd);
  if (output_app->parsed()) return output(output_cmd);
  if (keygen_app->parsed()) return keygen(keygen_cmd);
  if (import_px4_app->parsed()) return import_px4(import_cmd);
  if (import_ulog_app->parsed()) return import_ulog(import_ulog_cmd);
  if (mix_app->parsed()) return mix(mix_cmd);
  if (matrix_app->parsed()) return matrix(matrix_cmd);
  if (replay_app->parsed()) return replay(replay_cmd);
  if (sign_log_app->parsed()) return sign_log(sign_log_cmd);
  if (monitor_app->parsed()) return monitor(monitor_cmd);
  if (sim_app->parsed()) return sim(sim_cmd);
  if (test_app->parsed()) return motor_test(test_cmd);
  if (esc_app->parsed()) return esc_calibrate(esc_cmd);
  if (escc_app->parsed()) return esc_command(escc_cmd);
  return kExitUsage;
}
