#pragma once
// A vehicle's physical layout, as far as mixing cares: where each rotor is,
// which way it pushes and spins, and how strongly. Body frame FRD (x front,
// y right, z down); positive roll lowers the right side, positive pitch raises
// the nose, positive yaw turns the nose right (clockwise seen from above).

#include <motormix/eigen_layout.hpp>  // Eigen, at the libraries' alignment
#include <motormix/enum_names.hpp>

#include <vector>

namespace motormix {

enum class Spin : signed char {
  kCw = -1,   // clockwise seen from above: its drag turns the body counter-clockwise (negative yaw)
  kCcw = +1,  // counter-clockwise seen from above: pushes the body toward positive yaw
};
inline constexpr EnumName<Spin> kSpinNames[] = {{Spin::kCw, "cw"}, {Spin::kCcw, "ccw"}};
inline const char* to_string(Spin value) { return name_in(kSpinNames, value); }

struct Rotor {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // FRD, any consistent length unit
  Eigen::Vector3d axis{0.0, 0.0, -1.0};  // direction of thrust, FRD; default straight up
  Spin spin = Spin::kCcw;
  double thrust_coefficient = 1.0;  // thrust per unit command, relative to the other rotors
  double torque_ratio = 0.05;       // drag torque per unit thrust (same length unit as position)
};

// Wheeled vehicle driven by left and right sides (differential drive: one
// wheel per side; skid steer: two or three).
struct WheelBase {
  double wheel_radius = 0.05;     // metres
  double track_width = 0.30;      // metres between left and right wheels
  double max_wheel_speed = 10.0;  // rad/s at full command
  int wheels_per_side = 1;

  double max_forward_speed() const { return wheel_radius * max_wheel_speed; }
  double max_turn_rate() const { return 2.0 * wheel_radius * max_wheel_speed / track_width; }
};

}  // namespace motormix
