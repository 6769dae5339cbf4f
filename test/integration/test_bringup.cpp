// Bring-up tools on a private bus (run under scripts/private-bus): the motor
// test through a live `motormix run` and its client, and the ESC calibration
// sequence.

#include "integration/bus_recorder.hpp"
#include "integration/process.hpp"
#include "test_support.hpp"

#include <motormix/motor_test_t.hpp>
#include <motormix/pid_t.hpp>
#include <motormix/setpoint_t.hpp>

#include <gtest/gtest.h>

#include <unistd.h>

#include <array>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <thread>

namespace motormix::test {
namespace {

using namespace std::chrono_literals;

constexpr float kDisarmedUs = 900.0f;  // config/quad_x.yaml
constexpr float kMinUs = 1000.0f;
constexpr double kSpoolUpS = 0.5;        // config/quad_x.yaml's output.spool_up_s
constexpr double kSpoolUpSlackS = 0.03;  // a dozen cycles at 400 Hz, either way

std::int64_t now_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::string quad() { return source_path("config/quad_x.yaml"); }

std::optional<int> run_client(const std::vector<std::string>& args) {
  std::vector<std::string> argv = {motormix_binary()};
  argv.insert(argv.end(), args.begin(), args.end());
  ChildProcess client(argv);
  return client.wait_for(15s);
}

// A pilot on the bus: setpoint and pid at 200 Hz, armed on request, until
// it goes out of scope.
class BusPilot {
 public:
  BusPilot(float throttle, float roll) : throttle_(throttle), roll_(roll) {
    thread_ = std::thread([this] {
      while (!stop_) {
        setpoint_t sp;
        sp.utime = now_us();
        sp.throttle = throttle_;
        sp.yaw = 0.0f;
        sp.armed = armed;
        pid_t pid;
        pid.utime = sp.utime;
        pid.roll = roll_;
        pid.pitch = pid.yaw = 0.0f;
        lcm_.publish("SETPOINT", &sp);
        lcm_.publish("PID", &pid);
        std::this_thread::sleep_for(5ms);
      }
    });
  }
  ~BusPilot() {
    stop_ = true;
    thread_.join();
  }
  BusPilot(const BusPilot&) = delete;
  BusPilot& operator=(const BusPilot&) = delete;
  void publish_test(int motor, float throttle, float seconds) {
    motor_test_t test;
    test.utime = now_us();
    test.motor = motor;
    test.throttle = throttle;
    test.duration_s = seconds;
    lcm_.publish("MOTOR_TEST", &test);
  }
  std::atomic<bool> armed{false};

