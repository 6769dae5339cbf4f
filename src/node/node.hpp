#pragma once
// The node of `motormix run`: its subscriptions, each input verified,
// decoded and handed to the control loop, one cycle's logging and
// publishing. The loops that drive it (the timer's, or a simulator's
// lockstep ticks) are lcm_node.cpp's. One thread; no exception leaves an
// LCM callback.

#include "bus/clock.hpp"
#include "bus/process.hpp"
#include "bus/receive.hpp"
#include "bus/sealed_publisher.hpp"
#include "latency_histogram.hpp"
#include "loop/control_loop.hpp"
#include "messages/input_reader.hpp"
#include "messages/messages.hpp"
#include "node/run_log.hpp"
#include "realtime/realtime.hpp"
#include "socket_drops.hpp"
#include "window_stats.hpp"

#include <motormix/config/build_mixer.hpp>
#include <motormix/config/config.hpp>
#include <motormix/lockstep_t.hpp>
#include <motormix/mixer_status_t.hpp>
#include <motormix/motor_pwm_t.hpp>
#include <motormix/motor_status_t.hpp>
#include <motormix/signing_policy.hpp>

#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <ostream>
#include <string>
#include <utility>

namespace motormix::node {

// The node's time: the machine's clocks, or in lockstep the simulator's
// (both "monotonic" and "wall" are then the tick's utime).
struct NodeClock {
  bool lockstep = false;
  std::int64_t sim_us = 0;  // the last tick taken
  std::int64_t mono() const { return lockstep ? sim_us : bus::monotonic_us(); }
  std::int64_t wall() const { return lockstep ? sim_us : bus::wall_us(); }
};

class Node {
 public:
  Node(const config::Config& config, signing::Policy policy, lcm::LCM& lcm,
       const SocketDropsWatcher& drops, std::ostream& log)
      : config_(config),
        policy_(std::move(policy)),
        drops_(drops),
        lcm_(lcm),
        publisher_(lcm, policy_),
        log_(log),
        loop_(config, config::build_mixer(config)),
        routes_(config),
        period_stats_(window_capacity(config)),
        compute_stats_(window_capacity(config)),
        wake_stats_(window_capacity(config)) {
    const int n = config.motors();
    // One buffer, with room for the largest message and a signature.
    messages::size_pwm_message(pwm_msg_, n);
    status_msg_.num_motors = n;
    messages::fill_motor_status_message(motor_status_msg_, 0, n, 0);
    for (const int size : {pwm_msg_.getEncodedSize(), status_msg_.getEncodedSize(),
                           motor_status_msg_.getEncodedSize()})
      publisher_.reserve(static_cast<std::size_t>(size));
  }
  const loop::ControlLoop& loop() const { return loop_; }

  void subscribe() {
    for (const auto& [channel, kind] : routes_.channels())
      lcm_.subscribe(channel, &Node::on_input, this)->setQueueCapacity(bus::kQueueCapacity);
  }

  void drain() {
    for (int i = 0; i < bus::kMaxMessagesPerDrain; ++i) {
      // In lockstep a tick ends the drain: what comes after it belongs to
      // the next cycle.
      if (tick_pending_ || lcm_.handleTimeout(0) <= 0) break;
    }
    drained_us_ = clock_.mono();
  }

  // Lockstep (docs/lockstep.md): cycles come from a simulator's lockstep_t
  // on channels.lockstep, not from the timer, and every time the node
  // reads (input ages, stamps, rates) is the simulated one.
  void use_lockstep() {
    clock_.lockstep = true;
    lcm_.subscribe(config_.channels.lockstep, &Node::on_lockstep, this)
        ->setQueueCapacity(bus::kQueueCapacity);
  }
  // The tick to cycle at, once (false: none pending).
  bool take_tick(std::int64_t& utime) {
    if (!tick_pending_) return false;
    tick_pending_ = false;
    utime = clock_.sim_us;
    return true;
  }
  std::int64_t lockstep_refused() const { return lockstep_refused_; }

