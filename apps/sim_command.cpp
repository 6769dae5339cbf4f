// `motormix sim`: wiring of the simulator (src/sim) to the command line.

#include "commands.hpp"

#include <motormix/config/build_mixer.hpp>
#include <motormix/config/load_config.hpp>
#include "sim/bus/live_sim.hpp"
#include "sim/bus/sim_log.hpp"
#include "sim/lockstep.hpp"
#include "sim/result_json.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <iostream>

namespace motormix::app {

namespace {

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

}  // namespace

int sim(const SimCommand& cmd) {
  if (cmd.lockstep && !cmd.lcm) {
    std::cerr << "motormix sim: --lockstep drives a motormix run on the bus: it needs --lcm (the "
                 "simulator alone is in lockstep already)\n";
    return kExitUsage;
  }
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
  if (cmd.ideal) options.realism = sim::Realism::ideal();
  if (auto error = sim::apply_switches(options.realism, cmd.realism)) {
    std::cerr << "motormix sim: --realism " << cmd.realism << ": " << *error << "\n";
    return kExitUsage;
  }
  if (auto error = sim::parse_model_error(options.realism.truth, cmd.truth)) {
    std::cerr << "motormix sim: --truth " << cmd.truth << ": " << *error << "\n";
    return kExitUsage;
  }
  for (const std::string& f : cmd.fail) {
    sim::MotorFailure failure;
    if (!parse_failure(f, *config, failure)) {
      std::cerr << "motormix sim: --fail " << f << ": expected MOTOR@SECONDS[:KIND] with MOTOR 1.."
                << config->motors() << " or a motor name and KIND one of "
                << joined_names(sim::kFailureKindNames) << "\n";
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
      live.lockstep = cmd.lockstep;
      sim::LiveResult result;
      if (!sim::run_live(*config, *scenario, live, result, std::cerr)) return kExitRuntime;
      j = sim::result_json(result.sim, wheeled);
      j["mode"] = cmd.lockstep ? "lcm_lockstep" : "live";
      j["pwm_received"] = result.pwm_received;
      j["pwm_rejected"] = result.pwm_rejected;
      j["statuses_received"] = result.statuses_received;
      const bus::Refusals& refused = result.refused;
      j["refused"] = {{"signature", refused.signature},   {"truncated", refused.truncated},
                      {"trailing", refused.trailing},     {"wrong_type", refused.wrong_type},
                      {"bad_length", refused.bad_length}, {"undecodable", refused.undecodable}};
      j["interrupted"] = result.interrupted;
      if (cmd.lockstep) j["lockstep_lost"] = result.lockstep_lost;
      sim::add_detections(j, result.sim, *config);
      sim::add_spin(j, result.sim, *config, result.sim.failures);
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
      if (log && !log->close()) {
        std::cerr << "motormix sim: cannot write " << cmd.log_path << " (disk full or I/O error)\n";
        return kExitRuntime;
      }
      j = sim::result_json(r, wheeled);
      j["mode"] = "lockstep";
      sim::add_detections(j, r, *config);
      sim::add_spin(j, r, *config, r.failures);
      outcomes = r.failures;
    }
  } catch (const std::exception& e) {
    std::cerr << "motormix sim: " << e.what() << "\n";
    return kExitUsage;
  }
  j["scenario"] = scenario->name;
  j["vehicle"] = config->name;
  j["strategy"] = config::to_string(config->strategy);
  if (config->strategy == config::Strategy::kPrioritized) j["airmode"] = to_string(config->airmode);
  j["seed"] = cmd.seed;
  j["realism"] = sim::describe(options.realism);
  j["failures"] = sim::failures_json(outcomes, *config, cmd.undetected);
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
  if (j.value("lockstep_lost", false)) return kExitRuntime;
  return j["crashed"].get<bool>() ? kExitCrashed : kExitOk;
}

}  // namespace motormix::app
