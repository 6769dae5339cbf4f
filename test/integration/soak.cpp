// Soak: one `motormix run` at a high loop rate for a long, bounded time with
// a changing input stream. Samples the mixer's RSS and its own loop-timing
// reports, and checks at the end: RSS flat after warm-up, no drift in jitter,
// counters consistent with what was sent. Prints a Markdown report.
// Not a ctest (it takes minutes): scripts/robustness runs it.
//   scripts/private-bus motormix_soak --motormix BIN --config FILE [--seconds 600] [--rate 1000]
//     [--timing-report FILE]   (passed to motormix run: its whole run's loop timing)

#include "integration/bus_recorder.hpp"
#include "integration/process.hpp"
#include "integration/udp_drops.hpp"

#include <motormix/pid_t.hpp>
#include <motormix/setpoint_t.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

namespace {

long rss_kb(::pid_t pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  }
  return -1;
}

std::int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// The typical value of a series of per-window figures (robust to the odd
// window in which the machine was busy with something else).
double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  std::string motormix, config, timing_report;
  double seconds = 600.0;
  int rate = 1000;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--motormix") motormix = argv[i + 1];
    if (a == "--config") config = argv[i + 1];
    if (a == "--seconds") seconds = std::atof(argv[i + 1]);
    if (a == "--rate") rate = std::atoi(argv[i + 1]);
    if (a == "--timing-report") timing_report = argv[i + 1];
  }
  const char* bus_flag = std::getenv("MOTORMIX_PRIVATE_BUS");
  if (motormix.empty() || config.empty() || !bus_flag || std::string(bus_flag) != "1" ||
      !(seconds > 0 && seconds <= 7200) || rate < 50 || rate > 10000) {
    std::fprintf(stderr,
                 "usage: scripts/private-bus motormix_soak --motormix BIN --config FILE "
                 "[--seconds 1..7200] [--rate 50..10000]\n");
    return 2;
  }
  const double status_hz = 10.0;
  motormix::test::BusRecorder bus("SOAK_PWM", "SOAK_STATUS", /*keep_pwm=*/false);
  std::vector<std::string> run = {motormix,   "run",
                                  "--config", config,
                                  "--set",    "loop_rate_hz=" + std::to_string(rate),
                                  "--set",    "status_rate_hz=10",
                                  "--set",    "channels.setpoint=SOAK_SETPOINT",
                                  "--set",    "channels.pid=SOAK_PID",
                                  "--set",    "channels.motor_pwm=SOAK_PWM",
                                  "--set",    "channels.status=SOAK_STATUS",
                                  "--set",    "inputs.arm_max_throttle=0.1"};
  if (!timing_report.empty()) {
    run.push_back("--timing-report");
    run.push_back(timing_report);
  }
  motormix::test::ChildProcess mixer(run);
  const auto started = Clock::now() + 10s;
  while (bus.pwm_count() == 0 && Clock::now() < started) std::this_thread::sleep_for(10ms);
  if (bus.pwm_count() == 0) {
    std::fprintf(stderr, "soak: motormix did not start\n");
    return 1;
  }

  lcm::LCM lcm;
  const long drops_before = motormix::test::udp_receive_buffer_drops();
  const auto start = Clock::now();
  const auto end = start + std::chrono::duration<double>(seconds);
  auto next = start;
  std::int64_t sent_setpoints = 0, sent_pids = 0;
  std::vector<std::pair<double, long>> rss;  // (t, kB)
  auto next_sample = start;
  for (std::int64_t k = 0; Clock::now() < end && k < 10'000'000; ++k) {
    const double t = std::chrono::duration<double>(Clock::now() - start).count();
    const std::int64_t now = wall_us();
    motormix::pid_t pid{};
    pid.utime = now;
    pid.roll = static_cast<float>(0.6 * std::sin(2.0 * t));  // a changing stream
    pid.pitch = static_cast<float>(0.4 * std::sin(3.1 * t + 1.0));
    pid.yaw = static_cast<float>(0.3 * std::sin(0.7 * t));
    lcm.publish("SOAK_PID", &pid);
    ++sent_pids;
    if (k % 10 == 0) {  // setpoints at a tenth of the rate: disarmed, armed, flying
      motormix::setpoint_t sp{};
      sp.utime = now;
      sp.armed = t > 0.5;
      sp.throttle = t > 1.0 ? static_cast<float>(0.5 + 0.3 * std::sin(0.5 * t)) : 0.0F;
      lcm.publish("SOAK_SETPOINT", &sp);
      ++sent_setpoints;
    }
    if (Clock::now() >= next_sample) {
      rss.emplace_back(t, rss_kb(mixer.pid()));
      next_sample += 5s;
    }
    next += std::chrono::microseconds(1'000'000 / rate);
    std::this_thread::sleep_until(next);
  }
  const double flown = std::chrono::duration<double>(Clock::now() - start).count();
  // Land: disarm before the inputs stop, so the end is not a failsafe.
  for (int k = 0; k < 20; ++k) {
    motormix::setpoint_t sp{};
    sp.utime = wall_us();
    motormix::pid_t pid{};
    pid.utime = sp.utime;
    lcm.publish("SOAK_SETPOINT", &sp);
    lcm.publish("SOAK_PID", &pid);
    ++sent_setpoints;
    ++sent_pids;
    std::this_thread::sleep_for(1ms);
  }
  bus.wait_until(
      [&](const auto&, const auto& s) {
        return !s.empty() &&
               s.back().pid_received + s.back().rejected_decode + s.back().rejected_stale_order >=
                   sent_pids;
      },
      3s);
  const auto status = bus.status();
  const long kernel_drops = motormix::test::udp_receive_buffer_drops() - drops_before;
  mixer.signal(SIGTERM);
  const auto exit_code = mixer.wait_for(10s);

  // Warm-up: the first minute (or tenth of the run).
  const double warm = std::min(60.0, 0.1 * flown);
  long rss_min = 1L << 40, rss_max = 0;
  for (const auto& [t, kb] : rss) {
    if (t < warm || kb < 0) continue;
    rss_min = std::min(rss_min, kb);
    rss_max = std::max(rss_max, kb);
  }
  // Jitter: the typical reported period p99 in the first and the last fifth.
  std::vector<double> first_p99, last_p99, all_max;
  const std::size_t n = status.size();
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / status_hz;
    if (t < warm) continue;
    if (i < n / 5 + static_cast<std::size_t>(warm * status_hz))
      first_p99.push_back(status[i].period_us[3]);
    if (i >= n - n / 5) last_p99.push_back(status[i].period_us[3]);
    all_max.push_back(status[i].period_us[2]);
  }
  const auto& last = status.back();
  // Every message sent is accepted, or was dropped by the kernel (a UDP
  // receive buffer overflowed while a process was not scheduled: counted in
  // the namespace, and reported). Nothing valid may be rejected.
  const std::int64_t unaccounted =
      (sent_pids - last.pid_received) + (sent_setpoints - last.setpoint_received);
  const bool counters_ok =
      last.pid_received <= sent_pids && last.setpoint_received <= sent_setpoints &&
      unaccounted <= kernel_drops && last.rejected_decode == 0 && last.rejected_nonfinite == 0 &&
      last.rejected_range == 0 && last.rejected_stale_order == 0 && last.rejected_future == 0;
  // A failsafe is right only if the loop really stalled for longer than the
  // input timeout (100 ms by default).
  const double worst_period_us =
      all_max.empty() ? 0.0 : *std::max_element(all_max.begin(), all_max.end());
  const bool failsafe_ok = last.failsafe_events == 0 || worst_period_us > 100'000.0;
  const double expected_cycles = flown * rate;
  const double cycles_share = static_cast<double>(last.cycles) / expected_cycles;
  const long rss_growth = rss_max - rss_min;
  const double drift = median(last_p99) - median(first_p99);
  const bool rss_ok = rss_growth <= 1024;
  const bool jitter_ok = drift <= 0.25 * 1e6 / rate;  // p99 no worse by a quarter period
  const bool exit_ok = exit_code && *exit_code == 0 && !bus.last_pwm().armed;

  std::printf("| soak: %d Hz for %.0f s | result |\n|---|---|\n", rate, flown);
  std::printf("| RSS after %.0f s warm-up | %ld..%ld kB (growth %ld kB, bound 1024) %s |\n", warm,
              rss_min, rss_max, rss_growth, rss_ok ? "ok" : "FAIL");
  std::printf(
      "| period p99 per 0.1 s, median of first / last fifth | %.1f / %.1f us (drift %.1f us, "
      "bound %.1f) %s |\n",
      median(first_p99), median(last_p99), drift, 0.25 * 1e6 / rate, jitter_ok ? "ok" : "FAIL");
  std::printf("| worst period seen | %.1f us (nominal %.1f) |\n", worst_period_us, 1e6 / rate);
  std::printf("| cycles | %lld of %.0f expected (%.2f %%), overruns %lld |\n",
              static_cast<long long>(last.cycles), expected_cycles, 100.0 * cycles_share,
              static_cast<long long>(last.overruns));
  std::printf(
      "| inputs | pid %lld of %lld sent, setpoint %lld of %lld; %lld not received, %ld datagrams "
      "dropped by the kernel (full UDP receive buffers), %lld of them on motormix's own sockets "
      "(its kernel_drops); rejected %lld %s |\n",
      static_cast<long long>(last.pid_received), static_cast<long long>(sent_pids),
      static_cast<long long>(last.setpoint_received), static_cast<long long>(sent_setpoints),
      static_cast<long long>(unaccounted), kernel_drops, static_cast<long long>(last.kernel_drops),
      static_cast<long long>(last.rejected_decode + last.rejected_range + last.rejected_nonfinite +
                             last.rejected_stale_order + last.rejected_future),
      counters_ok ? "ok" : "FAIL");
  std::printf("| failsafes | %lld%s %s |\n", static_cast<long long>(last.failsafe_events),
              last.failsafe_events ? " (the loop stalled longer than the input timeout)" : "",
              failsafe_ok ? "ok" : "FAIL");
  std::printf("| exit | %s |\n", exit_ok ? "SIGTERM: exit 0, last output disarmed, ok" : "FAIL");
  return rss_ok && jitter_ok && counters_ok && failsafe_ok && exit_ok ? 0 : 1;
}
