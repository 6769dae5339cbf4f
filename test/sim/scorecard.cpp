// sim_scorecard: every strategy and airmode of motormix, and the PX4-style
// sequential desaturation of test/reference, flown in closed loop through
// every scenario (and every single motor failure, reported and undetected),
// worst case over seeds. Writes one JSON object per cell (vehicle, column,
// scenario) to standard output; tools/sim_scorecard.py turns them into
// SIM.md and plots. Run by scripts/sim-scorecard.
//
//   sim_scorecard SOURCE_DIR [--seeds N] [--jobs N] [--vehicles a,b] [--check]
//
// --check (ctest): prints nothing per cell, checks the targets and
// exits 1 on a miss: hexa X and octo X with optimal and prioritized survive
// any one motor stopping at hover, reported after 100 ms (not crashed,
// altitude loss <= 1 m, roll/pitch error <= 15 degrees), and prioritized with
// an airmode is never more than 5 % worse than the PX4-style row with the
// same airmode on attitude RMS (nor crashes where it does not).

#include "reference/px4_sequential_desaturation.hpp"
#include "sim/lockstep.hpp"
#include "sim/result_json.hpp"

#include <motormix/allocation/motor_failure.hpp>
#include <motormix/config/build_mixer.hpp>
#include <motormix/config/load_config.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace motormix::sim {
namespace {

// The PX4-style baseline as a motormix Allocator, reporting like every
// strategy (describe_allocation against the basis' effectiveness).
class Px4StyleAllocator final : public Allocator {
 public:
  Px4StyleAllocator(const MixingBasis& basis, reference::Px4Airmode airmode)
      : px4_(basis.mixing, airmode),
        effectiveness_(basis.effectiveness),
        limits_(CommandRange{0.0, 1.0}, basis.controlled),
        motors_(static_cast<int>(basis.mixing.rows())) {}
  std::string_view name() const override { return "px4_sequential_desaturation"; }
  int motors() const override { return motors_; }
  AllocationResult allocate(const AxisVector& demand, MotorVector& commands) const override {
    px4_.allocate({demand[0], demand[1], demand[2], demand[3]});
    commands.resize(motors_);
    for (int i = 0; i < motors_; ++i) commands[i] = px4_.actuator(i);
    return describe_allocation(effectiveness_, demand, commands, limits_);
  }

