#pragma once
// The physical vehicle behind a configuration, for `motormix sim`: mass,
// inertia, what each rotor or wheel can do, how fast the motors answer, the
// ESC curve, drag and the battery. Read from the configuration's `vehicle:`
// section (validated like every other key); every value has a documented
// default derived from the geometry, so a preset flies without one. The
// mixer process itself never reads any of it.
//
// Units are SI throughout; frames are the geometry's (body FRD).

#include <motormix/angles.hpp>
#include <motormix/effectiveness/geometry.hpp>
#include <motormix/enum_names.hpp>

#include <Eigen/Geometry>  // cross products

#include <cstdint>
#include <string>
#include <vector>

namespace motormix::config {

struct RotorPhysics {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  // from the centre of mass, FRD
  Eigen::Vector3d axis{0.0, 0.0, -1.0};                  // thrust direction, FRD, unit
  Spin spin = Spin::kCcw;
  double max_thrust_n = 0.0;    // at full ESC command and the battery's reference voltage
  double torque_ratio_m = 0.0;  // drag torque per newton of thrust

  // Torque on the body (N m, FRD) per newton of this rotor's thrust: its
  // moment about the centre of mass and its drag against the spin.
  Eigen::Vector3d torque_per_newton() const {
    return position_m.cross(axis) + static_cast<double>(spin) * torque_ratio_m * -axis;
  }
};

struct BatteryPhysics {
  int cells = 4;  // lithium-polymer cells in series
  double capacity_mah = 5000.0;
  double internal_resistance_ohm = 0.02;  // whole pack
  double initial_charge = 1.0;            // state of charge at the start, 0..1
  double reference_v = 15.4;              // voltage at which max_thrust_n is measured
  double full_throttle_current_a = 0.0;   // one motor at full thrust
  double avionics_current_a = 0.5;
};

struct WheelPhysics {
  double radius_m = 0.05;
  double track_m = 0.30;          // between the left and right wheels
  double max_speed_rad_s = 20.0;  // wheel speed at full command and reference voltage
  int per_side = 1;
};

// The flight controller's gyro as `motormix sim` plays it (docs/simulation.md
// says where each number comes from).
struct ImuPhysics {
  double rate_hz = 1000.0;       // the gyro is sampled at least this often
  double vibration_dps = 10.0;   // per rotor at full speed (first harmonic; the second half)
  double lowpass_hz = 40.0;      // the controller's second-order gyro low-pass (0: none)
  double bias_drift_dps = 0.02;  // bias random walk, deg/s per square root of a second
  // How late the filtered rates are: a second-order Butterworth low-pass
  // delays slow signals by sqrt(2) / (2 pi f).
  double rate_delay_s() const {
    return lowpass_hz > 0.0 ? 1.4142135623730951 / (kTwoPi * lowpass_hz) : 0.0;
  }
};

// A propeller's spinning inertia (with its motor's bell) from its diameter:
// a 10-inch (0.254 m) prop measures 5e-5..6e-5 kg m^2, and the inertia of
// props of one family grows about as the fourth power of the diameter.
inline double rotor_inertia_for(double prop_diameter_m) {
  constexpr double kTenInchM = 0.254, kTenInchKgm2 = 5.5e-5;
  const double r = prop_diameter_m / kTenInchM;
  return kTenInchKgm2 * r * r * r * r;
}

// What the motors' first-order lag acts on: the thrust (motormix sim's
// default, fitted to step responses of thrust), or the rotor's speed, as
// RotorPy, PX4's SIH and Gazebo model it (the thrust, the speed squared,
// then falls twice as fast as the speed).
enum class MotorLag : std::uint8_t { kThrust, kSpeed };
inline constexpr EnumName<MotorLag> kMotorLagNames[] = {
    {MotorLag::kThrust, "thrust"},
    {MotorLag::kSpeed, "speed"},
};
inline const char* to_string(MotorLag value) { return name_in(kMotorLagNames, value); }

struct VehiclePhysics {
  bool wheeled = false;
  double mass_kg = 0.0;
  Eigen::Vector3d inertia_kgm2 = Eigen::Vector3d::Zero();  // principal, about x, y, z (FRD)
  std::vector<RotorPhysics> rotors;                        // aircraft, in output order
  WheelPhysics wheels;                                     // ground vehicles
  double time_constant_up_s = 0.03;        // first-order motor lag while speeding up
  double time_constant_down_s = 0.05;      // and while slowing down
  MotorLag motor_lag = MotorLag::kThrust;  // what the lag acts on (motormix sim)
  // The driver's physical input range, per motor in output order, in the
  // output unit: thrust (or wheel speed) is zero at esc_min and full at
  // esc_max. Defaults to the output stage's range, as after an ESC
  // calibration with the mixer's endpoints.
  std::vector<double> esc_min;
  std::vector<double> esc_max;
  std::vector<double> esc_center;  // centered (reversible) drives: the stop value
  // Thrust fraction = e x^2 + (1 - e) x of the ESC input fraction x: the
  // curve output.thrust_model_factor inverts when it is set to the same e.
  double thrust_expo = 0.3;
  double drag_linear_n_per_mps = 0.0;         // force against the air-relative velocity
  double drag_rotational_nm_per_radps = 0.0;  // torque against the body rates
  // The propellers' diameter (m): what the rotor inertia and the ground
  // effect's reach are derived from. Default: 0.8 of the closest spacing of
  // two rotors (a 450 mm quad's 10-inch props).
  double prop_diameter_m = 0.0;
  // Each rotor's spinning inertia (prop and motor bell, kg m^2) and its
  // speed at full thrust (rad/s; the speed grows as the square root of the
  // thrust): their angular momentum gives the gyroscopic torque -w x h, and
  // their speeding up and slowing down a reaction torque about each rotor's
  // axis. Default: derived from prop_diameter_m (rotor_inertia_for).
  double rotor_inertia_kgm2 = 0.0;
  double max_rotor_speed_rad_s = 750.0;
  // Ground effect: each rotor gives more thrust within one diameter of the
  // ground (motormix sim only).
  bool ground_effect = true;
  ImuPhysics imu;
  BatteryPhysics battery;
  // Whether the section gives the mass and every rotor's thrust (not the
  // defaults derived from the geometry): where it hovers is then known.
  bool weight_and_thrust_given = false;
  // Empty when the physics is complete; otherwise why the vehicle cannot be
  // simulated (e.g. a mixing table with no `vehicle.rotors`).
  std::string incomplete;
};

}  // namespace motormix::config
