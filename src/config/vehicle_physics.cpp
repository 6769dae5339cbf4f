// The `vehicle:` section: physical parameters for `motormix sim`, with
// defaults derived from the geometry and the output stage (documented in
// docs/simulation.md).

#include "vehicle_physics_reader.hpp"

#include "config/yaml_reader.hpp"
#include "section_readers.hpp"

#include <motormix/gravity.hpp>

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

namespace motormix::config {

namespace {

using namespace reading;

// A rotor sits within this many metres of the centre of mass.
constexpr double kMaxPositionM = 10.0;

// Defaults of the 250-500 mm class: 0.3 kg per rotor (frame, motor, ESC,
// share of battery and avionics), twice the weight in thrust.
constexpr double kMassPerRotorKg = 0.3;
constexpr double kThrustToWeight = 2.0;
// Half the mass sits in the motors and arms (point masses at the rotors),
// half in a central box of this size.
constexpr double kCentralBoxM[3] = {0.15, 0.15, 0.08};
constexpr double kDefaultTorqueRatioM = 0.016;  // 10-inch class propeller, k_M / k_F
constexpr double kLinearDragPerKg = 0.25;       // N per m/s per kg: ~40 m/s terminal velocity
constexpr double kRotationalDrag = 0.002;       // N m per rad/s
constexpr double kCellNominalV = 3.85;
// One motor at full thrust draws this many amperes per newton of its
// maximum thrust. With current growing as thrust^1.5, a default multirotor
// then hovers on about 185 W per kilogram, the figure of ArduPilot SITL's
// default multicopter model (1.5 kg hovering on 22.7 A at 12.14 V).
constexpr double kAmpsPerNewton = 1.55;
constexpr double kMahPerRotor = 1250.0;
constexpr double kPackOhmsTimesRotors = 0.08;

// The team quad's table is an X quad, FL, FR, RL, RR; positive yaw raises FL
// and RR, so those two spin counter-clockwise.
std::vector<Rotor> team_quad_rotors() {
  const double a = 0.25 / std::sqrt(2.0);
  const double xy[4][2] = {{a, -a}, {a, a}, {-a, -a}, {-a, a}};
  const Spin spin[4] = {Spin::kCcw, Spin::kCw, Spin::kCw, Spin::kCcw};
  std::vector<Rotor> rotors(4);
  for (int i = 0; i < 4; ++i) {
    rotors[static_cast<std::size_t>(i)].position = {xy[i][0], xy[i][1], 0.0};
    rotors[static_cast<std::size_t>(i)].spin = spin[i];
  }
  return rotors;
}

// One entry of vehicle.rotors: where the rotor is, and optionally its own
// thrust and torque ratio (otherwise the vehicle-wide values).
struct RotorEntry {
  Rotor rotor;
  std::optional<double> max_thrust_n;
  std::optional<double> torque_ratio_m;
};

std::vector<RotorEntry> explicit_rotors(const YAML::Node& list, const std::string& path,
                                        int motors) {
  if (!list.IsSequence() || static_cast<int>(list.size()) != motors) {
    fail(path, describe(list),
         "a list of " + std::to_string(motors) + " rotors, one per motor in output order");
  }
  std::vector<RotorEntry> rotors;
  for (std::size_t i = 0; i < list.size(); ++i) {
    MapReader r(list[i], path + "[" + std::to_string(i) + "]");
    RotorEntry entry;
    entry.rotor = read_rotor_placement(r, {3, kMaxPositionM, "[x, y, z] in metres"});
    if (r.has("max_thrust_n")) entry.max_thrust_n = r.number("max_thrust_n", 1.0, 1e-3, 1e5);
    r.allow("max_thrust_n");
    if (r.has("torque_ratio_m")) entry.torque_ratio_m = r.number("torque_ratio_m", 0.0, 0.0, 1.0);
    r.allow("torque_ratio_m");
    r.finish();
    rotors.push_back(entry);
  }
  return rotors;
}

Eigen::Vector3d default_inertia(const std::vector<RotorPhysics>& rotors, double mass) {
  const double arm_share = 0.5 * mass / static_cast<double>(rotors.size());
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
  for (const RotorPhysics& r : rotors) {
    const Eigen::Vector3d& p = r.position_m;
    inertia += arm_share * (p.squaredNorm() * Eigen::Matrix3d::Identity() - p * p.transpose());
  }
  const double body = 0.5 * mass;
  const double a = kCentralBoxM[0], b = kCentralBoxM[1], c = kCentralBoxM[2];
  inertia.diagonal() +=
      Eigen::Vector3d(body * (b * b + c * c), body * (a * a + c * c), body * (a * a + b * b)) /
      12.0;
  return inertia.diagonal();
}

// 0.8 of the closest spacing of two rotors side by side (rotors stacked on
// one axis, as a coaxial pair, do not count): the props a frame of that size
// carries with room between their tips. 0.254 m (10 inches) when the
// rotors are unknown.
double default_prop_diameter(const std::vector<RotorPhysics>& rotors) {
  constexpr double kStackedM = 0.02;  // closer than this across the axis: one stack
  double closest = 0.0;
  for (std::size_t i = 0; i < rotors.size(); ++i) {
    for (std::size_t j = i + 1; j < rotors.size(); ++j) {
      const Eigen::Vector3d d = rotors[j].position_m - rotors[i].position_m;
      const double across = (d - d.dot(rotors[i].axis) * rotors[i].axis).norm();
      if (across > kStackedM && (closest == 0.0 || across < closest)) closest = across;
    }
  }
  return closest > 0.0 ? 0.8 * closest : 0.254;
}

void read_imu(MapReader m, ImuPhysics& imu) {
  imu.rate_hz = m.number("rate_hz", imu.rate_hz, 100.0, 1e5);
  imu.vibration_dps = m.number("vibration_dps", imu.vibration_dps, 0.0, 2000.0);
  imu.lowpass_hz = m.number("lowpass_hz", imu.lowpass_hz, 1.0, 1e4);
  imu.bias_drift_dps = m.number("bias_drift_dps", imu.bias_drift_dps, 0.0, 100.0);
  if (imu.lowpass_hz >= imu.rate_hz / 2) {
    fail(m.path_of("lowpass_hz"), std::to_string(imu.lowpass_hz),
         "below half of rate_hz (" + std::to_string(imu.rate_hz / 2) + ")");
  }
  m.finish();
}

// The pack grows with the vehicle: 1250 mAh per rotor (a quad's 4S 5000 mAh)
// at 0.08 ohm divided among them (parallel cells), so every default
// multirotor hovers on about the same share of its pack.
void read_battery(MapReader b, VehiclePhysics& v, double default_full_current) {
  BatteryPhysics& bat = v.battery;
  const double packs = v.rotors.empty() ? 4.0 : static_cast<double>(v.rotors.size());
  bat.cells = static_cast<int>(std::lround(b.number("cells", 4, 1, 14)));
  bat.capacity_mah = b.number("capacity_mah", kMahPerRotor * packs, 10.0, 1e6);
  bat.internal_resistance_ohm =
      b.number("internal_resistance_ohm", kPackOhmsTimesRotors / packs, 0.0, 10.0);
  bat.initial_charge = b.number("initial_charge", 1.0, 0.0, 1.0);
  bat.reference_v = b.number("reference_v", kCellNominalV * bat.cells, 0.5, 100.0);
  bat.full_throttle_current_a =
      b.number("full_throttle_current_a", default_full_current, 0.0, 1000.0);
  bat.avionics_current_a = b.number("avionics_current_a", 0.5, 0.0, 100.0);
  b.finish();
}

void read_escs(MapReader esc, const Config& config, VehiclePhysics& v) {
  const std::size_t n = config.outputs.size();
  v.esc_min.resize(n);
  v.esc_max.resize(n);
  v.esc_center.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const OutputChannel& ch = config.outputs[i];
    v.esc_min[i] = ch.mode == OutputMode::kUnipolar && ch.reversed ? ch.max : ch.min;
    v.esc_max[i] = ch.mode == OutputMode::kUnipolar && ch.reversed ? ch.min : ch.max;
    v.esc_center[i] = ch.center;
  }
  // One physical range for every driver, when given.
  if (esc.has("min") || esc.has("max")) {
    const double lo = esc.number("min", v.esc_min[0], 0.0, 1e5);
    const double hi = esc.number("max", v.esc_max[0], 0.0, 1e5);
    if (!(lo != hi)) {
      std::ostringstream found;
      found << "min " << lo << " and max " << hi;
      fail(esc.path_of("max"), found.str(), "a max different from min");
    }
    for (std::size_t i = 0; i < n; ++i) {
      v.esc_min[i] = lo;
      v.esc_max[i] = hi;
    }
  }
  esc.allow("min");
  esc.allow("max");
  v.thrust_expo = esc.number("thrust_expo", 0.3, 0.0, 1.0);
  esc.finish();
}

}  // namespace

