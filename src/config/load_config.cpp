#include "config/load_config.hpp"

#include "config/yaml_reader.hpp"

#include <motormix/presets.hpp>

#include <cmath>
#include <fstream>
#include <sstream>

namespace motormix::config {

namespace {

// Output values are microseconds by default; anything a servo or ESC driver
// could mean fits in this range.
constexpr double kMaxOutputValue = 100000.0;
// Budgets are fractions of full power; their sum may not exceed it.
constexpr double kBudgetSumTolerance = 1e-9;
// Mixing coefficients beyond this magnitude are almost certainly a typo.
constexpr double kMaxCoefficient = 1000.0;

void apply_override(YAML::Node& root, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0) {
    throw ConfigError("override '" + assignment + "': expected key.path=value");
  }
  const std::string path = assignment.substr(0, eq);
  YAML::Node value;
  try {
    value = YAML::Load(assignment.substr(eq + 1));
  } catch (const YAML::Exception& e) {
    throw ConfigError("override '" + assignment + "': value is not valid YAML: " + e.msg);
  }
  // Walk the path with fresh handles: yaml-cpp nodes are references, so
  // reassigning one in a loop would overwrite the tree.
  std::vector<std::string> keys;
  std::stringstream parts(path);
  for (std::string key; std::getline(parts, key, '.');) {
    if (key.empty()) throw ConfigError("override '" + assignment + "': empty key in path");
    keys.push_back(key);
  }
  std::vector<YAML::Node> chain{root};
  for (std::size_t i = 0; i + 1 < keys.size(); ++i) {
    YAML::Node next = chain.back()[keys[i]];
    if (next.IsDefined() && !next.IsNull() && !next.IsMap()) {
      throw ConfigError("override '" + assignment + "': '" + keys[i] + "' is not a mapping");
    }
    chain.push_back(next);
  }
  chain.back()[keys.back()] = value;
}

void read_geometry(MapReader geometry, Config& config) {
  const bool has_preset = geometry.has("preset");
  const bool has_mixing = geometry.has("mixing");
  if (has_preset == has_mixing) {
    fail(
        geometry.path_of("preset"),
        has_preset ? "both 'preset' and 'mixing'" : "neither", "exactly one of 'preset' (" + [] {
          std::string names;
          for (const auto& n : preset_names()) names += (names.empty() ? "" : ", ") + n;
          return names;
        }() + ") or 'mixing' (a list of [roll, pitch, yaw, thrust] rows)");
  }
  if (has_preset) {
    const std::string name = geometry.choice("preset", "", preset_names());
    const Preset preset = *find_preset(name);
    config.mixing = preset.mixing;
    config.motor_names = preset.motor_names;
    config.geometry_description = "preset " + name + ": " + preset.description;
  } else {
    const std::string path = geometry.path_of("mixing");
    const YAML::Node rows = geometry.raw("mixing");
    if (!rows.IsSequence() || rows.size() < 1 || rows.size() > kMaxMotors) {
      fail(path, describe(rows),
           "a list of 1 to " + std::to_string(kMaxMotors) + " rows [roll, pitch, yaw, thrust]");
    }
    config.mixing.resize(static_cast<Eigen::Index>(rows.size()), kNumAxes);
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const std::string row_path = path + "[" + std::to_string(i) + "]";
      if (!rows[i].IsSequence() || rows[i].size() != kNumAxes) {
        fail(row_path, describe(rows[i]), "a row of 4 numbers [roll, pitch, yaw, thrust]");
      }
      for (int a = 0; a < kNumAxes; ++a) {
        config.mixing(static_cast<Eigen::Index>(i), a) =
            to_number(rows[i][static_cast<std::size_t>(a)],
                      row_path + "[" + std::to_string(a) + "] (" + kAxisNames[a] + ")",
                      -kMaxCoefficient, kMaxCoefficient);
      }
    }
    config.geometry_description = "explicit mixing table";
  }
  const int motors = config.motors();
  if (geometry.has("motor_names")) {
    const std::string path = geometry.path_of("motor_names");
    const YAML::Node names = geometry.raw("motor_names");
    if (!names.IsSequence() || static_cast<int>(names.size()) != motors) {
      fail(path, describe(names), "a list of " + std::to_string(motors) + " names, one per motor");
    }
    config.motor_names.clear();
    for (const auto& n : names) config.motor_names.push_back(n.as<std::string>());
  } else {
    geometry.raw("motor_names");
    if (static_cast<int>(config.motor_names.size()) != motors) {
      config.motor_names.clear();
      for (int i = 0; i < motors; ++i) config.motor_names.push_back("m" + std::to_string(i + 1));
    }
  }
  geometry.finish();
}

