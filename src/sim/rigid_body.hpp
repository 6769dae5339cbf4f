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

#include <functional>

namespace motormix::sim {

struct BodyState {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // m, NED
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  // m/s, NED
  Eigen::Quaterniond attitude = Eigen::Quaterniond::Identity();  // body FRD -> NED
  Eigen::Vector3d rates = Eigen::Vector3d::Zero();     // rad/s, body FRD
};

struct MassProperties {
  double mass_kg = 1.0;
  Eigen::Vector3d inertia = Eigen::Vector3d::Ones();  // principal moments, kg m^2
};

struct Wrench {
  Eigen::Vector3d force_world = Eigen::Vector3d::Zero();  // N, gravity included
  Eigen::Vector3d torque_body = Eigen::Vector3d::Zero();  // N m
};

using WrenchOf = std::function<Wrench(const BodyState&)>;

BodyState rk4_step(const BodyState& s, const MassProperties& m, const WrenchOf& wrench, double dt);

// Tilt of the body's z axis from the world's, radians (0 level, pi upside down).
double tilt(const Eigen::Quaterniond& attitude);
// Euler angles roll, pitch, yaw (Z-Y-X), radians.
Eigen::Vector3d euler(const Eigen::Quaterniond& attitude);
Eigen::Quaterniond from_euler(double roll, double pitch, double yaw);

}  // namespace motormix::sim
