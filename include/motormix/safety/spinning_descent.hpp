#pragma once
// A quadrotor that has lost one motor can still come down alive if it gives
// up yaw: the three motors left keep the total thrust and the two torques
// that tilt the body, the yaw torque they leave over spins the body up until
// the yaw drag balances it, and the vehicle flies a "relaxed hover" about a
// spin axis a few degrees off its thrust axis (Mueller & D'Andrea, ICRA
// 2014; IJRR 2016). This header is that emergency controller. Pure: time is
// passed in, nothing is allocated after construction, no I/O.
//
// - The equilibrium (solve_spin_equilibrium): the body rates and the three
//   thrusts at which the rotor torques balance the gyroscopic and drag
//   torques, the thrust along the spin axis carries the weight, the two
//   motors beside the dead one share equally, and the spin rate is the one
//   configured. Solved once, at start-up, for each motor that could fail.
// - The controller (SpinningDescent::update), every cycle:
//   * reduced attitude: the direction the spin axis should point (straight
//     up; once the spin is reached, tilted at most max_tilt to brake the
//     horizontal velocity) is
//     brought onto the equilibrium axis by asking for body rates across it;
//     the rate about the axis is left alone (yaw is given up);
//   * the torque across the axis comes from nonlinear dynamic inversion:
//     I * rate error * gain + w x (Iw + h) + drag, the last two being exactly
//     what holds the equilibrium (h: the rotors' own angular momentum, when
//     the model has their inertia). The feedback part rotates with the body at the
//     spin rate, so it is led by the motors' time constant (the first-order
//     lag inverted for a vector turning at that rate);
//   * the collective thrust flies the configured descent rate from the
//     vertical velocity (proportional-integral, tilt compensated); without
//     a velocity it follows the setpoint's throttle;
//   * allocation: three motors, three demands (thrust and the two tilting
//     torques), solved exactly; when that leaves a motor's range, the
//     thrusts inside the ranges closest to the demands (least squares over
//     the box, the thrust weighted below the torques);
//   * the spin-up: until the spin is reached, the two motors beside the dead
//     one are raised together (which changes neither tilting torque) as far
//     as their range allows, so the yaw torque, and with it the spin and the
//     stiffness it brings, comes sooner; the vehicle may climb, at most as
//     fast as it will come down, and the raise ends after twice the spin-up
//     the model gives (spin_up_s) even if the spin falls short;
//   * landing: the controller says so (the loop then disarms) when the spin
//     it had reached is lost while the vehicle is still (the ground took
//     it: nothing in the air can), or once the descent has been flown and
//     the vertical speed stays near zero with little thrust asked for.

#include <motormix/enum_names.hpp>
#include <motormix/gravity.hpp>
#include <motormix/motor_vector.hpp>
#include <motormix/safety/touchdown.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <limits>
#include <string>

