#pragma once
// The output process's failsafe, pure (time passed in, no I/O, no heap per
// cycle): what goes to the pins now, given the last motor_pwm_t.
// Disarmed values at start, when the mixer says armed=false, and when the
// last accepted message is older than the timeout; armed values clamped
// into each motor's range and counted when they were outside it. A message
// of the wrong size, with a non-finite value, or armed with a value further
// outside its motor's range than the range is wide (1e30) is refused and
// counted, and changes nothing (the timeout then disarms if no good one
// follows).

#include <array>
#include <cstdint>
#include <motormix/enum_names.hpp>
#include <vector>

namespace motormix::output {

constexpr int kMaxOutputs = 16;

struct PulseRange {
  double low = 1000.0;  // the motor's range, whichever way round the output maps
  double high = 2000.0;
  double disarmed = 1000.0;
};

enum class GateState {
  kStarting,  // no motor_pwm_t accepted yet
  kDisarmed,  // the mixer says disarmed
  kStale,     // the last accepted message is older than the timeout
  kArmed,
};
inline constexpr EnumName<GateState> kGateStateNames[] = {
    {GateState::kStarting, "starting"},
    {GateState::kDisarmed, "disarmed"},
    {GateState::kStale, "stale"},
    {GateState::kArmed, "armed"},
};
inline const char* to_string(GateState value) { return name_in(kGateStateNames, value); }

struct GateCounters {
  std::uint64_t accepted = 0;
  std::uint64_t wrong_size = 0;    // num_motors is not the configured motor count
  std::uint64_t not_finite = 0;    // a NaN or infinite pwm value
  std::uint64_t clamped = 0;       // armed values outside the motor's range (per value)
  std::uint64_t out_of_range = 0;  // armed messages with a value further out than the range is wide
  std::uint64_t stale_events = 0;  // times the stream went older than the timeout
};

class OutputGate {
 public:
  OutputGate(std::vector<PulseRange> ranges, double timeout_s);

  int outputs() const { return static_cast<int>(ranges_.size()); }
  const PulseRange& range(int i) const { return ranges_[static_cast<std::size_t>(i)]; }

  // A decoded motor_pwm_t that arrived at now_s. False (counted) if refused.
  bool accept(const float* pwm, int count, bool armed, double now_s);
  // The values to write now (outputs() of them) and why.
  GateState decide(double now_s, double* out);
  const GateCounters& counters() const { return counters_; }

 private:
  std::vector<PulseRange> ranges_;
  double timeout_s_;
  std::array<double, kMaxOutputs> last_{};
  bool have_ = false;
  bool armed_ = false;
  bool stale_ = false;
  double received_s_ = 0.0;
  GateCounters counters_;
};

}  // namespace motormix::output
