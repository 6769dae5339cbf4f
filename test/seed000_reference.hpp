#pragma once
// An independent transcription of the team quad mixer as its document states
// it, kept deliberately naive (named motors, if-statements, no matrices) so
// the matrix-based core can be checked against it.

#include <algorithm>
#include <array>

namespace motormix::test {

struct Seed000Input {
  double throttle = 0.0;  // 0..1
  double roll = 0.0;      // -1..1
  double pitch = 0.0;     // -1..1
  double yaw = 0.0;       // -1..1
};

// Order: front left, front right, rear left, rear right.
inline std::array<double, 4> seed000_power(const Seed000Input& in) {
  struct Signs {
    double roll, pitch, yaw;
  };
  // Straight from the document's per-motor lists.
  const std::array<Signs, 4> motors = {{
      {+1, -1, +1},  // delantero izquierdo: roll, -pitch, yaw
      {-1, -1, -1},  // delantero derecho: -roll, -pitch, -yaw
      {+1, +1, -1},  // trasero izquierdo: roll, pitch, -yaw
      {-1, +1, +1},  // trasero derecho: -roll, pitch, yaw
  }};
  std::array<double, 4> power{};
  for (std::size_t i = 0; i < 4; ++i) {
    // Negative contributions are eliminated.
    double roll = std::max(0.0, motors[i].roll * in.roll) * 0.25;
    double pitch = std::max(0.0, motors[i].pitch * in.pitch) * 0.25;
    double yaw = std::max(0.0, motors[i].yaw * in.yaw) * 0.15;
    double throttle = in.throttle * 0.60;
    if (roll + pitch > 0.25) {
      roll = 0.125;
      pitch = 0.125;
    }
    power[i] = throttle + roll + pitch + yaw;
  }
  return power;
}

inline double seed000_pwm(double power) { return 1150.0 + power * (1924.0 - 1150.0); }

}  // namespace motormix::test