 private:
  lcm::LCM lcm_;
  const float throttle_;
  const float roll_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

class MixerOnTheBus : public ::testing::Test {
 protected:
  ChildProcess mixer_{{motormix_binary(), "run", "--config", quad(), "--max-cycles", "8000"}};
  BusRecorder bus_{"MOTOR_PWM", "MIXER_STATUS"};
  void SetUp() override {
    ASSERT_TRUE(bus_.good());
    ASSERT_TRUE(bus_.wait_until([](const auto& pwm, const auto&) { return pwm.size() > 10; }, 10s))
        << "no output from motormix run";
  }
  void TearDown() override {
    mixer_.signal(SIGTERM);
    mixer_.wait_for(5s);
  }
};

TEST_F(MixerOnTheBus, MotorTestSpinsTheRightMotorAloneAndEndsDisarmed) {
  EXPECT_EQ(run_client({"motor-test", "--config", quad(), "--motor", "3", "--throttle", "0.1",
                        "--seconds", "0.5"}),
            0);
  ASSERT_TRUE(bus_.wait_until(
      [](const auto&, const auto& status) {
        return !status.empty() &&
               status.back().motor_test_state == mixer_status_t::MOTOR_TEST_NONE &&
               status.back().motor_tests_started == 1;
      },
      5s));
  int spinning = 0;
  bool after_test_disarmed = false;
  for (const motor_pwm_t& m : bus_.pwm()) {
    EXPECT_FALSE(m.armed);
    if (m.pwm[2] > kMinUs) {
      ++spinning;
      after_test_disarmed = false;
      for (int i : {0, 1, 3}) EXPECT_EQ(m.pwm[static_cast<std::size_t>(i)], kDisarmedUs);
    } else if (spinning > 0) {
      after_test_disarmed = m.pwm[0] == kDisarmedUs && m.pwm[1] == kDisarmedUs &&
                            m.pwm[2] == kDisarmedUs && m.pwm[3] == kDisarmedUs;
    }
  }
  EXPECT_GT(spinning, 100);  // 0.5 s at 400 Hz: about 200 cycles
  EXPECT_TRUE(after_test_disarmed) << "the test must end on disarmed outputs";
  bool reported = false;
  for (const mixer_status_t& s : bus_.status()) {
    if (s.motor_test_state == mixer_status_t::MOTOR_TEST_RUNNING) {
      EXPECT_EQ(s.motor_test_motor, 3);
      reported = true;
    }
  }
  EXPECT_TRUE(reported);
}

TEST_F(MixerOnTheBus, TooMuchThrottleIsRefusedAndNothingSpins) {
  EXPECT_EQ(run_client({"motor-test", "--config", quad(), "--motor", "1", "--throttle", "0.5",
                        "--seconds", "1"}),
            5);  // refused
  std::this_thread::sleep_for(200ms);
  for (const motor_pwm_t& m : bus_.pwm()) {
    for (float v : m.pwm) EXPECT_EQ(v, kDisarmedUs);
  }
  const auto status = bus_.status();
  ASSERT_FALSE(status.empty());
  EXPECT_EQ(status.back().motor_tests_refused, 1);
  EXPECT_EQ(status.back().motor_test_result, mixer_status_t::MOTOR_TEST_REFUSED_THROTTLE);
}

TEST_F(MixerOnTheBus, AnArmedSetpointEndsTheTestAndArmedMixersRefuseOne) {
  BusPilot pilot(0.0f, 0.0f);  // disarmed, then armed at zero throttle
  std::this_thread::sleep_for(300ms);
  pilot.publish_test(2, 0.1f, 3.0f);
  EXPECT_TRUE(bus_.wait_until(
      [](const auto&, const auto& status) {
        return !status.empty() &&
               status.back().motor_test_state == mixer_status_t::MOTOR_TEST_RUNNING;
      },
      3s));
  pilot.armed = true;
  EXPECT_TRUE(bus_.wait_until(
      [](const auto&, const auto& status) {
        return !status.empty() && status.back().state == mixer_status_t::STATE_ARMED &&
               status.back().motor_test_state == mixer_status_t::MOTOR_TEST_NONE;
      },
      3s))
      << "the armed setpoint should end the test and arm";
  EXPECT_EQ(run_client({"motor-test", "--config", quad(), "--motor", "1", "--throttle", "0.1",
                        "--seconds", "1"}),
            5);  // refused
  // The client heard the refusal; the status saying so may reach this
  // test's own subscriber a moment later (a loaded machine): wait for it.
  EXPECT_TRUE(bus_.wait_until(
      [](const auto&, const auto& status) {
        return !status.empty() &&
               status.back().motor_test_result == mixer_status_t::MOTOR_TEST_REFUSED_NOT_DISARMED;
      },
      2s))
      << "the status never said MOTOR_TEST_REFUSED_NOT_DISARMED";
}

TEST_F(MixerOnTheBus, SpoolUpRampsMonotonicallyToTheMixedValue) {
  BusPilot pilot(0.08f, 0.05f);  // within the arming limit (0.1), held while spooling up
  std::this_thread::sleep_for(300ms);
  pilot.armed = true;
  // 0.5 s of spool-up (quad_x's default), then steady.
  EXPECT_TRUE(bus_.wait_until(
      [](const auto& pwm, const auto&) {
        int armed_count = 0;
        for (const auto& m : pwm) armed_count += m.armed ? 1 : 0;
        return armed_count > 320;  // 0.8 s at 400 Hz
      },
      5s));
  std::vector<motor_pwm_t> ramp;
  for (const motor_pwm_t& m : bus_.pwm()) {
    if (m.armed) ramp.push_back(m);
  }
  ASSERT_GT(ramp.size(), 320U);
  ramp.resize(320);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_LE(ramp.front().pwm[i], 1000.0f + 1e-3f)
        << "the first armed output starts at the ESC's zero (output.min)";
    for (const motor_pwm_t& m : ramp) EXPECT_GE(m.pwm[i], 1000.0f) << "armed, never below min";
    for (std::size_t k = 1; k < ramp.size(); ++k) {
      EXPECT_GE(ramp[k].pwm[i], ramp[k - 1].pwm[i]) << "motor " << i + 1 << ", output " << k;
    }
    EXPECT_EQ(ramp[319].pwm[i], ramp[260].pwm[i]) << "steady once spooled up";
  }
  // It ramps to what the same mixer gives without spool-up, for the same
  // inputs (not to the ESC's zero, where a mixer that never spun up would
  // also be "steady"), and the ramp lasts output.spool_up_s (0.5 s) in the
  // mixer's own clock, give or take a few cycles.
  const config::Config no_spool = config::load_config_file(quad(), {"output.spool_up_s=0"});
  const Mixer mixer = config::build_mixer(no_spool);
  MixerOutput out;
  AxisVector demand;
  demand << 0.05, 0.0, 0.0, 0.08;
  mixer.mix(demand, out);
  std::size_t reached = ramp.size();
  for (std::size_t k = 0; k < ramp.size() && reached == ramp.size(); ++k) {
    bool all = true;
    for (std::size_t i = 0; i < 4; ++i) {
      all =
          all && std::abs(ramp[k].pwm[i] - out.output[static_cast<Eigen::Index>(i)]) <= kFloatPwmUs;
    }
    if (all) reached = k;
  }
  ASSERT_LT(reached, ramp.size()) << "never reached the unramped mix " << out.output.transpose();
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_GT(out.output[static_cast<Eigen::Index>(i)], 1000.0 + 10.0) << "a demand that spins";
  }
  const double ramp_s = static_cast<double>(ramp[reached].utime - ramp.front().utime) / 1e6;
  EXPECT_GE(ramp_s, kSpoolUpS - kSpoolUpSlackS);
  EXPECT_LE(ramp_s, kSpoolUpS + kSpoolUpSlackS);
  bool spooling = false, spooled = false;
  for (const mixer_status_t& st : bus_.status()) {
    if (st.state != mixer_status_t::STATE_ARMED) continue;
    if (st.spooling_up) spooling = true;
    if (spooling && !st.spooling_up && st.spool_up == 1.0f) spooled = true;
  }
  EXPECT_TRUE(spooling);
  EXPECT_TRUE(spooled);
}

// Refused for its stated reason: its own exit code, the reason on stderr,
// and nothing at the maximum or armed on the bus (a bus that cannot open
// exits 1, and a run that went to the maximum first would show 2000 us).
TEST_F(MixerOnTheBus, EscCalibrationRefusesWhileAMixerRuns) {
  const std::string err_path = ::testing::TempDir() + "/esc_refusal_stderr.txt";
  std::vector<std::string> argv = {motormix_binary(), "esc-calibrate", "--config", quad(),
                                   "--props-off",     "--timeout",     "1"};
  ChildProcess client(argv, err_path);
  EXPECT_EQ(client.wait_for(15s), 5);
  std::ifstream err_file(err_path);
  const std::string err((std::istreambuf_iterator<char>(err_file)), {});
  EXPECT_NE(err.find("refused: a mixer is running on the bus"), std::string::npos) << err;
  std::this_thread::sleep_for(100ms);
  for (const motor_pwm_t& m : bus_.pwm()) {
    EXPECT_FALSE(m.armed) << "the disarmed mixer's outputs only";
    for (float v : m.pwm) EXPECT_EQ(v, kDisarmedUs);
  }
}

std::optional<int> run_shell(const std::string& line) {
  ChildProcess sh({"/bin/sh", "-c", line});
  return sh.wait_for(20s);
}

TEST(EscCalibration, RefusesWithoutPropsOffAndOnHBridges) {
  BusRecorder bus("MOTOR_PWM", "MIXER_STATUS");
  EXPECT_EQ(run_client({"esc-calibrate", "--config", quad(), "--timeout", "1"}), 2);
  EXPECT_EQ(run_client({"esc-calibrate", "--config", source_path("config/diff_drive.yaml"),
                        "--props-off", "--timeout", "1"}),
            2);
  std::this_thread::sleep_for(100ms);
  EXPECT_EQ(bus.pwm_count(), 0U) << "a refused calibration sends nothing";
}

// Maximum until the user's Enter, then minimum, then disarmed.
TEST(EscCalibration, MaximumThenMinimumThenDisarmed) {
  BusRecorder bus("MOTOR_PWM", "MIXER_STATUS");
  const std::string cmd = "(sleep 2; echo) | '" + std::string(motormix_binary()) +
                          "' esc-calibrate --config '" + quad() +
                          "' --props-off --timeout 10 --min-seconds 0.5";
  EXPECT_EQ(run_shell(cmd), 0);
  std::this_thread::sleep_for(100ms);
  // Phases in order: 2000 (armed), 1000 (armed), 900 (not armed).
  int phase = 0;
  std::array<int, 3> count{};
  const float value[3] = {2000.0f, kMinUs, kDisarmedUs};
  for (const motor_pwm_t& m : bus.pwm()) {
    while (phase < 3 && m.pwm[0] != value[phase]) ++phase;
    ASSERT_LT(phase, 3) << "an output outside the sequence: " << m.pwm[0];
    for (float v : m.pwm) EXPECT_EQ(v, value[phase]);
    EXPECT_EQ(m.armed, phase < 2);
    ++count[static_cast<std::size_t>(phase)];
  }
  EXPECT_GT(count[0], 100);  // about 0.8 s at 400 Hz after the listening second
  EXPECT_GT(count[1], 100);  // 0.5 s
  EXPECT_GT(count[2], 10);
}

TEST(EscCalibration, NoConfirmationAbortsToDisarmed) {
  BusRecorder bus("MOTOR_PWM", "MIXER_STATUS");
  const std::string cmd = "sleep 2 | '" + std::string(motormix_binary()) +
                          "' esc-calibrate --config '" + quad() + "' --props-off --timeout 0.5";
  EXPECT_EQ(run_shell(cmd), 1);
  std::this_thread::sleep_for(100ms);
  const auto pwm = bus.pwm();
  ASSERT_FALSE(pwm.empty());
  EXPECT_EQ(pwm.back().pwm[0], kDisarmedUs);
  EXPECT_FALSE(pwm.back().armed);
  for (const motor_pwm_t& m : pwm) EXPECT_NE(m.pwm[0], kMinUs) << "no minimum without confirmation";
}

TEST(EscCalibration, CtrlCAbortsToDisarmed) {
  BusRecorder bus("MOTOR_PWM", "MIXER_STATUS");
  // Standard input held open (a FIFO with a writer that says nothing), and
  // the shell replaced by motormix, so the signal reaches it.
  ChildProcess calibration(
      {"/bin/sh", "-c",
       "f=$(mktemp -u); mkfifo \"$f\"; (sleep 10 > \"$f\" &); exec 0<\"$f\"; rm -f \"$f\"; "
       "exec \"$0\" esc-calibrate --config \"$1\" --props-off --timeout 20",
       motormix_binary(), quad()});
  ASSERT_TRUE(bus.wait_until(
      [](const auto& pwm, const auto&) { return !pwm.empty() && pwm.back().pwm[0] == 2000.0f; },
      5s));
  calibration.signal(SIGINT);
  EXPECT_EQ(calibration.wait_for(5s), 1);
  std::this_thread::sleep_for(100ms);
  EXPECT_EQ(bus.last_pwm().pwm[0], kDisarmedUs);
  EXPECT_FALSE(bus.last_pwm().armed);
}

// A client waiting for an answer that does not come stops at Ctrl-C, not at
// the end of its wait (the signal wakes its wait on the bus).
TEST(EscCommand, CtrlCWhileWaitingForTheOutputEndsItAtOnce) {
  constexpr auto kPromptly = 2s;  // against a 30 s wait
  const std::string config = "/tmp/motormix-esc-command-" + std::to_string(::getpid()) + ".yaml";
  std::ofstream(config) << "geometry: {preset: quad_x}\n"
                           "output: {min: 1000, max: 2000, disarmed: 1000}\n"
                           "hardware: {driver: serial, protocol: dshot600, serial: {device: "
                           "/dev/null}}\n";
  ChildProcess cli(
      {motormix_binary(), "esc-command", "--config", config, "beep1", "--all", "--wait", "30"});
  std::this_thread::sleep_for(500ms);
  ASSERT_TRUE(cli.running());
  cli.signal(SIGINT);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(cli.wait_for(kPromptly), 1);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, kPromptly);
  std::remove(config.c_str());
}

}  // namespace
}  // namespace motormix::test
