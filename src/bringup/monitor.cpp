#include "bringup/monitor.hpp"

#include "bus/clock.hpp"
#include "bus/process.hpp"
#include "loop/control_loop.hpp"

#include <lcm/lcm-cpp.hpp>

#include <poll.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ostream>
#include <sstream>

namespace motormix::bringup {

namespace {

using Clock = bus::MonotonicClock;

// The wire's codes carry the control loop's own enums: their names are the
// ones the mixer logs (a code this build does not know reads "?").
std::string state_name(int8_t s) {
  std::string name = to_string(static_cast<loop::LoopState>(s));
  for (char& c : name) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return name;
}

const char* reason_name(int8_t r) { return to_string(static_cast<loop::FailsafeReason>(r)); }

const char* failure_name(int8_t f) {
  switch (f) {
    case mixer_status_t::FAILURE_NONE:
      return "none";
    case mixer_status_t::FAILURE_REALLOCATED:
      return "reallocated";
    case mixer_status_t::FAILURE_AXES_LOST:
      return "AXES LOST";
    case mixer_status_t::FAILURE_UNSUPPORTED:
      return "UNSUPPORTED (no promise)";
    default:
      return "?";
  }
}

const char* battery_name(int8_t b) { return to_string(static_cast<BatteryState>(b)); }

constexpr const char* kAxes[4] = {"roll", "pitch", "yaw", "thrust"};

std::string fixed(double v, int precision) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", precision, v);
  return buf;
}

std::string age(float ms) { return ms < 0.0F ? "never" : fixed(ms, 0) + " ms"; }

std::string motor_name(const MonitorOptions& o, int i) {
  const auto k = static_cast<std::size_t>(i);
  return k < o.motor_names.size() ? o.motor_names[k] : "m" + std::to_string(i + 1);
}

// A bar for a command: 0..1 fills from the left; a negative command (wheels)
// fills from the middle to the left, a positive one from the middle right.
std::string bar(double command, bool bipolar, int width) {
  std::string b(static_cast<std::size_t>(width), '.');
  if (!std::isfinite(command)) return std::string(static_cast<std::size_t>(width), '?');
  if (!bipolar) {
    const int filled = static_cast<int>(std::lround(std::clamp(command, 0.0, 1.0) * width));
    std::fill(b.begin(), b.begin() + filled, '#');
  } else {
    const int mid = width / 2;
    const int cells = static_cast<int>(std::lround(std::clamp(std::abs(command), 0.0, 1.0) * mid));
    if (command >= 0) {
      std::fill(b.begin() + mid, b.begin() + std::min(width, mid + cells), '#');
    } else {
      std::fill(b.begin() + (mid - cells), b.begin() + mid, '#');
    }
    b[static_cast<std::size_t>(mid)] = '|';
  }
  return "[" + b + "]";
}

}  // namespace

