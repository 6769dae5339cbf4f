#include <motormix/config/load_config.hpp>

#include "paparazzi_import.hpp"
#include "failure_detection_reader.hpp"
#include "motor_loss_reader.hpp"
#include "hardware_reader.hpp"
#include "security_reader.hpp"
#include "vehicle_physics_reader.hpp"
#include "config/yaml_reader.hpp"

#include <motormix/presets.hpp>

#include <cmath>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>
#include <utility>

namespace motormix::config {

namespace {

// Output values are microseconds by default; anything a servo or ESC driver
// could mean fits in this range.
constexpr double kMaxOutputValue = 100000.0;
// Budgets are fractions of full power; their sum may not exceed it.
constexpr double kBudgetSumTolerance = 1e-9;
// Mixing coefficients beyond this magnitude are almost certainly a typo.
constexpr double kMaxCoefficient = 1000.0;

// Where the configuration came from: relative file names inside it (e.g.
// geometry.paparazzi) are taken from its directory, and the text of every
// file it reads goes into the configuration hash.
struct LoadContext {
  std::string base_dir;
  std::string included_text;
};

std::optional<std::string> read_text_file(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) return std::nullopt;
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

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

// A list of numbers of a given length (or a range of lengths).
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

Vehicle rotors_vehicle(const YAML::Node& list, const std::string& path) {
  if (!list.IsSequence() || list.size() < 1 || list.size() > kMaxMotors) {
    fail(path, describe(list), "a list of 1 to " + std::to_string(kMaxMotors) + " rotors");
  }
  std::vector<Rotor> rotors;
  for (std::size_t i = 0; i < list.size(); ++i) {
    MapReader r(list[i], path + "[" + std::to_string(i) + "]");
    Rotor rotor;
    if (!r.has("position"))
      fail(r.path_of("position"), "nothing", "[x, y] or [x, y, z] (required)");
    rotor.position = read_vector(r.raw("position"), r.path_of("position"));
    rotor.spin = r.choice("spin", "", {"cw", "ccw"}) == "cw" ? Spin::kCw : Spin::kCcw;
    rotor.thrust_coefficient = r.number("thrust_coefficient", 1.0, 1e-6, 1e6);
    rotor.torque_ratio = r.number("torque_ratio", 0.05, 0.0, 10.0);
    if (r.has("axis")) {
      rotor.axis = read_vector(r.raw("axis"), r.path_of("axis"));
      if (rotor.axis.norm() < 1e-9) fail(r.path_of("axis"), "a zero vector", "a thrust direction");
    } else {
      r.allow("axis");
    }
    r.finish();
    rotors.push_back(rotor);
  }
  Vehicle v;
  v.name = "rotors";
  v.description = std::to_string(rotors.size()) + " rotors described one by one";
  v.effectiveness = rotor_effectiveness(rotors);
  v.rotors = rotors;
  for (std::size_t i = 0; i < rotors.size(); ++i)
    v.motor_names.push_back("m" + std::to_string(i + 1));
  return v;
}

Vehicle effectiveness_vehicle(MapReader rows) {
  std::vector<std::vector<double>> values(kNumAxes);
  std::size_t n = 0;
  for (int a = 0; a < kNumAxes; ++a) {
    const std::string axis = kAxisNames[static_cast<std::size_t>(a)];
    const bool optional_row = a == index(Axis::kThrust);
    if (!rows.has(axis)) {
      if (!optional_row)
        fail(rows.path_of(axis), "nothing", "a list of one number per motor (required)");
      rows.raw(axis);
      continue;
    }
    const std::size_t min_len = n == 0 ? 1 : n;
    const std::size_t max_len = n == 0 ? kMaxMotors : n;
    values[static_cast<std::size_t>(a)] = read_numbers(rows.raw(axis), rows.path_of(axis), min_len,
                                                       max_len, -kMaxCoefficient, kMaxCoefficient);
    n = values[static_cast<std::size_t>(a)].size();
  }
  rows.finish();
  auto& thrust = values[static_cast<std::size_t>(index(Axis::kThrust))];
  if (thrust.empty()) thrust.assign(n, 1.0);
  EffectivenessMatrix e(kNumAxes, static_cast<Eigen::Index>(n));
  for (int a = 0; a < kNumAxes; ++a) {
    for (std::size_t i = 0; i < n; ++i)
      e(a, static_cast<Eigen::Index>(i)) = values[static_cast<std::size_t>(a)][i];
  }
  Vehicle v;
  v.name = "effectiveness";
  v.description = "effectiveness matrix given row by row";
  v.effectiveness = e;
  for (std::size_t i = 0; i < n; ++i) v.motor_names.push_back("m" + std::to_string(i + 1));
  return v;
}

// A vehicle given by its mixing table: commanded in the axes the table uses,
// motors named m1, m2, ...
Vehicle mixing_table_vehicle(const MixingMatrix& m, std::string name, std::string description) {
  Vehicle v;
  v.name = std::move(name);
  v.description = std::move(description);
  v.mixing_table = m;
  v.controlled = controlled_axes(m);
  for (Eigen::Index i = 0; i < m.rows(); ++i) v.motor_names.push_back("m" + std::to_string(i + 1));
  return v;
}

Vehicle table_vehicle(const YAML::Node& rows, const std::string& path) {
  if (!rows.IsSequence() || rows.size() < 1 || rows.size() > kMaxMotors) {
    fail(path, describe(rows),
         "a list of 1 to " + std::to_string(kMaxMotors) + " rows [roll, pitch, yaw, thrust]");
  }
  MixingMatrix m(static_cast<Eigen::Index>(rows.size()), kNumAxes);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const std::string row_path = path + "[" + std::to_string(i) + "]";
    if (!rows[i].IsSequence() || rows[i].size() != kNumAxes) {
      fail(row_path, describe(rows[i]), "a row of 4 numbers [roll, pitch, yaw, thrust]");
    }
    for (int a = 0; a < kNumAxes; ++a) {
      m(static_cast<Eigen::Index>(i), a) =
          to_number(rows[i][static_cast<std::size_t>(a)],
                    row_path + "[" + std::to_string(a) + "] (" + kAxisNames[a] + ")",
                    -kMaxCoefficient, kMaxCoefficient);
    }
  }
  return mixing_table_vehicle(m, "mixing", "explicit mixing table");
}

WheelBase read_wheel_base(MapReader wheels, int default_per_side, bool per_side_allowed) {
  WheelBase base;
  base.wheels_per_side = default_per_side;
  if (per_side_allowed) {
    base.wheels_per_side =
        static_cast<int>(wheels.number("wheels_per_side", default_per_side, 2, 3));
    if (base.wheels_per_side != 2 && base.wheels_per_side != 3) {
      fail(wheels.path_of("wheels_per_side"), std::to_string(base.wheels_per_side), "2 or 3");
    }
  }
  base.wheel_radius = wheels.number("wheel_radius", base.wheel_radius, 1e-4, 100.0);
  base.track_width = wheels.number("track_width", base.track_width, 1e-4, 1000.0);
  base.max_wheel_speed = wheels.number("max_wheel_speed", base.max_wheel_speed, 1e-3, 1e5);
  wheels.finish();
  return base;
}

std::vector<int> read_motor_order(const YAML::Node& node, const std::string& path, int motors) {
  const std::string want = "a permutation of 1.." + std::to_string(motors);
  const std::vector<double> raw = read_numbers(node, path, static_cast<std::size_t>(motors),
                                               static_cast<std::size_t>(motors), 1, motors);
  std::vector<int> order;
  std::vector<bool> seen(static_cast<std::size_t>(motors) + 1, false);
  for (double v : raw) {
    const int k = static_cast<int>(v);
    if (k != v || seen[static_cast<std::size_t>(k)]) fail(path, describe(node), want);
    seen[static_cast<std::size_t>(k)] = true;
    order.push_back(k);
  }
  return order;
}

Vehicle paparazzi_vehicle(MapReader& geometry, LoadContext& context) {
  const std::string path_key = geometry.path_of("paparazzi");
  const YAML::Node node = geometry.raw("paparazzi");
  if (!node.IsScalar() || node.Scalar().empty()) {
    fail(path_key, describe(node), "the path of a Paparazzi airframe file or MIXING section");
  }
  std::string file = node.Scalar();
  if (file.front() != '/' && !context.base_dir.empty()) file = context.base_dir + "/" + file;
  const std::optional<std::string> text = read_text_file(file);
  if (!text) fail(path_key, "'" + file + "' (cannot open it)", "a readable file");
  context.included_text += *text;
  const MixingMatrix m = parse_paparazzi_mixing(*text, file);
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    for (int a = 0; a < kNumAxes; ++a) {
      if (std::abs(m(i, a)) > kMaxCoefficient) {
        fail(path_key,
             file + ": coefficient/SCALE " + std::to_string(m(i, a)) + " of motor " +
                 std::to_string(i + 1),
             "at most " + std::to_string(static_cast<int>(kMaxCoefficient)) + " in magnitude");
      }
    }
  }
  return mixing_table_vehicle(m, "paparazzi", "MIXING section of " + file);
}