  // One control cycle; `woke_us` is when the loop woke up for it.
  void cycle(std::int64_t now_us, std::int64_t woke_us) {
    if (last_cycle_us_ > 0) {
      const auto period = static_cast<double>(now_us - last_cycle_us_);
      period_stats_.add(period);
      period_run_.add(period, now_us);
    }
    last_cycle_us_ = now_us;
    const loop::CycleResult& r = loop_.cycle(now_us);
    if (r.arming_refused != loop::Arming::Refusal::kNone)
      log_ << "motormix: arming refused: " << loop::Arming::to_string(r.arming_refused)
           << std::endl;
    if (r.state_changed) {
      log_ << "motormix: " << to_string(r.state);
      if (r.state == loop::LoopState::kFailsafe) log_ << " (" << to_string(r.reason) << ")";
      log_ << std::endl;
    }
    if (r.detection_changed && r.detection.failed != 0) {
      log_ << "motormix: detected motor "
           << config_.motor_names()[static_cast<std::size_t>(r.detection.motor)] << " failed ("
           << to_string(r.detection.source) << ")" << std::endl;
    }
    if (r.landing_changed) log_landing(log_, config_, r);
    if (r.failed != logged_failed_) {
      log_failures(log_, config_, r);
      logged_failed_ = r.failed;
    }
    // What the detector found goes out on motor_status at once, then at
    // the status rate while it stands (a late listener learns it too), and
    // once more when disarming clears it.
    const bool detected_due =
        r.detection.failed != 0 && (status_every_cycle_ || now_us >= next_status_us_);
    if (r.detection_changed || detected_due) publish_motor_status(r);
    if (motor_test_answer_due_ && r.motor_test_result != loop::MotorTestResult::kOk) {
      log_ << "motormix: motor test refused: " << to_string(r.motor_test_result) << std::endl;
    }
    if (r.motor_test_changed) {
      if (r.motor_test >= 0) {
        log_ << "motormix: motor test, motor "
             << config_.motor_names()[static_cast<std::size_t>(r.motor_test)] << " at "
             << r.motor_test_throttle << std::endl;
      } else {
        log_ << "motormix: motor test ended" << std::endl;
      }
    }
    const bool answer = motor_test_answer_due_ || r.motor_test_changed;
    motor_test_answer_due_ = false;
    const bool status_due = status_every_cycle_ || now_us >= next_status_us_ || answer;
    // On the timer the outputs go first (the status can wait a few
    // microseconds, the motors not). In lockstep motor_pwm_t is the
    // cycle's last message: a simulator that has it has everything of the
    // tick (one sender's messages arrive in order), whenever it looks.
    if (clock_.lockstep && status_due) publish_status(r);
    publish_pwm(r);
    compute_stats_.add(static_cast<double>(bus::monotonic_us() - woke_us));
    if (!clock_.lockstep && status_due) publish_status(r);
    if (status_due) {
      next_status_us_ = now_us + static_cast<std::int64_t>(1e6 / config_.status_rate_hz);
      warn_about_rejections(now_us);
    }
  }

  // At most one line per second, and only when something was rejected: a
  // flood of bad input cannot flood the log.
  void warn_about_rejections(std::int64_t now_us) {
    const loop::Counters& c = loop_.counters();
    const bus::Refusals& bus_refused = reader_.refusals();
    const std::int64_t total = c.rejected() + static_cast<std::int64_t>(bus_refused.refused());
    if (total == warned_total_ || now_us - last_warning_us_ < 1'000'000) return;
    // The names are the status' and the monitor's (docs/troubleshooting.md).
    log_ << "motormix: warning: " << total - warned_total_
         << " input messages rejected since the last warning (totals: on the bus "
         << bus::describe(bus_refused) << "; by the loop: non-finite " << c.rejected_nonfinite
         << ", out of range " << c.rejected_range << ", out of order " << c.rejected_out_of_order
         << ", from the future " << c.rejected_future << ", array size " << c.rejected_size;
    if (c.rejected_size > 0) log_ << " (the last on " << last_wrong_size_channel_ << ")";
    if (policy_.signs()) {
      const signing::PolicyCounts& sc = policy_.counts();
      log_ << "; signatures: unsigned " << sc.rejected_unsigned << ", bad signature "
           << sc.rejected_bad_signature << ", replayed " << sc.rejected_replayed
           << ", stale signature " << sc.rejected_stale + sc.rejected_other;
    }
    log_ << ")" << std::endl;
    warned_total_ = total;
    last_warning_us_ = now_us;
  }

  void add_overruns(std::uint64_t missed) { overruns_ += static_cast<std::int64_t>(missed); }
  // How late the loop woke for a timer tick: actual minus scheduled.
  void add_wake_latency(double late_us, std::int64_t at_us) {
    wake_stats_.add(late_us);
    wake_run_.add(late_us, at_us);
  }

