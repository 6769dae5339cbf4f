#pragma once
// Inputs in newtons and newton-metres (inputs.units: physical): what a
// controller working in physical units (an SE(3) controller, most research
// code) asks for, turned into the demands the mixer takes, through the
// vehicle's own physics: its rotors (positions, axes, maximum thrust, drag
// torque), the ESCs' curve and the configured mixer and output stage.
//
// The collective: the setpoint's throttle is the total thrust along the
// body's up axis, newtons; the throttle demand that gives it at zero torque
// is read off a table of the whole chain from 0 to 1 (monotonic), so it is
// exact wherever the table's steps are, not only near hover. The torques:
// pid_t's roll, pitch and yaw (and the setpoint's yaw with yaw_source
// setpoint) are body torques (FRD: roll about forward, right side down
// positive), newton-metres; the demands are the inverse of the chain's
// slope at hover, the torque-per-demand matrix, off-diagonal terms
// included. Demands beyond the range are clamped to it (the mixer's
// allocation then reports what it could not give).
//
// Built once at start-up; converting allocates nothing.

#include <motormix/axes.hpp>
#include <motormix/config/config.hpp>
#include <motormix/mixer.hpp>

#include <Eigen/Core>

#include <array>
#include <optional>

namespace motormix::loop {

class PhysicalInputs {
 public:
  // Nothing when the vehicle section does not give a hover (see
  // config::hover_point) or the chain's slope cannot be inverted.
  static std::optional<PhysicalInputs> build(const config::Config& config, const Mixer& mixer);

  // Throttle demand 0..1 for a total thrust in newtons (clamped).
  double throttle_for(double thrust_n) const;
  // Roll, pitch and yaw demands (-1..1, clamped) for body torques, N m.
  Eigen::Vector3d torques_for(const Eigen::Vector3d& torque_nm) const;

  // The scale, for the start-up banner and users: N m per unit of each
  // torque demand at hover (the diagonal), the total thrust at throttle 1,
  // and the hover's thrust and throttle.
  const Eigen::Matrix3d& torque_per_demand() const { return per_demand_; }
  double thrust_at_full_n() const { return table_.back(); }
  double hover_thrust_n() const { return hover_thrust_n_; }
  double hover_throttle() const { return hover_throttle_; }

  static constexpr int kTableSteps = 200;

 private:
  std::array<double, kTableSteps + 1> table_{};  // total upward thrust, N, at throttle k / steps
  Eigen::Matrix3d per_demand_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d demand_per_nm_ = Eigen::Matrix3d::Zero();
  double hover_thrust_n_ = 0.0;
  double hover_throttle_ = 0.0;
};

}  // namespace motormix::loop