void read_geometry(MapReader geometry, Config& config, LoadContext& context) {
  const std::vector<std::string> forms = {"preset",    "rotors",    "effectiveness",
                                          "mixing",    "paparazzi", "differential_drive",
                                          "skid_steer"};
  std::vector<std::string> given;
  for (const auto& f : forms) {
    if (geometry.has(f)) given.push_back(f);
  }
  if (given.size() != 1) {
    fail(geometry.path_of(given.empty() ? "preset" : given[1]),
         given.empty() ? "none of them" : join(given),
         "exactly one of " + join(forms) + "; presets: " + join(preset_names()));
  }
  const std::string form = given[0];
  config.geometry_source = form;
  const bool preset_form = form == "preset";
  for (const char* key : {"arm_length", "reverse_spin", "motor_order"}) {
    if (!preset_form && geometry.has(key)) {
      fail(geometry.path_of(key), "'" + std::string(key) + "' with '" + form + "'",
           "preset options only with 'preset'");
    }
  }
  if (preset_form) {
    const std::string name = geometry.choice("preset", "", preset_names());
    PresetOptions options;
    if (geometry.has("arm_length"))
      options.arm_length = geometry.number("arm_length", 0.25, 1e-4, 1e3);
    geometry.allow("arm_length");
    options.reverse_spin = read_bool(geometry, "reverse_spin", false);
    if (geometry.has("motor_order")) {
      const int motors = find_preset(name)->motors();
      options.motor_order =
          read_motor_order(geometry.raw("motor_order"), geometry.path_of("motor_order"), motors);
    } else {
      geometry.allow("motor_order");
    }
    config.geometry = *find_preset(name, options);
    config.geometry_source = "preset " + name;
    if (name == "differential_drive" || name.rfind("skid_steer", 0) == 0) {
      WheelBase base;
      base.wheels_per_side = config.geometry.motors() / 2;
      config.wheel_base = base;
    }
  } else if (form == "rotors") {
    config.geometry = rotors_vehicle(geometry.raw("rotors"), geometry.path_of("rotors"));
  } else if (form == "effectiveness") {
    config.geometry = effectiveness_vehicle(geometry.map("effectiveness"));
  } else if (form == "mixing") {
    config.geometry = table_vehicle(geometry.raw("mixing"), geometry.path_of("mixing"));
  } else if (form == "paparazzi") {
    config.geometry = paparazzi_vehicle(geometry, context);
  } else {
    const bool skid = form == "skid_steer";
    const WheelBase base = read_wheel_base(geometry.map(form), skid ? 2 : 1, skid);
    const std::string preset =
        skid ? "skid_steer_" + std::to_string(2 * base.wheels_per_side) : "differential_drive";
    config.geometry = *find_preset(preset);
    config.wheel_base = base;
  }
  for (const auto& f : forms) geometry.raw(f);

  const std::string norm =
      geometry.choice("normalization", "axis_max", {"axis_max", "px4", "none"});
  config.normalization = norm == "px4"    ? Normalization::kPx4
                         : norm == "none" ? Normalization::kNone
                                          : Normalization::kAxisMax;
  if (config.geometry.effectiveness) {
    config.derivation = derive_mixing(*config.geometry.effectiveness, config.geometry.controlled,
                                      config.normalization);
    if (!config.derivation->ok()) {
      fail(geometry.path_of(given[0]),
           "a geometry whose effectiveness has rank " + std::to_string(config.derivation->rank) +
               "; it cannot command " + axis_list(config.derivation->uncontrollable) +
               " independently of the other axes",
           "a geometry that controls " + axis_list(config.geometry.controlled) +
               " (e.g. not all rotors on one line, not all spinning the same way)");
    }
    config.mixing = config.derivation->mixing;
  } else {
    config.mixing = *config.geometry.mixing_table;
  }

  const int motors = config.motors();
  if (geometry.has("motor_names")) {
    const std::string path = geometry.path_of("motor_names");
    const YAML::Node names = geometry.raw("motor_names");
    if (!names.IsSequence() || static_cast<int>(names.size()) != motors) {
      fail(path, describe(names), "a list of " + std::to_string(motors) + " names, one per motor");
    }
    config.geometry.motor_names.clear();
    for (const auto& n : names) {
      if (!n.IsScalar()) fail(path, describe(n), "names (strings)");
      config.geometry.motor_names.push_back(n.Scalar());
    }
  } else {
    geometry.allow("motor_names");
  }
  geometry.finish();
}

