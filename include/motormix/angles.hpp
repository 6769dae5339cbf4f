#pragma once
// π and the degree, once for every part of motormix that turns an angle
// given in degrees (geometry presets, scenarios, the simulator) into
// radians.

namespace motormix {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kRadPerDeg = kPi / 180.0;

}  // namespace motormix
