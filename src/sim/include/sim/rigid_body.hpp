#pragma once
// A rigid body in world NED with a quaternion attitude, integrated with a
// fixed-step classical Runge-Kutta (RK4) scheme; the quaternion is
// renormalized after each step. Forces are given in the world frame, torques
// in the body frame (FRD), both as a function of the state, so drag is
// evaluated at every stage. The equations are Newton-Euler's, as in PX4's
// SIH and most multicopter textbooks (Beard & McLain, "Small Unmanned
// Aircraft", ch. 3; Mahony, Kumar & Corke, IEEE RAM 2012):
//   p' = v,  v' = F / m,  q' = q (0, w) / 2,  w' = I^-1 (tau - w x I w).

#include <motormix/eigen_layout.hpp>

#include <Eigen/Geometry>

namespace motormix::sim {

struct BodyState {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();            // m, NED
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();            // m/s, NED
  Eigen::Quaterniond attitude = Eigen::Quaterniond::Identity();  // body FRD -> NED
  Eigen::Vector3d rates = Eigen::Vector3d::Zero();               // rad/s, body FRD
};

struct MassProperties {
  double mass_kg = 1.0;
  Eigen::Vector3d inertia = Eigen::Vector3d::Ones();  // principal moments, kg m^2
};

struct Wrench {
  Eigen::Vector3d force_world = Eigen::Vector3d::Zero();  // N, gravity included
  Eigen::Vector3d torque_body = Eigen::Vector3d::Zero();  // N m
};

// One RK4 step; `wrench` is called four times, with the state of each stage.
template <typename WrenchOf>
BodyState rk4_step(const BodyState& s, const MassProperties& m, const WrenchOf& wrench, double dt);

// Tilt of the body's z axis from the world's, radians (0 level, pi upside down).
double tilt(const Eigen::Quaterniond& attitude);
// Euler angles roll, pitch, yaw (Z-Y-X), radians.
Eigen::Vector3d euler(const Eigen::Quaterniond& attitude);
double heading(const Eigen::Quaterniond& attitude);  // the yaw of euler(), alone
Eigen::Quaterniond from_euler(double roll, double pitch, double yaw);

namespace detail {

struct Derivative {
  Eigen::Vector3d dp, dv;
  Eigen::Vector4d dq;  // w, x, y, z
  Eigen::Vector3d dw;
};

Derivative derivative(const BodyState& s, const MassProperties& m, const Wrench& f);
BodyState advance(const BodyState& s, const Derivative& d, double h);
BodyState combine(const BodyState& s, const Derivative& k1, const Derivative& k2,
                  const Derivative& k3, const Derivative& k4, double dt);

}  // namespace detail

template <typename WrenchOf>
BodyState rk4_step(const BodyState& s, const MassProperties& m, const WrenchOf& wrench, double dt) {
  using detail::advance;
  using detail::derivative;
  const detail::Derivative k1 = derivative(s, m, wrench(s));
  const BodyState s2 = advance(s, k1, dt / 2);
  const detail::Derivative k2 = derivative(s2, m, wrench(s2));
  const BodyState s3 = advance(s, k2, dt / 2);
  const detail::Derivative k3 = derivative(s3, m, wrench(s3));
  const BodyState s4 = advance(s, k3, dt);
  const detail::Derivative k4 = derivative(s4, m, wrench(s4));
  return detail::combine(s, k1, k2, k3, k4, dt);
}

}  // namespace motormix::sim
