#pragma once
// Battery-voltage compensation: as the pack sags, the same ESC command gives
// less thrust, so the thrust demand is scaled up by
//     gain = (nominal_v / filtered voltage) ^ exponent,   1 <= gain <= max_gain.
// Only a voltage that is fresh and plausible compensates; anything else
// (none yet, stale, implausible, NaN) means gain 1 and a state that says why.
// Time is passed in (microseconds, monotonic): no clock here.

#include <cstdint>
#include <limits>
#include <motormix/enum_names.hpp>

namespace motormix {

struct BatterySettings {
  double nominal_v = 16.8;  // voltage at which gain is 1 (typically full charge)
  double exponent = 1.0;    // thrust ~ voltage^exponent at a fixed command
  double max_gain = 1.5;    // largest multiplication of the thrust demand
  double filter_hz = 2.0;   // first-order low-pass cutoff on the measured voltage
  double timeout_s = 0.5;   // older voltages are stale
  double min_v = 8.4;       // plausible range: outside it a reading is a sensor fault
  double max_v = 21.0;
};

enum class BatteryState : std::uint8_t {
  kOff = 0,          // compensation not configured
  kOk = 1,           // compensating from a fresh, plausible voltage
  kMissing = 2,      // no plausible voltage received yet
  kStale = 3,        // the last plausible voltage is older than the timeout
  kImplausible = 4,  // the latest reading was outside the plausible range or not finite
};

inline constexpr EnumName<BatteryState> kBatteryStateNames[] = {
    {BatteryState::kOff, "off"},
    {BatteryState::kOk, "ok"},
    {BatteryState::kMissing, "missing"},
    {BatteryState::kStale, "stale"},
    {BatteryState::kImplausible, "implausible"},
};
inline const char* to_string(BatteryState value) { return name_in(kBatteryStateNames, value); }

// The gain for one voltage, unfiltered (1 for a voltage that is not finite
// or not positive).
double battery_gain(const BatterySettings& settings, double voltage);

class BatteryCompensation {
 public:
  explicit BatteryCompensation(BatterySettings settings);

  enum class Reading : std::uint8_t { kAccepted, kNonFinite, kImplausible };

  // One measured voltage received at now_us. An implausible or non-finite
  // reading is refused (the filter keeps its state, so it goes stale unless
  // plausible readings return).
  Reading add(double voltage, std::int64_t now_us);

  // Gain and state at now_us; 1 unless kOk.
  double gain(std::int64_t now_us) const;
  BatteryState state(std::int64_t now_us) const;
  double filtered_v() const { return filtered_v_; }  // NaN until the first plausible reading
  const BatterySettings& settings() const { return settings_; }

 private:
  static constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::min();
  BatterySettings settings_;
  double filtered_v_ = std::numeric_limits<double>::quiet_NaN();
  std::int64_t last_plausible_us_ = kNever;
  bool last_implausible_ = false;
};

}  // namespace motormix