namespace {

const char* pins_name(int8_t p) {
  switch (p) {
    case output_status_t::PINS_STARTING:
      return "disarmed (nothing taken yet)";
    case output_status_t::PINS_ARMED:
      return "ARMED";
    case output_status_t::PINS_DISARMED:
      return "disarmed";
    case output_status_t::PINS_STALE:
      return "disarmed (motor_pwm_t STALE)";
    case output_status_t::PINS_MOTOR_TEST:
      return "MOTOR TEST (one pin, the others disarmed)";
    default:
      return "?";
  }
}

// motormix output's lines: the pins, what it took and refused, the chip.
std::string output_lines(const MonitorSnapshot& snap, const MonitorOptions& o) {
  std::ostringstream s;
  if (!snap.output) {
    if (o.expect_output)
      s << "output    NOT HEARD on " << o.output_status_channel
        << " (is motormix output running?)\n";
    return s.str();
  }
  const output_status_t& out = *snap.output;
  s << "output    "
    << (out.driver == output_status_t::DRIVER_SERIAL  ? "serial"
        : out.driver == output_status_t::DRIVER_SYSFS ? "sysfs"
                                                      : "?")
    << "   pins " << pins_name(out.pins) << "   age " << fixed(snap.output_age_s * 1e3, 0)
    << " ms   taken " << out.taken << "   refused: signature " << out.refused_signature
    << "   malformed " << out.refused_malformed << "   array size " << out.refused_wrong_size
    << "   non-finite " << out.refused_not_finite << "   range " << out.refused_out_of_range
    << "   clamped " << out.clamped << "   stale " << out.stale_events << "   write failures "
    << out.write_failures;
  if (out.telemetry_frames > 0) s << "   esc_telemetry " << out.telemetry_frames;
  if (out.esc_commands_sent + out.esc_commands_refused > 0)
    s << "   ESC commands sent " << out.esc_commands_sent << ", refused "
      << out.esc_commands_refused;
  if (!out.device_open) s << "   DEVICE LOST (reopening)";
  if (out.device_reopened > 0) s << "   reopened " << out.device_reopened;
  s << "\n";
  if (out.firmware_report) {
    s << "firmware  "
      << ((out.firmware_flags & output_status_t::FIRMWARE_CONFIGURED) ? "configured"
                                                                      : "NOT CONFIGURED")
      << ((out.firmware_flags & output_status_t::FIRMWARE_ARMED) ? ", armed" : ", disarmed")
      << ((out.firmware_flags & output_status_t::FIRMWARE_TIMED_OUT) ? " (LINK TIMED OUT)" : "")
      << "   frames " << out.firmware_frames << "   crc errors " << out.firmware_crc_errors
      << "   malformed " << out.firmware_malformed << "   link timeouts "
      << out.firmware_link_timeouts << "   watchdog resets " << out.firmware_watchdog_resets
      << "   rejected " << out.firmware_rejected << "\n";
  } else if (out.driver == output_status_t::DRIVER_SERIAL) {
    s << "firmware  no report from the chip yet\n";
  }
  return s.str();
}

}  // namespace

