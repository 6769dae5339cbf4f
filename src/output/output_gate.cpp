#include "output/output_gate.hpp"

#include <algorithm>
#include <cmath>

namespace motormix::output {

OutputGate::OutputGate(std::vector<PulseRange> ranges, double timeout_s)
    : ranges_(std::move(ranges)), timeout_s_(timeout_s) {
  if (ranges_.size() > static_cast<std::size_t>(kMaxOutputs)) ranges_.resize(kMaxOutputs);
}

bool OutputGate::accept(const float* pwm, int count, bool armed, double now_s) {
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
    last_[static_cast<std::size_t>(i)] = v;
  }
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
  } else if (!armed_) {
    state = GateState::kDisarmed;
  }
  for (int i = 0; i < outputs(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    out[i] = state == GateState::kArmed ? last_[k] : ranges_[k].disarmed;
  }
  return state;
}

}  // namespace motormix::output
