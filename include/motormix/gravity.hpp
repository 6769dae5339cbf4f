#pragma once
// Standard gravity, once for every part of motormix that turns a mass into
// a weight (the vehicle's hover, the descents, the simulator).

namespace motormix {

inline constexpr double kStandardGravity = 9.80665;  // m/s^2

}  // namespace motormix