 private:
  mutable reference::SequentialDesaturation<double> px4_;
  EffectivenessMatrix effectiveness_;
  CycleConstants limits_;
  int motors_;
};

struct Column {
  std::string name;
  std::vector<std::string> overrides;  // for motormix strategies
  bool px4 = false;
  reference::Px4Airmode airmode = reference::Px4Airmode::kDisabled;
};

std::vector<Column> columns() {
  const auto prio = [](const char* airmode) {
    return std::vector<std::string>{"mixer.strategy=prioritized",
                                    std::string("mixer.prioritized.airmode=") + airmode};
  };
  return {
      {"legacy_budget", {"mixer.strategy=legacy_budget"}},
      {"budget", {"mixer.strategy=budget"}},
      {"shift", {"mixer.strategy=shift"}},
      {"clip", {"mixer.strategy=clip"}},
      {"prioritized/off", prio("off")},
      {"prioritized/roll_pitch", prio("roll_pitch")},
      {"prioritized/roll_pitch_yaw", prio("roll_pitch_yaw")},
      {"optimal", {"mixer.strategy=optimal"}},
      {"px4/off", {}, true, reference::Px4Airmode::kDisabled},
      {"px4/roll_pitch", {}, true, reference::Px4Airmode::kRollPitch},
      {"px4/roll_pitch_yaw", {}, true, reference::Px4Airmode::kRollPitchYaw},
  };
}

Mixer px4_mixer(const config::Config& c, reference::Px4Airmode airmode) {
  const CommandRange range = config::command_range(c);
  FailurePlan plan = prepare_failures(c.mixing, range, 0.5,
                                      [airmode](const FailureMixing&, const MixingBasis& basis) {
                                        return std::unique_ptr<const Allocator>(
                                            std::make_unique<Px4StyleAllocator>(basis, airmode));
                                      });
  return Mixer(std::make_unique<Px4StyleAllocator>(MixingBasis(c.mixing), airmode),
               OutputStage(c.outputs), c.thrust_range(), std::move(plan));
}

struct Case {
  std::string vehicle;  // config file stem
  std::string scenario;
  int failed_motor = -1;  // motor_out: 0-based
  bool undetected = false;
  // Detected mode: never reported, found by motormix's own detector from
  // these sources ("telemetry", "rates", "both", "outputs"); empty: off.
  std::string detect;
};

// failure_detection.sources for a detected mode.
std::string detection_sources(const std::string& detect) {
  return detect == "both" ? "[telemetry, rates]" : "[" + detect + "]";
}

struct Cell {
  const Column* column;
  Case c;
};

nlohmann::json run_cell(const std::string& source, const Cell& cell, int seeds) {
  nlohmann::json out;
  out["vehicle"] = cell.c.vehicle;
  out["column"] = cell.column->name;
  std::string label = cell.c.scenario;
  if (cell.c.failed_motor >= 0) {
    label += " m" + std::to_string(cell.c.failed_motor + 1) +
             (!cell.c.detect.empty() ? " detected " + cell.c.detect
              : cell.c.undetected    ? " undetected"
                                     : " reported");
  }
  out["scenario"] = label;
  std::vector<std::string> overrides = cell.column->overrides;
  if (!cell.c.detect.empty()) {
    overrides.push_back("failure_detection.sources=" + detection_sources(cell.c.detect));
  }
  config::Config config;
  try {
    config = config::load_config_file(source + "/config/" + cell.c.vehicle + ".yaml", overrides);
  } catch (const config::ConfigError& e) {
    out["skipped"] = e.what();
    // Expected only where motormix refuses by design: the budget strategies
    // on a ground vehicle (they assume motors that only push).
    const bool budget_column =
        cell.column->name == "budget" || cell.column->name == "legacy_budget";
    const config::Config base =
        config::load_config_file(source + "/config/" + cell.c.vehicle + ".yaml");
    if (budget_column && base.thrust_range() == ThrustRange::kBipolar) out["expected_skip"] = true;
    return out;
  }
  const bool wheeled = config.thrust_range() == ThrustRange::kBipolar;
  if (cell.column->px4 && wheeled) {
    out["skipped"] = "the PX4-style mixer is for multirotors";
    out["expected_skip"] = true;
    return out;
  }
  Scenario scenario = load_scenario(cell.c.scenario);
  SimOptions options;
  if (cell.c.failed_motor >= 0) {
    scenario.timeline.erase(
        std::remove_if(scenario.timeline.begin(), scenario.timeline.end(),
                       [](const ScenarioEvent& e) { return e.fail.has_value(); }),
        scenario.timeline.end());
    options.failures.push_back({cell.c.failed_motor, 6.0});
    options.undetected = cell.c.undetected;
  }
  SimResult worst;
  double wall = 0, sim_s = 0;
  double armed_fraction = 1.0;  // the least over the seeds
  bool reached = true;          // on every seed
  int landed_seeds = 0;         // touched down alive (a spin landing)
  // Detected mode: the slowest detection and the seeds missed or named wrong.
  double detected_ms = 0.0;
  int missed = 0, named_wrong = 0;
  for (int seed = 1; seed <= seeds; ++seed) {
    options.seed = static_cast<std::uint64_t>(seed);
    Mixer mixer =
        cell.column->px4 ? px4_mixer(config, cell.column->airmode) : config::build_mixer(config);
    const SimResult r = run_lockstep(config, std::move(mixer), scenario, options);
    wall += r.wall_seconds;
    sim_s += r.sim_seconds;
    // A quad's spin landing ends armed time at the touchdown (the loop
    // disarms): the share counts up to there.
    const bool landed = !r.crashed && r.touchdown_time_s > 0.0;
    const double flown_s = landed ? std::min(r.sim_seconds, r.touchdown_time_s) : r.sim_seconds;
    landed_seeds += landed ? 1 : 0;
    armed_fraction =
        std::min(armed_fraction, flown_s > 0 ? std::min(1.0, r.armed_s / flown_s) : 0.0);
    reached = reached && r.reached_altitude;
    if (!cell.c.detect.empty() && !r.failures.empty()) {
      const FailureOutcome& f = r.failures.front();
      if (f.detected_at_s < 0) {
        ++missed;
      } else {
        detected_ms = std::max(detected_ms, (f.detected_at_s - f.failure.at_s) * 1e3);
        if (f.detected_motor != f.failure.motor) ++named_wrong;
      }
    }
    if (r.crashed && !worst.crashed) {
      worst.crashed = true;
      worst.crash_reason = r.crash_reason;
      worst.crash_time_s = r.crash_time_s;
    }
    worst.attitude_error_rms_deg = std::max(worst.attitude_error_rms_deg, r.attitude_error_rms_deg);
    worst.attitude_error_max_deg = std::max(worst.attitude_error_max_deg, r.attitude_error_max_deg);
    worst.yaw_error_rms_deg = std::max(worst.yaw_error_rms_deg, r.yaw_error_rms_deg);
    worst.altitude_loss_m = std::max(worst.altitude_loss_m, r.altitude_loss_m);
    worst.saturated_fraction = std::max(worst.saturated_fraction, r.saturated_fraction);
    worst.speed_error_rms_mps = std::max(worst.speed_error_rms_mps, r.speed_error_rms_mps);
    worst.yaw_rate_error_rms_dps = std::max(worst.yaw_rate_error_rms_dps, r.yaw_rate_error_rms_dps);
  }
  // The worst over the seeds, named and computed as motormix sim names them.
  out.update(flight_errors_json(worst, wheeled));
  if (!cell.c.detect.empty()) {
    out["detected_ms"] = detected_ms;
    out["detection_missed"] = missed;
    out["named_wrong"] = named_wrong;
  }
  out["armed_fraction"] = armed_fraction;
  if (!wheeled) out["reached_altitude"] = reached;
  if (landed_seeds > 0) out["landed_seeds"] = landed_seeds;
  out["seeds"] = seeds;
  out["sim_seconds"] = sim_s;
  out["wall_seconds"] = wall;
  return out;
}

// with_detected: also the detected modes (the scorecard's tables; --check
// leaves them to detection_sim_tests, which checks the detector's targets).
std::vector<Case> cases(const std::string& source, const std::vector<std::string>& vehicles,
                        bool with_detected) {
  std::vector<Case> out;
  for (const std::string& v : vehicles) {
    const config::Config c = config::load_config_file(source + "/config/" + v + ".yaml");
    if (c.thrust_range() == ThrustRange::kBipolar) {
      out.push_back({v, "drive", -1, false, ""});
      continue;
    }
    for (const char* s : {"hover", "steps", "flips", "battery_sag", "gusts"})
      out.push_back({v, s, -1, false, ""});
    for (int m = 0; m < c.motors(); ++m) {
      out.push_back({v, "motor_out", m, false, ""});
      out.push_back({v, "motor_out", m, true, ""});
    }
    if (!with_detected) continue;
    for (const char* detect : {"telemetry", "rates", "both", "outputs"}) {
      // The outputs source needs six rotors (the configuration refuses it on fewer).
      if (std::string(detect) == "outputs" && c.motors() < 6) continue;
      for (int m = 0; m < c.motors(); ++m) out.push_back({v, "motor_out", m, true, detect});
    }
  }
  return out;
}

constexpr double kTargetAltitudeLossM = 1.0;
constexpr double kTargetAttitudeMaxDeg = 15.0;
constexpr double kPx4Margin = 1.05;
// Every cell must have flown: armed for at least this share of its
// simulated time (the scenarios arm within half a second), and an aircraft
// must have climbed to its commanded altitude; a vehicle left on the
// ground would otherwise score no loss and no error.
constexpr double kArmedFractionMin = 0.9;
// The motor-out target cells with every vehicle: hexa X (6 motors) and octo
// X (8), each with optimal and prioritized in three airmodes.
constexpr std::size_t kTargetCells = (6 + 8) * 4;

// The misses of the targets among `results`, one line each.
std::vector<std::string> target_misses(const std::vector<nlohmann::json>& results,
                                       std::size_t& target_cells) {
  std::vector<std::string> misses;
  target_cells = 0;
  std::map<std::string, const nlohmann::json*> by;
  for (const nlohmann::json& r : results) {
    by[r["vehicle"].get<std::string>() + "|" + r["column"].get<std::string>() + "|" +
       r["scenario"].get<std::string>()] = &r;
  }
  const auto describe = [](const nlohmann::json& r) {
    return r["vehicle"].get<std::string>() + " " + r["column"].get<std::string>() + " " +
           r["scenario"].get<std::string>();
  };
  for (const nlohmann::json& r : results) {
    if (r.contains("skipped")) {
      // A configuration error (a renamed strategy, say) must not pass as a skip.
      if (!r.value("expected_skip", false))
        misses.push_back("skipped: " + describe(r) + ": " + r.dump());
      continue;
    }
    const std::string v = r["vehicle"], c = r["column"], s = r["scenario"];
    // The budget strategies cap thrust at 60 % of the range: on a sagging
    // battery they cannot climb to the commanded altitude (documented in
    // docs/strategies.md), and their cells say so rather than fail.
    const bool budget = c == "budget" || c == "legacy_budget";
    if (r["armed_fraction"].get<double>() < kArmedFractionMin ||
        (!budget && !r.value("reached_altitude", true))) {
      misses.push_back("not flown: " + describe(r) + ": " + r.dump());
    }
    const bool target_vehicle = v == "hexa_x" || v == "octo_x";
    const bool target_column = c == "optimal" || c.rfind("prioritized/", 0) == 0;
    const bool reported =
        s.rfind("motor_out", 0) == 0 && s.size() > 8 && s.compare(s.size() - 8, 8, "reported") == 0;
    if (target_vehicle && target_column && reported) ++target_cells;
    if (target_vehicle && target_column && reported &&
        (r["crashed"].get<bool>() || r["altitude_loss_m"].get<double>() > kTargetAltitudeLossM ||
         r["attitude_error_max_deg"].get<double>() > kTargetAttitudeMaxDeg)) {
      misses.push_back("motor out: " + describe(r) + ": " + r.dump());
    }
    for (const char* airmode : {"roll_pitch", "roll_pitch_yaw"}) {
      if (c != std::string("prioritized/") + airmode) continue;
      const auto px4 = by.find(v + "|px4/" + airmode + "|" + s);
      if (px4 == by.end() || px4->second->contains("skipped")) continue;
      const nlohmann::json& p = *px4->second;
      const bool worse = (r["crashed"].get<bool>() && !p["crashed"].get<bool>()) ||
                         (!r["crashed"].get<bool>() && !p["crashed"].get<bool>() &&
                          r["attitude_error_rms_deg"].get<double>() >
                              kPx4Margin * p["attitude_error_rms_deg"].get<double>() + 1e-9);
      if (worse)
        misses.push_back("against PX4: " + describe(r) + ": " + r.dump() + " vs " + p.dump());
    }
  }
  return misses;
}

}  // namespace
}  // namespace motormix::sim