std::string render_monitor(const MonitorSnapshot& snap, const MonitorOptions& o, int bar_width) {
  std::ostringstream s;
  s << "motormix monitor: status '" << o.status_channel << "', outputs '" << o.pwm_channel << "'\n";
  if (!snap.status) {
    s << "no mixer_status received yet\n";
    return s.str();
  }
  const mixer_status_t& st = *snap.status;
  if (snap.status_age_s > 1.0) {
    s << "STATUS STALE: last status " << fixed(snap.status_age_s, 1)
      << " s ago (is motormix still running?)\n";
  }
  char hash[32];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(st.config_hash));
  s << "state     " << state_name(st.state);
  if (st.state == mixer_status_t::STATE_FAILSAFE)
    s << " (" << reason_name(st.failsafe_reason) << ")";
  if (st.spooling_up) s << ", spooling up " << fixed(100.0 * st.spool_up, 0) << " %";
  if (st.motor_test_state == mixer_status_t::MOTOR_TEST_RUNNING) {
    s << ", motor test, motor " << motor_name(o, st.motor_test_motor - 1) << " at "
      << fixed(st.motor_test_throttle, 2);
  }
  s << "    config " << hash << "    status " << fixed(snap.status_age_s * 1e3, 0) << " ms ago\n";
  s << "inputs    setpoint " << age(st.input_age_ms[0]) << (st.setpoint_stale ? " STALE" : "")
    << "   pid " << age(st.input_age_ms[1]) << (st.pid_stale ? " STALE" : "") << "   motor_status "
    << age(st.input_age_ms[3]) << "   battery " << age(st.input_age_ms[2]) << "\n";
  // What failure detection and the spin landing read, and how fresh: on but
  // never fed, they can find nothing and land nothing.
  if (st.detector_sources != 0 || st.motor_loss_on) {
    const bool telemetry = (st.detector_sources & mixer_status_t::DETECTOR_TELEMETRY) != 0;
    const bool rates = (st.detector_sources & mixer_status_t::DETECTOR_RATES) != 0;
    const bool outputs = (st.detector_sources & mixer_status_t::DETECTOR_OUTPUTS) != 0;
    const std::string sources = std::string(telemetry ? " telemetry" : "") +
                                (rates ? " rates" : "") + (outputs ? " outputs" : "");
    s << "feeds     detection" << (sources.empty() ? " off" : sources) << "   spin landing "
      << (st.motor_loss_on ? "on" : "off");
    if (telemetry) {
      s << "   esc_telemetry " << age(st.esc_telemetry_age_ms)
        << (st.esc_telemetry_age_ms < 0.0F ? " NOT FED" : "");
    }
    if (rates || st.motor_loss_on) {
      s << "   attitude " << age(st.attitude_age_ms)
        << (st.attitude_age_ms < 0.0F ? " NOT FED" : "");
    }
    s << "\n";
  }
  s << "battery   " << battery_name(st.battery_state);
  if (st.battery_state != mixer_status_t::BATTERY_OFF) {
    s << ", " << fixed(st.battery_voltage, 2) << " V, thrust x" << fixed(st.thrust_gain, 3);
  }
  s << "\n";
  s << "failures  ";
  if (st.failed_motors == 0) {
    s << "none";
  } else {
    for (int i = 0; i < st.num_motors && i < 32; ++i) {
      if ((st.failed_motors >> i) & 1) s << motor_name(o, i) << " ";
    }
    s << "failed: " << failure_name(st.failure_handling) << "; held:";
    bool any = false;
    for (int a = 0; a < 4; ++a) {
      if (st.axis_held[a]) s << " " << kAxes[a], any = true;
    }
    if (!any) s << " none";
  }
  // motormix's own failure detector, when it has something to say.
  if (st.detected_motors != 0 || st.telemetry_silent != 0) {
    s << "\ndetector  ";
    if (st.detected_motor > 0) {
      s << motor_name(o, st.detected_motor - 1) << " declared failed by "
        << to_string(static_cast<DetectionSource>(st.detected_by));
    }
    if (st.telemetry_silent != 0) {
      s << (st.detected_motor > 0 ? "; " : "") << "telemetry silent:";
      for (int i = 0; i < st.num_motors && i < 32; ++i) {
        if ((st.telemetry_silent >> i) & 1) s << " " << motor_name(o, i);
      }
    }
  }
  // The spin landing, while it has something to say.
  if (st.landing_state != mixer_status_t::LANDING_OFF) {
    s << "\nlanding   ";
    const std::string motor = st.landing_motor > 0 ? motor_name(o, st.landing_motor - 1) : "?";
    switch (st.landing_state) {
      case mixer_status_t::LANDING_DESCENDING:
        s << "spinning down without " << motor << ": " << fixed(st.spin_rate, 1)
          << " rad/s, spin axis " << fixed(st.spin_axis_error_deg, 1) << " deg off";
        break;
      case mixer_status_t::LANDING_LANDED:
        s << "landed without " << motor << ", disarmed";
        break;
      default:
        s << motor << " failed, no fresh attitude: no spin landing";
        break;
    }
  }
  s << "\nauthority";
  for (int a = 0; a < 4; ++a) s << "  " << kAxes[a] << " " << fixed(st.authority[a], 2);
  s << "\n\n";

  const bool have_pwm = snap.pwm && snap.pwm->num_motors == st.num_motors;
  bool bipolar = false;
  if (have_pwm) {
    for (float c : snap.pwm->command) bipolar = bipolar || c < 0.0F;
  }
  s << "motor     command" << std::string(static_cast<std::size_t>(std::max(0, bar_width - 5)), ' ')
    << "output\n";
  for (int i = 0; i < st.num_motors; ++i) {
    const auto k = static_cast<std::size_t>(i);
    std::string name = motor_name(o, i);
    name.resize(std::max<std::size_t>(name.size(), 8), ' ');
    s << "  " << name;
    const bool failed = (st.failed_motors >> i) & 1;
    if (have_pwm) {
      s << bar(snap.pwm->command[k], bipolar, bar_width) << " " << fixed(snap.pwm->pwm[k], 1) << " "
        << o.output_unit;
    } else {
      s << "[" << std::string(static_cast<std::size_t>(bar_width), ' ') << "] (no outputs seen)";
    }
    if (failed) s << "  FAILED";
    if ((st.saturated_upper >> i) & 1) s << "  SAT-HIGH";
    if ((st.saturated_lower >> i) & 1) s << "  SAT-LOW";
    s << "\n";
  }
  if (have_pwm && !snap.pwm->armed) s << "  (outputs disarmed)\n";
  s << "\nunallocated";
  for (int a = 0; a < 4; ++a) {
    s << "  " << kAxes[a] << " " << (st.unallocated[a] >= 0 ? "+" : "")
      << fixed(st.unallocated[a], 3) << (st.axis_limited[a] ? "!" : "");
  }
  s << "   (! = not fully delivered)\n";
  s << "loop      period us min/mean/max/p99 " << fixed(st.period_us[0], 0) << "/"
    << fixed(st.period_us[1], 0) << "/" << fixed(st.period_us[2], 0) << "/"
    << fixed(st.period_us[3], 0) << "   compute us mean/p99 " << fixed(st.compute_us[1], 1) << "/"
    << fixed(st.compute_us[3], 1) << "   overruns " << st.overruns << "   cycles " << st.cycles
    << "\n";
  s << "wake-up   late us mean/p99/max " << fixed(st.wake_latency_us[1], 1) << "/"
    << fixed(st.wake_latency_us[3], 0) << "/" << fixed(st.wake_latency_us[2], 0)
    << "   kernel drops "
    << (st.kernel_drops < 0 ? std::string("unknown") : std::to_string(st.kernel_drops)) << "\n";
  s << "accepted  setpoint " << st.setpoint_received << "   pid " << st.pid_received
    << "   motor_status " << st.motor_status_received << "   battery " << st.battery_received;
  if (st.esc_telemetry_received > 0 || st.attitude_received > 0) {
    s << "   esc_telemetry " << st.esc_telemetry_received << "   attitude " << st.attitude_received;
  }
  s << "\n";
  if (snap.refused.refused() > 0) {
    const bus::Refusals& r = snap.refused;
    s << "monitor   " << bus::describe(r) << " here\n";
  }
  // The mixer's refusals under the bus's names (bus::Refusal), then the
  // loop's: the words of its log and of docs/troubleshooting.md.
  s << "refused   truncated " << st.rejected_truncated << "   trailing bytes "
    << st.rejected_trailing << "   wrong type " << st.rejected_wrong_type << "   bad length "
    << st.rejected_bad_length << "   undecodable " << st.rejected_undecodable << "\n";
  s << "rejected  non-finite " << st.rejected_nonfinite << "   range " << st.rejected_range
    << "   order " << st.rejected_stale_order << "   future " << st.rejected_future
    << "   array size " << st.rejected_size << "\n";
  if (st.security_mode != mixer_status_t::SECURITY_OFF) {
    s << "signed    " << (st.security_mode == mixer_status_t::SECURITY_REQUIRE ? "require" : "sign")
      << "   verified " << st.signed_received << "   unsigned taken " << st.unsigned_received
      << "   refused: unsigned " << st.rejected_unsigned << "   bad signature "
      << st.rejected_bad_signature << "   replayed " << st.rejected_replayed << "   stale "
      << st.rejected_stale_signature << "\n";
  }
  s << "events    failsafe " << st.failsafe_events << "   arming refused " << st.arming_refused
    << " (throttle " << st.arming_refused_throttle << ", not disarmed first "
    << st.arming_refused_not_disarmed_first << ")   motor tests " << st.motor_tests_started
    << " (refused " << st.motor_tests_refused << ")\n";
  // Why the latest armed request did not arm, until the mixer arms: the
  // run log's words (loop::Arming).
  if (st.arming_refusal == mixer_status_t::ARMING_REFUSAL_THROTTLE) {
    s << "ARMING REFUSED: throttle above inputs.arm_max_throttle: lower it, then ask again\n";
  } else if (st.arming_refusal == mixer_status_t::ARMING_REFUSAL_NOT_DISARMED_FIRST) {
    s << "ARMING REFUSED: no setpoint with armed false came first: send armed false, then true\n";
  }
  s << output_lines(snap, o);
  return s.str();
}