namespace motormix {

// The vehicle as the controller needs it (SI units, body FRD).
struct SpinningDescentModel {
  double mass_kg = 0.0;
  Eigen::Vector3d inertia_kgm2 = Eigen::Vector3d::Ones();  // principal moments
  double rotational_drag = 0.0;                            // N m per rad/s, each axis
  double time_constant_s = 0.04;                           // motor lag (mean of up and down)
  double rate_delay_s = 0.0;  // how late the measured rates are (the gyro's low-pass)
  // Per rotor: force direction (unit), torque per newton of thrust (arm x
  // axis plus the drag torque against its spin), thrust at full command.
  std::array<Eigen::Vector3d, 4> axis{};
  std::array<Eigen::Vector3d, 4> torque_per_newton{};
  std::array<double, 4> max_thrust_n{};
  std::array<double, 4> min_thrust_n{};  // the least the controller asks of a motor
  // The rotors' own angular momentum: each rotor spins about its axis
  // (spin +1: counter-clockwise seen from above, about +axis) at
  // max_rotor_speed_rad_s * sqrt(thrust / max thrust), with this inertia.
  // With one motor stopped it no longer cancels, and its gyroscopic torque
  // -w x h is as large as the body's own during the spin-up.
  std::array<double, 4> spin{};
  double rotor_inertia_kgm2 = 0.0;
  double max_rotor_speed_rad_s = 0.0;
  // The gyro's full scale (0: unknown). A two-rotor descent spins faster
  // than a gyro can measure: beyond 90 % of it the spin rate is the model's.
  double gyro_range_rad_s = 0.0;
};

struct SpinningDescentSettings {
  double spin_rate_rad_s = 20.0;  // equilibrium spin rate (magnitude of the body rates)
  double descent_rate_mps = 1.0;  // vertical speed flown down
  double max_tilt_deg = 8.0;      // largest tilt of the spin axis asked to brake drift
  // At most these; the controller lowers them to what the motors' lag and
  // the rates' delay allow (rate_gain(), attitude_gain()).
  double attitude_gain = 12.0;     // 1/s: spin-axis error to rate across it
  double rate_gain = 30.0;         // 1/s: rate error to angular acceleration
  double velocity_gain = 1.5;      // 1/s: vertical speed error to acceleration
  double velocity_integral = 0.6;  // 1/s^2
  double drift_gain = 0.4;         // 1/s: horizontal velocity to acceleration asked against it
  double landed_after_s = 0.5;     // vertical speed near zero this long: landed
  // Before the spin is reached, raise the motors beside the dead one
  // together along the torque rows' null direction (spin_up() in
  // spinning_descent.cpp): the spin, and the stiffness it gives, come
  // sooner, for a bounded climb. Off: the demands as they are.
  bool spin_up_raise = true;
};

// The relaxed hover with motor `failed` stopped.
struct SpinEquilibrium {
  bool found = false;
  std::string why;  // when not found: what could not be met
  int failed = -1;
  std::array<int, 3> working{};                        // the other motors, in index order
  Eigen::Vector3d rates = Eigen::Vector3d::Zero();     // rad/s, body
  Eigen::Vector3d thrust_n = Eigen::Vector3d::Zero();  // of working[0..2]
  Eigen::Vector3d up = Eigen::Vector3d::Zero();        // the spin axis, pointing up (body)
  double axis_tilt_deg = 0.0;                          // between the spin axis and the thrust axis
};

// Solves the equilibrium by Newton's method (start-up only).
SpinEquilibrium solve_spin_equilibrium(const SpinningDescentModel& model, int failed,
                                       double spin_rate_rad_s);

// The equilibrium with each of the four motors stopped, solved once at
// start-up (the configuration keeps them; the descent and the simulator's
// report read them).
using SpinEquilibria = std::array<SpinEquilibrium, 4>;
SpinEquilibria solve_spin_equilibria(const SpinningDescentModel& model, double spin_rate_rad_s);

// Where a spin landing is; also what the status reports (mixer_status_t
// LANDING_*, the same numbers).
enum class DescentPhase : std::uint8_t {
  kOff = 0,         // not running (or not configured)
  kDescending = 1,  // spinning, coming down on three motors
  kLanded = 2,      // on the ground: the loop disarms (and reports it until the next arming)
  kNoAttitude = 3,  // one motor failed, but no fresh attitude: the caller mixes as before
};

inline constexpr EnumName<DescentPhase> kDescentPhaseNames[] = {
    {DescentPhase::kOff, "off"},
    {DescentPhase::kDescending, "descending"},
    {DescentPhase::kLanded, "landed"},
    {DescentPhase::kNoAttitude, "no attitude"},
};
inline const char* to_string(DescentPhase value) { return name_in(kDescentPhaseNames, value); }

struct DescentInput {
  Eigen::Quaterniond attitude = Eigen::Quaterniond::Identity();  // body FRD -> NED
  Eigen::Vector3d rates = Eigen::Vector3d::Zero();               // rad/s, body
  Eigen::Vector3d velocity =
      Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());  // m/s NED; NaN: unknown
  double throttle = 0.0;  // the setpoint's, 0..1: the collective when the velocity is unknown
};

