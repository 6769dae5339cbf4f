// `motormix sim`: wiring of the simulator (src/sim) to the command line.

#include "commands.hpp"

#include <motormix/config/build_mixer.hpp>
#include <motormix/config/load_config.hpp>
#include "sim/bus/live_sim.hpp"
#include "sim/bus/sim_log.hpp"
#include "sim/lockstep.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <iostream>

namespace motormix::app {

namespace {

const char* airmode_name(Airmode a) {
  return a == Airmode::kRollPitch      ? "roll_pitch"
         : a == Airmode::kRollPitchYaw ? "roll_pitch_yaw"
                                       : "off";
}

// "3@6.5" or "FL@6.5:desync": motor number as `motormix matrix` prints it,
// or name; the kind of failure after a colon (stop when none).
bool parse_failure(const std::string& text_in, const config::Config& config,
                   sim::MotorFailure& out) {
  std::string text = text_in;
  out.kind = sim::FailureKind::kStop;
  if (const auto colon = text.find(':'); colon != std::string::npos) {
    const auto kind = sim::failure_kind(text.substr(colon + 1));
    if (!kind) return false;
    out.kind = *kind;
    text.resize(colon);
  }
  const auto at = text.find('@');
  if (at == std::string::npos || at == 0 || at + 1 == text.size()) return false;
  const std::string motor = text.substr(0, at);
  char* end = nullptr;
  const double seconds = std::strtod(text.c_str() + at + 1, &end);
  if (*end != '\0' || !std::isfinite(seconds) || seconds < 0) return false;
  out.at_s = seconds;
  out.motor = config.motor_index(motor);
  return out.motor >= 0;
}

// Each failure: which motor, when, what kind, whether something outside
// motormix reported it, and what motormix's own detector made of it.
nlohmann::json failures_json(const std::vector<sim::FailureOutcome>& outcomes,
                             const config::Config& config, bool undetected) {
  nlohmann::json failures = nlohmann::json::array();
  const auto name = [&](int m) { return config.motor_names()[static_cast<std::size_t>(m)]; };
  for (const sim::FailureOutcome& o : outcomes) {
    nlohmann::json f = {{"motor", name(o.failure.motor)},
                        {"at_s", o.failure.at_s},
                        {"kind", sim::to_string(o.failure.kind)},
                        {"reported", !undetected && sim::reported_outside(o.failure.kind)}};
    f["detected_at_s"] = o.detected_at_s >= 0 ? nlohmann::json(o.detected_at_s) : nlohmann::json();
    f["detected_motor"] =
        o.detected_motor >= 0 ? nlohmann::json(name(o.detected_motor)) : nlohmann::json();
    f["detected_by"] =
        o.detected_at_s >= 0 ? nlohmann::json(to_string(o.detected_by)) : nlohmann::json();
    failures.push_back(f);
  }
  return failures;
}

// What motormix's own detector declared: working motors stopped, and every
// declaration (live: as its status reported them).
void add_detections(nlohmann::json& j, const sim::SimResult& r, const config::Config& config) {
  j["false_detections"] = r.false_detections;
  nlohmann::json declared = nlohmann::json::array();
  for (const sim::SimResult::Declaration& d : r.declarations) {
    declared.push_back({{"at_s", d.at_s},
                        {"motor", config.motor_names()[static_cast<std::size_t>(d.motor)]},
                        {"by", to_string(d.source)}});
  }
  j["detections"] = declared;
}

// A quad that lost one motor: the spin and thrusts it settled at before
// touchdown, next to the relaxed-hover equilibrium of the same vehicle.
void add_spin(nlohmann::json& j, const sim::SimResult& r, const config::Config& config,
              const std::vector<sim::FailureOutcome>& outcomes) {
  if (!config.motor_loss || outcomes.empty() || r.settled_thrust_n.empty()) return;
  const int failed = outcomes.front().failure.motor;
  const SpinEquilibrium eq = solve_spin_equilibrium(config.motor_loss->model, failed,
                                                    config.motor_loss->settings.spin_rate_rad_s);
  nlohmann::json thrust = nlohmann::json::array();
  for (int i = 0, w = 0; i < config.motors(); ++i) {
    thrust.push_back(i == failed ? 0.0 : eq.thrust_n[w++]);
  }
  j["spin"] = {
      {"settled", {{"rate_rad_s", r.settled_spin_rate_rad_s}, {"thrust_n", r.settled_thrust_n}}},
      {"equilibrium",
       {{"rate_rad_s", eq.rates.norm()},
        {"thrust_n", thrust},
        {"axis_tilt_deg", eq.axis_tilt_deg}}}};
}

nlohmann::json to_json(const sim::SimResult& r, bool wheeled) {
  nlohmann::json j;
  j["crashed"] = r.crashed;
  if (r.crashed) {
    j["crash_reason"] = r.crash_reason;
    j["crash_time_s"] = r.crash_time_s;
  }
  if (wheeled) {
    j["speed_error_rms_mps"] = r.speed_error_rms_mps;
    j["yaw_rate_error_rms_dps"] = r.yaw_rate_error_rms_dps;
  }
  j["armed_s"] = r.armed_s;
  if (!wheeled) {
    j["reached_altitude"] = r.reached_altitude;
    j["altitude_error_max_m"] = r.altitude_error_max_m;
  }
  j["attitude_error_rms_deg"] = r.attitude_error_rms_deg;
  j["attitude_error_max_deg"] = r.attitude_error_max_deg;
  j["yaw_error_rms_deg"] = r.yaw_error_rms_deg;
  j["altitude_loss_m"] = r.altitude_loss_m;
  if (!wheeled) j["failure_attitude_error_max_deg"] = r.failure_attitude_error_max_deg;
  if (!wheeled) {
    const auto or_null = [](double v) { return v >= 0 ? nlohmann::json(v) : nlohmann::json(); };
    j["touchdown_speed_mps"] = or_null(r.touchdown_speed_mps);
    j["touchdown_time_s"] = or_null(r.touchdown_time_s);
    j["drift_m"] = r.drift_m;
    j["max_spin_rate_rad_s"] = r.max_spin_rate_rad_s;
    j["max_thrust_axis_tilt_deg"] = r.max_thrust_axis_tilt_deg;
  }
  j["saturated_fraction"] = r.saturated_fraction;
  j["min_battery_v"] = r.min_battery_v;
  j["final_charge"] = r.final_charge;
  j["failsafe_events"] = r.failsafe_events;
  j["cycles"] = r.cycles;
  j["sim_seconds"] = r.sim_seconds;
  j["wall_seconds"] = r.wall_seconds;
  j["realtime_factor"] = r.wall_seconds > 0 ? r.sim_seconds / r.wall_seconds : 0.0;
  return j;
}

}  // namespace

int sim(const SimCommand& cmd) {
  std::optional<config::Config> config;
  std::optional<sim::Scenario> scenario;
  try {
    config = load_vehicle(cmd.common, "sim");
    if (!config) return kExitUsage;
    scenario = sim::load_scenario(cmd.scenario);
    if (cmd.no_scenario_failures) {
      auto& events = scenario->timeline;
      events.erase(std::remove_if(events.begin(), events.end(),
                                  [](const sim::ScenarioEvent& e) { return e.fail.has_value(); }),
                   events.end());
    }
    if (!config->vehicle_model.incomplete.empty())
      throw config::ConfigError(config->vehicle_model.incomplete);
    sim::scenario_config(*config, *scenario);  // the scenario fits the vehicle
  } catch (const config::ConfigError& e) {
    std::cerr << "motormix sim: " << e.what() << "\n";
    return kExitUsage;
  }
  sim::SimOptions options;
  options.seed = cmd.seed;
  options.undetected = cmd.undetected;
  options.duration_s = cmd.duration_s;
  for (const std::string& f : cmd.fail) {
    sim::MotorFailure failure;
    if (!parse_failure(f, *config, failure)) {
      std::cerr << "motormix sim: --fail " << f << ": expected MOTOR@SECONDS[:KIND] with MOTOR 1.."
                << config->motors() << " or a motor name and KIND one of " << sim::kFailureKindNames
                << "\n";
      return kExitUsage;
    }
    options.failures.push_back(failure);
  }
  if (!cmd.lcm && !cmd.controller) {
    std::cerr << "motormix sim: --no-controller needs --lcm (a controller of your own flies the "
                 "vehicle over the bus)\n";
    return kExitUsage;
  }
  if (cmd.lcm && !cmd.log_path.empty()) {
    std::cerr << "motormix sim: --log is for lockstep runs; record a live run with lcm-logger\n";
    return kExitUsage;
  }
  if (cmd.parse_only) {
    try {
      const sim::ScenarioClock clock(*scenario, *config, options.failures);  // motors exist
      (void)clock;
    } catch (const config::ConfigError& e) {
      std::cerr << "motormix sim: " << e.what() << "\n";
      return kExitUsage;
    }
    return kExitOk;
  }

  const bool wheeled = config->thrust_range() == ThrustRange::kBipolar;
  nlohmann::json j;
  // The run's failures and what the detector made of them (filled by the
  // run; as flown if it throws).
  std::vector<sim::FailureOutcome> outcomes;
  const sim::ScenarioClock failure_clock(*scenario, *config, options.failures);
  for (const sim::MotorFailure& f : failure_clock.failures()) {
    outcomes.push_back({f, -1.0, -1, DetectionSource::kNone});
  }
  try {
    if (cmd.lcm) {
      sim::LiveOptions live;
      live.sim = options;
      live.lcm_url = cmd.lcm_url;
      live.controller = cmd.controller;
      sim::LiveResult result;
      if (!sim::run_live(*config, *scenario, live, result, std::cerr)) return kExitRuntime;
      j = to_json(result.sim, wheeled);
      j["mode"] = "live";
      j["pwm_received"] = result.pwm_received;
      j["pwm_rejected"] = result.pwm_rejected;
      j["statuses_received"] = result.statuses_received;
      const bus::Refusals& refused = result.refused;
      j["refused"] = {{"signature", refused.signature},   {"truncated", refused.truncated},
                      {"trailing", refused.trailing},     {"wrong_type", refused.wrong_type},
                      {"bad_length", refused.bad_length}, {"undecodable", refused.undecodable}};
      j["interrupted"] = result.interrupted;
      add_detections(j, result.sim, *config);
      add_spin(j, result.sim, *config, result.sim.failures);
      outcomes = result.sim.failures;
    } else {
      std::optional<sim::SimLogWriter> log;
      if (!cmd.log_path.empty()) {
        log.emplace(cmd.log_path, *config);
        if (!log->good()) {
          std::cerr << "motormix sim: cannot write " << cmd.log_path << "\n";
          return kExitRuntime;
        }
      }
      sim::FrameObserver observer;
      if (log) observer = [&log](const sim::SimFrame& f) { log->write(f, *f.counters); };
      const sim::SimResult r =
          sim::run_lockstep(*config, config::build_mixer(*config), *scenario, options, observer);
      j = to_json(r, wheeled);
      j["mode"] = "lockstep";
      add_detections(j, r, *config);
      add_spin(j, r, *config, r.failures);
      outcomes = r.failures;
    }
  } catch (const std::exception& e) {
    std::cerr << "motormix sim: " << e.what() << "\n";
    return kExitUsage;
  }
  j["scenario"] = scenario->name;
  j["vehicle"] = config->name;
  j["strategy"] = config::to_string(config->strategy);
  if (config->strategy == config::Strategy::kPrioritized)
    j["airmode"] = airmode_name(config->airmode);
  j["seed"] = cmd.seed;
  j["failures"] = failures_json(outcomes, *config, cmd.undetected);
  if (!cmd.json) {
    std::cerr << "motormix sim: " << config->name << " (" << config::to_string(config->strategy)
              << "), scenario " << scenario->name << ", " << j["sim_seconds"].get<double>()
              << " s simulated in " << j["wall_seconds"].get<double>() << " s: "
              << (j["crashed"].get<bool>()
                      ? "CRASHED (" + j["crash_reason"].get<std::string>() + ")"
                      : std::string("not crashed"))
              << "\n";
  }
  std::cout << j.dump() << "\n";
  return j["crashed"].get<bool>() ? kExitCrashed : kExitOk;
}

}  // namespace motormix::app
