#include "sim/scenario.hpp"

#include "config/yaml_reader.hpp"
#include "shipped_scenarios.hpp"

#include <algorithm>
#include <fstream>
#include <sstream>

namespace motormix::sim {

namespace {

using config::fail;
using config::MapReader;

Eigen::Vector3d vector3(const YAML::Node& node, const std::string& path, double limit) {
  if (!node.IsSequence() || node.size() != 3) fail(path, config::describe(node), "[x, y, z]");
  Eigen::Vector3d v;
  for (std::size_t i = 0; i < 3; ++i) {
    v[static_cast<Eigen::Index>(i)] =
        config::to_number(node[i], path + "[" + std::to_string(i) + "]", -limit, limit);
  }
  return v;
}

std::optional<double> optional_number(MapReader& m, const std::string& key, double lo, double hi) {
  if (!m.has(key)) {
    m.raw(key);
    return std::nullopt;
  }
  return m.number(key, 0.0, lo, hi);
}

ScenarioEvent read_event(MapReader e, double duration) {
  ScenarioEvent ev;
  ev.at_s = e.required_number("at", 0.0, duration);
  ev.roll_deg = optional_number(e, "roll_deg", -80.0, 80.0);
  ev.pitch_deg = optional_number(e, "pitch_deg", -80.0, 80.0);
  ev.yaw_deg = optional_number(e, "yaw_deg", -3600.0, 3600.0);
  ev.altitude_m = optional_number(e, "altitude_m", 0.0, 1000.0);
  ev.speed_mps = optional_number(e, "speed_mps", -100.0, 100.0);
  ev.yaw_rate_dps = optional_number(e, "yaw_rate_dps", -3600.0, 3600.0);
  if (const auto m = optional_number(e, "fail", 1, kMaxMotors)) ev.fail = static_cast<int>(*m) - 1;
  if (e.has("kind")) {
    const std::string name = e.text("kind", "stop");
    const auto kind = failure_kind(name);
    if (!kind || !ev.fail) {
      config::fail(e.path_of("kind"), "'" + name + "'",
                   "one of " + joined_names(kFailureKindNames) + ", beside fail:");
    }
    ev.fail_kind = *kind;
  }
  e.allow("kind");
  if (e.has("wind_mps")) ev.wind_mps = vector3(e.raw("wind_mps"), e.path_of("wind_mps"), 100.0);
  e.allow("wind_mps");
  if (e.has("gust")) {
    MapReader g = e.map("gust");
    Gust gust;
    if (g.has("force_n")) gust.force_n = vector3(g.raw("force_n"), g.path_of("force_n"), 1e4);
    g.allow("force_n");
    if (g.has("torque_nm"))
      gust.torque_nm = vector3(g.raw("torque_nm"), g.path_of("torque_nm"), 1e3);
    g.allow("torque_nm");
    gust.for_s = g.number("for_s", 0.5, 1e-3, 1e3);
    g.finish();
    ev.gust = gust;
  }
  e.allow("gust");
  e.finish();
  return ev;
}

}  // namespace

Scenario parse_scenario(const std::string& yaml_text, const std::string& source) {
  YAML::Node doc;
  try {
    doc = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw config::ConfigError(source + ": not valid YAML: " + e.what());
  }
  try {
    MapReader root(doc, "");
    Scenario s;
    s.name = root.text("name", "scenario");
    s.description = root.text("description", "");
    const std::string kind = root.choice("vehicle", "any", {"any", "aircraft", "ground"});
    s.vehicle = kind == "aircraft" ? ScenarioVehicle::kAircraft
                : kind == "ground" ? ScenarioVehicle::kGround
                                   : ScenarioVehicle::kAny;
    s.duration_s = root.number("duration_s", 10.0, 0.1, 3600.0);
    MapReader score = root.map("score");
    s.score_from_s = score.number("from_s", 0.0, 0.0, s.duration_s);
    s.score_to_s = score.number("to_s", s.duration_s, s.score_from_s, s.duration_s);
    score.finish();
    s.arm_at_s = root.number("arm_at_s", 0.2, 0.05, s.duration_s);
    s.altitude_m = root.number("altitude_m", 3.0, 0.0, 1000.0);
    s.failure_detection_s = root.number("failure_detection_ms", 100.0, 0.0, 60000.0) / 1e3;
    MapReader noise = root.map("noise");
    s.noise.gyro_rad_s = noise.number("gyro_rad_s", 0.0, 0.0, 10.0);
    s.noise.attitude_deg = noise.number("attitude_deg", 0.0, 0.0, 30.0);
    s.noise.altitude_m = noise.number("altitude_m", 0.0, 0.0, 10.0);
    s.noise.speed_mps = noise.number("speed_mps", 0.0, 0.0, 10.0);
    noise.finish();
    MapReader battery = root.map("battery");
    if (battery.has("initial_charge"))
      s.battery_initial_charge = battery.number("initial_charge", 1.0, 0.0, 1.0);
    battery.allow("initial_charge");
    if (battery.has("resistance_factor"))
      s.battery_resistance_factor = battery.number("resistance_factor", 1.0, 0.0, 100.0);
    battery.allow("resistance_factor");
    battery.finish();
    const YAML::Node timeline = root.raw("timeline");
    if (timeline.IsDefined() && !timeline.IsNull()) {
      if (!timeline.IsSequence()) {
        fail("timeline", config::describe(timeline), "a list of events {at: seconds, ...}");
      }
      for (std::size_t i = 0; i < timeline.size(); ++i) {
        s.timeline.push_back(read_event(
            MapReader(timeline[i], "timeline[" + std::to_string(i) + "]"), s.duration_s));
      }
    }
    std::stable_sort(
        s.timeline.begin(), s.timeline.end(),
        [](const ScenarioEvent& a, const ScenarioEvent& b) { return a.at_s < b.at_s; });
    root.finish();
    return s;
  } catch (const config::ConfigError& e) {
    throw config::ConfigError(source + ": " + e.what());
  } catch (const YAML::Exception& e) {
    throw config::ConfigError(source + ": " + e.what());
  }
}

Scenario load_scenario(const std::string& name_or_path) {
  for (const ShippedScenario& s : shipped_scenario_texts()) {
    if (name_or_path == s.name) return parse_scenario(s.text, std::string("scenario ") + s.name);
  }
  std::ifstream file(name_or_path, std::ios::binary);
  if (!file) {
    std::string names;
    for (const std::string& n : shipped_scenarios()) names += (names.empty() ? "" : ", ") + n;
    throw config::ConfigError("scenario '" + name_or_path + "': neither a shipped scenario (" +
                              names + ") nor a readable file");
  }
  std::stringstream text;
  text << file.rdbuf();
  return parse_scenario(text.str(), name_or_path);
}

std::vector<std::string> shipped_scenarios() {
  std::vector<std::string> names;
  for (const ShippedScenario& s : shipped_scenario_texts()) names.emplace_back(s.name);
  return names;
}

}  // namespace motormix::sim
