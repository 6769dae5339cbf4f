#pragma once
// The mixing matrix of a configuration, written out for people and for other
// tools: a readable table, JSON, a config fragment that freezes it, the
// MIXING section of a Paparazzi airframe file, a C header for firmware, PX4's
// control-allocation parameters and an ArduPilot scripted frame.

#include <motormix/config/config.hpp>
#include <motormix/enum_names.hpp>

#include <string>
#include <vector>

namespace motormix::config {

enum class MatrixFormat { kTable, kJson, kYaml, kPaparazzi, kHeader, kPx4, kArdupilot };
inline constexpr EnumName<MatrixFormat> kMatrixFormatNames[] = {
    {MatrixFormat::kTable, "table"},         {MatrixFormat::kJson, "json"},
    {MatrixFormat::kYaml, "yaml"},           {MatrixFormat::kPaparazzi, "paparazzi"},
    {MatrixFormat::kHeader, "header"},       {MatrixFormat::kPx4, "px4"},
    {MatrixFormat::kArdupilot, "ardupilot"},
};

// kPx4 (PX4's CA_* parameters) needs the rotor geometry and kArdupilot (a
// scripted MotorsMatrix frame) an aircraft: for other vehicles they throw
// ConfigError saying why.
std::string export_matrix(const Config& config, MatrixFormat format);

// Per axis, the largest pure demand the configuration can deliver: torques
// from half thrust (aircraft) or standstill (ground), thrust from zero.
AxisVector authority_of(const Config& config);

// Coefficients scaled to `scale` and rounded half to even, the rounding of
// the numpy script that Paparazzi users run.
std::vector<std::vector<long>> scaled_coefficients(const MixingMatrix& mixing, double scale);

}  // namespace motormix::config
