#pragma once
// Reads the MIXING section of a Paparazzi airframe file (or the section
// alone) as a mixing table: the inverse of `motormix matrix --format paparazzi`.
// Set-up time only; every error is a ConfigError naming the file, the define
// and the value.

#include <motormix/config/config.hpp>
#include <motormix/effectiveness/mixing_matrix.hpp>

#include <string>

namespace motormix::config {

// command[i] = (ROLL_COEF[i] roll + PITCH_COEF[i] pitch + YAW_COEF[i] yaw +
// THRUST_COEF[i] thrust) / SCALE: the table is each coefficient over SCALE.
// THRUST_COEF defaults to SCALE for every motor, SCALE to 256. Non-zero TRIM_*
// values are refused (they have no counterpart in a mixing table), and so is
// a frame given only by TYPE (Paparazzi's built-in tables are not read).
MixingMatrix parse_paparazzi_mixing(const std::string& xml_text, const std::string& source);

}  // namespace motormix::config
