// Sign checks through the bus (run under scripts/private-bus): a live
// `motormix run`, `motormix sim --lcm --no-controller`, and this test as the
// user's own controller, flying from VEHICLE_STATE. It takes off on throttle
// alone, then raises on one axis what the mixing matrix says makes that
// axis positive; the body rate the simulator publishes must follow.

#include "integration/process.hpp"
#include "test_support.hpp"

#include <motormix/motor_pwm_t.hpp>
#include <motormix/pid_t.hpp>
#include <motormix/setpoint_t.hpp>
#include <motormix/vehicle_state_t.hpp>

#include <lcm/lcm-cpp.hpp>

#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cmath>
#include <csignal>
#include <string>
#include <thread>

namespace motormix::test {
namespace {

using Clock = std::chrono::steady_clock;

constexpr double kClimbThrottle = 0.62;  // above the quad's hover demand (about 0.45)
constexpr double kTakenOffM = 1.0;       // altitude before the axis step
constexpr double kStep = 0.15;           // demand on the axis under test
// How long the step lasts, per axis: yaw, the weakest, gets longer. Measured
// (wall clock, unloaded): roll and pitch about 1 rad/s after 0.15 s, yaw
// 0.16 rad/s after 0.15 s and about 0.4 rad/s after 0.4 s.
constexpr double kStepS[3] = {0.15, 0.15, 0.4};
// A body rate that clearly has a sign: a quarter of the weakest measured.
constexpr double kClearRateRadS = 0.1;
constexpr auto kBound = std::chrono::seconds(8);

struct Bus {
  lcm::LCM lcm;
  bool armed = false;
  bool have_state = false;
  vehicle_state_t state;
  void on_pwm(const lcm::ReceiveBuffer*, const std::string&, const motor_pwm_t* m) {
    armed = m->armed;
  }
  void on_state(const lcm::ReceiveBuffer*, const std::string&, const vehicle_state_t* s) {
    state = *s;
    have_state = true;
  }
};

std::int64_t now_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// Flies one step on `axis` (0 roll, 1 pitch, 2 yaw) and returns the body
// rates at its end; NaN if the vehicle never took off within the bound.
std::array<double, 3> rates_after_step(int axis) {
  const std::string config = source_path("config/quad_x.yaml");
  ChildProcess mixer({motormix_binary(), "run", "--config", config, "--max-cycles", "4000"});
  ChildProcess sim({motormix_binary(), "sim", "--config", config, "--scenario", "hover", "--lcm",
                    "--no-controller", "--duration", "9", "--json"});
  Bus bus;
  EXPECT_TRUE(bus.lcm.good());
  bus.lcm.subscribe("MOTOR_PWM", &Bus::on_pwm, &bus);
  bus.lcm.subscribe("VEHICLE_STATE", &Bus::on_state, &bus);
  const auto start = Clock::now();
  Clock::time_point step_start{};
  std::array<double, 3> rates{NAN, NAN, NAN};
  while (Clock::now() - start < kBound) {
    while (bus.lcm.handleTimeout(0) > 0) {
    }
    const double t = std::chrono::duration<double>(Clock::now() - start).count();
    const bool airborne = bus.have_state && -bus.state.position[2] > kTakenOffM;
    if (airborne && step_start == Clock::time_point{}) step_start = Clock::now();
    const bool stepping = step_start != Clock::time_point{};
    if (stepping && Clock::now() - step_start > std::chrono::duration<double>(kStepS[axis])) {
      for (int i = 0; i < 3; ++i) rates[static_cast<std::size_t>(i)] = bus.state.rates[i];
      break;
    }
    setpoint_t sp;
    sp.utime = now_us();
    sp.armed = t > 0.5;
    sp.throttle = static_cast<float>(bus.armed ? kClimbThrottle : 0.0);
    pid_t pid;
    pid.utime = sp.utime;
    pid.roll = pid.pitch = pid.yaw = 0.0f;
    const float step = stepping ? static_cast<float>(kStep) : 0.0f;
    (axis == 0 ? pid.roll : axis == 1 ? pid.pitch : pid.yaw) = step;
    sp.yaw = 0.0f;  // quad_x takes yaw from pid
    bus.lcm.publish("SETPOINT", &sp);
    bus.lcm.publish("PID", &pid);
    std::this_thread::sleep_for(std::chrono::milliseconds(4));
  }
  sim.signal(SIGTERM);
  mixer.signal(SIGTERM);
  sim.wait_for(std::chrono::seconds(5));
  mixer.wait_for(std::chrono::seconds(5));
  return rates;
}

TEST(SitlSigns, EachAxisOfTheMixingMatrixTurnsTheSimulatedBodyThatWay) {
  for (int axis = 0; axis < 3; ++axis) {
    const std::array<double, 3> w = rates_after_step(axis);
    ASSERT_FALSE(std::isnan(w[0])) << "never took off (axis " << axis << ")";
    EXPECT_GT(w[static_cast<std::size_t>(axis)], kClearRateRadS) << "axis " << axis;
    for (int other = 0; other < 3; ++other) {
      if (other != axis) {
        EXPECT_LT(std::abs(w[static_cast<std::size_t>(other)]), w[static_cast<std::size_t>(axis)])
            << "axis " << axis << " moved axis " << other;
      }
    }
  }
}

}  // namespace
}  // namespace motormix::test
