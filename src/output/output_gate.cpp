#include "output/output_gate.hpp"

#include <algorithm>
#include <cmath>

namespace motormix::output {

namespace {
// A disarmed pulse this close to an end of the range stops the motor there.
constexpr double kEndUs = 1.0;
}  // namespace

OutputGate::OutputGate(std::vector<PulseRange> ranges, double timeout_s, BringupLimits bringup)
    : ranges_(std::move(ranges)), timeout_s_(timeout_s), limits_(bringup) {
  if (ranges_.size() > static_cast<std::size_t>(kMaxOutputs)) ranges_.resize(kMaxOutputs);
}

bool OutputGate::accept(const float* pwm, int count, bool armed, std::uint32_t bringup,
                        double now_s) {
  if (count != outputs()) {
    ++counters_.wrong_size;
    return false;
  }
  for (int i = 0; i < count; ++i) {
    if (!std::isfinite(pwm[i])) {
      ++counters_.not_finite;
      return false;
    }
  }
  if (armed) bringup = 0;  // armed values are armed values
  // One motor of this vehicle, and only with tests enabled here.
  const bool one_motor =
      bringup != 0 && (bringup & (bringup - 1U)) == 0 && (count >= 32 || (bringup >> count) == 0);
  if (bringup != 0 && (!limits_.enabled || !one_motor)) {
    ++counters_.bringup_refused;
    return false;
  }
  // Clamping makes sense for a value a little outside the range (another
  // range on the mixer's side, rounding); one further out than the range is
  // wide (1e30, a sign error) is no command to approximate.
  if (armed) {
    for (int i = 0; i < count; ++i) {
      const PulseRange& r = ranges_[static_cast<std::size_t>(i)];
      const double span = std::max(r.high - r.low, 1.0);
      if (pwm[i] < r.low - span || pwm[i] > r.high + span) {
        ++counters_.out_of_range;
        return false;
      }
    }
  }
  for (int i = 0; i < count; ++i) {
    const PulseRange& r = ranges_[static_cast<std::size_t>(i)];
    double v = pwm[i];
    if (armed && (v < r.low || v > r.high)) {
      ++counters_.clamped;
      v = std::clamp(v, r.low, r.high);
    }
    if (((bringup >> i) & 1U) != 0) {
      // At most max_share of the way from where the motor stops: the end of
      // the range nearer the disarmed pulse, or, for a reversible drive
      // whose disarmed pulse is inside the range (centered), that pulse,
      // either way by max_share of a half range.
      const double span = r.high - r.low;
      const bool centered = r.disarmed > r.low + kEndUs && r.disarmed < r.high - kEndUs;
      const bool low_stops = std::abs(r.disarmed - r.low) <= std::abs(r.disarmed - r.high);
      const double reach = limits_.max_share * (centered ? span / 2.0 : span);
      const double lo = centered ? r.disarmed - reach : low_stops ? r.low : r.high - reach;
      const double hi = centered ? r.disarmed + reach : low_stops ? r.low + reach : r.high;
      if (v < lo || v > hi) {
        ++counters_.bringup_clamped;
        v = std::clamp(v, lo, hi);
      }
    }
    last_[static_cast<std::size_t>(i)] = v;
  }
  if (bringup == 0) {
    bringup_expired_ = false;
  } else if (bringup != bringup_) {
    bringup_since_s_ = now_s;  // a test of another motor starts its own time
    bringup_expired_ = false;
  }
  bringup_ = bringup;
  armed_ = armed;
  have_ = true;
  received_s_ = now_s;
  stale_ = false;
  ++counters_.accepted;
  return true;
}

GateState OutputGate::decide(double now_s, double* out) {
  GateState state = GateState::kArmed;
  if (!have_) {
    state = GateState::kStarting;
  } else if (now_s - received_s_ > timeout_s_) {
    if (!stale_) ++counters_.stale_events;
    stale_ = true;
    state = GateState::kStale;
  } else if (!armed_ && bringup_ != 0) {
    if (!bringup_expired_ &&
        now_s - bringup_since_s_ > limits_.max_seconds + BringupLimits::kGraceS) {
      bringup_expired_ = true;
      ++counters_.bringup_refused;
    }
    state = bringup_expired_ ? GateState::kDisarmed : GateState::kMotorTest;
  } else if (!armed_) {
    state = GateState::kDisarmed;
  }
  for (int i = 0; i < outputs(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    const bool live = state == GateState::kArmed ||
                      (state == GateState::kMotorTest && ((bringup_ >> i) & 1U) != 0);
    out[i] = live ? last_[k] : ranges_[k].disarmed;
  }
  return state;
}

}  // namespace motormix::output
