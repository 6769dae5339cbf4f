#pragma once
// What the strategies are configured with, apart from the allocators: the
// budgets of the budgeted strategies, prioritized's airmode and tie
// tolerance, optimal's weights. A configuration (config/config.hpp) holds
// these without pulling in the allocator classes.

#include <motormix/axes.hpp>
#include <motormix/enum_names.hpp>

#include <cstdint>

namespace motormix {

// Fractions of full power per axis group (legacy_budget and budget); their
// sum may not exceed 1.
struct LegacyBudgets {
  double throttle = 0.60;
  double roll_pitch = 0.25;
  double yaw = 0.15;
};

// prioritized: which axes may use the thrust range to stay delivered.
enum class Airmode : std::uint8_t { kOff, kRollPitch, kRollPitchYaw };
inline constexpr EnumName<Airmode> kAirmodeNames[] = {
    {Airmode::kOff, "off"},
    {Airmode::kRollPitch, "roll_pitch"},
    {Airmode::kRollPitchYaw, "roll_pitch_yaw"},
};
inline const char* to_string(Airmode value) { return name_in(kAirmodeNames, value); }

// prioritized: results within this much are ties (see prioritized_allocator.hpp).
inline constexpr double kDefaultTieTolerance = 1e-3;

// optimal: the weight of each axis's undelivered demand, and its iteration cap.
struct OptimalSettings {
  AxisVector weights{1.0, 1.0, 0.2, 0.5};  // roll, pitch, yaw, thrust
  int max_iterations = 100;
};

}  // namespace motormix
