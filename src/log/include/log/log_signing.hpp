#pragma once
// `motormix sign-log`: a copy of an LCM event log with every event signed
// (signing.hpp) with the configuration's key and link id. For rehearsing a
// signed bus with recorded flights: replayed offline under `require`, or,
// stamped from now (`--now`), played onto a live bus with lcm-logplayer.
// An event that already carries a signature is copied as it is. Damaged
// stretches are skipped and reported, as by the replay.

#include <motormix/config/config.hpp>
#include "log/log_reader.hpp"

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace motormix::lcmlog {

struct SignLogOptions {
  // Stamp the signatures from this host's clock now, keeping the events'
  // spacing, instead of at the times the log recorded them: what a live
  // mixer takes as fresh when lcm-logplayer plays the copy (once).
  bool from_now = false;
};

struct SignLogSummary {
  std::int64_t signed_events = 0;
  std::int64_t already_signed = 0;  // copied as they were
  std::vector<SkippedRange> skipped;
};

// Returns false (with a message on `log`) if a log or the key cannot be
// read, or the copy cannot be written. The key: security.key_file, whatever
// security.mode says.
bool sign_log(const config::Config& config, const std::string& in_path, const std::string& out_path,
              const SignLogOptions& options, SignLogSummary& summary, std::ostream& log);

}  // namespace motormix::lcmlog
