#pragma once
// What `motormix replay` says when the log also holds another mixer's motor
// commands: how far motormix's differ, per motor, and where.

#include <motormix/motor_pwm_t.hpp>
#include <motormix/motor_vector.hpp>

#include <array>

#include <cstdint>
#include <deque>
#include <string>
#include <vector>

namespace motormix::lcmlog {

// motormix's commands against another mixer's, recorded on a channel of the
// log as motor_pwm_t (`motormix import ulog` puts PX4's there): each
// reference message is paired with motormix's output computed from the
// same inputs (equal setpoint_utime and pid_utime). With such a channel the
// replay cycles right after every input, so every pair exists.
struct ReferenceComparison {
  std::string channel;
  std::int64_t references = 0;          // messages on the channel
  std::int64_t compared = 0;            // paired, both armed
  std::int64_t unpaired = 0;            // no motormix output from the same inputs
  std::int64_t reference_disarmed = 0;  // the reference stopped: not compared
  std::int64_t motormix_disarmed = 0;   // motormix not armed while the reference was
  std::vector<double> max_difference;   // per motor, normalized command
  std::vector<double> p99_difference;   // per motor
  double worst = 0.0;
  int worst_motor = 0;      // 1-based
  double worst_at_s = 0.0;  // log time, seconds from the first event
  // Compared samples where some motor differs by more than kSameCommand, by
  // where they were: motormix ramping its outputs up after arming
  // (output.spool_up_s), else a motor at 0 or 1 on either side
  // (saturation), else motormix's allocation could not deliver an axis
  // (limited: airmode, priorities), else elsewhere.
  static constexpr double kSameCommand = 1e-5;
  std::int64_t differing_spool_up = 0;
  std::int64_t differing_saturated = 0;
  std::int64_t differing_limited = 0;
  std::int64_t differing_other = 0;
  bool present() const { return references > 0; }
};

// Pairs and accumulates (replay's per-event work, no I/O).
class ReferenceComparer {
 public:
  ReferenceComparer(std::string channel, int motors);
  // Every output motormix writes; `limited`: its allocation's axis_limited;
  // `spooling_up`: the ramp after arming was on.
  void on_output(const motor_pwm_t& out, std::uint8_t limited, bool spooling_up);
  // A message on the reference channel at log time `t_s`. Undecodable or
  // of another motor count: counted as unpaired.
  void on_reference(const void* data, int size, double t_s);
  // Fills the per-motor maxima and p99s.
  ReferenceComparison finish();

 private:
  struct Output {
    std::int64_t setpoint_utime, pid_utime;
    bool armed;
    std::uint8_t limited;
    bool spooling_up;
    std::array<float, kMaxMotors> command;  // no allocation per output
  };
  // motormix's recent outputs (a reference follows its inputs closely).
  static constexpr std::size_t kRecentOutputs = 512;
  std::deque<Output> recent_;
  ReferenceComparison result_;
  int motors_;
  std::vector<std::vector<double>> differences_;  // per motor, every compared sample
};

}  // namespace motormix::lcmlog