  // The whole run's loop timing as JSON (`motormix run --timing-report`).
  void write_timing_report(std::ostream& out, const realtime::RealtimeGranted& granted,
                           std::int64_t ticks) const {
    const auto section = [](const LatencyHistogram& h) {
      return nlohmann::json{{"count", h.count()},
                            {"min", h.min()},
                            {"mean", h.mean()},
                            {"p50", h.percentile(0.5)},
                            {"p99", h.percentile(0.99)},
                            {"p999", h.percentile(0.999)},
                            {"max", h.max()},
                            {"max_at_monotonic_us", h.max_at_us()}};
    };
    nlohmann::json j;
    j["loop_rate_hz"] = config_.loop_rate_hz;
    j["timer_ticks"] = ticks;
    j["overruns"] = overruns_;
    j["kernel_drops"] = own_udp_socket_drops();
    j["realtime"] = {{"policy", granted.policy},
                     {"priority", granted.priority},
                     {"cpus", granted.cpus},
                     {"memory_locked", granted.memory_locked},
                     {"stack_prefaulted", granted.stack_prefaulted},
                     {"other_threads_moved", granted.other_threads},
                     {"other_cpus", granted.other_cpus}};
    j["wake_latency_us"] = section(wake_run_);
    j["period_us"] = section(period_run_);
    j["units"] = "microseconds; percentiles rounded up to the microsecond";
    out << j.dump(2) << "\n";
  }

  // publish: on_input: a pid message accepted since the last cycle.
  bool take_new_pid() {
    const bool fresh = new_pid_;
    new_pid_ = false;
    return fresh;
  }

  // Final word on shutdown: every output at its disarmed value.
  void publish_disarmed() {
    loop::CycleResult r = loop_.last();
    loop_.mixer().disarm(r.mix);
    r.state = loop::LoopState::kDisarmed;
    publish_pwm(r);
    publish_status(r);
  }

 private:
  // When a message arrived, on the monotonic clock. A message can wait in the
  // socket while this process is frozen (SIGSTOP, a debugger, a starved
  // CPU): it is as old as the kernel's receive time (LCM's recv_utime, wall
  // clock) says, not as fresh as the moment it is handled. The wait counted
  // is at most the time since the previous drain, so a step of the wall clock
  // (NTP) cannot age a message that cannot have waited.
  std::int64_t received_us(const lcm::ReceiveBuffer* rbuf, std::int64_t now_us,
                           std::int64_t wall_now_us) const {
    const std::int64_t waited = std::clamp<std::int64_t>(
        wall_now_us - rbuf->recv_utime, 0, std::max<std::int64_t>(0, now_us - drained_us_));
    return now_us - waited;
  }

  // No exception may leave an LCM callback: messages::InputReader (bus::receive)
  // reports a refusal as a value, counted by its reason, and nothing else
  // here throws. The signing policy comes first: a message it refuses
  // (unsigned under `require`, a bad signature, a replay) is never decoded.
  //
  // Every input channel's callback: routed by the one table the replay
  // uses too (messages::InputRoutes).
  void on_input(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    const std::optional<messages::InputKind> kind = routes_.kind(channel);
    if (!kind || rbuf == nullptr) return;
    const std::int64_t wall = clock_.wall();
    // A request refused on the bus (unsigned under `require`, malformed) is
    // not answered: only its sender could take the answer for its own.
    if (reader_.read(*kind, policy_, channel, rbuf->data, rbuf->data_size, wall, sample_) !=
        bus::Refusal::kNone)
      return;
    // Our own motor_status comes back to us over the bus: it is what the
    // detector already holds, and taken as a report it would outlive the
    // disarming that clears the detector's declarations.
    if (const auto* status = std::get_if<loop::MotorStatusSample>(&sample_);
        status != nullptr && std::find(own_status_utimes_.begin(), own_status_utimes_.end(),
                                       status->utime) != own_status_utimes_.end()) {
      return;
    }
    const std::int64_t wrong_sizes = loop_.counters().rejected_size;
    const std::int64_t now =
        clock_.lockstep ? clock_.sim_us : received_us(rbuf, clock_.mono(), wall);
    const bool taken = messages::hand_over(loop_, sample_, now, wall);
    if (loop_.counters().rejected_size != wrong_sizes) last_wrong_size_channel_ = channel;
    if (*kind == messages::InputKind::kPid && taken) new_pid_ = true;
    // Answered by the next status, whatever the status rate.
    if (*kind == messages::InputKind::kMotorTest) motor_test_answer_due_ = true;
  }