void read_mixer(MapReader mixer, Config& config) {
  const std::string strategy = mixer.choice("strategy", "legacy_budget", {"legacy_budget"});
  if (strategy == "legacy_budget") config.strategy = Strategy::kLegacyBudget;

  MapReader budgets = mixer.map("legacy_budget");
  config.legacy_budgets.throttle = budgets.number("throttle", 0.60, 0.0, 1.0);
  config.legacy_budgets.roll_pitch = budgets.number("roll_pitch", 0.25, 0.0, 1.0);
  config.legacy_budgets.yaw = budgets.number("yaw", 0.15, 0.0, 1.0);
  const double sum =
      config.legacy_budgets.throttle + config.legacy_budgets.roll_pitch + config.legacy_budgets.yaw;
  if (sum > 1.0 + kBudgetSumTolerance) {
    std::ostringstream found;
    found << "throttle + roll_pitch + yaw = " << sum;
    fail(mixer.path_of("legacy_budget"), found.str(), "a sum of at most 1 (full power)");
  }
  budgets.finish();
  mixer.finish();
}

void read_output(MapReader output, Config& config) {
  OutputChannel ch;
  ch.min = output.number("min_us", 1000.0, 0.0, kMaxOutputValue);
  ch.max = output.number("max_us", 2000.0, 0.0, kMaxOutputValue);
  ch.disarmed = output.number("disarmed_us", 1000.0, 0.0, kMaxOutputValue);
  if (!(ch.min < ch.max)) {
    std::ostringstream found;
    found << "min_us " << ch.min << " and max_us " << ch.max;
    fail(output.path_of("max_us"), found.str(), "max_us greater than min_us");
  }
  output.finish();
  config.outputs.assign(static_cast<std::size_t>(config.motors()), ch);
}

void read_inputs(MapReader inputs, Config& config) {
  const std::string yaw = inputs.choice("yaw_source", "setpoint", {"setpoint", "pid"});
  config.inputs.yaw_source = yaw == "pid" ? YawSource::kPid : YawSource::kSetpoint;
  config.inputs.setpoint_timeout_s =
      inputs.number("setpoint_timeout_ms", 100.0, 1.0, 10000.0) / 1e3;
  config.inputs.pid_timeout_s = inputs.number("pid_timeout_ms", 100.0, 1.0, 10000.0) / 1e3;
  inputs.finish();
}

void read_channels(MapReader channels, Config& config) {
  Channels& c = config.channels;
  c.setpoint = channels.text("setpoint", c.setpoint);
  c.pid = channels.text("pid", c.pid);
  c.motor_pwm = channels.text("motor_pwm", c.motor_pwm);
  c.status = channels.text("status", c.status);
  channels.finish();
}

Config read_document(const YAML::Node& document) {
  MapReader root(document, "");
  Config config;
  config.name = root.text("name", "motormix");
  if (!root.has("geometry")) fail("geometry", "nothing", "a 'geometry' section (required)");
  read_geometry(root.map("geometry"), config);
  read_mixer(root.map("mixer"), config);
  read_output(root.map("output"), config);
  read_inputs(root.map("inputs"), config);
  read_channels(root.map("channels"), config);
  config.loop_rate_hz = root.number("loop_rate_hz", 400.0, 50.0, 10000.0);
  config.status_rate_hz = root.number("status_rate_hz", 10.0, 0.1, 1000.0);
  if (config.status_rate_hz > config.loop_rate_hz) {
    std::ostringstream found;
    found << config.status_rate_hz << " with loop_rate_hz " << config.loop_rate_hz;
    fail("status_rate_hz", found.str(), "at most loop_rate_hz");
  }
  root.finish();
  return config;
}

}  // namespace

const char* to_string(Strategy strategy) {
  switch (strategy) {
    case Strategy::kLegacyBudget:
      return "legacy_budget";
  }
  return "?";
}

const char* to_string(YawSource source) { return source == YawSource::kPid ? "pid" : "setpoint"; }

Config load_config_text(const std::string& yaml_text, const std::string& source_name,
                        const std::vector<std::string>& overrides) {
  YAML::Node document;
  try {
    document = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(source_name + ": not valid YAML: " + e.what());
  }
  if (!document.IsDefined() || document.IsNull()) document = YAML::Node(YAML::NodeType::Map);
  for (const std::string& o : overrides) apply_override(document, o);
  try {
    return read_document(document);
  } catch (const ConfigError& e) {
    throw ConfigError(source_name + ": " + e.what());
  } catch (const YAML::Exception& e) {
    throw ConfigError(source_name + ": " + e.what());
  }
}

Config load_config_file(const std::string& path, const std::vector<std::string>& overrides) {
  std::ifstream file(path);
  if (!file) throw ConfigError(path + ": cannot open config file");
  std::stringstream text;
  text << file.rdbuf();
  return load_config_text(text.str(), path, overrides);
}

}  // namespace motormix::config