struct DescentCommand {
  DescentPhase phase = DescentPhase::kOff;
  // Thrust fraction (0..1) per motor; the dead one 0.
  MotorVector thrust_fraction;
  Eigen::Vector3d thrust_n = Eigen::Vector3d::Zero();  // of the working motors
  double measured_rate_rad_s = 0.0;  // |rates| measured (the configured one: settings)
  double axis_error_deg = 0.0;       // between the spin axis and where it should point
  bool saturated = false;            // a torque demand did not fit
};

class SpinningDescent {
 public:
  // The equilibria must have been found for every motor (see
  // solve_spin_equilibria; the config layer checks it at start-up).
  SpinningDescent(const SpinningDescentModel& model, const SpinningDescentSettings& settings,
                  const SpinEquilibria& equilibria);
  // Solves them here.
  SpinningDescent(const SpinningDescentModel& model, const SpinningDescentSettings& settings);

  const SpinEquilibrium& equilibrium(int failed) const {
    return equilibria_[static_cast<std::size_t>(failed)];
  }
  const SpinningDescentSettings& settings() const { return s_; }
  // The gains flown: the settings', lowered to the model's lag (see there).
  double rate_gain() const { return rate_gain_; }
  double attitude_gain() const { return attitude_gain_; }
  // How long the spin-up's raise may last with motor `failed` stopped (s).
  double spin_up_s(int failed) const { return spin_up_s_[static_cast<std::size_t>(failed)]; }

  // Takes over with motor `failed` (0-based) stopped; `thrust_fraction`:
  // what each motor was asked for last (for the rotors' momentum).
  void start(int failed, std::int64_t now_us, const MotorVector& thrust_fraction);
  void stop();
  bool running() const { return cmd_.phase != DescentPhase::kOff; }
  int failed() const { return failed_; }

  // One cycle at now_us.
  const DescentCommand& update(const DescentInput& in, std::int64_t now_us);
  const DescentCommand& command() const { return cmd_; }

 private:
  double collective(const DescentInput& in, const Eigen::Vector3d& up_body, double dt);
  // The working motors' thrusts closest to demand (thrust, torque x, y).
  Eigen::Vector3d allocate(const SpinEquilibrium& eq, const Eigen::Vector3d& demand) const;
  // Before the spin is reached: `f` raised toward the yaw torque's most (see there).
  Eigen::Vector3d spin_up(const SpinEquilibrium& eq, const Eigen::Vector3d& f,
                          const DescentInput& in) const;

  SpinningDescentModel m_;
  SpinningDescentSettings s_;
  SpinEquilibria equilibria_{};
  // Per failed motor: [thrust; tau_x; tau_y] of the working motors per newton, and its inverse.
  std::array<Eigen::Matrix3d, 4> allocation_{};
  std::array<Eigen::Matrix3d, 4> allocation_inverse_{};
  // Per failed motor: the spin-up's raise (thrusts per unit, changing
  // neither tilting torque) and how long it may last (s).
  std::array<Eigen::Vector3d, 4> spin_up_direction_{};
  std::array<double, 4> spin_up_s_{};
  double since_start_s_ = 0.0;  // since the take-over
  double thrust_weight_ = 1.0;
  double rate_gain_ = 0.0;
  double attitude_gain_ = 0.0;
  int failed_ = -1;
  std::int64_t last_us_ = 0;
  double velocity_integral_ = 0.0;
  double up_force_ = 0.0;  // the collective's vertical force asked for (N)
  Eigen::Vector3d lagged_n_ = Eigen::Vector3d::Zero();  // working motors' thrust through the lag
  Touchdown touchdown_;
  bool spin_reached_ = false;  // the spin has been near the equilibrium's
  DescentCommand cmd_;
};

}  // namespace motormix
