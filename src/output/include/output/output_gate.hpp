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
//
// Bring-up: a message that is not armed may carry one motor's bring-up
// value (motor_pwm_t bringup_motors: the mixer's motor test). It reaches
// that motor's pin within this process's own limits, the others stay
// disarmed: only with motor_test.enabled in its configuration, one motor
// at a time, the value clamped to motor_test.max_throttle of the range
// from its stopped end (of half the range either way around a disarmed
// pulse inside it: a reversible drive), and for motor_test.max_seconds (plus a grace for
// the mixer's own end) at most: then disarmed until a message without it.
// The staleness timeout and the failsafe chain stay as they are.

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
  kMotorTest,  // disarmed but for one motor's bring-up value
};
inline constexpr EnumName<GateState> kGateStateNames[] = {
    {GateState::kStarting, "starting"},    {GateState::kDisarmed, "disarmed"},
    {GateState::kStale, "stale"},          {GateState::kArmed, "armed"},
    {GateState::kMotorTest, "motor test"},
};

// The output's own limits on a bring-up value (its configuration's
// motor_test section).
struct BringupLimits {
  bool enabled = true;
  double max_share = 0.15;  // of the range, from its stopped end
  double max_seconds = 3.0;
  static constexpr double kGraceS = 0.5;  // past max_seconds: the mixer's own end may lag
};
inline const char* to_string(GateState value) { return name_in(kGateStateNames, value); }

struct GateCounters {
  std::uint64_t accepted = 0;
  std::uint64_t wrong_size = 0;    // num_motors is not the configured motor count
  std::uint64_t not_finite = 0;    // a NaN or infinite pwm value
  std::uint64_t clamped = 0;       // armed values outside the motor's range (per value)
  std::uint64_t out_of_range = 0;  // armed messages with a value further out than the range is wide
  std::uint64_t stale_events = 0;  // times the stream went older than the timeout
  // Bring-up values refused: tests disabled here, more than one motor, or
  // a motor test longer than its limit (then disarmed).
  std::uint64_t bringup_refused = 0;
  std::uint64_t bringup_clamped = 0;  // bring-up values brought under max_share
};

class OutputGate {
 public:
  OutputGate(std::vector<PulseRange> ranges, double timeout_s, BringupLimits bringup = {});

  int outputs() const { return static_cast<int>(ranges_.size()); }
  const PulseRange& range(int i) const { return ranges_[static_cast<std::size_t>(i)]; }

  // A decoded motor_pwm_t that arrived at now_s (bringup: its
  // bringup_motors). False (counted) if refused.
  bool accept(const float* pwm, int count, bool armed, std::uint32_t bringup, double now_s);
  // The values to write now (outputs() of them) and why.
  GateState decide(double now_s, double* out);
  const GateCounters& counters() const { return counters_; }
  // The motors whose pins carry a bring-up value now (kMotorTest).
  std::uint32_t bringup() const { return bringup_; }

 private:
  std::vector<PulseRange> ranges_;
  double timeout_s_;
  BringupLimits limits_;
  std::uint32_t bringup_ = 0;
  double bringup_since_s_ = 0.0;  // when the current motor's test started
  bool bringup_expired_ = false;  // past its limit: disarmed until a message without it
  std::array<double, kMaxOutputs> last_{};
  bool have_ = false;
  bool armed_ = false;
  bool stale_ = false;
  double received_s_ = 0.0;
  GateCounters counters_;
};

}  // namespace motormix::output
