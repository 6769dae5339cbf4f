#pragma once
// The simulated vehicle: what the drivers do with the mixer's outputs, and
// what the vehicle does with that. One class for both kinds the geometry can
// describe:
// - aircraft: each rotor's ESC maps its input (PWM microseconds by default)
//   to a thrust fraction through the physical curve e x^2 + (1 - e) x,
//   scaled with the pack voltage as (1 - e) v + e v^2 of v = V / V_ref; the
//   rotor follows with a first-order lag (separate up and down time
//   constants), pushes along its axis (more within a diameter of the
//   ground) and drags against its spin; its angular momentum turns the body
//   gyroscopically (-w x h) and its speeding up or slowing down pushes the
//   body the other way about its axis; a 6-DOF
//   rigid body (rigid_body.hpp) with linear and rotational drag, gravity, a
//   flat ground at z = 0 and crash detection;
// - ground vehicles: each wheel's driver maps centered PWM or duty plus
//   direction pin to a wheel speed (linear in the pack voltage), the wheel
//   follows with a first-order lag, and a unicycle without slip moves by
//   the mean speed of each side (skid steer: the wheels of a side together).
// Every driver's input is read as a physical ESC would: anything outside its
// range is clipped, the disarmed value stops the motor.

#include "sim/battery_model.hpp"
#include "sim/motor_health.hpp"
#include "sim/rigid_body.hpp"

#include <motormix/config/config.hpp>
#include <motormix/gravity.hpp>
#include <motormix/output/output_stage.hpp>

#include <string>
#include <vector>

namespace motormix::sim {

inline constexpr double kGravity = kStandardGravity;
inline constexpr double kCrashSpeedMps = 2.0;  // hitting the ground faster than this is a crash

struct Environment {
  Eigen::Vector3d wind_ned =
      Eigen::Vector3d::Zero();  // m/s: drag acts on the air-relative velocity
  Eigen::Vector3d force_world = Eigen::Vector3d::Zero();  // N, e.g. a gust's push
  Eigen::Vector3d torque_body = Eigen::Vector3d::Zero();  // N m, e.g. a gust on one side
};

class VehicleModel {
 public:
  // Throws std::invalid_argument when config.vehicle_model is incomplete.
  explicit VehicleModel(const config::Config& config);

  // Advances dt seconds with `outputs` (the mixer's output-stage values) and
  // `direction` held; `health` says what each motor can do (physical
  // failures: motor_health.hpp).
  void step(const MotorVector& outputs, const DirectionVector& direction, const MotorHealth& health,
            const Environment& env, double dt);
  // The same with every motor healthy but those in `stopped`.
  void step(const MotorVector& outputs, const DirectionVector& direction, MotorMask stopped,
            const Environment& env, double dt);

  int motors() const { return static_cast<int>(speed_.size()); }
  bool wheeled() const { return p_.wheeled; }
  const BodyState& body() const { return body_; }
  double thrust_n(int i) const {
    const auto k = static_cast<std::size_t>(i);
    return p_.wheeled ? 0.0 : p_.rotors[k].max_thrust_n * speed_[k] * prop_[k];
  }
  // Rotors: the thrust fraction the motor's speed gives with a whole prop
  // (rpm grows as its square root); wheels: rad/s.
  double motor_speed(int i) const { return speed_[static_cast<std::size_t>(i)]; }
  // Rotors: the thrust fraction it gives now (a damaged prop gives less).
  double thrust_fraction(int i) const {
    const auto k = static_cast<std::size_t>(i);
    return speed_[k] * prop_[k];
  }
  // Rotors: the motor is unpowered and its rotor freewheels (rotor momentum on).
  bool freewheeling(int i) const { return freewheel_[static_cast<std::size_t>(i)] != 0; }
  const BatteryModel& battery() const { return battery_; }
  bool landed() const { return landed_; }
  // The vertical speed of the latest touchdown after having flown (m/s,
  // down positive); -1 before any.
  double touchdown_speed() const { return touchdown_speed_; }
  bool taken_off() const { return taken_off_; }
  bool crashed() const { return crashed_; }
  const std::string& crash_reason() const { return crash_reason_; }
  double forward_speed() const { return forward_speed_; }  // wheels, m/s
  const config::VehiclePhysics& physics() const { return p_; }

  // Per unit thrust fraction (rotors) or unit wheel command (wheels) of each
  // motor, at the reference voltage: rows roll, pitch, yaw torque (N m) and
  // upward thrust (N) for aircraft; 0, 0, yaw rate (rad/s) and forward speed
  // (m/s) for wheels. What a controller's gains are derived from.
  Eigen::Matrix<double, 4, Eigen::Dynamic> command_effect() const;

  // The factor on rotor i's thrust from the ground below it now (1 higher
  // than one diameter up, or with vehicle.ground_effect off).
  double ground_effect(int i) const;

  // Places the vehicle (e.g. in the air, for tests).
  void set_body(const BodyState& body, bool landed);

 private:
  double driver_fraction(int i, double output, int direction) const;
  void sum_rotors(double dt);  // the rotors' force and torque, held over one step
  double rotor_speed_rad_s(int i) const;
  // The thrust fraction of an unpowered rotor after dt: I dw/dt = -Q(w).
  double freewheel(int i, double dt) const;
  Wrench wrench(const BodyState& s, const Environment& env) const;
  void step_aircraft(const Environment& env, double dt);
  void step_wheels(double dt);

  config::VehiclePhysics p_;
  std::vector<OutputMode> modes_;
  MassProperties mass_;
  BodyState body_;
  BatteryModel battery_;
  std::vector<double> speed_;  // rotors: thrust fraction; wheels: rad/s
  std::vector<double> prop_;   // rotors: thrust per unit speed fraction (1: whole prop)
  std::vector<double> rotor_speed_before_;  // rad/s, at the start of the step
  // Rotors: 1 while the motor is unpowered (its rotor freewheels: no torque
  // on the body, slowed by its own air drag only).
  std::vector<char> freewheel_;
  double forward_speed_ = 0.0;
  // Rotor i: force and torque per newton (fixed capacity: no allocation per step).
  Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::ColMajor, 6, kMaxMotors> per_newton_;
  Eigen::Vector3d rotor_force_ = Eigen::Vector3d::Zero();     // body
  Eigen::Vector3d rotor_torque_ = Eigen::Vector3d::Zero();    // body
  Eigen::Vector3d rotor_momentum_ = Eigen::Vector3d::Zero();  // body, N m s (gyroscopic)
  double lag_dt_ = 0.0, alpha_up_ = 0.0, alpha_down_ = 0.0;
  bool landed_ = true;
  bool taken_off_ = false;
  bool crashed_ = false;
  double touchdown_speed_ = -1.0;
  std::string crash_reason_;
};

}  // namespace motormix::sim