// mixer.failed_motors: motors stopped from the start, by number as `motormix
// matrix` prints them (m3 is 3) or by name.
void read_failed_motors(MapReader& mixer, Config& config) {
  const YAML::Node list = mixer.raw("failed_motors");
  if (!list.IsDefined() || list.IsNull()) return;
  const std::string path = mixer.path_of("failed_motors");
  const int n = config.motors();
  const std::string allowed = "a list of motor numbers 1.." + std::to_string(n) +
                              " (as motormix matrix prints them) or motor names (" +
                              join(config.motor_names()) + ")";
  if (!list.IsSequence()) fail(path, describe(list), allowed);
  const bool budgeted =
      config.strategy == Strategy::kLegacyBudget || config.strategy == Strategy::kBudget;
  if (budgeted && list.size() > 0) {
    fail(path, describe(list) + " with strategy " + to_string(config.strategy),
         "failed motors only with strategy shift, clip, prioritized or optimal (the budget "
         "strategies have no reallocation)");
  }
  MotorMask mask = 0;
  for (std::size_t k = 0; k < list.size(); ++k) {
    const std::string item_path = path + "[" + std::to_string(k) + "]";
    const YAML::Node& item = list[k];
    if (!item.IsScalar()) fail(item_path, describe(item), allowed);
    const int motor = config.motor_index(item.Scalar());
    if (motor < 0) fail(item_path, describe(item), allowed);
    const MotorMask b = MotorMask{1} << motor;
    if (mask & b) fail(item_path, describe(item) + ", listed twice", "each motor once");
    mask |= b;
  }
  if (count_motors(mask) >= n) {
    fail(path, describe(list), "at least one working motor");
  }
  config.failed_motors = mask;
}

