#pragma once
// `motormix replay`: the control loop run offline over an LCM event log, with
// the log's own timestamps as the clock. Damaged logs are replayed as far as
// they can be: broken stretches are skipped and reported (see log_reader.hpp),
// and a timestamp that jumps back, or forward by more than max_gap_s, is a
// discontinuity: one such event between two that agree is skipped as a
// damaged timestamp; otherwise a new segment starts there, as a freshly
// started mixer (disarmed until armed again). An event whose timestamp is
// negative or after year 5138 is skipped as damaged. No cycle is ever synthesized
// across a gap, so the output holds at most loop_rate x (time covered by
// segments, each plus the tail) cycles, plus the input events. The loop ticks at the configured
// rate from the first event; inputs are handled at their timestamps, exactly
// as the live node would see them arrive. The output log holds every input
// event plus the produced motor_pwm_t and mixer_status_t. Deterministic: the
// same log and configuration give the same bytes.
//
// Signatures (security:) are read as the live node reads them, the log's
// receive time standing for the clock: under `require` an unsigned, forged
// or replayed input is refused and counted, under `off` a signature is cut
// off unread. The outputs the replay writes are not signed (they are made
// offline, not sent). With ReplayOptions::verify every event on every
// channel is checked as under `require` (see ChannelVerification).

#include <motormix/config/config.hpp>
#include <motormix/signing_policy.hpp>
#include "log/log_reader.hpp"
#include "log/reference_comparison.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace motormix::lcmlog {

// What verifying a log found on one channel (ReplayOptions::verify). Per
// link and channel, timestamps must increase through the log; a link's
// first message must be stamped within security.max_skew_s of the time the
// log recorded it (the signer's clock agreed with the recorder's). How old
// the log itself is cannot be told from it: a log is a recording.
struct ChannelVerification {
  std::string channel;
  signing::PolicyCounts counts;  // signed_accepted: verified; rejected_*: why not
};

struct ReplaySummary {
  double duration_s = 0.0;
  std::int64_t input_events = 0;  // on the setpoint and pid channels
  std::int64_t other_events = 0;  // copied through untouched
  std::int64_t outputs = 0;       // motor_pwm_t written
  double armed_s = 0.0;           // time with armed outputs
  std::array<double, 4>
      limited_s{};  // per axis (roll, pitch, yaw, thrust): armed time not fully delivered
  std::int64_t failsafe_events = 0;
  double failed_s = 0.0;             // armed time with motors treated as failed
  std::int64_t failure_changes = 0;  // times the failure set in force changed
  std::int64_t detections = 0;       // motors motormix's own detector declared failed
  double compensated_s = 0.0;        // armed time with battery compensation (gain > 1)
  double max_thrust_gain = 1.0;
  std::int64_t rejected = 0;          // all rejection counters together
  std::int64_t discontinuities = 0;   // timestamps that jumped back or beyond max_gap_s
  std::int64_t skipped_events = 0;    // of those, single events skipped as damaged timestamps
  std::vector<SkippedRange> skipped;  // byte ranges of the input that held no valid event
  std::vector<ChannelVerification> verification;  // ReplayOptions::verify: per channel, sorted
  std::int64_t unverified = 0;    // ReplayOptions::verify: events (any channel) refused
  ReferenceComparison reference;  // when the log holds ReplayOptions::reference_channel
  bool damaged() const { return !skipped.empty(); }
};

struct ReplayOptions {
  bool progress = false;  // a progress bar on `log`
  double tail_s = -1.0;   // loop time after the last event; < 0: twice the longest timeout
  // Also run a cycle right after every input event, so the output log holds
  // the result for every combination of inputs that is ever in force (what
  // the golden files of the regression suite are made of).
  bool cycle_on_every_input = false;
  // Largest forward step between consecutive events that is still time
  // passing; beyond it (or any step back) is a discontinuity.
  double max_gap_s = 10.0;
  // Verify every event's signature with security.key_file, whatever
  // security.mode says, and mix as under `require`.
  bool verify = false;
  // A channel of another mixer's motor_pwm_t to compare with (see
  // ReferenceComparison); empty: none. Looked for in the log's first
  // kReferenceLookAheadS.
  std::string reference_channel = "PX4_MOTORS";
};

// How far into a log the reference channel is looked for before the replay
// starts: log time, and events at most (those read ahead wait in memory;
// the log is read once). A PX4 import writes it from the flight's first
// outputs.
inline constexpr double kReferenceLookAheadS = 10.0;
inline constexpr std::size_t kReferenceLookAheadEvents = 100000;

// Returns false (with a message on `log`) if a log cannot be read or written.
bool replay_log(const config::Config& config, const std::string& in_path,
                const std::string& out_path, const ReplayOptions& options, ReplaySummary& summary,
                std::ostream& log);

}  // namespace motormix::lcmlog
