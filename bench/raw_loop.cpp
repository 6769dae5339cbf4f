// The floor for `motormix run`'s loop: a bare process that ticks a timerfd
// at a fixed rate, drains LCM (subscribed to the same input channels) and
// publishes one message of motor_pwm_t's size per tick, nothing else. It
// stops by itself after `cycles` ticks and prints its own period statistics
// (p50, p99, max in microseconds), overruns and the CPU time it used.
//
//   raw_loop RATE_HZ CYCLES

#include <motormix/motor_pwm_t.hpp>

#include <lcm/lcm-cpp.hpp>

#include <poll.h>
#include <sys/resource.h>
#include <sys/timerfd.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <vector>

namespace {
std::int64_t monotonic_us() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000 + ts.tv_nsec / 1000;
}
class Ignore {
 public:
  void on(const lcm::ReceiveBuffer*, const std::string&) {}
};
}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: raw_loop RATE_HZ CYCLES\n");
    return 2;
  }
  const double rate = std::atof(argv[1]);
  const long cycles = std::atol(argv[2]);
  lcm::LCM lcm;
  if (!lcm.good()) return 1;
  Ignore sink;
  lcm.subscribe("SETPOINT", &Ignore::on, &sink);
  lcm.subscribe("PID", &Ignore::on, &sink);
  motormix::motor_pwm_t msg{};
  msg.num_motors = 4;
  msg.command.assign(4, 0.0F);
  msg.pwm.assign(4, 1000.0F);
  msg.direction.assign(4, 0);
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(msg.getEncodedSize()));
  const int timer = timerfd_create(CLOCK_MONOTONIC, TFD_CLOEXEC);
  const auto period_ns = static_cast<long long>(std::llround(1e9 / rate));
  itimerspec spec{};
  spec.it_interval.tv_sec = static_cast<time_t>(period_ns / 1'000'000'000);
  spec.it_interval.tv_nsec = static_cast<long>(period_ns % 1'000'000'000);
  spec.it_value = spec.it_interval;
  timerfd_settime(timer, 0, &spec, nullptr);
  pollfd fds[2] = {{lcm.getFileno(), POLLIN, 0}, {timer, POLLIN, 0}};
  std::vector<double> periods;
  periods.reserve(static_cast<std::size_t>(cycles));
  long overruns = 0;
  std::int64_t last = 0;
  for (long k = 0; k < cycles;) {
    if (poll(fds, 2, -1) < 0) continue;
    if (fds[0].revents & POLLIN) {
      for (int i = 0; i < 1000 && lcm.handleTimeout(0) > 0; ++i) {
      }
    }
    if (fds[1].revents & POLLIN) {
      std::uint64_t expirations = 0;
      if (read(timer, &expirations, sizeof expirations) != sizeof expirations) continue;
      overruns += static_cast<long>(expirations - 1);
      const std::int64_t now = monotonic_us();
      if (last != 0) periods.push_back(static_cast<double>(now - last));
      last = now;
      msg.utime = now;
      const int len = msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
      lcm.publish("RAW_PWM", buf.data(), static_cast<unsigned>(len));
      ++k;
    }
  }
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  const double cpu_s = static_cast<double>(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
                       static_cast<double>(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec) / 1e6;
  std::sort(periods.begin(), periods.end());
  const auto at = [&](double p) {
    return periods.empty()
               ? 0.0
               : periods[static_cast<std::size_t>(p * static_cast<double>(periods.size() - 1))];
  };
  std::printf(
      "raw_loop rate %.0f Hz cycles %ld cpu_s %.3f period_us p50 %.1f p99 %.1f max %.1f overruns "
      "%ld\n",
      rate, cycles, cpu_s, at(0.5), at(0.99), periods.empty() ? 0.0 : periods.back(), overruns);
  close(timer);
  return 0;
}
