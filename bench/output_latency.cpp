// Bus to serial bytes: a motor_pwm_t goes out on LCM, the PULSES frame
// carrying it comes out of a pseudo-terminal's other end. Against
// `motormix output` (serial driver) and, as the baseline in the same run,
// against this tool's `relay` mode: a bare LCM subscriber that decodes the
// message and writes the same frame, with no gate, no clamping, no timer.
//
//   output_latency relay DEVICE                (the baseline process)
//   output_latency measure --motormix BIN --count N --rate HZ [--protocol P]
//
// --protocol (pwm, dshot150, dshot300, dshot600; default pwm) is what
// `motormix output` is configured with; the host's path, motor_pwm_t to a
// PULSES frame, is the same for each, which the run shows.
//
// Run inside a private bus (scripts/private-bus). Bounded: N messages, then
// the children are stopped.

#include "motormix_link.h"

#include <motormix/motor_pwm_t.hpp>

#include <lcm/lcm-cpp.hpp>

#include <fcntl.h>
#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "output/serial_port.hpp"

namespace {

std::int64_t now_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

struct Relay {
  int fd;
  std::uint32_t seq = 1;
  void on(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    motormix::motor_pwm_t m{};
    if (m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0 || m.num_motors < 1 ||
        m.num_motors > 8)
      return;
    mm_link_pulses p{};
    p.sequence = seq++;
    p.armed = static_cast<std::uint8_t>(m.armed ? (1u << m.num_motors) - 1u : 0u);
    p.count = static_cast<std::uint8_t>(m.num_motors);
    for (int i = 0; i < m.num_motors; ++i)
      p.pulse_hus[i] =
          static_cast<std::uint16_t>(std::lround(2.0 * m.pwm[static_cast<std::size_t>(i)]));
    std::uint8_t buf[MM_LINK_MAX_FRAME];
    [[maybe_unused]] const ssize_t w = ::write(fd, buf, mm_link_encode_pulses(&p, buf));
  }
};

int relay(const std::string& device) {
  Relay r{motormix::output::open_serial_port(device, 250000)};
  lcm::LCM lcm;
  lcm.subscribe("MOTOR_PWM", &Relay::on, &r);
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (std::chrono::steady_clock::now() < end) lcm.handleTimeout(100);
  return 0;
}

pid_t spawn(const std::vector<std::string>& argv) {
  const pid_t pid = fork();
  if (pid == 0) {
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    const int null = ::open("/dev/null", O_WRONLY);
    if (std::getenv("OUTPUT_LATENCY_VERBOSE") == nullptr) dup2(null, STDERR_FILENO);
    execv(args[0], args.data());
    _exit(127);
  }
  return pid;
}

double pct(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v.empty() ? NAN : v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

// One target: its process started on the pty's other end, N messages, the
// frames read back.
void measure_one(const char* name, const std::vector<std::string>& argv_without_device,
                 bool device_last, int count, double rate) {
  const int master = posix_openpt(O_RDWR | O_NOCTTY);
  grantpt(master);
  unlockpt(master);
  char slave[128];
  ptsname_r(master, slave, sizeof slave);
  std::vector<std::string> argv = argv_without_device;
  if (device_last) {
    argv.push_back(slave);
  } else {
    for (auto& a : argv) {
      const std::size_t at = a.find("@DEVICE@");
      if (at != std::string::npos) a.replace(at, 8, slave);
    }
  }
  const pid_t child = spawn(argv);
  std::this_thread::sleep_for(std::chrono::milliseconds(800));  // up and subscribed

  std::map<int, std::int64_t> sent;  // code -> when
  std::vector<double> latency;
  std::atomic<bool> stop{false};
  std::thread reader([&] {
    mm_link_parser parser;
    mm_link_parser_init(&parser);
    std::uint8_t buf[512];
    pollfd pfd{master, POLLIN, 0};
    // The chip's report every 50 ms names its session: motormix output
    // sends nothing before it has one (the bare relay does not care).
    auto next_report = std::chrono::steady_clock::now();
    while (!stop) {
      if (std::chrono::steady_clock::now() >= next_report) {
        mm_link_report r{};
        r.session = 0x10001;
        r.version = MM_LINK_VERSION;
        std::uint8_t out[MM_LINK_MAX_FRAME];
        [[maybe_unused]] const ssize_t w = ::write(master, out, mm_link_encode_report(&r, 0, out));
        next_report += std::chrono::milliseconds(50);
      }
      if (poll(&pfd, 1, 10) <= 0) continue;
      const ssize_t n = ::read(master, buf, sizeof buf);
      const std::int64_t t = now_us();
      for (ssize_t i = 0; i < n; ++i) {
        mm_link_frame f{};
        if (mm_link_feed(&parser, buf[i], &f) != MM_LINK_PULSES || !f.u.pulses.armed) continue;
        const int code = f.u.pulses.pulse_hus[0];
        auto it = sent.find(code);
        if (it != sent.end()) {
          latency.push_back(static_cast<double>(t - it->second));
          sent.erase(it);
        }
      }
    }
  });
  lcm::LCM lcm;
  const auto start = std::chrono::steady_clock::now();
  for (int k = 0; k < count; ++k) {
    motormix::motor_pwm_t m{};
    m.num_motors = 4;
    const float w0 = 1100.0f + static_cast<float>(k % 800);
    m.pwm = {w0, 1500, 1500, 1500};
    m.command.assign(4, 0.5f);
    m.direction.assign(4, 0);
    m.armed = true;
    std::this_thread::sleep_until(start +
                                  std::chrono::microseconds(static_cast<long>(1e6 / rate * k)));
    sent[static_cast<int>(std::lround(2.0 * w0))] = now_us();
    lcm.publish("MOTOR_PWM", &m);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  stop = true;
  reader.join();
  kill(child, SIGTERM);
  waitpid(child, nullptr, 0);
  ::close(master);
  std::printf(
      "%s: %zu of %d frames; bus to serial bytes us: median %.1f, p90 %.1f, p99 %.1f, max %.1f\n",
      name, latency.size(), count, pct(latency, 0.5), pct(latency, 0.9), pct(latency, 0.99),
      pct(latency, 1.0));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 3 && std::strcmp(argv[1], "relay") == 0) return relay(argv[2]);
  std::string motormix, self = argv[0];
  int count = 2000;
  double rate = 400;
  std::string protocol = "pwm";
  for (int i = 2; i + 1 < argc; i += 2) {
    if (std::strcmp(argv[i], "--protocol") == 0) protocol = argv[i + 1];
    if (std::strcmp(argv[i], "--motormix") == 0) motormix = argv[i + 1];
    if (std::strcmp(argv[i], "--count") == 0) count = std::atoi(argv[i + 1]);
    if (std::strcmp(argv[i], "--rate") == 0) rate = std::atof(argv[i + 1]);
  }
  if (argc < 2 || std::strcmp(argv[1], "measure") != 0 || motormix.empty() || count < 1 ||
      count > 100000 || rate <= 0 || rate > 2000 ||
      (protocol != "pwm" && protocol != "dshot150" && protocol != "dshot300" &&
       protocol != "dshot600")) {
    std::fprintf(stderr,
                 "usage: output_latency measure --motormix BIN [--count N] [--rate HZ] "
                 "[--protocol pwm|dshot150|dshot300|dshot600]\n"
                 "       output_latency relay DEVICE\n");
    return 2;
  }
  const std::string config = "/tmp/motormix-output-latency.yaml";
  std::ofstream(config) << "geometry: {preset: quad_x}\n"
                           "hardware: {driver: serial, serial: {device: /dev/null}, protocol: "
                        << protocol << "}\n";
  measure_one("bare relay (baseline)", {self, "relay"}, true, count, rate);
  measure_one(("motormix output, " + protocol).c_str(),
              {motormix, "output", "--config", config, "--set", "hardware.serial.device=@DEVICE@"},
              false, count, rate);
  std::remove(config.c_str());
  return 0;
}
