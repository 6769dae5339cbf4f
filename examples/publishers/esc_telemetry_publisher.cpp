// Publishes esc_telemetry_t for motormix's failure detector (source
// `telemetry`): what your ESC driver reads back (bidirectional DShot eRPM,
// BLHeli_32/AM32/KISS telemetry frames), one message per read-out.
//
// `motormix output` already publishes this from KISS telemetry wires
// (hardware.telemetry); this example is for ESCs read by something else.
// The driver here is a stand-in (four motors at a steady 9000 rpm); replace
// `read_escs()` with yours. Motors are numbered as `motormix matrix` numbers
// them (1-based); a message may carry any subset of them, so ESCs on
// separate buses or rates can publish separately. 100 Hz per ESC or more
// keeps detection under 100 ms.
//
//   esc_telemetry_publisher [--channel ESC_TELEMETRY] [--motors 4] [--rate-hz 200]
//                           [--count N] [--lcm-url URL]

#include "options.hpp"

#include <lcm/lcm-cpp.hpp>
#include <motormix/esc_telemetry_t.hpp>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <string>
#include <thread>
#include <vector>

namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

constexpr float kUnknown = std::numeric_limits<float>::quiet_NaN();

struct EscReading {
  int motor;        // 1-based, as motormix numbers the motors
  float rpm;        // mechanical; NaN if the ESC gives eRPM only
  float erpm;       // electrical (rpm times pole pairs); NaN if unknown
  float current_a;  // NaN if unknown (bidirectional DShot gives none)
  float voltage_v;
  float temperature_c;
};

// Stand-in driver: every motor at 9000 rpm, eRPM only as bidirectional
// DShot gives it (motormix divides by failure_detection.motor_poles / 2).
std::vector<EscReading> read_escs(int motors) {
  std::vector<EscReading> r;
  for (int m = 1; m <= motors; ++m)
    r.push_back({m, kUnknown, 9000.0F * 7.0F, kUnknown, 16.0F, 40.0F});
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  std::string channel = "ESC_TELEMETRY", url, rate = "200", how_many = "-1", motor_count = "4";
  const int done = parse_options(
      argc, argv,
      {{"--channel", &channel},
       {"--motors", &motor_count},
       {"--rate-hz", &rate},
       {"--count", &how_many},
       {"--lcm-url", &url}},
      "usage: esc_telemetry_publisher [--channel NAME] [--motors N] [--rate-hz HZ] [--count N]\n"
      "                               [--lcm-url URL]\n"
      "publishes esc_telemetry_t until Ctrl-C (or N messages); unsigned: for a configuration\n"
      "with security.mode require, sign as examples/signed_controller does\n");
  if (done >= 0) return done;
  const double rate_hz = std::atof(rate.c_str());
  const long count = std::atol(how_many.c_str());
  const int motors = std::atoi(motor_count.c_str());
  if (!(rate_hz > 0.0 && rate_hz <= 10000.0) || motors < 1 || motors > 16) {
    std::cerr << "--rate-hz: 0 < rate <= 10000; --motors: 1..16\n";
    return 2;
  }
  lcm::LCM bus(url);
  if (!bus.good()) {
    std::cerr << "cannot open the LCM bus\n";
    return 1;
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  const auto period = std::chrono::duration<double>(1.0 / rate_hz);
  auto next = std::chrono::steady_clock::now();
  for (long sent = 0; !g_stop && (count < 0 || sent < count); ++sent) {
    const std::vector<EscReading> readings = read_escs(motors);
    motormix::esc_telemetry_t msg{};
    msg.utime = std::chrono::duration_cast<std::chrono::microseconds>(
                    std::chrono::system_clock::now().time_since_epoch())
                    .count();
    msg.count = static_cast<std::int32_t>(readings.size());
    for (const EscReading& e : readings) {
      msg.motor.push_back(static_cast<std::int8_t>(e.motor));
      msg.rpm.push_back(e.rpm);
      msg.erpm.push_back(e.erpm);
      msg.current_a.push_back(e.current_a);
      msg.voltage_v.push_back(e.voltage_v);
      msg.temperature_c.push_back(e.temperature_c);
      msg.consumption_mah.push_back(kUnknown);
    }
    bus.publish(channel, &msg);
    next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    std::this_thread::sleep_until(next);
  }
  return 0;
}
