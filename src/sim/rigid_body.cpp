#include "sim/rigid_body.hpp"

#include <algorithm>
#include <cmath>

namespace motormix::sim {

namespace detail {

Derivative derivative(const BodyState& s, const MassProperties& m, const Wrench& f) {
  Derivative d;
  d.dp = s.velocity;
  d.dv = f.force_world / m.mass_kg;
  const Eigen::Quaterniond omega(0.0, s.rates.x(), s.rates.y(), s.rates.z());
  const Eigen::Quaterniond qdot = s.attitude * omega;
  d.dq = 0.5 * Eigen::Vector4d(qdot.w(), qdot.x(), qdot.y(), qdot.z());
  const Eigen::Vector3d iw = m.inertia.cwiseProduct(s.rates);
  d.dw = (f.torque_body - s.rates.cross(iw)).cwiseQuotient(m.inertia);
  return d;
}

BodyState advance(const BodyState& s, const Derivative& d, double h) {
  BodyState out;
  out.position = s.position + h * d.dp;
  out.velocity = s.velocity + h * d.dv;
  const Eigen::Vector4d q =
      Eigen::Vector4d(s.attitude.w(), s.attitude.x(), s.attitude.y(), s.attitude.z()) + h * d.dq;
  out.attitude = Eigen::Quaterniond(q[0], q[1], q[2], q[3]);
  out.rates = s.rates + h * d.dw;
  return out;
}

BodyState combine(const BodyState& s, const Derivative& k1, const Derivative& k2,
                  const Derivative& k3, const Derivative& k4, double dt) {
  Derivative sum;
  sum.dp = (k1.dp + 2 * k2.dp + 2 * k3.dp + k4.dp) / 6;
  sum.dv = (k1.dv + 2 * k2.dv + 2 * k3.dv + k4.dv) / 6;
  sum.dq = (k1.dq + 2 * k2.dq + 2 * k3.dq + k4.dq) / 6;
  sum.dw = (k1.dw + 2 * k2.dw + 2 * k3.dw + k4.dw) / 6;
  BodyState out = advance(s, sum, dt);
  out.attitude.normalize();
  return out;
}

}  // namespace detail

double tilt(const Eigen::Quaterniond& attitude) {
  const Eigen::Vector3d z = attitude * Eigen::Vector3d::UnitZ();
  return std::acos(std::clamp(z.z(), -1.0, 1.0));
}

Eigen::Vector3d euler(const Eigen::Quaterniond& q) {
  const double w = q.w(), x = q.x(), y = q.y(), z = q.z();
  const double roll = std::atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y));
  const double pitch = std::asin(std::clamp(2 * (w * y - z * x), -1.0, 1.0));
  const double yaw = std::atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z));
  return {roll, pitch, yaw};
}

double heading(const Eigen::Quaterniond& q) {
  return std::atan2(2 * (q.w() * q.z() + q.x() * q.y()), 1 - 2 * (q.y() * q.y() + q.z() * q.z()));
}

Eigen::Quaterniond from_euler(double roll, double pitch, double yaw) {
  return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
         Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX());
}

}  // namespace motormix::sim
