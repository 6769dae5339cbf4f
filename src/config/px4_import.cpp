// `motormix import px4-params` (px4_import.hpp): PX4 parameters, from a
// QGroundControl .params file or a ULog's parameter messages, into a
// commented configuration.

#include <motormix/config/px4_import.hpp>
#include <motormix/config/ulog.hpp>

#include <motormix/motor_vector.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <iterator>
#include <limits>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

namespace motormix::config {

namespace {

// PX4's defaults where a parameter is absent.
constexpr double kDefaultKm = 0.05;
constexpr double kDefaultCt = 6.5;
constexpr double kDefaultPwmMin = 1000.0, kDefaultPwmMax = 2000.0, kDefaultPwmDisarmed = 900.0;
constexpr int kMotorFunctionFirst = 101;  // PWM_MAIN_FUNCi: 101 is motor 1

std::string read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open " + path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

Px4Parameters read_ulog(const std::string& bytes, const std::string& path) {
  Px4Parameters p;
  p.format = "ulog";
  p.values = Ulog::parse(bytes, path).parameters();
  if (p.values.empty()) throw std::runtime_error(path + ": a ULog without parameters");
  return p;
}

// QGroundControl: "vehicle<TAB>component<TAB>NAME<TAB>value<TAB>type" per
// line, '#' comments.
Px4Parameters read_params(const std::string& text, const std::string& path) {
  Px4Parameters p;
  p.format = "params";
  std::istringstream in(text);
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty() || line[0] == '#' || line.find_first_not_of(" \t\r") == std::string::npos)
      continue;
    std::istringstream fields(line);
    std::string vehicle, component, name, value;
    if (!(fields >> vehicle >> component >> name >> value)) {
      throw std::runtime_error(path + ":" + std::to_string(number) +
                               ": not a parameter line (vehicle, component, name, value, type)");
    }
    char* end = nullptr;
    const double v = std::strtod(value.c_str(), &end);
    if (end == value.c_str() || *end != '\0' || !std::isfinite(v)) {
      throw std::runtime_error(path + ":" + std::to_string(number) + ": " + name + " = '" + value +
                               "' is not a number");
    }
    p.values[name] = v;
  }
  if (p.values.empty()) throw std::runtime_error(path + ": no parameters");
  return p;
}

// Seven significant digits: PX4 keeps its parameters as 32-bit floats
// (0.1515 is stored as 0.151500002), and no more are meant.
std::string number(double v) {
  std::ostringstream s;
  s << std::setprecision(7) << v;
  return s.str();
}

struct Reader {
  const std::map<std::string, double>& values;
  std::set<std::string> used;
  std::optional<double> get(const std::string& name) {
    const auto it = values.find(name);
    if (it == values.end()) return std::nullopt;
    used.insert(name);
    return it->second;
  }
  double get(const std::string& name, double fallback) { return get(name).value_or(fallback); }
};

// Pre-1.13 airframes (SYS_AUTOSTART ranges, PX4's numbering) that a preset
// describes with PX4's motor numbering.
const char* preset_of_autostart(int id) {
  switch (id / 1000) {
    case 4:
      return "quad_x";
    case 5:
      return "quad_plus";
    case 6:
      return "hexa_x";
    case 7:
      return "hexa_plus";
    case 8:
      return "octo_x";
    case 9:
      return "octo_plus";
    case 11:
      return "y6";
    case 12:
      return "octo_coax_x8";
    default:
      return nullptr;
  }
}

struct Axis3 {
  double x, y, z;
};

struct Range {
  double min, max, disarmed;
  bool operator==(const Range& o) const {
    return min == o.min && max == o.max && disarmed == o.disarmed;
  }
};

}  // namespace

Px4Parameters read_px4_parameters(const std::string& path) {
  return parse_px4_parameters(read_all(path), path);
}

Px4Parameters parse_px4_parameters(const std::string& bytes, const std::string& path) {
  if (Ulog::is_ulog(bytes)) return read_ulog(bytes, path);
  if (bytes.find('\0') != std::string::npos) {
    throw std::runtime_error(path + ": neither a QGroundControl .params file nor a ULog");
  }
  return read_params(bytes, path);
}

