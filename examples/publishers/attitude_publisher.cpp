// Publishes attitude_t for motormix's failure detector (source `rates`) and
// the quad's spin landing: the estimator's attitude, body rates and velocity,
// stamped with the gyro sample time, on every gyro update.
//
// The estimator here is a stand-in (a vehicle turning slowly on the spot,
// given in FLU/ENU as many estimators give it); replace `estimate()` with
// yours. Publish at 250 Hz or more: the rates source differentiates the rates
// between consecutive stamps, and below that the detector is slower and the
// spin landing's attitude goes stale (motor_loss.attitude_timeout_ms).
//
//   attitude_publisher [--channel ATTITUDE] [--rate-hz 500] [--count N] [--lcm-url URL]
//
// Without --count it runs until SIGINT/SIGTERM.

#include "frames.hpp"
#include "options.hpp"

#include <lcm/lcm-cpp.hpp>
#include <motormix/attitude_t.hpp>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <string>
#include <thread>

namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

std::int64_t now_us() {
  using namespace std::chrono;
  return duration_cast<microseconds>(system_clock::now().time_since_epoch()).count();
}

// What a FLU/ENU estimator reports: attitude, body rates, velocity.
struct Estimate {
  frames::Quaternion q_enu_flu;
  frames::Vector3 rates_flu;     // rad/s
  frames::Vector3 velocity_enu;  // m/s
};

// Stand-in: level, turning left (counter-clockwise seen from above) at 0.2 rad/s.
Estimate estimate(double t) {
  const double yaw_rate = 0.2;
  const double half = 0.5 * yaw_rate * t;
  return {{std::cos(half), 0.0, 0.0, std::sin(half)}, {0.0, 0.0, yaw_rate}, {0.0, 0.0, 0.0}};
}

}  // namespace

int main(int argc, char** argv) {
  std::string channel = "ATTITUDE", url, rate = "500", how_many = "-1";
  const int done = parse_options(
      argc, argv,
      {{"--channel", &channel}, {"--rate-hz", &rate}, {"--count", &how_many}, {"--lcm-url", &url}},
      "usage: attitude_publisher [--channel NAME] [--rate-hz HZ] [--count N] [--lcm-url URL]\n"
      "publishes attitude_t until Ctrl-C (or N messages); unsigned: for a configuration with\n"
      "security.mode require, sign as examples/signed_controller does\n");
  if (done >= 0) return done;
  const double rate_hz = std::atof(rate.c_str());
  const long count = std::atol(how_many.c_str());
  if (!(rate_hz > 0.0 && rate_hz <= 10000.0)) {
    std::cerr << "--rate-hz: 0 < rate <= 10000\n";
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
  const std::int64_t start = now_us();
  for (long sent = 0; !g_stop && (count < 0 || sent < count); ++sent) {
    const std::int64_t utime = now_us();  // stamp with the gyro sample time
    const Estimate e = estimate(static_cast<double>(utime - start) / 1e6);
    const frames::Quaternion q = frames::frd_ned_from_flu_enu(e.q_enu_flu);
    const frames::Vector3 rates = frames::frd_from_flu(e.rates_flu);
    const frames::Vector3 velocity = frames::ned_from_enu(e.velocity_enu);
    motormix::attitude_t msg{};
    msg.utime = utime;
    for (int k = 0; k < 4; ++k) msg.q[k] = static_cast<float>(q[k]);
    for (int k = 0; k < 3; ++k) {
      msg.rates[k] = static_cast<float>(rates[k]);
      // Unknown? Publish NaN: the spin landing then follows the throttle.
      msg.velocity[k] = static_cast<float>(velocity[k]);
    }
    bus.publish(channel, &msg);
    next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    std::this_thread::sleep_until(next);
  }
  return 0;
}
