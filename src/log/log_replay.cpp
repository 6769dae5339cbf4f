#include "log/log_replay.hpp"

#include <motormix/config/build_mixer.hpp>
#include "log/log_reader.hpp"
#include "log/reference_comparison.hpp"
#include "loop/control_loop.hpp"
#include "messages/input_reader.hpp"
#include "messages/log_writer.hpp"
#include "messages/messages.hpp"

#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <ostream>
#include <vector>

namespace motormix::lcmlog {

namespace {

// Year 5138: no log is from later than this, and sums of such times with any
// gap or tail stay far from the int64 limit.
constexpr std::int64_t kLatestTimestampUs = 100'000'000'000'000'000;

loop::Counters add(loop::Counters a, const loop::Counters& b) { return a += b; }

void draw_progress(std::ostream& log, double fraction) {
  constexpr int kWidth = 40;
  const int filled = static_cast<int>(std::lround(fraction * kWidth));
  log << "\r[" << std::string(static_cast<std::size_t>(filled), '#')
      << std::string(static_cast<std::size_t>(kWidth - filled), ' ') << "] "
      << static_cast<int>(std::lround(fraction * 100)) << "%" << std::flush;
}

}  // namespace

bool replay_log(const config::Config& config, const std::string& in_path,
                const std::string& out_path, const ReplayOptions& options, ReplaySummary& summary,
                std::ostream& log) {
  LogReader in(in_path);
  if (!in.good()) {
    log << "motormix replay: cannot read " << in_path << "\n";
    return false;
  }
  // Timestamps are microseconds since 1970; outside [0, kLatestTimestampUs]
  // one is damaged, and keeping every timestamp in that range keeps all the
  // time arithmetic below far from overflow.
  const auto plausible = [](std::int64_t t) { return t >= 0 && t <= kLatestTimestampUs; };
  const auto skip_implausible = [&](const LogEventView& ev) {
    ++summary.discontinuities;
    ++summary.skipped_events;
    log << "motormix replay: warning: event " << ev.eventnum << " (byte " << ev.offset
        << ", channel " << ev.channel << ") has timestamp " << ev.timestamp
        << ", outside any plausible time; skipped\n";
  };
  while (in.peek() && !plausible(in.peek()->timestamp)) skip_implausible(*in.next());
  const LogEventView* first_event = in.peek();
  if (!first_event) {
    log << "motormix replay: " << in_path << " holds no valid events";
    if (in.skipped_bytes() > 0) log << " (" << in.skipped_bytes() << " bytes of damaged data)";
    log << "\n";
    summary.skipped = in.skipped();
    return false;
  }
  // Which input, if any, a channel carries: the node's routing, for a loop
  // of this configuration (each segment's loop reads the same channels).
  const messages::InputRoutes routes(config);
  const auto input_kind = [&routes](const std::string& channel) { return routes.kind(channel); };
  // Signatures: one policy per channel (a verifier keeps timestamps for a
  // bounded number of channels; a log may hold more).
  const config::Security& security = config.security;
  const signing::Mode mode = options.verify ? signing::Mode::kRequire : security.mode;
  std::optional<signing::Key> key;
  if (mode != signing::Mode::kOff) {
    if (security.key_file.empty()) {
      log << "motormix replay: --verify needs the key: set security.key_file\n";
      return false;
    }
    try {
      key = signing::load_key(security.key_file);
    } catch (const signing::KeyError& e) {
      log << "motormix replay: security.key_file: " << e.what() << "\n";
      return false;
    }
  }
  std::map<std::string, signing::Policy> policies;
  const auto policy_of = [&](const std::string& channel) -> signing::Policy& {
    auto it = policies.find(channel);
    if (it == policies.end()) {
      it = policies
               .emplace(channel, key ? signing::Policy(mode, *key,
                                                       static_cast<std::uint8_t>(security.link_id),
                                                       security.max_skew_s)
                                     : signing::Policy())
               .first;
    }
    return it->second;
  };
  // Every input the node's way (bus::receive through its channel's policy),
  // refusals counted by reason.
  messages::InputReader reader;
  messages::InputSample sample;
  // What the mixer's status reports: the input channels' counts together.
  const auto input_accounting = [&]() {
    messages::InputAccounting sum;
    sum.mode = mode;
    for (const auto& [channel, policy] : policies) {
      if (input_kind(channel)) sum.security += policy.counts();
    }
    sum.refused = reader.refusals();
    return sum;
  };

  // Another mixer's commands to compare with: when the log holds them, a
  // cycle follows every input so each of them has motormix's answer to the
  // same inputs. They are looked for in the log's first kReferenceLookAheadS
  // (read once: the events read ahead are replayed from memory); one that
  // comes later is compared only with --every-input (cycles on every input
  // from the start), else named in a warning.
  std::optional<ReferenceComparer> reference;
  if (!options.reference_channel.empty() &&
      in.look_ahead_for(options.reference_channel,
                        static_cast<std::int64_t>(kReferenceLookAheadS * 1e6),
                        kReferenceLookAheadEvents)) {
    reference.emplace(options.reference_channel, config.motors());
  }
  const bool cycle_on_every_input = options.cycle_on_every_input || reference.has_value();
  bool late_reference_named = false;

  messages::LogWriter out(out_path);
  if (!out.good()) {
    log << "motormix replay: cannot write " << out_path << "\n";
    return false;
  }

  motor_pwm_t pwm;
  messages::size_pwm_message(pwm, config.motors());
  mixer_status_t status{};
  const auto period_us = static_cast<std::int64_t>(std::llround(1e6 / config.loop_rate_hz));
  const auto status_period_us =
      static_cast<std::int64_t>(std::llround(1e6 / config.status_rate_hz));
  const double tail_s = options.tail_s >= 0.0 ? options.tail_s
                                              : 2.0 * std::max(config.inputs.setpoint_timeout_s,
                                                               config.inputs.pid_timeout_s);
  const auto tail_us = static_cast<std::int64_t>(tail_s * 1e6);
  const auto max_gap_us = static_cast<std::int64_t>(options.max_gap_s * 1e6);

  // The log is replayed in segments of continuous time. A segment starts as a
  // freshly started mixer would (disarmed until the controller arms it), and
  // no loop cycle is ever synthesized across the gap between two segments.
  std::optional<loop::ControlLoop> loop;
  loop::Counters totals;
  std::int64_t segment_first = 0;
  std::int64_t next_tick = 0;
  std::int64_t next_status = 0;
  const auto start_segment = [&](std::int64_t t) {
    if (loop) totals = add(totals, loop->counters());
    loop.emplace(config, config::build_mixer(config));
    segment_first = t;
    next_tick = t + period_us;
    next_status = t;
  };

  MotorMask last_failed = config.failed_motors;
  MotorMask detected_before = 0;
  const auto cycle_at = [&](std::int64_t t) {
    const loop::CycleResult& r = loop->cycle(t);
    messages::fill_pwm_message(pwm, r, t);
    out.write(config.channels.motor_pwm, t, pwm);
    if (reference) reference->on_output(pwm, r.mix.allocation.axis_limited, r.spooling_up);
    ++summary.outputs;
    if (r.failed != last_failed) {
      ++summary.failure_changes;
      last_failed = r.failed;
    }
    if (r.detection_changed) {
      const MotorMask fresh = r.detection.failed & ~detected_before;
      for (int m = 0; m < kMaxMotors; ++m) summary.detections += (fresh >> m) & 1U;
      detected_before = r.detection.failed;
    }
    if (r.mix.armed) {
      const double dt = static_cast<double>(period_us) / 1e6;
      summary.armed_s += dt;
      if (r.failed != 0) summary.failed_s += dt;
      if (r.thrust_gain > 1.0) summary.compensated_s += dt;
      summary.max_thrust_gain = std::max(summary.max_thrust_gain, r.thrust_gain);
      for (int a = 0; a < kNumAxes; ++a) {
        if ((r.mix.allocation.axis_limited >> a) & 1U)
          summary.limited_s[static_cast<std::size_t>(a)] += dt;
      }
    }
    if (t >= next_status) {
      messages::fill_status_message(status, r, add(totals, loop->counters()),
                                    messages::LoopTiming{}, config.hash, config.motors(), t,
                                    input_accounting());
      out.write(config.channels.status, t, status);
      next_status = t + status_period_us;
    }
  };
  const auto run_ticks_until = [&](std::int64_t t) {
    while (next_tick <= t) {
      cycle_at(next_tick);
      next_tick += period_us;
    }
  };
  const auto end_segment = [&](std::int64_t last) {
    run_ticks_until(last + tail_us);
    summary.duration_s += static_cast<double>(last + tail_us - segment_first) / 1e6;
  };

  const std::int64_t first_time = first_event->timestamp;
  start_segment(first_event->timestamp);
  std::int64_t previous = first_event->timestamp;
  int last_drawn = -1;
  while (const LogEventView* ev = in.next()) {
    if (!plausible(ev->timestamp)) {
      skip_implausible(*ev);
      continue;
    }
    const std::int64_t jump = ev->timestamp - previous;
    if (jump < 0 || jump > max_gap_us) {
      ++summary.discontinuities;
      // One event whose timestamp is off while the next one carries on the
      // timeline is a damaged timestamp: skip that event alone.
      const LogEventView* after = in.peek();
      const bool outlier = after && plausible(after->timestamp) && after->timestamp >= previous &&
                           after->timestamp - previous <= max_gap_us;
      log << "motormix replay: warning: event " << ev->eventnum << " (byte " << ev->offset
          << ", channel " << ev->channel << ") jumps " << static_cast<double>(jump) / 1e6
          << " s in time; "
          << (outlier ? "skipped, the next event carries on the timeline"
                      : "a new segment starts there (no cycles across the gap, the mixer "
                        "restarts disarmed)")
          << "\n";
      if (outlier) {
        ++summary.skipped_events;
        continue;
      }
      end_segment(previous);
      start_segment(ev->timestamp);
    }
    previous = ev->timestamp;
    run_ticks_until(ev->timestamp);
    out.raw(ev->channel, ev->timestamp, ev->data.data(), static_cast<int>(ev->data.size()));
    const std::optional<messages::InputKind> kind = input_kind(ev->channel);
    if (kind) {
      ++summary.input_events;
      // The signing policy sees every input event at the time the log
      // received it, then the wire checks and the decoder, as in the node.
      const bus::Refusal r = reader.read(*kind, policy_of(ev->channel), ev->channel,
                                         ev->data.data(), ev->data.size(), ev->timestamp, sample);
      if (r == bus::Refusal::kSignature && options.verify) ++summary.unverified;
      const bool accepted = r == bus::Refusal::kNone &&
                            messages::hand_over(*loop, sample, ev->timestamp, ev->timestamp);
      if (cycle_on_every_input || (accepted && *kind == messages::InputKind::kPid &&
                                   config.publish == config::PublishMode::kOnInput)) {
        cycle_at(ev->timestamp);
      }
    } else {
      ++summary.other_events;
      // With --verify every event's signature is checked, and the reference
      // is read without its trailer.
      std::size_t payload = ev->data.size();
      if (options.verify) {
        const signing::Inbound verdict =
            policy_of(ev->channel)
                .check(ev->channel, ev->data.data(), ev->data.size(), ev->timestamp);
        if (!verdict.accept) ++summary.unverified;
        payload = verdict.payload_size;
      }
      if (!reference && !options.reference_channel.empty() &&
          ev->channel == options.reference_channel) {
        if (cycle_on_every_input) {
          reference.emplace(options.reference_channel, config.motors());
        } else if (!late_reference_named) {
          late_reference_named = true;
          log << "motormix replay: warning: " << options.reference_channel << " first appears "
              << static_cast<double>(ev->timestamp - first_time) / 1e6
              << " s into the log, after the first " << kReferenceLookAheadS
              << " s where it is looked for: not compared (replay with --every-input to compare "
                 "it)\n";
        }
      }
      if (reference && ev->channel == options.reference_channel) {
        reference->on_reference(ev->data.data(), static_cast<int>(payload),
                                static_cast<double>(ev->timestamp - first_time) / 1e6);
      }
    }
    if (options.progress && in.size() > 0) {
      const int percent = static_cast<int>(100 * ev->offset / in.size());
      if (percent != last_drawn) {
        draw_progress(log, percent / 100.0);
        last_drawn = percent;
      }
    }
  }
  end_segment(previous);
  if (options.progress) log << "\n";

  if (!out.close()) {
    log << "motormix replay: cannot write " << out_path << " (disk full or I/O error)\n";
    return false;
  }
  totals = add(totals, loop->counters());
  summary.failsafe_events = totals.failsafe_events;
  summary.rejected = totals.rejected() + static_cast<std::int64_t>(reader.refusals().refused());
  if (options.verify) {
    for (const auto& [channel, policy] : policies) {
      summary.verification.push_back({channel, policy.counts()});
    }
  }
  if (reference) summary.reference = reference->finish();
  summary.skipped = in.skipped();
  for (const SkippedRange& r : summary.skipped) {
    log << "motormix replay: warning: " << in_path << " is damaged: bytes " << r.begin << ".."
        << r.end << " (" << r.end - r.begin << " bytes) hold no valid event and were skipped\n";
  }
  return true;
}

}  // namespace motormix::lcmlog
