#include <motormix/config/matrix_export.hpp>

#include <motormix/angles.hpp>
#include <motormix/config/build_mixer.hpp>

#include <motormix/version.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <map>
#include <sstream>

namespace motormix::config {

namespace {

// Enough digits that the text reads back as the same double.
std::string exact(double v) {
  if (v == 0.0) v = 0.0;  // no "-0"
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

std::string fixed(double v, int width = 8) {
  if (std::abs(v) < 5e-5) v = 0.0;
  std::ostringstream s;
  s << std::fixed << std::setprecision(4) << std::setw(width) << v;
  return s.str();
}

std::string detail(const Config& c, int i) {
  const auto& d = c.geometry.motor_details;
  return static_cast<std::size_t>(i) < d.size() ? d[static_cast<std::size_t>(i)] : "";
}

// Top view of a rotor vehicle (front up, right to the right), recovered from
// its effectiveness matrix: for upright rotors, pitch effectiveness is x and
// roll effectiveness is -y; the sign of yaw gives the spin. Coaxial rotors
// share a spot. Tables and wheels have no positions to draw.
std::string diagram(const Config& c) {
  if (!c.geometry.effectiveness || c.wheel_base) return "";
  const EffectivenessMatrix& e = *c.geometry.effectiveness;
  constexpr int kRows = 9;
  constexpr int kCols = 41;
  double extent = 0.0;
  for (Eigen::Index i = 0; i < e.cols(); ++i) {
    extent =
        std::max({extent, std::abs(e(index(Axis::kRoll), i)), std::abs(e(index(Axis::kPitch), i))});
  }
  if (extent <= 0.0) return "";
  std::vector<std::string> grid(kRows, std::string(kCols, ' '));
  std::map<std::pair<int, int>, std::string> spots;
  for (Eigen::Index i = 0; i < e.cols(); ++i) {
    const double x = e(index(Axis::kPitch), i) / extent;
    const double y = -e(index(Axis::kRoll), i) / extent;
    const int row = static_cast<int>(std::lround((1.0 - x) * (kRows - 1) / 2.0));
    const int col = static_cast<int>(std::lround((1.0 + y) * (kCols - 9) / 2.0)) + 4;
    std::string& label = spots[{row, col}];
    label += (label.empty() ? "" : "/") + std::to_string(i + 1) +
             (e(index(Axis::kYaw), i) > 0 ? "ccw" : "cw");
  }
  grid[(kRows - 1) / 2][kCols / 2] = '+';
  for (const auto& [at, label] : spots) {
    const int start = std::clamp(at.second - static_cast<int>(label.size()) / 2, 0,
                                 kCols - static_cast<int>(label.size()));
    grid[static_cast<std::size_t>(at.first)].replace(static_cast<std::size_t>(start), label.size(),
                                                     label);
  }
  std::string out = std::string(kCols / 2 - 2, ' ') + "front\n";
  for (const std::string& line : grid) {
    const auto end = line.find_last_not_of(' ');
    out += (end == std::string::npos ? "" : line.substr(0, end + 1)) + "\n";
  }
  return out;
}

std::string table(const Config& c) {
  std::ostringstream s;
  s << "vehicle: " << c.description() << "\n";
  s << "normalization: " << to_string(c.normalization) << ", rank: " << rank_of(c.mixing) << " of "
    << kNumAxes << " axes";
  if (c.wheel_base) {
    s << "\nwheels: radius " << c.wheel_base->wheel_radius << ", track "
      << c.wheel_base->track_width << ", max wheel speed " << c.wheel_base->max_wheel_speed
      << " rad/s -> forward " << c.wheel_base->max_forward_speed() << " m/s, turn "
      << c.wheel_base->max_turn_rate() << " rad/s at full command";
  }
  int where_width = 20;  // the widest motor detail, and at least this
  for (int i = 0; i < c.motors(); ++i) {
    where_width = std::max(where_width, static_cast<int>(detail(c, i).size()) + 2);
  }
  s << "\n\n"
    << std::left << std::setw(7) << "motor" << std::setw(where_width) << "where" << std::right;
  for (const char* axis : kAxisNames) s << std::setw(9) << axis;
  s << "\n";
  for (int i = 0; i < c.motors(); ++i) {
    s << std::left << std::setw(7) << c.motor_names()[static_cast<std::size_t>(i)]
      << std::setw(where_width) << detail(c, i) << std::right;
    for (int a = 0; a < kNumAxes; ++a) s << " " << fixed(c.mixing(i, a));
    s << "\n";
  }
  const AxisVector authority = authority_of(c);
  s << "\nauthority (largest pure demand deliverable; torques from "
    << (c.thrust_range() == ThrustRange::kUnipolar ? "half thrust" : "standstill") << "):";
  for (int a = 0; a < kNumAxes; ++a)
    s << " " << kAxisNames[static_cast<std::size_t>(a)] << " " << fixed(authority[a], 0);
  s << "\n";
  const std::string top_view = diagram(c);
  if (!top_view.empty()) s << "\ntop view (motor number, spin seen from above):\n" << top_view;
  return s.str();
}

std::string json(const Config& c) {
  nlohmann::json j;
  j["motors"] = c.motors();
  j["names"] = c.motor_names();
  j["details"] = nlohmann::json::array();
  for (int i = 0; i < c.motors(); ++i) j["details"].push_back(detail(c, i));
  j["axes"] = {"roll", "pitch", "yaw", "thrust"};
  j["normalization"] = to_string(c.normalization);
  j["rank"] = rank_of(c.mixing);
  j["matrix"] = nlohmann::json::array();
  for (int i = 0; i < c.motors(); ++i) {
    std::vector<double> row;
    for (int a = 0; a < kNumAxes; ++a) row.push_back(c.mixing(i, a) == 0.0 ? 0.0 : c.mixing(i, a));
    j["matrix"].push_back(row);
  }
  const AxisVector authority = authority_of(c);
  for (int a = 0; a < kNumAxes; ++a)
    j["authority"][kAxisNames[static_cast<std::size_t>(a)]] = authority[a];
  return j.dump() + "\n";
}

std::string yaml(const Config& c) {
  std::ostringstream s;
  s << "# mixing matrix of " << c.description() << ", normalization " << to_string(c.normalization)
    << "\n# columns: roll, pitch, yaw, thrust\ngeometry:\n  mixing:\n";
  for (int i = 0; i < c.motors(); ++i) {
    s << "    - [";
    for (int a = 0; a < kNumAxes; ++a) s << (a ? ", " : "") << exact(c.mixing(i, a));
    s << "]";
    const std::string d = detail(c, i);
    if (!d.empty()) s << "  # " << c.motor_names()[static_cast<std::size_t>(i)] << ": " << d;
    s << "\n";
  }
  s << "  motor_names: [";
  for (int i = 0; i < c.motors(); ++i)
    s << (i ? ", " : "") << c.motor_names()[static_cast<std::size_t>(i)];
  s << "]\n";
  return s.str();
}

std::string coefficient_list(const std::vector<std::vector<long>>& coeffs, int axis) {
  std::ostringstream s;
  s << "{";
  for (std::size_t i = 0; i < coeffs.size(); ++i) {
    s << (i ? ", " : " ") << std::setw(4) << coeffs[i][static_cast<std::size_t>(axis)];
  }
  s << "}";
  return s.str();
}

std::string paparazzi(const Config& c) {
  const auto coeffs = scaled_coefficients(c.mixing, 256.0);
  std::ostringstream s;
  s << "<section name=\"MIXING\" prefix=\"MOTOR_MIXING_\">\n"
    << "  <define name=\"TRIM_ROLL\" value=\"0\"/>\n"
    << "  <define name=\"TRIM_PITCH\" value=\"0\"/>\n"
    << "  <define name=\"TRIM_YAW\" value=\"0\"/>\n"
    << "  <define name=\"NB_MOTOR\" value=\"" << c.motors() << "\"/>\n"
    << "  <define name=\"SCALE\" value=\"256\"/>\n";
  const char* names[] = {"ROLL_COEF\"  ", "PITCH_COEF\" ", "YAW_COEF\"   ", "THRUST_COEF\""};
  for (int a = 0; a < kNumAxes; ++a) {
    s << "  <define name=\"" << names[a] << " value=\"" << coefficient_list(coeffs, a) << "\"/>\n";
  }
  s << "</section>\n";
  return s.str();
}

std::string header(const Config& c) {
  std::ostringstream s;
  s << "/* Mixing matrix generated by motormix: " << c.description() << ".\n"
    << " * command[i] = sum over axes of MOTORMIX_MIXING[i][axis] * demand[axis];\n"
    << " * axes: roll, pitch, yaw, thrust. Normalization: " << to_string(c.normalization)
    << ". */\n#ifndef MOTORMIX_MIXING_H\n#define MOTORMIX_MIXING_H\n\n"
    << "#define MOTORMIX_NUM_MOTORS " << c.motors() << "\n#define MOTORMIX_NUM_AXES 4\n\n"
    << "static const float MOTORMIX_MIXING[MOTORMIX_NUM_MOTORS][MOTORMIX_NUM_AXES] = {\n";
  for (int i = 0; i < c.motors(); ++i) {
    s << "    {";
    for (int a = 0; a < kNumAxes; ++a) {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.9gf", c.mixing(i, a) == 0.0 ? 0.0 : c.mixing(i, a));
      s << (a ? ", " : "") << buf;
    }
    s << "}, /* " << c.motor_names()[static_cast<std::size_t>(i)];
    const std::string d = detail(c, i);
    if (!d.empty()) s << ": " << d;
    s << " */\n";
  }
  s << "};\n\n#endif /* MOTORMIX_MIXING_H */\n";
  return s.str();
}

// A value for a parameter file: short, exact enough (1e-6), no "-0".
std::string param(double v) {
  if (std::abs(v) < 5e-7) v = 0.0;
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

// PX4's default CA_ROTORn_CT (thrust at full command, N): a rotor with
// motormix's relative thrust coefficient 1 gets PX4's default.
constexpr double kPx4DefaultCt = 6.5;

std::string px4(const Config& c) {
  const std::vector<Rotor>& rotors = c.geometry.rotors;
  if (rotors.empty()) {
    throw ConfigError("format px4 needs a rotor geometry (a rotor preset or geometry.rotors); " +
                      c.description() +
                      " has no rotor positions to write (use --format json or paparazzi for its "
                      "matrix)");
  }
  std::ostringstream s;
  s << "# PX4 control allocation parameters for " << c.description() << "\n"
    << "# written by motormix " << kVersion << " (matrix --format px4): body frame FRD, metres;\n"
    << "# KM > 0 spins counter-clockwise seen from above; CT is thrust at full command,\n"
    << "# motormix's relative thrust_coefficient x " << kPx4DefaultCt << " (PX4's default).\n"
    << "# CA_ROTORn is motormix motor m(n+1).\n"
    << "param set-default CA_AIRFRAME 0\n"
    << "param set-default CA_ROTOR_COUNT " << rotors.size() << "\n";
  for (std::size_t i = 0; i < rotors.size(); ++i) {
    const Rotor& r = rotors[i];
    const std::string p = "param set-default CA_ROTOR" + std::to_string(i) + "_";
    s << p << "PX " << param(r.position.x()) << "\n"
      << p << "PY " << param(r.position.y()) << "\n"
      << p << "PZ " << param(r.position.z()) << "\n"
      << p << "CT " << param(r.thrust_coefficient * kPx4DefaultCt) << "\n"
      << p << "KM " << param(static_cast<double>(r.spin) * r.torque_ratio) << "\n";
    const Eigen::Vector3d axis = r.axis.normalized();
    if ((axis - Eigen::Vector3d(0.0, 0.0, -1.0)).norm() > 1e-9) {  // tilted: PX4's default is up
      s << p << "AX " << param(axis.x()) << "\n"
        << p << "AY " << param(axis.y()) << "\n"
        << p << "AZ " << param(axis.z()) << "\n";
    }
  }
  return s.str();
}

std::string ardupilot(const Config& c) {
  if (c.thrust_range() != ThrustRange::kUnipolar) {
    throw ConfigError("format ardupilot writes a multirotor frame; " + c.description() +
                      " is a ground vehicle");
  }
  const int n = c.motors();
  // Testing order: clockwise from the nose, as ArduPilot numbers its own
  // frames. The position is read off the matrix (roll ~ -y, pitch ~ x), so
  // tables without geometry get one too; coaxial motors keep their order.
  std::vector<std::pair<double, int>> bearing;
  for (int i = 0; i < n; ++i) {
    const double x = c.mixing(i, index(Axis::kPitch));
    const double y = -c.mixing(i, index(Axis::kRoll));
    double deg = std::atan2(y, x) * 180.0 / kPi;
    if (deg < -1e-9) deg += 360.0;
    bearing.emplace_back(std::max(deg, 0.0), i);
  }
  std::stable_sort(bearing.begin(), bearing.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first - 1e-6; });
  std::vector<int> testing_order(static_cast<std::size_t>(n));
  for (std::size_t k = 0; k < bearing.size(); ++k) {
    testing_order[static_cast<std::size_t>(bearing[k].second)] = static_cast<int>(k) + 1;
  }
  const auto thrust = c.mixing.col(index(Axis::kThrust));
  const bool uniform_thrust = (thrust.array() - thrust.mean()).abs().maxCoeff() < 1e-9;

  std::ostringstream s;
  s << "-- ArduPilot scripted motor matrix for " << c.description() << "\n"
    << "-- written by motormix " << kVersion << " (matrix --format ardupilot).\n"
    << "-- Needs FRAME_CLASS = 15 (Scripting Matrix) and SCR_ENABLE = 1; copy to APM/scripts/.\n"
    << "-- add_motor_raw(motor, roll, pitch, yaw, testing order): motor 0 is motormix m1;\n"
    << "-- ArduPilot normalizes the factors itself.\n";
  if (!uniform_thrust) {
    s << "-- Note: the motors do not share the thrust equally in this matrix; these calls\n"
      << "-- carry roll, pitch and yaw only, and ArduPilot gives every motor equal thrust.\n";
  }
  for (int i = 0; i < n; ++i) {
    s << "MotorsMatrix:add_motor_raw(" << i << ", " << param(c.mixing(i, index(Axis::kRoll)))
      << ", " << param(c.mixing(i, index(Axis::kPitch))) << ", "
      << param(c.mixing(i, index(Axis::kYaw))) << ", " << testing_order[static_cast<std::size_t>(i)]
      << ")  -- " << c.motor_names()[static_cast<std::size_t>(i)];
    const std::string d = detail(c, i);
    if (!d.empty()) s << ": " << d;
    s << "\n";
  }
  s << "assert(MotorsMatrix:init(" << n << "), \"Failed to init MotorsMatrix\")\n"
    << "motors:set_frame_string(\"motormix " << c.geometry.name << "\")\n";
  return s.str();
}

}  // namespace

AxisVector authority_of(const Config& config) {
  return authority_at_half_thrust(config, config.mixing);
}

std::vector<std::vector<long>> scaled_coefficients(const MixingMatrix& mixing, double scale) {
  std::vector<std::vector<long>> out;
  for (Eigen::Index i = 0; i < mixing.rows(); ++i) {
    std::vector<long> row;
    for (int a = 0; a < kNumAxes; ++a) row.push_back(std::lrint(scale * mixing(i, a)));
    out.push_back(row);
  }
  return out;
}

std::string export_matrix(const Config& config, MatrixFormat format) {
  switch (format) {
    case MatrixFormat::kTable:
      return table(config);
    case MatrixFormat::kJson:
      return json(config);
    case MatrixFormat::kYaml:
      return yaml(config);
    case MatrixFormat::kPaparazzi:
      return paparazzi(config);
    case MatrixFormat::kHeader:
      return header(config);
    case MatrixFormat::kPx4:
      return px4(config);
    case MatrixFormat::kArdupilot:
      return ardupilot(config);
  }
  return "";
}

}  // namespace motormix::config
