#pragma once
// π and the degree, once for every part of motormix that turns an angle
// between degrees and radians or a frequency into a time constant.

namespace motormix {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kTwoPi = 2.0 * kPi;
inline constexpr double kRadPerDeg = kPi / 180.0;
inline constexpr double kDegPerRad = 180.0 / kPi;

}  // namespace motormix