void read_battery(MapReader battery, Config& config) {
  if (!battery.has("nominal_v")) {
    fail(battery.path_of("nominal_v"), "nothing",
         "the pack voltage at which no compensation is applied, 1 to 100 V (required when "
         "'battery' is present)");
  }
  BatterySettings b;
  b.nominal_v = battery.required_number("nominal_v", 1.0, 100.0);
  b.exponent = battery.number("exponent", 1.0, 0.0, 3.0);
  b.max_gain = battery.number("max_gain", 1.5, 1.0, 3.0);
  b.filter_hz = battery.number("filter_hz", 2.0, 0.01, config.loop_rate_hz / 2.0);
  b.timeout_s = battery.number("timeout_ms", 500.0, 1.0, 10000.0) / 1e3;
  b.min_v = battery.number("min_v", 0.5 * b.nominal_v, 0.0, 100.0);
  b.max_v = battery.number("max_v", 1.25 * b.nominal_v, 0.0, 150.0);
  if (!(b.min_v < b.nominal_v && b.nominal_v <= b.max_v)) {
    std::ostringstream found;
    found << "min_v " << b.min_v << ", nominal_v " << b.nominal_v << ", max_v " << b.max_v;
    fail(battery.path_of("min_v"), found.str(), "min_v < nominal_v <= max_v");
  }
  battery.finish();
  config.battery = b;
}

