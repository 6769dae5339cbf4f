#include <motormix/output/battery_compensation.hpp>

#include <motormix/angles.hpp>

#include <algorithm>
#include <cmath>

namespace motormix {

double battery_gain(const BatterySettings& s, double voltage) {
  if (!std::isfinite(voltage) || voltage <= 0.0) return 1.0;
  const double gain = std::pow(s.nominal_v / voltage, s.exponent);
  return std::isfinite(gain) ? std::clamp(gain, 1.0, s.max_gain) : 1.0;
}

BatteryCompensation::BatteryCompensation(BatterySettings settings) : settings_(settings) {}

BatteryCompensation::Reading BatteryCompensation::add(double voltage, std::int64_t now_us) {
  if (!std::isfinite(voltage)) {
    last_implausible_ = true;
    return Reading::kNonFinite;
  }
  if (voltage < settings_.min_v || voltage > settings_.max_v) {
    last_implausible_ = true;
    return Reading::kImplausible;
  }
  last_implausible_ = false;
  const bool restart =
      last_plausible_us_ == kNever || now_us < last_plausible_us_ ||
      now_us - last_plausible_us_ > static_cast<std::int64_t>(settings_.timeout_s * 1e6);
  if (restart) {
    // First reading, or after a gap longer than the timeout: the old state
    // says nothing about the pack any more.
    filtered_v_ = voltage;
  } else {
    const double dt = static_cast<double>(now_us - last_plausible_us_) / 1e6;
    const double alpha = 1.0 - std::exp(-kTwoPi * settings_.filter_hz * dt);
    filtered_v_ += alpha * (voltage - filtered_v_);
  }
  last_plausible_us_ = now_us;
  return Reading::kAccepted;
}

BatteryState BatteryCompensation::state(std::int64_t now_us) const {
  if (last_implausible_) return BatteryState::kImplausible;
  if (last_plausible_us_ == kNever) return BatteryState::kMissing;
  if (now_us - last_plausible_us_ > static_cast<std::int64_t>(settings_.timeout_s * 1e6)) {
    return BatteryState::kStale;
  }
  return BatteryState::kOk;
}

double BatteryCompensation::gain(std::int64_t now_us) const {
  return state(now_us) == BatteryState::kOk ? battery_gain(settings_, filtered_v_) : 1.0;
}

}  // namespace motormix