void read_vehicle_physics(MapReader vehicle, Config& config) {
  VehiclePhysics& v = config.vehicle_model;
  v = VehiclePhysics{};
  v.wheeled = config.thrust_range() == ThrustRange::kBipolar;
  const int motors = config.motors();

  if (v.wheeled) {
    if (vehicle.has("rotors")) {
      fail(vehicle.path_of("rotors"), "rotors on a ground vehicle", "wheel_radius_m, track_m");
    }
    vehicle.allow("rotors");
    v.mass_kg = vehicle.number("mass_kg", 2.0, 0.01, 1e4);
    v.wheels.per_side = config.wheel_base ? config.wheel_base->wheels_per_side : motors / 2;
    v.wheels.radius_m = vehicle.number("wheel_radius_m", v.wheels.radius_m, 1e-3, 10.0);
    v.wheels.track_m = vehicle.number("track_m", v.wheels.track_m, 1e-3, 100.0);
    v.wheels.max_speed_rad_s =
        vehicle.number("max_wheel_speed_rad_s", v.wheels.max_speed_rad_s, 1e-3, 1e4);
    v.inertia_kgm2 = {0.0, 0.0, v.mass_kg * v.wheels.track_m * v.wheels.track_m / 8.0};
    v.time_constant_up_s = 0.1;
    v.time_constant_down_s = 0.1;
  } else {
    for (const char* key : {"wheel_radius_m", "track_m", "max_wheel_speed_rad_s"}) {
      if (vehicle.has(key))
        fail(vehicle.path_of(key), "a wheel setting on an aircraft", "rotor settings");
      vehicle.raw(key);
    }
    const double scale = vehicle.number("length_scale", 1.0, 1e-6, 1e6);
    std::vector<Rotor> rotors = config.geometry.rotors;
    std::vector<RotorEntry> entries;
    if (vehicle.has("rotors")) {
      entries = explicit_rotors(vehicle.raw("rotors"), vehicle.path_of("rotors"), motors);
      rotors.clear();
      for (const RotorEntry& e : entries) rotors.push_back(e.rotor);
    } else {
      vehicle.allow("rotors");
      if (rotors.empty() && config.geometry.name == "team_quad") rotors = team_quad_rotors();
    }
    const std::string rotor_path = vehicle.path_of("rotors");
    const int n = static_cast<int>(rotors.size());
    // Whether the weight and the rotors' thrust are the configuration's own
    // (not defaults from the geometry): what hovers where is then known.
    bool thrust_given = vehicle.has("max_thrust_n");
    if (!thrust_given && !entries.empty()) {
      thrust_given = std::all_of(entries.begin(), entries.end(),
                                 [](const RotorEntry& e) { return e.max_thrust_n.has_value(); });
    }
    v.weight_and_thrust_given = vehicle.has("mass_kg") && thrust_given;
    v.mass_kg = vehicle.number("mass_kg", kMassPerRotorKg * std::max(n, 2), 0.01, 1e4);
    const double weight = v.mass_kg * kStandardGravity;
    const double thrust =
        vehicle.number("max_thrust_n", n > 0 ? kThrustToWeight * weight / n : 1.0, 1e-3, 1e5);
    const double torque_ratio = vehicle.number("torque_ratio_m", kDefaultTorqueRatioM, 0.0, 1.0);
    for (std::size_t i = 0; i < rotors.size(); ++i) {
      const Rotor& r = rotors[i];
      RotorPhysics p;
      p.position_m = scale * r.position;
      p.axis = r.axis.normalized();
      p.spin = r.spin;
      p.max_thrust_n = thrust * r.thrust_coefficient;
      p.torque_ratio_m = torque_ratio;
      if (i < entries.size() && entries[i].max_thrust_n) p.max_thrust_n = *entries[i].max_thrust_n;
      if (i < entries.size() && entries[i].torque_ratio_m)
        p.torque_ratio_m = *entries[i].torque_ratio_m;
      v.rotors.push_back(p);
    }
    if (rotors.empty()) {
      v.incomplete = "a " + config.geometry_source +
                     " geometry says nothing of where the rotors are: give '" + rotor_path +
                     "' (position [x, y, z] in metres and spin, one per motor) to simulate it";
    }
    if (vehicle.has("inertia_kgm2")) {
      const auto i = read_numbers(vehicle.raw("inertia_kgm2"), vehicle.path_of("inertia_kgm2"), 3,
                                  3, 1e-7, 1e4);
      v.inertia_kgm2 = {i[0], i[1], i[2]};
    } else {
      vehicle.raw("inertia_kgm2");
      if (!v.rotors.empty()) v.inertia_kgm2 = default_inertia(v.rotors, v.mass_kg);
    }
  }
  v.time_constant_up_s = vehicle.number("time_constant_up_s", v.time_constant_up_s, 1e-4, 5.0);
  v.time_constant_down_s =
      vehicle.number("time_constant_down_s", v.time_constant_down_s, 1e-4, 5.0);
  v.motor_lag = vehicle.choice("motor_lag", MotorLag::kThrust, kMotorLagNames);
  if (!v.wheeled) {
    v.prop_diameter_m =
        vehicle.number("prop_diameter_m", default_prop_diameter(v.rotors), 0.01, 10.0);
    v.rotor_inertia_kgm2 =
        vehicle.number("rotor_inertia_kgm2", rotor_inertia_for(v.prop_diameter_m), 0.0, 10.0);
    v.max_rotor_speed_rad_s =
        vehicle.number("max_rotor_speed_rad_s", v.max_rotor_speed_rad_s, 1.0, 1e5);
    read_imu(vehicle.map("imu"), v.imu);
  } else {
    for (const char* key :
         {"prop_diameter_m", "rotor_inertia_kgm2", "max_rotor_speed_rad_s", "imu"}) {
      if (vehicle.has(key))
        fail(vehicle.path_of(key), "a rotor setting on a ground vehicle", "wheel settings");
      vehicle.raw(key);
    }
  }
  MapReader drag = vehicle.map("drag");
  v.drag_linear_n_per_mps = drag.number("linear", kLinearDragPerKg * v.mass_kg, 0.0, 1e4);
  v.drag_rotational_nm_per_radps = drag.number("rotational", kRotationalDrag, 0.0, 1e3);
  drag.finish();
  read_escs(vehicle.map("esc"), config, v);

  double full_current = 10.0;  // a wheel motor
  if (!v.rotors.empty()) full_current = kAmpsPerNewton * v.rotors.front().max_thrust_n;
  read_battery(vehicle.map("battery"), v, full_current);
  vehicle.finish();
}

}  // namespace motormix::config