Px4Import import_px4(const Px4Parameters& params, const std::string& source_name) {
  Px4Import out;
  Reader r{params.values, {}};
  std::ostringstream y;
  y << "# Imported by `motormix import px4-params` from " << source_name << " ("
    << params.values.size() << " parameters).\n";
  const std::optional<double> airframe = r.get("CA_AIRFRAME");
  if (airframe && *airframe != 0.0) {
    throw std::runtime_error("CA_AIRFRAME = " + number(*airframe) +
                             ": not a multicopter (0); motormix mixes multirotors here");
  }
  const std::optional<double> count = r.get("CA_ROTOR_COUNT");
  int motors = 0;
  y << "name: px4_import\n";
  if (count) {
    motors = static_cast<int>(std::lround(*count));
    if (motors < 1 || motors > kMaxMotors) {
      throw std::runtime_error("CA_ROTOR_COUNT = " + number(*count) + ": motormix mixes 1 to " +
                               std::to_string(kMaxMotors) + " rotors");
    }
    y << "# The rotors as PX4's control allocation places them (CA_ROTORi_*, body FRD,\n"
         "# metres); KM's sign is the spin (positive: counter-clockwise), CT the thrust\n"
         "# coefficient. PX4's normalization: the same scaling of each axis.\n"
         "geometry:\n  normalization: px4\n  rotors:\n";
    for (int i = 0; i < motors; ++i) {
      const std::string p = "CA_ROTOR" + std::to_string(i) + "_";
      const double km = r.get(p + "KM", kDefaultKm);
      const Axis3 axis{r.get(p + "AX", 0.0), r.get(p + "AY", 0.0), r.get(p + "AZ", -1.0)};
      y << "    - {position: [" << number(r.get(p + "PX", 0.0)) << ", "
        << number(r.get(p + "PY", 0.0)) << ", " << number(r.get(p + "PZ", 0.0))
        << "], spin: " << (km >= 0.0 ? "ccw" : "cw")
        << ", thrust_coefficient: " << number(r.get(p + "CT", kDefaultCt))
        << ", torque_ratio: " << number(std::abs(km));
      if (!(axis.x == 0.0 && axis.y == 0.0 && axis.z == -1.0))
        y << ", axis: [" << number(axis.x) << ", " << number(axis.y) << ", " << number(axis.z)
          << "]";
      y << "}  # motor " << i + 1 << "\n";
    }
  } else if (const std::optional<double> autostart = r.get("SYS_AUTOSTART")) {
    const int id = static_cast<int>(std::lround(*autostart));
    const char* preset = preset_of_autostart(id);
    if (preset == nullptr) {
      throw std::runtime_error("no CA_ROTOR_COUNT, and SYS_AUTOSTART = " + std::to_string(id) +
                               " is no multirotor airframe motormix has a preset for");
    }
    y << "# From before control allocation: SYS_AUTOSTART " << id
      << ", PX4's generic airframe of this\n# shape (motor numbering as PX4's).\n"
      << "geometry: {preset: " << preset << "}\n";
    out.notes.push_back("SYS_AUTOSTART " + std::to_string(id) + " read as the preset " + preset +
                        ": the frame's exact arm lengths are not in the parameters");
    for (const char* m : {"quad_x", "quad_plus"})
      if (std::string(preset) == m) motors = 4;
    if (motors == 0)
      motors = std::string(preset).find("hexa") != std::string::npos || std::string(preset) == "y6"
                   ? 6
                   : 8;
  } else {
    throw std::runtime_error(
        "neither CA_ROTOR_COUNT nor SYS_AUTOSTART: no multirotor geometry in these parameters");
  }

  // The strategy: PX4's sequential desaturation, or its plain clipping.
  const double method = r.get("CA_METHOD", 2.0);
  const double airmode = r.get("MC_AIRMODE", 0.0);
  const char* airmode_name = airmode >= 2.0   ? "roll_pitch_yaw"
                             : airmode >= 1.0 ? "roll_pitch"
                                              : "off";
  y << "mixer:\n";
  if (method == 0.0) {
    y << "  strategy: clip  # CA_METHOD 0: pseudo-inverse with output clipping\n";
  } else {
    y << "  strategy: prioritized  # CA_METHOD " << number(method)
      << ": sequential desaturation\n  prioritized: {airmode: " << airmode_name
      << "}  # MC_AIRMODE " << number(airmode) << "\n";
  }

  // Outputs: the channels PWM_MAIN_FUNCi gives to motors.
  std::vector<int> channel(static_cast<std::size_t>(motors), 0);
  bool functions = false;
  for (int c = 1; c <= 16; ++c) {
    const std::optional<double> f = r.get("PWM_MAIN_FUNC" + std::to_string(c));
    if (!f) continue;
    functions = true;
    const int motor = static_cast<int>(std::lround(*f)) - kMotorFunctionFirst;
    if (motor >= 0 && motor < motors) {
      channel[static_cast<std::size_t>(motor)] = c;
    } else if (*f != 0.0) {
      out.not_mapped.push_back(
          "PWM_MAIN_FUNC" + std::to_string(c) + " = " + number(*f) + ": output " +
          std::to_string(c) + " drives something other than a motor (motormix drives motors only)");
    }
  }
  const double global_min = r.get("PWM_MAIN_MIN", kDefaultPwmMin);
  const double global_max = r.get("PWM_MAIN_MAX", kDefaultPwmMax);
  const double global_dis = r.get("PWM_MAIN_DISARM", kDefaultPwmDisarmed);
  std::vector<Range> ranges;
  std::vector<int> motor_channels;  // the output each motor is on
  for (int m = 0; m < motors; ++m) {
    int c = channel[static_cast<std::size_t>(m)];
    if (c == 0) {
      if (functions) {
        out.notes.push_back("motor " + std::to_string(m + 1) +
                            " has no PWM_MAIN_FUNC output: the default range is used");
      }
      c = m + 1;
    }
    motor_channels.push_back(c);
    const std::string n = std::to_string(c);
    ranges.push_back({r.get("PWM_MAIN_MIN" + n, global_min), r.get("PWM_MAIN_MAX" + n, global_max),
                      r.get("PWM_MAIN_DIS" + n, global_dis)});
  }
  const double thr_mdl = r.get("THR_MDL_FAC", 0.0);
  y << "# PWM_MAIN_MIN/MAX/DIS of each motor's output (PWM_MAIN_FUNC)";
  if (functions) {
    y << ": ";
    for (int m = 0; m < motors; ++m)
      y << (m ? ", " : "") << "motor " << m + 1 << " on output "
        << (channel[static_cast<std::size_t>(m)] ? channel[static_cast<std::size_t>(m)] : m + 1);
  }
  y << ".\n# motormix publishes the motors in order: wire output i to motor i, or remap.\n";
  y << "output:\n  mode: unipolar\n";
  const bool same = std::all_of(ranges.begin(), ranges.end(),
                                [&](const Range& x) { return x == ranges.front(); });
  if (same) {
    y << "  min: " << number(ranges.front().min) << "\n  max: " << number(ranges.front().max)
      << "\n  disarmed: " << number(ranges.front().disarmed) << "\n";
  } else {
    y << "  per_motor:\n";
    for (const Range& x : ranges)
      y << "    - {min: " << number(x.min) << ", max: " << number(x.max)
        << ", disarmed: " << number(x.disarmed) << "}\n";
  }
  y << "  thrust_model_factor: " << number(std::clamp(thr_mdl, 0.0, 1.0)) << "  # THR_MDL_FAC\n";
  if (thr_mdl < 0.0 || thr_mdl > 1.0)
    out.notes.push_back("THR_MDL_FAC = " + number(thr_mdl) + " clamped into 0..1");

  // Whatever else concerns mixing or outputs, not taken: named.
  const auto concerns = [](const std::string& name) {
    for (const char* prefix : {"CA_", "PWM_MAIN_", "MOT_", "THR_MDL", "MC_AIRMODE"})
      if (name.rfind(prefix, 0) == 0) return true;
    return false;
  };
  int zero = 0;
  for (const auto& [name, value] : params.values) {
    if (r.used.count(name) || !concerns(name)) continue;
    // The outputs that are not motors: their function is named above.
    if (name.rfind("PWM_MAIN_", 0) == 0) {
      const std::size_t digit = name.find_first_of("0123456789");
      const int c = digit == std::string::npos ? 0 : std::atoi(name.c_str() + digit);
      if (c > 0 &&
          std::find(motor_channels.begin(), motor_channels.end(), c) == motor_channels.end())
        continue;
    }
    if (name.rfind("CA_ROTOR", 0) == 0 && name != "CA_ROTOR_COUNT") {
      // Another rotor index than those counted: PX4 ignores it too.
      const int i = std::atoi(name.c_str() + 8);
      if (i >= motors) continue;
    }
    // A feature at 0 is off: nothing is lost by not taking it (counted).
    if (value == 0.0) {
      ++zero;
      continue;
    }
    std::string why = "not mapped";
    if (name == "CA_R_REV" && value != 0.0) why = "reversible motors (3D): not supported";
    if (name == "MOT_ORDERING" && value != 0.0)
      why = "outputs in another order than PX4's: set geometry.motor_order by hand";
    if (name.rfind("PWM_MAIN_REV", 0) == 0 && value != 0.0)
      why = "a reversed output: set output.per_motor[].reversed by hand";
    out.not_mapped.push_back(name + " = " + number(value) + ": " + why);
  }
  if (zero > 0)
    out.notes.push_back(std::to_string(zero) +
                        " more mixing and output parameters at 0 (off) not taken");
  for (const std::string& n : out.notes) y << "# note: " << n << "\n";
  out.yaml = y.str();
  return out;
}

}  // namespace motormix::config
