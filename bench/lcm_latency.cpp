// End-to-end latency over LCM: a pid message goes out, the answer that names
// it comes back. Against motormix (`publish: on_input`) the answer is the
// motor_pwm_t whose pid_utime is the message's utime; against `echo` (this
// tool republishing raw bytes, the baseline) it is the message itself.
//
//   lcm_latency echo IN OUT
//   lcm_latency measure --target motormix|echo --count N --rate HZ
//
// Bounded: `measure` sends N messages and waits at most 100 ms for each; `echo`
// stops after 60 s or when it sees a message on STOP.

#include <motormix/motor_pwm_t.hpp>
#include <motormix/pid_t.hpp>
#include <motormix/setpoint_t.hpp>

#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

std::int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

struct Echo {
  lcm::LCM* lcm;
  std::string out;
  bool stop = false;
  void on_in(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    lcm->publish(out, rbuf->data, rbuf->data_size);
  }
  void on_stop(const lcm::ReceiveBuffer*, const std::string&) { stop = true; }
};

int echo(const std::string& in, const std::string& out) {
  lcm::LCM lcm;
  Echo e{&lcm, out};
  lcm.subscribe(in, &Echo::on_in, &e);
  lcm.subscribe("LATENCY_STOP", &Echo::on_stop, &e);
  const auto end = Clock::now() + std::chrono::seconds(60);
  while (!e.stop && Clock::now() < end) lcm.handleTimeout(100);
  return 0;
}

struct Waiter {
  bool motormix = false;
  std::int64_t want = 0;
  bool got = false;
  bool seen_any = false;
  void on_reply(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    seen_any = true;
    std::int64_t id = 0;
    if (motormix) {
      motormix::motor_pwm_t m{};
      if (m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0) return;
      id = m.pid_utime;
    } else {
      motormix::pid_t p{};
      if (p.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0) return;
      id = p.utime;
    }
    if (id == want) got = true;
  }
};

int measure(bool motormix, int count, double rate) {
  lcm::LCM lcm;
  Waiter w{motormix};
  lcm.subscribe(motormix ? "MOTOR_PWM" : "ECHO_OUT", &Waiter::on_reply, &w)
      ->setQueueCapacity(10000);
  const std::string pid_channel = motormix ? "PID" : "ECHO_IN";
  // Wait (bounded) until the mixer is up, then arm it (disarmed, then armed
  // at zero throttle), so the measured cycles mix for real.
  const auto up_by = Clock::now() + std::chrono::seconds(10);
  while (motormix && !w.seen_any && Clock::now() < up_by) lcm.handleTimeout(10);
  motormix::setpoint_t sp{};
  for (int k = 0; motormix && k < 2; ++k) {
    sp.utime = wall_us();
    sp.armed = k == 1;
    lcm.publish("SETPOINT", &sp);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));  // pacing, not synchronization
  }
  std::vector<double> latencies;
  int lost = 0;
  const auto period = std::chrono::microseconds(static_cast<int>(1e6 / rate));
  auto next = Clock::now();
  for (int k = 0; k < count; ++k) {
    if (motormix && k % 8 == 0) {  // keep the setpoint fresh (50 Hz at 400 Hz pid)
      sp.utime = wall_us();
      sp.armed = true;
      sp.throttle = 0.05F;
      lcm.publish("SETPOINT", &sp);
    }
    motormix::pid_t pid{};
    pid.utime = wall_us();
    pid.roll = 0.1F * static_cast<float>(k % 7) - 0.3F;
    w.want = pid.utime;
    w.got = false;
    const auto sent = Clock::now();
    lcm.publish(pid_channel, &pid);
    const auto deadline = sent + std::chrono::milliseconds(100);
    while (!w.got && Clock::now() < deadline) lcm.handleTimeout(1);
    if (w.got) {
      latencies.push_back(std::chrono::duration<double, std::micro>(Clock::now() - sent).count());
    } else {
      ++lost;
    }
    next += period;
    std::this_thread::sleep_until(next);
  }
  if (!motormix) lcm.publish("LATENCY_STOP", "", 0);
  std::sort(latencies.begin(), latencies.end());
  const auto pct = [&](double p) {
    return latencies.empty()
               ? 0.0
               : latencies[static_cast<std::size_t>(p * static_cast<double>(latencies.size() - 1))];
  };
  std::printf("%s: %zu replies, %d lost; latency us: median %.1f, p90 %.1f, p99 %.1f, max %.1f\n",
              motormix ? "motormix" : "raw LCM echo", latencies.size(), lost, pct(0.5), pct(0.9),
              pct(0.99), latencies.empty() ? 0.0 : latencies.back());
  return lost > count / 100 ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 4 && std::strcmp(argv[1], "echo") == 0) return echo(argv[2], argv[3]);
  if (argc >= 2 && std::strcmp(argv[1], "measure") == 0) {
    bool motormix = true;
    int count = 1000;
    double rate = 200;
    for (int i = 2; i + 1 < argc; i += 2) {
      const std::string key = argv[i];
      if (key == "--target") motormix = std::string(argv[i + 1]) == "motormix";
      if (key == "--count") count = std::max(1, std::atoi(argv[i + 1]));
      if (key == "--rate") rate = std::max(1.0, std::atof(argv[i + 1]));
    }
    return measure(motormix, count, rate);
  }
  std::fprintf(
      stderr,
      "usage: lcm_latency echo IN OUT | measure --target motormix|echo --count N --rate HZ\n");
  return 2;
}