  // A tick: verified as any input, then taken only if later than the last
  // (a repeated or older one, a second simulator, is counted and dropped).
  void on_lockstep(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    if (bus::receive(policy_, rbuf, channel, clock_.wall(), tick_, lockstep_refusals_) !=
            bus::Refusal::kNone ||
        tick_.utime <= clock_.sim_us) {
      ++lockstep_refused_;
      return;
    }
    clock_.sim_us = tick_.utime;
    tick_pending_ = true;
  }

  void publish_pwm(const loop::CycleResult& r) {
    // In lockstep its utime is the tick's: the simulator waits for it.
    messages::fill_pwm_message(pwm_msg_, r, clock_.wall());
    publisher_.publish(config_.channels.motor_pwm, pwm_msg_);
  }

  void publish_motor_status(const loop::CycleResult& r) {
    // A utime of ours never repeats, so the echo filter cannot swallow
    // another publisher's message for long.
    std::int64_t utime = clock_.wall();
    if (utime <= last_own_status_utime_) utime = last_own_status_utime_ + 1;
    last_own_status_utime_ = utime;
    messages::fill_motor_status_message(motor_status_msg_, r.failed, config_.motors(), utime);
    own_status_utimes_[own_status_next_++ % own_status_utimes_.size()] = utime;
    publisher_.publish(config_.channels.motor_status, motor_status_msg_);
  }

  void publish_status(const loop::CycleResult& r) {
    messages::LoopTiming timing;
    timing.period_us = period_stats_.take();
    timing.compute_us = compute_stats_.take();
    timing.wake_latency_us = wake_stats_.take();
    timing.overruns = overruns_;
    timing.kernel_drops = drops_.latest();
    timing.wall_minus_loop_clock_us = clock_.wall() - clock_.mono();
    messages::fill_status_message(
        status_msg_, r, loop_.counters(), timing, config_.hash, config_.motors(), clock_.wall(),
        messages::InputAccounting{policy_.mode(), policy_.counts(), reader_.refusals()});
    publisher_.publish(config_.channels.status, status_msg_);
  }

  const config::Config& config_;
  signing::Policy policy_;
  const SocketDropsWatcher& drops_;
  lcm::LCM& lcm_;
  bus::SealedPublisher publisher_;  // signs with policy_ when it signs
  std::ostream& log_;
  loop::ControlLoop loop_;
  const messages::InputRoutes routes_;  // which input each subscribed channel carries
  messages::InputReader reader_;        // every input through bus::receive, refusals by reason
  messages::InputSample sample_;        // the latest input read (kept: no allocation per message)
  lockstep_t tick_{};
  bus::Refusals lockstep_refusals_;
  std::string last_wrong_size_channel_;  // named in the rejection warning
  motor_pwm_t pwm_msg_;
  mixer_status_t status_msg_;
  motor_status_t motor_status_msg_;
  // The utimes of the motor_status messages this process published lately.
  std::array<std::int64_t, 8> own_status_utimes_{};
  std::size_t own_status_next_ = 0;
  std::int64_t last_own_status_utime_ = 0;
  std::int64_t next_status_us_ = 0;
  // status_rate_hz equal to loop_rate_hz: a status after every cycle's
  // outputs, whatever the wake-ups' jitter (a due time, now + one period,
  // would skip the cycle after a late one). Tests and diagnostics pair each
  // cycle's outputs with its state and input ages this way.
  const bool status_every_cycle_ = config_.status_rate_hz >= config_.loop_rate_hz;
  std::int64_t last_cycle_us_ = 0;
  std::int64_t overruns_ = 0;
  std::int64_t warned_total_ = 0;
  std::int64_t last_warning_us_ = 0;
  NodeClock clock_;
  bool tick_pending_ = false;
  std::int64_t lockstep_refused_ = 0;
  std::int64_t drained_us_ = bus::monotonic_us();  // end of the previous drain, monotonic
  bool new_pid_ = false;
  bool motor_test_answer_due_ = false;
  MotorMask logged_failed_ = 0;
  WindowStats period_stats_;
  WindowStats compute_stats_;
  WindowStats wake_stats_;
  LatencyHistogram wake_run_;  // the whole run, for the timing report
  LatencyHistogram period_run_;

  static std::size_t window_capacity(const config::Config& c) {
    return static_cast<std::size_t>(c.loop_rate_hz / c.status_rate_hz) * 2 + 64;
  }
};

}  // namespace motormix::node
