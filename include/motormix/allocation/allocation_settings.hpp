#pragma once
// What the strategies are configured with, apart from the allocators: the
// budgets of the budgeted strategies, prioritized's airmode and tie
// tolerance, optimal's weights. A configuration (config/config.hpp) holds
// these without pulling in the allocator classes.

#include <motormix/axes.hpp>
#include <motormix/enum_names.hpp>

#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>

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

// prioritized: how far the thrust may rise, as a share of the command range
// (0..1; 1: as far as the range allows), to keep roll and pitch, and yaw,
// delivered when motors saturate; lowering the thrust is always allowed.
// Below 1 for roll and pitch, what the rise cannot fix is taken from roll
// and pitch as with airmode off. The named modes are three corners, and
// flown by the same code: off (0, 0), roll_pitch (1, 0), roll_pitch_yaw (1, 1).
struct AirmodeLimits {
  double roll_pitch = 0.0;
  double yaw = 0.0;
};
inline constexpr AirmodeLimits limits_of(Airmode mode) {
  return mode == Airmode::kOff         ? AirmodeLimits{0.0, 0.0}
         : mode == Airmode::kRollPitch ? AirmodeLimits{1.0, 0.0}
                                       : AirmodeLimits{1.0, 1.0};
}
// The named mode limits are, when they are one of its corners.
inline constexpr std::optional<Airmode> named_airmode(const AirmodeLimits& l) {
  if (l.roll_pitch == 0.0 && l.yaw == 0.0) return Airmode::kOff;
  if (l.roll_pitch == 1.0 && l.yaw == 0.0) return Airmode::kRollPitch;
  if (l.roll_pitch == 1.0 && l.yaw == 1.0) return Airmode::kRollPitchYaw;
  return std::nullopt;
}
// The named mode's name, or "limits roll_pitch R, yaw Y".
inline std::string to_string(const AirmodeLimits& l) {
  if (const std::optional<Airmode> named = named_airmode(l)) return to_string(*named);
  char text[64];
  std::snprintf(text, sizeof text, "limits roll_pitch %g, yaw %g", l.roll_pitch, l.yaw);
  return text;
}

// prioritized: results within this much are ties (see prioritized_allocator.hpp).
inline constexpr double kDefaultTieTolerance = 1e-3;

// optimal: the weight of each axis's undelivered demand, and its iteration cap.
struct OptimalSettings {
  AxisVector weights{1.0, 1.0, 0.2, 0.5};  // roll, pitch, yaw, thrust
  int max_iterations = 100;
};

}  // namespace motormix
