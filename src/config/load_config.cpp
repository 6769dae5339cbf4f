#include <motormix/config/load_config.hpp>

#include "config/yaml_reader.hpp"
#include "failure_detection_reader.hpp"
#include "hardware_reader.hpp"
#include "motor_loss_reader.hpp"
#include "section_readers.hpp"
#include "security_reader.hpp"
#include "vehicle_physics_reader.hpp"

#include <motormix/config/hover_point.hpp>

#include <cmath>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>
#include <utility>

namespace motormix::config {

namespace reading {

std::optional<std::string> read_text_file(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) return std::nullopt;
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& i : items) out += (out.empty() ? "" : ", ") + i;
  return out;
}

std::string axis_list(AxisMask mask) {
  std::vector<std::string> names;
  for (int a = 0; a < kNumAxes; ++a) {
    if ((mask >> a) & 1U) names.emplace_back(kAxisNames[static_cast<std::size_t>(a)]);
  }
  return join(names);
}

std::vector<double> read_numbers(const YAML::Node& node, const std::string& path,
                                 std::size_t min_len, std::size_t max_len, double lo, double hi) {
  const std::string want = min_len == max_len ? "a list of " + std::to_string(min_len) + " numbers"
                                              : "a list of " + std::to_string(min_len) + " to " +
                                                    std::to_string(max_len) + " numbers";
  if (!node.IsSequence() || node.size() < min_len || node.size() > max_len) {
    fail(path, describe(node), want);
  }
  std::vector<double> out;
  for (std::size_t i = 0; i < node.size(); ++i) {
    out.push_back(to_number(node[i], path + "[" + std::to_string(i) + "]", lo, hi));
  }
  return out;
}

bool read_bool(MapReader& map, const std::string& key, bool fallback) {
  return map.boolean(key, fallback);
}

Eigen::Vector3d read_vector(const YAML::Node& node, const std::string& path) {
  const std::vector<double> v = read_numbers(node, path, 2, 3, -kMaxCoefficient, kMaxCoefficient);
  return {v[0], v[1], v.size() == 3 ? v[2] : 0.0};
}

Rotor read_rotor_placement(MapReader& r, const PositionForm& form) {
  Rotor rotor;
  if (!r.has("position"))
    fail(r.path_of("position"), "nothing", std::string(form.hint) + " (required)");
  const std::vector<double> p = read_numbers(r.raw("position"), r.path_of("position"),
                                             form.min_coordinates, 3, -form.extent, form.extent);
  rotor.position = {p[0], p[1], p.size() == 3 ? p[2] : 0.0};
  rotor.spin = *parse_in(kSpinNames, r.choice("spin", "", names_in(kSpinNames)));
  if (r.has("axis")) {
    rotor.axis = read_vector(r.raw("axis"), r.path_of("axis"));
    if (rotor.axis.norm() < 1e-9) fail(r.path_of("axis"), "a zero vector", "a thrust direction");
  } else {
    r.allow("axis");
  }
  return rotor;
}

}  // namespace reading

namespace {

using namespace reading;

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

Config read_document(const YAML::Node& document, LoadContext& context) {
  MapReader root(document, "");
  Config config;
  config.name = root.text("name", "motormix");
  if (!root.has("geometry")) fail("geometry", "nothing", "a 'geometry' section (required)");
  read_geometry(root.map("geometry"), config, context);
  read_mixer(root.map("mixer"), config);
  read_output(root.map("output"), config);
  read_inputs(root.map("inputs"), config);
  read_channels(root.map("channels"), config);
  read_motor_test(root.map("motor_test"), config);
  read_realtime(root.map("realtime"), config);
  config.publish = root.choice("publish", PublishMode::kTimer, kPublishModeNames);
  config.loop_rate_hz = root.number("loop_rate_hz", 400.0, 50.0, 10000.0);
  config.status_rate_hz = root.number("status_rate_hz", 10.0, 0.1, 1000.0);
  if (root.has("battery")) read_battery(root.map("battery"), config);
  read_vehicle_physics(root.map("vehicle"), config);
  // Newtons and newton-metres are converted through the vehicle's own
  // physics: its weight and thrust must be given, and it must hover.
  if (config.inputs.units == InputUnits::kPhysical && !hover_point(config).known) {
    fail("inputs.units", "physical",
         "normalized, or physical with a `vehicle:` section giving mass_kg and max_thrust_n "
         "of an aircraft that can hover");
  }
  read_failure_detection(root.map("failure_detection"), root.has("failure_detection"), config);
  read_motor_loss(root.map("motor_loss"), config);
  read_hardware(root.map("hardware"), config);
  read_security(root.map("security"), context.base_dir, config);
  if (config.status_rate_hz > config.loop_rate_hz) {
    std::ostringstream found;
    found << config.status_rate_hz << " with loop_rate_hz " << config.loop_rate_hz;
    fail("status_rate_hz", found.str(), "at most loop_rate_hz");
  }
  root.finish();
  return config;
}

}  // namespace

namespace {

Config load_in_context(const std::string& yaml_text, const std::string& source_name,
                       const std::vector<std::string>& overrides, LoadContext& context) {
  YAML::Node document;
  try {
    document = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(source_name + ": not valid YAML: " + e.what());
  }
  if (!document.IsDefined() || document.IsNull()) document = YAML::Node(YAML::NodeType::Map);
  for (const std::string& o : overrides) apply_override(document, o);
  try {
    Config config = read_document(document, context);
    // FNV-1a over the text, the overrides and every file the configuration
    // reads: tells which configuration a status message came from.
    std::uint64_t h = 1469598103934665603ULL;
    std::string all = yaml_text;
    for (const std::string& o : overrides) all += "\n--set " + o;
    all += context.included_text;
    for (unsigned char c : all) h = (h ^ c) * 1099511628211ULL;
    config.hash = h;
    return config;
  } catch (const ConfigError& e) {
    throw ConfigError(source_name + ": " + e.what());
  } catch (const YAML::Exception& e) {
    throw ConfigError(source_name + ": " + e.what());
  }
}

}  // namespace

Config load_config_text(const std::string& yaml_text, const std::string& source_name,
                        const std::vector<std::string>& overrides) {
  LoadContext context;
  return load_in_context(yaml_text, source_name, overrides, context);
}

Config load_config_file(const std::string& path, const std::vector<std::string>& overrides) {
  const std::optional<std::string> text = read_text_file(path);
  if (!text) throw ConfigError(path + ": cannot open config file");
  LoadContext context;
  const auto slash = path.rfind('/');
  context.base_dir = slash == std::string::npos ? "" : path.substr(0, slash == 0 ? 1 : slash);
  return load_in_context(*text, path, overrides, context);
}

}  // namespace motormix::config

namespace motormix::config {

int Config::motor_index(const std::string& text) const {
  const auto& names = motor_names();
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i] == text) return static_cast<int>(i);
  }
  // A number alone, digits only (no sign, space or suffix), 1..motors.
  if (text.empty() || text.size() > 4 ||
      text.find_first_not_of("0123456789") != std::string::npos) {
    return -1;
  }
  const int number = std::stoi(text);
  return number >= 1 && number <= motors() ? number - 1 : -1;
}

std::string Config::description() const {
  return geometry_source + " (" + geometry.description + ")";
}

}  // namespace motormix::config
