#include <motormix/effectiveness/effectiveness.hpp>

#include <Eigen/Geometry>

namespace motormix {

EffectivenessMatrix rotor_effectiveness(const std::vector<Rotor>& rotors) {
  EffectivenessMatrix e(kNumAxes, static_cast<Eigen::Index>(rotors.size()));
  for (std::size_t i = 0; i < rotors.size(); ++i) {
    const Rotor& r = rotors[i];
    const Eigen::Vector3d thrust = r.thrust_coefficient * r.axis.normalized();
    const Eigen::Vector3d torque =
        r.position.cross(thrust) + static_cast<double>(r.spin) * r.torque_ratio * -thrust;
    const auto col = static_cast<Eigen::Index>(i);
    e(index(Axis::kRoll), col) = torque.x();
    e(index(Axis::kPitch), col) = torque.y();
    e(index(Axis::kYaw), col) = torque.z();
    e(index(Axis::kThrust), col) = -thrust.z();
  }
  return e;
}

EffectivenessMatrix wheel_effectiveness(const WheelBase& base) {
  const int n = 2 * base.wheels_per_side;
  EffectivenessMatrix e = EffectivenessMatrix::Zero(kNumAxes, n);
  for (int i = 0; i < n; ++i) {
    const double side = (i % 2 == 0) ? -1.0 : 1.0;  // even: left, odd: right
    e(index(Axis::kYaw), i) = side / n;
    e(index(Axis::kThrust), i) = 1.0 / n;
  }
  return e;
}

}  // namespace motormix