bool monitor_shows(const output_status_t& status) {
  return status.num_motors >= 1 && status.num_motors <= kMaxMotors;
}

bool monitor_shows(const mixer_status_t& status) {
  return status.num_motors >= 1 && status.num_motors <= kMaxMotors;
}

namespace {

class Listener {
 public:
  explicit Listener(signing::Policy* policy) : policy_(policy) {}
  // Nothing thrown out of either callback (bus::receive); a message refused
  // is counted by reason and leaves the last good one on the screen.
  void on_status(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    if (bus::receive(*policy_, rbuf, channel, bus::wall_us(), status_msg_, refused_) !=
        bus::Refusal::kNone)
      return;
    if (!monitor_shows(status_msg_)) {
      refused_.refuse_taken(bus::Refusal::kBadLength);
      return;
    }
    status = status_msg_;
    status_at = Clock::now();
  }
  void on_output(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    if (bus::receive(*policy_, rbuf, channel, bus::wall_us(), output_msg_, refused_) !=
        bus::Refusal::kNone)
      return;
    if (!monitor_shows(output_msg_)) {
      refused_.refuse_taken(bus::Refusal::kBadLength);
      return;
    }
    output = output_msg_;
    output_at = Clock::now();
  }
  void on_pwm(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    if (bus::receive(*policy_, rbuf, channel, bus::wall_us(), pwm_msg_, refused_) !=
        bus::Refusal::kNone)
      return;
    pwm = pwm_msg_;
    pwm_at = Clock::now();
  }
  MonitorSnapshot snapshot() const {
    MonitorSnapshot s;
    s.status = status;
    s.pwm = pwm;
    const auto now = Clock::now();
    s.status_age_s = std::chrono::duration<double>(now - status_at).count();
    s.pwm_age_s = std::chrono::duration<double>(now - pwm_at).count();
    s.output = output;
    s.output_age_s = std::chrono::duration<double>(now - output_at).count();
    s.refused = refused_;
    return s;
  }

