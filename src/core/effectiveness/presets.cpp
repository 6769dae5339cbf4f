#include <motormix/effectiveness/presets.hpp>

#include <motormix/angles.hpp>

#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <sstream>

namespace motormix {

namespace {

constexpr double kDefaultArm = 0.25;

// A rotor at `angle_deg` from the nose, clockwise positive seen from above
// (90 = right), as PX4 and ArduPilot number their frames.
struct ArmSpec {
  double angle_deg;
  Spin spin;
};

// Where a rotor sits, as a person names it: front, rear, left, right, or
// two of them. Off the axes and the diagonals (an octo's 22.5 and 67.5
// degrees, a hexa's 30 and 150) two rotors share a quadrant, so the angle
// from the nose is added: "front right, 22.5 deg off the nose".
std::string side_of(double x, double y) {
  const auto part = [](double v, const char* pos, const char* neg) -> std::string {
    return std::abs(v) < 1e-9 ? "" : (v > 0 ? pos : neg);
  };
  std::string fb = part(x, "front", "rear");
  std::string lr = part(y, "right", "left");
  if (fb.empty()) return lr;
  if (lr.empty()) return fb;
  const double off_nose = std::atan2(std::abs(y), x) * 180.0 / kPi;  // 0..180
  const double from_diagonal = std::abs(std::fmod(off_nose, 90.0) - 45.0);
  if (from_diagonal < 1.0) return fb + " " + lr;
  std::ostringstream angle;
  angle << std::round(off_nose * 10.0) / 10.0;
  return fb + " " + lr + ", " + angle.str() + " deg off the nose";
}

const char* spin_name(Spin s) { return s == Spin::kCw ? "CW" : "CCW"; }

Vehicle rotor_vehicle(std::string name, std::string description, const std::vector<Rotor>& rotors) {
  Vehicle v;
  v.name = std::move(name);
  v.description = std::move(description);
  for (std::size_t i = 0; i < rotors.size(); ++i) {
    v.motor_names.push_back("m" + std::to_string(i + 1));
    v.motor_details.push_back(side_of(rotors[i].position.x(), rotors[i].position.y()) + ", " +
                              spin_name(rotors[i].spin));
  }
  v.effectiveness = rotor_effectiveness(rotors);
  v.rotors = rotors;
  return v;
}

std::vector<Rotor> arms(const std::vector<ArmSpec>& specs, double arm) {
  std::vector<Rotor> rotors;
  for (const ArmSpec& s : specs) {
    Rotor r;
    const double a = s.angle_deg * kPi / 180.0;
    r.position = {arm * std::cos(a), arm * std::sin(a), 0.0};
    r.spin = s.spin;
    rotors.push_back(r);
  }
  return rotors;
}

constexpr Spin CW = Spin::kCw;
constexpr Spin CCW = Spin::kCcw;

Vehicle multirotor(const std::string& name, const std::string& description,
                   const std::vector<ArmSpec>& specs, double arm) {
  return rotor_vehicle(name, description, arms(specs, arm));
}

Vehicle team_quad() {
  Vehicle v;
  v.name = "team_quad";
  v.description = "the team's quad: a sign table per motor, order FL, FR, RL, RR";
  v.motor_names = {"FL", "FR", "RL", "RR"};
  v.motor_details = {"front left", "front right", "rear left", "rear right"};
  MixingMatrix m(4, kNumAxes);
  // In this table a positive pitch demand raises the rear motors (nose down),
  // and FL/RR take positive yaw.
  //    roll  pitch  yaw  thrust
  m << +1.0, -1.0, +1.0, 1.0,  // FL
      -1.0, -1.0, -1.0, 1.0,   // FR
      +1.0, +1.0, -1.0, 1.0,   // RL
      -1.0, +1.0, +1.0, 1.0;   // RR
  v.mixing_table = m;
  return v;
}

// Seed frame of the pseudo-inverse mixing document: an H hexarotor, x front
// and y right, torque ratio 0.1 as in its worked example.
Vehicle h_hexa(double arm) {
  const double k = arm / kDefaultArm;
  const std::vector<std::array<double, 2>> xy = {{-0.35, 0.17}, {-0.35, -0.17}, {0.0, 0.25},
                                                 {0.0, -0.25},  {0.35, 0.33},   {0.35, -0.33}};
  const std::vector<Spin> spins = {CW, CCW, CCW, CW, CW, CCW};
  std::vector<Rotor> rotors;
  for (std::size_t i = 0; i < xy.size(); ++i) {
    Rotor r;
    r.position = {k * xy[i][0], k * xy[i][1], 0.0};
    r.spin = spins[i];
    r.torque_ratio = 0.1;
    rotors.push_back(r);
  }
  return rotor_vehicle("h_hexa", "H hexarotor: three rows of two, rear to front", rotors);
}

// Y6: three arms (right front, left front, rear), two coaxial rotors each,
// numbered as ArduPilot's default Y6. Arms at x = 2/3 and -4/3 of the
// lateral offset, so the centre of thrust is the centre of the frame.
Vehicle y6(double arm) {
  const double s = arm * 0.75;
  const Eigen::Vector3d right{2.0 / 3.0 * s, s, 0.0};
  const Eigen::Vector3d left{2.0 / 3.0 * s, -s, 0.0};
  const Eigen::Vector3d rear{-4.0 / 3.0 * s, 0.0, 0.0};
  const std::vector<std::pair<Eigen::Vector3d, Spin>> spec = {
      {right, CCW}, {left, CW}, {left, CCW}, {rear, CW}, {right, CW}, {rear, CCW}};
  std::vector<Rotor> rotors;
  for (const auto& [pos, spin] : spec) {
    Rotor r;
    r.position = pos;
    r.spin = spin;
    rotors.push_back(r);
  }
  return rotor_vehicle("y6", "Y6: three arms with coaxial pairs (ArduPilot numbering)", rotors);
}

Vehicle wheeled(const std::string& name, const std::string& description, int per_side,
                std::vector<std::string> names) {
  Vehicle v;
  v.name = name;
  v.description = description;
  v.motor_names = std::move(names);
  v.thrust_range = ThrustRange::kBipolar;
  v.controlled = bit(Axis::kYaw) | bit(Axis::kThrust);
  WheelBase base;
  base.wheels_per_side = per_side;
  v.effectiveness = wheel_effectiveness(base);
  for (std::size_t i = 0; i < v.motor_names.size(); ++i) {
    v.motor_details.push_back(i % 2 == 0 ? "left side" : "right side");
  }
  return v;
}

using Factory = std::function<Vehicle(double arm)>;

const std::map<std::string, Factory>& factories() {
  static const std::map<std::string, Factory> table = {
      {"quad_x",
       [](double a) {
         return multirotor("quad_x", "quadrotor X (PX4 and ArduPilot numbering)",
                           {{45, CCW}, {-135, CCW}, {-45, CW}, {135, CW}}, a);
       }},
      {"quad_plus",
       [](double a) {
         return multirotor("quad_plus", "quadrotor + (PX4 and ArduPilot numbering)",
                           {{90, CCW}, {-90, CCW}, {0, CW}, {180, CW}}, a);
       }},
      {"team_quad", [](double) { return team_quad(); }},
      {"hexa_x",
       [](double a) {
         return multirotor("hexa_x", "hexarotor X (PX4 and ArduPilot numbering)",
                           {{90, CW}, {-90, CCW}, {-30, CW}, {150, CCW}, {30, CCW}, {-150, CW}}, a);
       }},
      {"hexa_plus",
       [](double a) {
         return multirotor("hexa_plus", "hexarotor + (PX4 and ArduPilot numbering)",
                           {{0, CW}, {180, CCW}, {-120, CW}, {60, CCW}, {-60, CCW}, {120, CW}}, a);
       }},
      {"h_hexa", [](double a) { return h_hexa(a); }},
      {"octo_x",
       [](double a) {
         return multirotor("octo_x", "octorotor X (ArduPilot numbering)",
                           {{22.5, CW},
                            {-157.5, CW},
                            {67.5, CCW},
                            {157.5, CCW},
                            {-22.5, CCW},
                            {-112.5, CCW},
                            {-67.5, CW},
                            {112.5, CW}},
                           a);
       }},
      {"octo_plus",
       [](double a) {
         return multirotor("octo_plus", "octorotor + (ArduPilot numbering)",
                           {{0, CW},
                            {180, CW},
                            {45, CCW},
                            {135, CCW},
                            {-45, CCW},
                            {-135, CCW},
                            {-90, CW},
                            {90, CW}},
                           a);
       }},
      {"octo_coax_x8",
       [](double a) {
         return multirotor("octo_coax_x8", "coaxial X8 (ArduPilot OctaQuad X numbering)",
                           {{45, CCW},
                            {-45, CW},
                            {-135, CCW},
                            {135, CW},
                            {-45, CCW},
                            {45, CW},
                            {135, CCW},
                            {-135, CW}},
                           a);
       }},
      {"y6", [](double a) { return y6(a); }},
      {"differential_drive",
       [](double) {
         return wheeled("differential_drive", "two driven wheels, left and right", 1,
                        {"left", "right"});
       }},
      {"skid_steer_4",
       [](double) {
         return wheeled("skid_steer_4", "four wheels, two per side", 2, {"FL", "FR", "RL", "RR"});
       }},
      {"skid_steer_6",
       [](double) {
         return wheeled("skid_steer_6", "six wheels, three per side", 3,
                        {"FL", "FR", "ML", "MR", "RL", "RR"});
       }},
  };
  return table;
}

template <typename Permutable>
Permutable reorder_rows(const Permutable& m, const std::vector<int>& order) {
  Permutable out = m;
  for (std::size_t i = 0; i < order.size(); ++i) {
    out.row(static_cast<Eigen::Index>(i)) = m.row(order[i] - 1);
  }
  return out;
}

}  // namespace

std::optional<Vehicle> find_preset(std::string_view name, const PresetOptions& options) {
  const auto it = factories().find(std::string(name));
  if (it == factories().end()) return std::nullopt;
  Vehicle v = it->second(options.arm_length.value_or(kDefaultArm));
  if (options.reverse_spin) {
    if (v.effectiveness) v.effectiveness->row(index(Axis::kYaw)) *= -1.0;
    if (v.mixing_table) v.mixing_table->col(index(Axis::kYaw)) *= -1.0;
    for (Rotor& r : v.rotors) r.spin = r.spin == Spin::kCw ? Spin::kCcw : Spin::kCw;
    for (std::string& d : v.motor_details) {
      const auto cw = d.rfind(", CW");
      const auto ccw = d.rfind(", CCW");
      if (ccw != std::string::npos) {
        d.replace(ccw, 5, ", CW");
      } else if (cw != std::string::npos) {
        d.replace(cw, 4, ", CCW");
      }
    }
  }
  if (!options.motor_order.empty()) {
    const std::vector<int>& order = options.motor_order;  // validated by the caller
    if (v.effectiveness) {
      EffectivenessMatrix e = *v.effectiveness;
      for (std::size_t i = 0; i < order.size(); ++i) {
        e.col(static_cast<Eigen::Index>(i)) = v.effectiveness->col(order[i] - 1);
      }
      v.effectiveness = e;
    }
    if (v.mixing_table) v.mixing_table = reorder_rows(*v.mixing_table, order);
    if (!v.rotors.empty()) {
      std::vector<Rotor> rotors;
      for (int o : order) rotors.push_back(v.rotors[static_cast<std::size_t>(o - 1)]);
      v.rotors = rotors;
    }
    std::vector<std::string> names;
    std::vector<std::string> details;
    for (int o : order) {
      names.push_back(v.motor_names[static_cast<std::size_t>(o - 1)]);
      if (!v.motor_details.empty())
        details.push_back(v.motor_details[static_cast<std::size_t>(o - 1)]);
    }
    v.motor_names = names;
    v.motor_details = details;
  }
  return v;
}

std::vector<std::string> preset_names() {
  std::vector<std::string> names;
  for (const auto& entry : factories()) names.push_back(entry.first);
  return names;
}

}  // namespace motormix
