// geometry: the five forms (preset, rotors, table, effectiveness, paparazzi),
// the wheel base of ground vehicles, motor order and names.

#include "section_readers.hpp"

#include "interop/paparazzi_import.hpp"

#include <motormix/effectiveness/presets.hpp>

#include <cmath>
#include <sstream>
#include <utility>

namespace motormix::config::reading {

namespace {

Vehicle rotors_vehicle(const YAML::Node& list, const std::string& path) {
  if (!list.IsSequence() || list.size() < 1 || list.size() > kMaxMotors) {
    fail(path, describe(list), "a list of 1 to " + std::to_string(kMaxMotors) + " rotors");
  }
  std::vector<Rotor> rotors;
  for (std::size_t i = 0; i < list.size(); ++i) {
    MapReader r(list[i], path + "[" + std::to_string(i) + "]");
    Rotor rotor = read_rotor_placement(r, {2, kMaxCoefficient, "[x, y] or [x, y, z]"});
    rotor.thrust_coefficient = r.number("thrust_coefficient", 1.0, 1e-6, 1e6);
    rotor.torque_ratio = r.number("torque_ratio", 0.05, 0.0, 10.0);
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

}  // namespace

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

  config.normalization =
      geometry.choice("normalization", Normalization::kAxisMax, kNormalizationNames);
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

}  // namespace motormix::config::reading