void read_mixer(MapReader mixer, Config& config) {
  const std::vector<std::string> names = {"legacy_budget", "budget",      "shift",
                                          "clip",          "prioritized", "optimal"};
  // Default: sequential desaturation for aircraft, shifting for wheels.
  const std::string fallback =
      config.thrust_range() == ThrustRange::kBipolar ? "shift" : "prioritized";
  const std::string strategy = mixer.choice("strategy", fallback, names);
  const std::vector<Strategy> values = {Strategy::kLegacyBudget, Strategy::kBudget,
                                        Strategy::kShift,        Strategy::kClip,
                                        Strategy::kPrioritized,  Strategy::kOptimal};
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i] == strategy) config.strategy = values[i];
  }
  const bool budgeted =
      config.strategy == Strategy::kLegacyBudget || config.strategy == Strategy::kBudget;
  if (budgeted && config.thrust_range() == ThrustRange::kBipolar) {
    fail(mixer.path_of("strategy"), "'" + strategy + "' for a wheeled vehicle",
         "shift, clip, prioritized or optimal (budgets assume motors that only push)");
  }

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

  MapReader prioritized = mixer.map("prioritized");
  const std::string airmode =
      prioritized.choice("airmode", "off", {"off", "roll_pitch", "roll_pitch_yaw"});
  config.airmode = airmode == "roll_pitch"       ? Airmode::kRollPitch
                   : airmode == "roll_pitch_yaw" ? Airmode::kRollPitchYaw
                                                 : Airmode::kOff;
  config.yaw_headroom = prioritized.number("yaw_headroom", 0.15, 0.0, 1.0);
  config.tie_tolerance = prioritized.number("tie_tolerance", config.tie_tolerance, 0.0, 0.1);
  prioritized.finish();

  MapReader optimal = mixer.map("optimal");
  MapReader weights = optimal.map("weights");
  for (int a = 0; a < kNumAxes; ++a) {
    config.optimal.weights[a] = weights.number(kAxisNames[static_cast<std::size_t>(a)],
                                               config.optimal.weights[a], 0.0, 1e3);
  }
  weights.finish();
  config.optimal.max_iterations = static_cast<int>(optimal.number("max_iterations", 100, 1, 1000));
  optimal.finish();
  read_failed_motors(mixer, config);
  mixer.finish();
}

// Range, centre and disarmed value of one channel; shared by the defaults and
// the per-motor overrides.
void read_range(MapReader& map, OutputChannel& ch) {
  ch.min = map.number("min", ch.min, 0.0, kMaxOutputValue);
  ch.max = map.number("max", ch.max, 0.0, kMaxOutputValue);
  ch.center =
      map.number("center", ch.mode == OutputMode::kCentered ? (ch.min + ch.max) / 2 : ch.center,
                 0.0, kMaxOutputValue);
  ch.disarmed = map.number("disarmed", ch.disarmed, 0.0, kMaxOutputValue);
  if (!(ch.min < ch.max)) {
    std::ostringstream found;
    found << "min " << ch.min << " and max " << ch.max;
    fail(map.path_of("max"), found.str(), "max greater than min");
  }
  if (ch.mode == OutputMode::kCentered && !(ch.center > ch.min && ch.center < ch.max)) {
    std::ostringstream found;
    found << ch.center << " with min " << ch.min << " and max " << ch.max;
    fail(map.path_of("center"), found.str(), "a value strictly between min and max");
  }
}