  std::optional<mixer_status_t> status;
  std::optional<motor_pwm_t> pwm;
  std::optional<output_status_t> output;
  Clock::time_point status_at;
  Clock::time_point output_at;
  Clock::time_point pwm_at;

 private:
  signing::Policy* policy_;
  mixer_status_t status_msg_{};
  motor_pwm_t pwm_msg_{};
  output_status_t output_msg_{};
  bus::Refusals refused_;
};

}  // namespace

int run_monitor(const MonitorOptions& o, std::ostream& out, std::ostream& log) {
  bus::Process process("motormix monitor", o.lcm_url, log);
  if (!process.good()) return 1;
  lcm::LCM& lcm = process.lcm();
  signing::Policy off;  // no key: a trailer is cut off unread
  Listener listener(o.policy ? o.policy.get() : &off);
  lcm.subscribe(o.status_channel, &Listener::on_status, &listener);
  lcm.subscribe(o.pwm_channel, &Listener::on_pwm, &listener);
  lcm.subscribe(o.output_status_channel, &Listener::on_output, &listener);

  const auto start = Clock::now();
  const auto refresh = std::chrono::duration<double>(1.0 / o.refresh_hz);
  auto next_draw = start;
  int rc = 0;
  while (true) {
    const auto now = Clock::now();
    const double elapsed = std::chrono::duration<double>(now - start).count();
    if (!listener.status && elapsed > o.wait_s) {
      log << "motormix monitor: no mixer_status on channel '" << o.status_channel << "' within "
          << o.wait_s << " s (lcm url " << (o.lcm_url.empty() ? "default" : o.lcm_url)
          << "): is motormix run running on this bus, with these channels?\n";
      rc = 1;
      break;
    }
    if (o.once && listener.status && (listener.pwm || elapsed > o.wait_s)) {
      out << render_monitor(listener.snapshot(), o) << std::flush;
      break;
    }
    if (!o.once && listener.status && now >= next_draw) {
      out << "\x1b[H\x1b[2J" << render_monitor(listener.snapshot(), o) << std::flush;
      next_draw = now + std::chrono::duration_cast<Clock::duration>(refresh);
    }
    if (!o.once && o.duration_s > 0.0 && elapsed >= o.duration_s) break;
    constexpr std::int64_t kRedrawLookNs = 20'000'000;
    if (process.wait_and_drain_ns(kRedrawLookNs).signal) break;
  }
  return rc;
}

}  // namespace motormix::bringup
