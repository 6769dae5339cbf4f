#pragma once
// The built-in controller `motormix sim` flies with: what a flight stack
// upstream of motormix would send, as the seed quad's controller does
// (setpoint_t with throttle, yaw and arming; pid_t with roll, pitch, yaw).
//
// Aircraft: attitude (quaternion error, proportional) -> body rates
// (proportional-integral) -> torques, and altitude (proportional) -> climb
// rate (proportional-integral) -> collective thrust, tilt-compensated.
// Ground vehicles: forward speed and yaw rate, each feed-forward plus
// proportional-integral.
//
// Torques and thrust become normalized demands through the inverse of G =
// (what each motor command does, from the physics) x (how the configured
// mixer moves each command per unit demand, measured by mixing small steps
// around hover). So the gains are physical (rad/s^2 per rad/s, not per unit
// demand), the mixing table's sign convention is whatever it is (the team
// quad's positive pitch lowers the nose), and a strategy that scales its
// demands (the seed's budgets) is flown as it behaves.
//
// Gains (docs/simulation.md): with tau the mean motor time constant plus one
// loop period, the rate loop's proportional gain is 0.5 / tau (about 60
// degrees of phase margin against the lag), its integral gain a fifth of
// that squared; the attitude loop runs at a quarter of the rate loop's
// bandwidth (yaw at an eighth); altitude 1 /s onto a climb rate of at most
// 2 m/s, climb rate 3 /s plus 1 /s^2 integral.

#include "sim/rigid_body.hpp"
#include "sim/vehicle_model.hpp"

#include <motormix/config/config.hpp>
#include <motormix/mixer.hpp>

namespace motormix::sim {

// What the scenario asks of the vehicle at one moment.
struct Reference {
  bool armed = true;
  double roll = 0.0, pitch = 0.0, yaw = 0.0;  // rad (aircraft)
  double altitude_m = 0.0;                    // up, from the take-off point
  double speed_mps = 0.0;                     // ground: forward
  double yaw_rate = 0.0;                      // ground: rad/s, clockwise seen from above
};

struct ControllerGains {
  double rate_p = 0.0;      // 1/s: angular acceleration per rad/s of rate error
  double rate_i = 0.0;      // 1/s^2
  double attitude_p = 0.0;  // 1/s: rate per rad of attitude error, roll and pitch
  double yaw_p = 0.0;
  double max_rate = 0.0;      // rad/s, roll and pitch
  double max_yaw_rate = 0.0;  // rad/s
  double altitude_p = 1.0;    // 1/s
  double climb_p = 3.0;       // 1/s
  double climb_i = 1.0;       // 1/s^2
  double max_climb = 2.0;     // m/s
  double speed_p = 2.0;       // ground: per m/s of speed error
  double speed_i = 2.0;       // 1/s
  double hover_thrust = 0.0;  // demand that holds the weight, as linearized
};

struct ControllerCommand {
  double roll = 0.0, pitch = 0.0, yaw = 0.0, thrust = 0.0;  // normalized demands
  bool armed = false;
  Eigen::Quaterniond attitude_sp = Eigen::Quaterniond::Identity();
};

class Controller {
 public:
  // command_effect: VehicleModel::command_effect(); mixer: one built from the
  // same configuration, only linearized here.
  Controller(const config::Config& config, const Mixer& mixer,
             const Eigen::Matrix<double, 4, Eigen::Dynamic>& command_effect, double mass_kg,
             const Eigen::Vector3d& inertia, double time_constant_s);

  // The controller of the vehicle model built from `config` (its mass,
  // inertia and the mean of its motors' up and down time constants).
  static Controller for_vehicle(const config::Config& config, const Mixer& mixer,
                                const VehicleModel& vehicle);

  // One update of dt seconds. mixer_armed: the mixer's outputs are armed
  // (until then the throttle stays at zero so arming is accepted); on_ground:
  // integrators stay reset. unallocated: the mixer's report of the last
  // cycle, per axis demanded minus produced (mixer_status_t.unallocated):
  // an integrator that would push its axis further the way the mixer could
  // not go holds still (anti-windup by clamping, from the allocation report);
  // one that would take it back integrates.
  ControllerCommand update(const Reference& ref, const BodyState& measured, double forward_speed,
                           bool mixer_armed, bool on_ground, const AxisVector& unallocated,
                           double dt);
  void reset();

  const ControllerGains& gains() const { return gains_; }
  const Eigen::Matrix4d& demand_effect() const { return g_; }  // G, see above

 private:
  bool wheeled_;
  double mass_kg_;
  Eigen::Vector3d inertia_;
  Eigen::Matrix4d g_;  // demand -> torque/thrust (aircraft) or rate/speed (wheels)
  Eigen::Matrix4d g_inv_;
  ControllerGains gains_;
  // Whether integrating `error` on `axis` would push the demand further the
  // way the mixer could not deliver.
  bool winds_up(Axis axis, double error, const AxisVector& unallocated) const;
  Eigen::Vector3d rate_integral_ = Eigen::Vector3d::Zero();
  double climb_integral_ = 0.0;
  double speed_integral_ = 0.0;
  double yaw_rate_integral_ = 0.0;
  Eigen::Vector3d sp_euler_ = Eigen::Vector3d::Zero();  // the attitude_sp_ below, as asked
  Eigen::Quaterniond attitude_sp_ = Eigen::Quaterniond::Identity();
};

}  // namespace motormix::sim
