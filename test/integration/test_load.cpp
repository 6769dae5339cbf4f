// Twenty motormix processes on one private bus, each with its own channels
// and its own publisher at 400 Hz, for a bounded time. Each vehicle's outputs
// must follow from its own inputs only (every output names the inputs it was
// computed from, and each publisher's utimes carry its vehicle number), stay
// in range, and keep coming; the shares of cycles run and outputs received,
// and the CPU of each process, are printed. No check depends on how fast the
// machine is: this load saturates two cores, and the shares follow the
// machine (seen: 86-99 % of cycles run and 70-97 % of outputs received on
// one, 74-79 % and 35-41 % on a slower one).

#include "integration/process.hpp"
#include "test_support.hpp"

#include <motormix/mixer_status_t.hpp>
#include <motormix/motor_pwm_t.hpp>
#include <motormix/pid_t.hpp>
#include <motormix/setpoint_t.hpp>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <unistd.h>
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>
#include <thread>
#include <vector>

namespace motormix::test {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

constexpr int kVehicles = 20;
constexpr auto kFlight = 8s;
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// CPU seconds (user + system) a process has used so far.
double cpu_seconds(::pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  std::getline(stat, line);
  std::istringstream fields(line.substr(line.rfind(')') + 2));
  std::string skip;
  for (int i = 0; i < 11; ++i) fields >> skip;  // fields 3..13
  double utime = 0, stime = 0;
  fields >> utime >> stime;
  return (utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

std::string channel(const char* kind, int v) { return std::string(kind) + "_" + std::to_string(v); }

// Every vehicle's outputs through one LCM instance on one thread. (One
// recorder per vehicle would make this process receive all of the bus's
// traffic twenty times over, and measure its own receive capacity instead of
// the mixers' loops.) Checks each output as it arrives: it must name its own
// vehicle's inputs and stay in range.
class FleetRecorder {
 public:
  FleetRecorder() {
    lcm_.subscribe("PWM_[0-9]+", &FleetRecorder::on_pwm, this)->setQueueCapacity(1000000);
    lcm_.subscribe("STATUS_[0-9]+", &FleetRecorder::on_status, this)->setQueueCapacity(100000);
    thread_ = std::thread([this] {
      while (!stop_) lcm_.handleTimeout(20);
    });
  }
  ~FleetRecorder() {
    stop_ = true;
    thread_.join();
  }
  FleetRecorder(const FleetRecorder&) = delete;
  FleetRecorder& operator=(const FleetRecorder&) = delete;

  struct Vehicle {
    std::atomic<long> outputs{0};
    std::atomic<long> armed{0};
    std::atomic<long> cross_talk{0};
    std::atomic<long> out_of_range{0};
    std::atomic<long> undecodable{0};
    std::atomic<long> cycles{0};  // the mixer's own cycle count, from its latest status
  };
  Vehicle& operator[](int v) { return vehicles_[static_cast<std::size_t>(v)]; }

 private:
  void on_status(const lcm::ReceiveBuffer* rbuf, const std::string& ch) {
    const int v = std::atoi(ch.c_str() + 7);
    if (v < 0 || v >= kVehicles) return;
    mixer_status_t m{};
    if (m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) > 0) {
      vehicles_[static_cast<std::size_t>(v)].cycles = m.cycles;
    }
  }
  void on_pwm(const lcm::ReceiveBuffer* rbuf, const std::string& ch) {
    const int v = std::atoi(ch.c_str() + 4);
    if (v < 0 || v >= kVehicles) return;
    Vehicle& vehicle = vehicles_[static_cast<std::size_t>(v)];
    motor_pwm_t m{};
    if (m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) <= 0) {
      ++vehicle.undecodable;
      return;
    }
    ++vehicle.outputs;
    vehicle.armed += m.armed ? 1 : 0;
    if ((m.setpoint_utime != 0 && m.setpoint_utime % 1000 != v) ||
        (m.pid_utime != 0 && m.pid_utime % 1000 != v)) {
      ++vehicle.cross_talk;
    }
    for (float p : m.pwm) {
      if (!(m.armed ? p >= 1150.0F && p <= 1924.0F : p == 1000.0F)) ++vehicle.out_of_range;
    }
  }

  lcm::LCM lcm_;
  std::array<Vehicle, kVehicles> vehicles_{};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

TEST(Load, TwentyVehiclesOnOneBusWithoutCrossTalk) {
  const char* flag = std::getenv("MOTORMIX_PRIVATE_BUS");
  ASSERT_TRUE(flag && std::string(flag) == "1") << "run through scripts/private-bus";
  FleetRecorder fleet;
  std::vector<std::unique_ptr<ChildProcess>> mixers;
  for (int v = 0; v < kVehicles; ++v) {
    mixers.push_back(std::make_unique<ChildProcess>(std::vector<std::string>{
        motormix_binary(), "run", "--config", source_path("config/team_quad.yaml"), "--set",
        "output.spool_up_s=0", "--set", "channels.setpoint=" + channel("SETPOINT", v), "--set",
        "channels.pid=" + channel("PID", v), "--set", "channels.motor_pwm=" + channel("PWM", v),
        "--set", "channels.status=" + channel("STATUS", v),
        // Throughput and cross-talk are measured here, not failsafe timing
        // (tested alone elsewhere): with sixty busy threads on two cores a
        // publisher or a loop can sleep past 100 ms, and a failsafe would end
        // that vehicle's flight.
        "--set", "inputs.setpoint_timeout_ms=500", "--set", "inputs.pid_timeout_ms=500"}));
  }
  for (int v = 0; v < kVehicles; ++v) {
    const auto deadline = Clock::now() + 20s;
    while (fleet[v].outputs == 0 && Clock::now() < deadline) std::this_thread::sleep_for(10ms);
    ASSERT_GT(fleet[v].outputs, 0) << "vehicle " << v << " never published";
  }

  // One publisher per vehicle at 400 Hz: utimes = k * 1000 + vehicle, so any
  // output names the vehicle whose inputs it used. Armed after a disarmed
  // second, at a throttle and roll of its own.
  std::atomic<bool> stop{false};
  std::vector<std::thread> pilots;
  for (int v = 0; v < kVehicles; ++v) {
    pilots.emplace_back([v, &stop] {
      lcm::LCM lcm;
      const auto start = Clock::now();
      auto next = start;
      for (std::int64_t k = 0; !stop && k < 400 * 60; ++k) {  // bounded: at most a minute
        const std::int64_t utime = (wall_us() / 1000) * 1000 + v;
        setpoint_t sp{};
        sp.utime = utime;
        sp.armed = Clock::now() - start > 300ms;
        sp.throttle =
            sp.armed && Clock::now() - start > 600ms ? 0.3F + 0.02F * static_cast<float>(v) : 0.0F;
        pid_t pid{};
        pid.utime = utime;
        pid.roll = -0.5F + 0.05F * static_cast<float>(v);
        lcm.publish(channel("SETPOINT", v), &sp);
        lcm.publish(channel("PID", v), &pid);
        next += 2500us;
        std::this_thread::sleep_until(next);
      }
    });
  }

  std::this_thread::sleep_for(1s);  // armed and flying
  std::vector<long> count0;
  std::vector<long> cycles0;
  std::vector<long> armed0;
  std::vector<double> cpu0;
  for (int v = 0; v < kVehicles; ++v) {
    count0.push_back(fleet[v].outputs);
    cycles0.push_back(fleet[v].cycles);
    armed0.push_back(fleet[v].armed);
    cpu0.push_back(cpu_seconds(mixers[v]->pid()));
  }
  const auto t0 = Clock::now();
  std::this_thread::sleep_for(kFlight);
  const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  std::vector<double> cpu_share;
  std::vector<double> delivered;
  std::vector<double> cycled;
  std::vector<long> received;  // outputs, then armed ones, in the flight window
  std::vector<long> armed;
  for (int v = 0; v < kVehicles; ++v) {
    received.push_back(fleet[v].outputs - count0[v]);
    armed.push_back(fleet[v].armed - armed0[v]);
    cpu_share.push_back((cpu_seconds(mixers[v]->pid()) - cpu0[v]) / seconds);
    delivered.push_back(static_cast<double>(received.back()) / (400.0 * seconds));
    cycled.push_back(static_cast<double>(fleet[v].cycles - cycles0[v]) / (400.0 * seconds));
  }
  stop = true;
  for (auto& t : pilots) t.join();

  const double median_cycled = median(cycled);
  const double median_delivered = median(delivered);
  std::printf("fleet median: %.1f %% of cycles run, %.1f %% of outputs received\n",
              100.0 * median_cycled, 100.0 * median_delivered);
  double cpu_total = 0;
  for (int v = 0; v < kVehicles; ++v) {
    SCOPED_TRACE("vehicle " + std::to_string(v));
    cpu_total += cpu_share[v];
    std::printf(
        "vehicle %2d: %.1f %% of its cycles run, %.1f %% of its outputs received, CPU %.2f %% of a "
        "core\n",
        v, 100.0 * cycled[v], 100.0 * delivered[v], 100.0 * cpu_share[v]);
    EXPECT_EQ(fleet[v].cross_talk, 0) << "outputs computed from another vehicle's inputs";
    EXPECT_EQ(fleet[v].out_of_range, 0);
    EXPECT_EQ(fleet[v].undecodable, 0);
    // Every loop kept running and flying through the window: its own cycle
    // count moved, and armed outputs of its own came.
    EXPECT_GT(fleet[v].cycles, cycles0[v]);
    EXPECT_GT(armed[v], 0) << "no armed output during the flight window";
  }
  std::printf("20 mixers at 400 Hz: %.1f %% of one core in all (%.2f %% each on average)\n",
              100.0 * cpu_total, 100.0 * cpu_total / kVehicles);
  for (auto& m : mixers) m->signal(SIGTERM);
  for (auto& m : mixers) EXPECT_EQ(m->wait_for(10s), 0);
}

}  // namespace
}  // namespace motormix::test