int main(int argc, char** argv) {
  using namespace motormix::sim;
  if (argc < 2) {
    std::cerr << "usage: sim_scorecard SOURCE_DIR [--seeds N] [--jobs N] [--vehicles a,b]\n";
    return 2;
  }
  const std::string source = argv[1];
  bool check = false;
  for (int i = 2; i < argc; ++i) {
    if (std::string(argv[i]) == "--check") check = true;
  }
  int seeds = 3;
  unsigned jobs = std::max(1U, std::thread::hardware_concurrency());
  std::vector<std::string> vehicles = {"quad_x", "hexa_x", "octo_x", "team_quad", "diff_drive"};
  for (int i = 2; i + 1 < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--seeds") seeds = std::max(1, std::atoi(argv[++i]));
    if (flag == "--jobs") jobs = static_cast<unsigned>(std::max(1, std::atoi(argv[++i])));
    if (flag == "--vehicles") {
      ++i;
      vehicles.clear();
      std::string list = argv[i];
      for (std::size_t p = 0; p <= list.size();) {
        const std::size_t comma = std::min(list.find(',', p), list.size());
        vehicles.push_back(list.substr(p, comma - p));
        p = comma + 1;
      }
    }
  }
  const std::vector<Column> cols = columns();
  std::vector<Cell> cells;
  for (const Case& c : cases(source, vehicles, !check)) {
    for (const Column& col : cols) cells.push_back({&col, c});
  }
  std::atomic<std::size_t> next{0};
  std::mutex out;
  std::vector<nlohmann::json> results;
  std::vector<std::thread> workers;
  for (unsigned w = 0; w < jobs; ++w) {
    workers.emplace_back([&] {
      for (std::size_t i = next++; i < cells.size(); i = next++) {
        nlohmann::json j = run_cell(source, cells[i], seeds);
        const std::lock_guard<std::mutex> lock(out);
        if (!check) std::cout << j.dump() << "\n";
        results.push_back(std::move(j));
      }
    });
  }
  for (std::thread& t : workers) t.join();
  std::cerr << "sim_scorecard: " << cells.size() << " cells, " << seeds << " seeds each\n";
  if (!check) return 0;
  std::size_t target_cells = 0;
  std::vector<std::string> misses = target_misses(results, target_cells);
  const bool every_vehicle =
      std::find(vehicles.begin(), vehicles.end(), "hexa_x") != vehicles.end() &&
      std::find(vehicles.begin(), vehicles.end(), "octo_x") != vehicles.end();
  if (every_vehicle && target_cells != kTargetCells) {
    misses.push_back("checked " + std::to_string(target_cells) +
                     " motor-out target cells, expected " + std::to_string(kTargetCells));
  }
  for (const std::string& m : misses) std::cout << "MISSED " << m << "\n";
  std::cout << (misses.empty() ? "every target met" : "targets missed") << " in " << results.size()
            << " cells (" << target_cells << " motor-out target cells)\n";
  return misses.empty() ? 0 : 1;
}
