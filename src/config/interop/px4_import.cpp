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

// PX4's output groups whose FUNCi parameters can name a motor: PWM outputs
// (MIN/MAX/DIS per channel, a group default without the number) and
// UAVCAN ESCs, which motormix does not drive.
struct OutputGroup {
  const char* prefix;  // "PWM_MAIN_"
  const char* label;   // "MAIN"
  bool pwm;
};
constexpr OutputGroup kOutputGroups[] = {
    {"PWM_MAIN_", "MAIN", true}, {"PWM_AUX_", "AUX", true}, {"UAVCAN_EC_", "UAVCAN ESC", false}};
constexpr int kMaxChannelsPerGroup = 16;

const OutputGroup* group_of(const std::string& name) {
  for (const OutputGroup& g : kOutputGroups)
    if (name.rfind(g.prefix, 0) == 0) return &g;
  return nullptr;
}

// Where a motor's commands go: a group's channel (1-based).
struct Output {
  const OutputGroup* group = nullptr;
  int channel = 0;
  std::string name() const { return std::string(group->label) + " " + std::to_string(channel); }
};

// Why a parameter that concerns the outputs is not taken, where PX4's
// meaning says more than "not mapped".
std::string why_not_mapped(const std::string& name, double value) {
  if (name.find("_TIM") != std::string::npos && group_of(name) != nullptr) {
    // PWM_MAIN_TIMn / PWM_AUX_TIMn: a timer group's protocol.
    const int v = static_cast<int>(std::lround(value));
    if (v == -5 || v == -4 || v == -3) {
      const char* speed = v == -5 ? "150" : v == -4 ? "300" : "600";
      return std::string("DShot") + speed +
             " on this timer's outputs: with the pulse firmware set hardware.protocol: dshot" +
             speed + " (docs/wiring-it-to-motors.md); the output range stays in microseconds";
    }
    if (v == -2) return "DShot1200: the pulse firmware sends DShot150, 300 or 600";
    if (v == -1) return "OneShot125: not supported (servo PWM or DShot)";
    if (v > 0)
      return "PWM at " + number(value) +
             " Hz on this timer's outputs: hardware.pulse_rate_hz with the pulse firmware";
  }
  if (name == "DSHOT_CONFIG") {
    return "DShot " + number(value) +
           ": with the pulse firmware set hardware.protocol (dshot150, dshot300 or dshot600)";
  }
  if (name.rfind("DSHOT_", 0) == 0) return "PX4's DShot driver setting: see hardware: instead";
  if (name.rfind("UAVCAN_EC_", 0) == 0)
    return "a UAVCAN ESC's setting: motormix does not drive UAVCAN ESCs";
  if (name.rfind("CA_SV_CS", 0) == 0) {
    return "control surfaces: motormix mixes the rotors only; the surfaces need another "
           "mixer";
  }
  if (name.rfind("CA_SV_TL", 0) == 0) return "tilt servos: motormix drives no servo";
  return "not mapped";
}

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
      const std::optional<double> tilt = r.get(p + "TILT");
      if (tilt && *tilt != 0.0) {
        throw std::runtime_error(p + "TILT = " + number(*tilt) +
                                 ": a rotor a servo tilts in flight; motormix's mixing matrix is "
                                 "fixed, so it cannot mix this vehicle");
      }
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
  // Airmode: the continuous limits where the airframe has them (PX4's
  // limited airmode, MC_AIRMODE_LIM for roll/pitch and MC_AIRMODE_YLIM for
  // yaw, each a share of the range in [0, 1]: the same quantity as
  // motormix's airmode_limits), else the named MC_AIRMODE.
  const std::optional<double> lim = r.get("MC_AIRMODE_LIM");
  const std::optional<double> ylim = r.get("MC_AIRMODE_YLIM");
  std::ostringstream prioritized;
  if (lim || ylim) {
    const auto share = [&](const char* name, const std::optional<double>& v) {
      const double x = v.value_or(0.0);
      const double clamped = std::isfinite(x) ? std::clamp(x, 0.0, 1.0) : 0.0;
      if (clamped != x)
        out.notes.push_back(std::string(name) + " = " + number(x) + " clamped into 0..1");
      return clamped;
    };
    const double rp = share("MC_AIRMODE_LIM", lim);
    const double yaw = share("MC_AIRMODE_YLIM", ylim);
    prioritized << "{airmode_limits: {roll_pitch: " << number(rp) << ", yaw: " << number(yaw)
                << "}}  # MC_AIRMODE_LIM " << number(lim.value_or(0.0)) << ", MC_AIRMODE_YLIM "
                << number(ylim.value_or(0.0));
    r.get("MC_AIRMODE");  // superseded by the limits: taken, not listed as left out
  } else {
    const double airmode = r.get("MC_AIRMODE", 0.0);
    prioritized << "{airmode: "
                << (airmode >= 2.0   ? "roll_pitch_yaw"
                    : airmode >= 1.0 ? "roll_pitch"
                                     : "off")
                << "}  # MC_AIRMODE " << number(airmode);
  }
  y << "mixer:\n";
  if (method == 0.0) {
    y << "  strategy: clip  # CA_METHOD 0: pseudo-inverse with output clipping\n";
  } else {
    y << "  strategy: prioritized  # CA_METHOD " << number(method)
      << ": sequential desaturation\n  prioritized: " << prioritized.str() << "\n";
  }

  // Outputs: the channels each group's FUNCi parameters give to motors.
  std::vector<Output> where(static_cast<std::size_t>(motors));
  bool functions = false;
  for (const OutputGroup& g : kOutputGroups) {
    for (int c = 1; c <= kMaxChannelsPerGroup; ++c) {
      const std::string name = std::string(g.prefix) + "FUNC" + std::to_string(c);
      const std::optional<double> f = r.get(name);
      if (!f) continue;
      functions = true;
      const int motor = static_cast<int>(std::lround(*f)) - kMotorFunctionFirst;
      if (motor >= 0 && motor < motors) {
        Output& w = where[static_cast<std::size_t>(motor)];
        if (w.group != nullptr) {
          out.not_mapped.push_back(name + " = " + number(*f) + ": motor " +
                                   std::to_string(motor + 1) + " is on " + w.name() +
                                   " already: only that output is taken");
        } else {
          w = {&g, c};
        }
      } else if (*f != 0.0) {
        out.not_mapped.push_back(name + " = " + number(*f) + ": " + g.label + " output " +
                                 std::to_string(c) +
                                 " drives something other than a motor (motormix drives motors "
                                 "only)");
      }
    }
  }
  std::vector<Range> ranges;
  for (int m = 0; m < motors; ++m) {
    Output& w = where[static_cast<std::size_t>(m)];
    if (w.group == nullptr) {
      if (functions) {
        out.notes.push_back("motor " + std::to_string(m + 1) +
                            " has no FUNC output: the default range is used");
      }
      w = {&kOutputGroups[0], m + 1};
    }
    if (!w.group->pwm) {
      out.notes.push_back("motor " + std::to_string(m + 1) + " is on " + w.name() +
                          ", an ESC motormix cannot drive (it drives PWM and DShot ESCs through "
                          "its pulse firmware): wire it there; the default range is used");
      ranges.push_back({kDefaultPwmMin, kDefaultPwmMax, kDefaultPwmDisarmed});
      continue;
    }
    const std::string g = w.group->prefix, n = std::to_string(w.channel);
    ranges.push_back({r.get(g + "MIN" + n, r.get(g + "MIN", kDefaultPwmMin)),
                      r.get(g + "MAX" + n, r.get(g + "MAX", kDefaultPwmMax)),
                      r.get(g + "DIS" + n, r.get(g + "DISARM", kDefaultPwmDisarmed))});
  }
  const double thr_mdl = r.get("THR_MDL_FAC", 0.0);
  y << "# MIN/MAX/DIS of each motor's output (its FUNC parameter)";
  if (functions) {
    y << ": ";
    for (int m = 0; m < motors; ++m)
      y << (m ? ", " : "") << "motor " << m + 1 << " on "
        << where[static_cast<std::size_t>(m)].name();
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

  y << "# PX4 keeps no mass, inertia or thrust: no spin landing on a guessed vehicle.\n"
       "# Add a measured `vehicle:` section and remove this (docs/motor-loss-landing.md).\n"
       "motor_loss: {mode: off}\n";

  // Whatever else concerns mixing or outputs, not taken: named, with why.
  const auto concerns = [](const std::string& name) {
    for (const char* prefix :
         {"CA_", "PWM_MAIN_", "PWM_AUX_", "UAVCAN_EC_", "DSHOT_", "MOT_", "THR_MDL", "MC_AIRMODE"})
      if (name.rfind(prefix, 0) == 0) return true;
    return false;
  };
  int zero = 0;
  for (const auto& [name, value] : params.values) {
    if (r.used.count(name) || !concerns(name)) continue;
    // The outputs that are not motors: their function is named above. A
    // timer's protocol (TIMn) concerns the motors on it whatever its number.
    const OutputGroup* group = group_of(name);
    if (group != nullptr && name.find("_TIM") == std::string::npos) {
      const std::size_t digit = name.find_first_of("0123456789");
      const int c = digit == std::string::npos ? 0 : std::atoi(name.c_str() + digit);
      const bool motor = std::any_of(where.begin(), where.end(), [&](const Output& w) {
        return w.group == group && w.channel == c;
      });
      if (c > 0 && !motor) continue;
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
    std::string why = why_not_mapped(name, value);
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
