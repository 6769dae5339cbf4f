#pragma once
// A scenario: a timeline of references and events for one simulated flight
// or drive, read from YAML (the shipped ones under scenarios/, or a user's
// file). Loading is strict like the configuration: unknown keys are errors
// naming their path.
//
//   name: steps
//   vehicle: aircraft            # aircraft | ground | any
//   duration_s: 14
//   score: {from_s: 4, to_s: 14}
//   altitude_m: 3                # initial altitude reference
//   noise: {gyro_rad_s: 0.003, attitude_deg: 0.1, altitude_m: 0.01, speed_mps: 0.01}
//   failure_detection_ms: 100    # a stopped motor is reported this much later
//   battery: {initial_charge: 0.4, resistance_factor: 4}   # a tired pack: 4x the resistance
//   timeline:
//     - {at: 5, roll_deg: 20}
//     - {at: 7, roll_deg: 0, yaw_deg: 90}
//     - {at: 9, fail: 3}                       # motor number as `motormix matrix` prints it
//     - {at: 9, fail: 2, kind: desync}         # stop (default), half_thrust, intermittent,
//                                              # desync, telemetry, prop_lost or
//                                              # prop_damaged (motor_health.hpp)
//     - {at: 10, gust: {force_n: [4, 0, 0], torque_nm: [0.2, 0, 0], for_s: 0.5}}
//     - {at: 11, wind_mps: [3, 0, 0]}
//     - {at: 2, speed_mps: 0.4, yaw_rate_dps: 90}   # ground vehicles

#include "sim/controller.hpp"
#include "sim/motor_health.hpp"

#include <motormix/eigen_layout.hpp>

#include <optional>
#include <string>
#include <vector>

namespace motormix::sim {

struct Gust {
  Eigen::Vector3d force_n = Eigen::Vector3d::Zero();    // world NED
  Eigen::Vector3d torque_nm = Eigen::Vector3d::Zero();  // body FRD
  double for_s = 0.5;
};

struct ScenarioEvent {
  double at_s = 0.0;
  std::optional<double> roll_deg, pitch_deg, yaw_deg, altitude_m, speed_mps, yaw_rate_dps;
  std::optional<int> fail;  // motor index, 0-based
  FailureKind fail_kind = FailureKind::kStop;
  std::optional<Eigen::Vector3d> wind_mps;
  std::optional<Gust> gust;
};

struct SensorNoise {
  double gyro_rad_s = 0.0;
  double attitude_deg = 0.0;
  double altitude_m = 0.0;
  double speed_mps = 0.0;
};

enum class ScenarioVehicle { kAny, kAircraft, kGround };

struct Scenario {
  std::string name;
  std::string description;
  ScenarioVehicle vehicle = ScenarioVehicle::kAny;
  double duration_s = 10.0;
  double score_from_s = 0.0;
  double score_to_s = 10.0;
  double arm_at_s = 0.2;  // disarmed setpoints before, armed after
  double altitude_m = 3.0;
  double failure_detection_s = 0.1;
  SensorNoise noise;
  std::optional<double> battery_initial_charge;
  std::optional<double> battery_resistance_factor;  // times the vehicle's internal resistance
  std::vector<ScenarioEvent> timeline;              // sorted by at_s
};

// Throws config::ConfigError naming the key path, the value and what is allowed.
Scenario parse_scenario(const std::string& yaml_text, const std::string& source);
// A shipped scenario's name, or a path to a YAML file.
Scenario load_scenario(const std::string& name_or_path);
std::vector<std::string> shipped_scenarios();

}  // namespace motormix::sim