void read_output(MapReader output, Config& config) {
  const bool wheels = config.thrust_range() == ThrustRange::kBipolar;
  const std::string mode =
      output.choice("mode", wheels ? "centered" : "unipolar",
                    wheels ? std::vector<std::string>{"centered", "magnitude_direction"}
                           : std::vector<std::string>{"unipolar"});
  OutputChannel ch;
  if (mode == "centered") {
    ch.mode = OutputMode::kCentered;
    ch.disarmed = 1500.0;
  } else if (mode == "magnitude_direction") {
    ch.mode = OutputMode::kMagnitudeDirection;
    ch.min = 0.0;
    ch.max = 255.0;
    ch.disarmed = 0.0;
  }
  config.output_unit =
      output.text("unit", ch.mode == OutputMode::kMagnitudeDirection ? "duty" : "us");
  read_range(output, ch);
  if (ch.mode == OutputMode::kUnipolar) {
    ch.idle = output.number("idle", 0.0, 0.0, 0.5);
    ch.thrust_model_factor = output.number("thrust_model_factor", 0.0, 0.0, 1.0);
  } else {
    for (const char* key : {"idle", "thrust_model_factor"}) {
      if (output.has(key))
        fail(output.path_of(key), "'" + std::string(key) + "' with mode " + mode,
             "only with mode unipolar");
      output.raw(key);
    }
  }
  ch.slew_per_s = output.number("slew_per_s", 0.0, 0.0, 1e9);
  // Aircraft spool up over half a second by default; wheels start at once.
  config.spool_up_s = output.number("spool_up_s", wheels ? 0.0 : 0.5, 0.0, 10.0);
  config.outputs.assign(static_cast<std::size_t>(config.motors()), ch);

  const YAML::Node per_motor = output.raw("per_motor");
  if (per_motor.IsDefined() && !per_motor.IsNull()) {
    const std::string path = output.path_of("per_motor");
    if (!per_motor.IsSequence() || static_cast<int>(per_motor.size()) != config.motors()) {
      fail(path, describe(per_motor),
           "a list of " + std::to_string(config.motors()) + " entries, one per motor");
    }
    for (std::size_t i = 0; i < per_motor.size(); ++i) {
      MapReader m(per_motor[i], path + "[" + std::to_string(i) + "]");
      OutputChannel& c = config.outputs[i];
      read_range(m, c);
      c.trim = m.number("trim", 0.0, -0.5, 0.5);
      c.reversed = read_bool(m, "reversed", false);
      m.finish();
    }
  }
  output.finish();
}

void read_inputs(MapReader inputs, Config& config) {
  const std::string yaw = inputs.choice("yaw_source", "setpoint", {"setpoint", "pid"});
  config.inputs.yaw_source = yaw == "pid" ? YawSource::kPid : YawSource::kSetpoint;
  config.inputs.setpoint_timeout_s =
      inputs.number("setpoint_timeout_ms", 100.0, 1.0, 10000.0) / 1e3;
  config.inputs.pid_timeout_s = inputs.number("pid_timeout_ms", 100.0, 1.0, 10000.0) / 1e3;
  const std::string failsafe = inputs.choice("failsafe", "disarm", {"disarm", "hold_last", "idle"});
  config.inputs.failsafe = failsafe == "hold_last" ? FailsafeAction::kHoldLast
                           : failsafe == "idle"    ? FailsafeAction::kIdle
                                                   : FailsafeAction::kDisarm;
  config.inputs.hold_last_s = inputs.number("hold_last_ms", 500.0, 1.0, 5000.0) / 1e3;
  config.inputs.max_future_s = inputs.number("max_future_ms", 1000.0, 1.0, 3.6e6) / 1e3;
  config.inputs.arm_max_throttle = inputs.number("arm_max_throttle", 0.1, 0.0, 1.0);
  inputs.finish();
}

