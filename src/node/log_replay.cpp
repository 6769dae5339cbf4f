#include "node/log_replay.hpp"

#include <motormix/config/build_mixer.hpp>
#include "node/control_loop.hpp"
#include "node/messages.hpp"

#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cmath>
#include <ostream>
#include <vector>

namespace motormix::node {

namespace {

class Writer {
 public:
  explicit Writer(const std::string& path) : file_(path, "w") {}
  bool good() { return file_.good(); }

  template <typename Message>
  void write(const std::string& channel, std::int64_t utime, const Message& msg) {
    buffer_.resize(static_cast<std::size_t>(msg.getEncodedSize()));
    msg.encode(buffer_.data(), 0, static_cast<int>(buffer_.size()));
    raw(channel, utime, buffer_.data(), static_cast<int>(buffer_.size()));
  }
  void raw(const std::string& channel, std::int64_t utime, const void* data, int size) {
    lcm::LogEvent ev{};
    ev.eventnum = eventnum_++;
    ev.timestamp = utime;
    ev.channel = channel;
    ev.datalen = size;
    ev.data = const_cast<void*>(data);
    file_.writeEvent(&ev);
  }

 private:
  lcm::LogFile file_;
  std::vector<std::uint8_t> buffer_;
  std::int64_t eventnum_ = 0;
};

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
  // First pass: the time span, for the progress bar and the summary.
  std::int64_t first = 0;
  std::int64_t last = 0;
  {
    lcm::LogFile scan(in_path, "r");
    if (!scan.good()) {
      log << "motormix replay: cannot read " << in_path << "\n";
      return false;
    }
    bool any = false;
    while (const lcm::LogEvent* ev = scan.readNextEvent()) {
      if (!any) first = ev->timestamp;
      last = std::max(last, ev->timestamp);
      any = true;
    }
    if (!any) {
      log << "motormix replay: " << in_path << " holds no events\n";
      return false;
    }
  }
  lcm::LogFile in(in_path, "r");
  Writer out(out_path);
  if (!out.good()) {
    log << "motormix replay: cannot write " << out_path << "\n";
    return false;
  }

  ControlLoop loop(config, config::build_mixer(config));
  motor_pwm_t pwm;
  size_pwm_message(pwm, config.motors());
  mixer_status_t status{};
  const auto period_us = static_cast<std::int64_t>(std::llround(1e6 / config.loop_rate_hz));
  const auto status_period_us =
      static_cast<std::int64_t>(std::llround(1e6 / config.status_rate_hz));
  const double tail_s = options.tail_s >= 0.0 ? options.tail_s
                                              : 2.0 * std::max(config.inputs.setpoint_timeout_s,
                                                               config.inputs.pid_timeout_s);
  const std::int64_t end = last + static_cast<std::int64_t>(tail_s * 1e6);
  std::int64_t next_tick = first + period_us;
  std::int64_t next_status = first;
  int last_drawn = -1;

  const auto cycle_at = [&](std::int64_t t) {
    const CycleResult& r = loop.cycle(t);
    fill_pwm_message(pwm, r, t);
    out.write(config.channels.motor_pwm, t, pwm);
    ++summary.outputs;
    if (r.mix.armed) {
      const double dt = static_cast<double>(period_us) / 1e6;
      summary.armed_s += dt;
      for (int a = 0; a < kNumAxes; ++a) {
        if ((r.mix.allocation.axis_limited >> a) & 1U)
          summary.limited_s[static_cast<std::size_t>(a)] += dt;
      }
    }
    if (t >= next_status) {
      fill_status_message(status, r, loop.counters(), LoopTiming{}, config.hash, config.motors(),
                          t);
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

  while (const lcm::LogEvent* ev = in.readNextEvent()) {
    run_ticks_until(ev->timestamp);
    const bool is_setpoint = ev->channel == config.channels.setpoint;
    const bool is_pid = ev->channel == config.channels.pid;
    out.raw(ev->channel, ev->timestamp, ev->data, ev->datalen);
    if (is_setpoint || is_pid) {
      ++summary.input_events;
      bool accepted = false;
      if (is_setpoint) {
        SetpointSample s;
        if (decode_setpoint(ev->data, ev->datalen, s)) {
          loop.on_setpoint(s, ev->timestamp, ev->timestamp);
        } else {
          loop.on_undecodable();
        }
      } else {
        PidSample p;
        if (decode_pid(ev->data, ev->datalen, p)) {
          accepted = loop.on_pid(p, ev->timestamp, ev->timestamp) == Rejection::kNone;
        } else {
          loop.on_undecodable();
        }
      }
      if (options.cycle_on_every_input ||
          (accepted && config.publish == config::PublishMode::kOnInput)) {
        cycle_at(ev->timestamp);
      }
    } else {
      ++summary.other_events;
    }
    if (options.progress && last > first) {
      const int percent = static_cast<int>(100 * (ev->timestamp - first) / (last - first));
      if (percent != last_drawn) {
        draw_progress(log, percent / 100.0);
        last_drawn = percent;
      }
    }
  }
  run_ticks_until(end);
  if (options.progress) log << "\n";

  const Counters& c = loop.counters();
  summary.duration_s = static_cast<double>(end - first) / 1e6;
  summary.failsafe_events = c.failsafe_events;
  summary.rejected = c.rejected();
  return true;
}

}  // namespace motormix::node