void read_motor_test(MapReader test, Config& config) {
  config.motor_test.enabled = read_bool(test, "enabled", true);
  config.motor_test.max_throttle = test.number("max_throttle", 0.15, 0.0, 1.0);
  config.motor_test.max_seconds = test.number("max_seconds", 3.0, 0.0, 60.0);
  test.finish();
}

void read_realtime(MapReader rt, Config& config) {
  config.realtime.priority = static_cast<int>(rt.number("priority", 0, 0, 99));
  const YAML::Node cpus = rt.raw("cpus");
  if (cpus.IsDefined() && !cpus.IsNull()) {
    // An empty list, like no list, leaves the affinity alone.
    for (double c : read_numbers(cpus, rt.path_of("cpus"), 0, 1024, 0, 1023)) {
      config.realtime.cpus.push_back(static_cast<int>(c));
    }
  }
  config.realtime.lock_memory = read_bool(rt, "lock_memory", false);
  rt.finish();
}

void read_channels(MapReader channels, Config& config) {
  Channels& c = config.channels;
  c.setpoint = channels.text("setpoint", c.setpoint);
  c.pid = channels.text("pid", c.pid);
  c.motor_pwm = channels.text("motor_pwm", c.motor_pwm);
  c.status = channels.text("status", c.status);
  c.motor_status = channels.text("motor_status", c.motor_status);
  c.battery = channels.text("battery", c.battery);
  c.motor_test = channels.text("motor_test", c.motor_test);
  c.esc_telemetry = channels.text("esc_telemetry", c.esc_telemetry);
  c.attitude = channels.text("attitude", c.attitude);
  channels.finish();
  // One channel, one message type: a shared input channel would hand each
  // message to two decoders (one of which rejects it, cycle after cycle),
  // and an output on an input's channel would feed the mixer its own
  // messages. Offline replay, reading each channel once, would behave
  // differently again.
  const std::pair<const char*, const std::string*> named[] = {
      {"setpoint", &c.setpoint},         {"pid", &c.pid},
      {"motor_pwm", &c.motor_pwm},       {"status", &c.status},
      {"motor_status", &c.motor_status}, {"battery", &c.battery},
      {"motor_test", &c.motor_test},     {"esc_telemetry", &c.esc_telemetry},
      {"attitude", &c.attitude}};
  for (std::size_t i = 0; i < std::size(named); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (*named[i].second == *named[j].second) {
        fail(std::string("channels.") + named[i].first,
             "'" + *named[i].second + "', the channel of channels." + named[j].first,
             "a channel name no other input or output of this mixer uses");
      }
    }
  }
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
  config.publish = root.choice("publish", "timer", {"timer", "on_input"}) == "on_input"
                       ? PublishMode::kOnInput
                       : PublishMode::kTimer;
  config.loop_rate_hz = root.number("loop_rate_hz", 400.0, 50.0, 10000.0);
  config.status_rate_hz = root.number("status_rate_hz", 10.0, 0.1, 1000.0);
  if (root.has("battery")) read_battery(root.map("battery"), config);
  read_vehicle_physics(root.map("vehicle"), config);
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

const char* to_string(Strategy strategy) {
  switch (strategy) {
    case Strategy::kLegacyBudget:
      return "legacy_budget";
    case Strategy::kBudget:
      return "budget";
    case Strategy::kShift:
      return "shift";
    case Strategy::kClip:
      return "clip";
    case Strategy::kPrioritized:
      return "prioritized";
    case Strategy::kOptimal:
      return "optimal";
  }
  return "?";
}

const char* to_string(YawSource source) { return source == YawSource::kPid ? "pid" : "setpoint"; }

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
