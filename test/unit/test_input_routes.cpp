// The one routing of input channels (messages::InputRoutes), which the node's
// subscriptions and the offline replay share: attitude_t reaches the loop
// whenever the loop reads it, for the spin landing as for the detector. A
// spin landing replayed without the detector used to lose its attitude (the
// replay passed attitude on only with failure_detection on).

#include "bus/receive.hpp"
#include "log/log_reader.hpp"
#include "log/log_replay.hpp"
#include "loop/control_loop.hpp"
#include "messages/log_writer.hpp"
#include "messages/messages.hpp"
#include "test_support.hpp"

#include <motormix/config/build_mixer.hpp>
#include <motormix/config/load_config.hpp>

#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>

namespace motormix {
namespace {

config::Config quad_without_detector() {
  return config::load_config_file(test::source_path("config/quad_x.yaml"), {"output.spool_up_s=0"});
}

TEST(InputRoutes, TheLoopsReadersAreRoutedAndNothingElse) {
  const config::Config config = quad_without_detector();
  ASSERT_FALSE(config.failure_detection);
  const loop::ControlLoop loop(config, config::build_mixer(config));
  ASSERT_TRUE(loop.reads_attitude()) << "quad_x lands on three motors: it reads attitude_t";
  const messages::InputRoutes routes(config);
  EXPECT_EQ(routes.kind("ATTITUDE"), messages::InputKind::kAttitude);
  EXPECT_EQ(routes.kind("SETPOINT"), messages::InputKind::kSetpoint);
  EXPECT_EQ(routes.kind("MOTOR_TEST"), messages::InputKind::kMotorTest);
  EXPECT_FALSE(routes.kind("ESC_TELEMETRY").has_value()) << "no detector: telemetry unread";
  EXPECT_FALSE(routes.kind("BATTERY").has_value()) << "no battery: section";
  EXPECT_FALSE(routes.kind("MOTOR_PWM").has_value());
}

// The routing is taken from the configuration alone (the replay builds no
// loop for it): it must say what a loop of that configuration reads, for
// every bundled configuration and the detector's source sets.
TEST(InputRoutes, TheConfigurationAloneSaysWhatTheLoopReads) {
  int checked = 0;
  for (const auto& entry : std::filesystem::directory_iterator(test::source_path("config"))) {
    if (entry.path().extension() != ".yaml") continue;
    for (const std::vector<std::string>& sets :
         {std::vector<std::string>{},
          {"failure_detection.enabled=true", "failure_detection.sources=[telemetry]"},
          {"failure_detection.enabled=true", "failure_detection.sources=[rates]"},
          {"failure_detection.enabled=true", "failure_detection.sources=[telemetry, rates]"},
          {"motor_loss.mode=off"}}) {
      config::Config config;
      try {
        config = config::load_config_file(entry.path().string(), sets);
      } catch (const std::exception&) {
        continue;  // an override this configuration refuses (a key file, a ground robot)
      }
      SCOPED_TRACE(entry.path().filename().string() + " " + testing::PrintToString(sets));
      const loop::ControlLoop loop(config, config::build_mixer(config));
      EXPECT_EQ(loop::ControlLoop::reads_esc_telemetry(config), loop.reads_esc_telemetry());
      EXPECT_EQ(loop::ControlLoop::reads_attitude(config), loop.reads_attitude());
      ++checked;
    }
  }
  EXPECT_GE(checked, 20);
}

TEST(InputRoutes, ASpinLandingReplayedWithoutTheDetectorKeepsItsAttitude) {
  const config::Config config = quad_without_detector();
  const std::string dir = testing::TempDir() + "/motormix-routes";
  std::filesystem::create_directories(dir);
  const std::string in = dir + "/spin.lcmlog", out = dir + "/spin.out";
  {
    // Hover commands at 200 Hz, a level attitude at 250 Hz, and motor m1
    // reported failed from 2 s on: the spin landing takes over when it has
    // a fresh attitude, and says "no attitude" when it has none.
    messages::LogWriter w(in);
    ASSERT_TRUE(w.good());
    const std::int64_t t0 = 1'764'000'000'000'000;
    for (std::int64_t t = 0; t <= 4'000'000; t += 1000) {
      const std::int64_t utime = t0 + t;
      if (t % 5000 == 0) {
        setpoint_t sp{};
        sp.utime = utime;
        sp.throttle = t < 100'000 ? 0.0F : 0.5F;
        sp.armed = t >= 50'000;  // disarmed first, armed at low throttle, then hover
        w.write("SETPOINT", utime, sp);
        pid_t pid{};
        pid.utime = utime;
        w.write("PID", utime, pid);
      }
      if (t % 4000 == 0) {
        attitude_t a{};
        a.utime = utime;
        a.q[0] = 1.0F;  // level; rates and velocity 0
        w.write("ATTITUDE", utime, a);
      }
      if (t >= 2'000'000 && t % 50'000 == 0) {
        motor_status_t ms{};
        bus::WireShape<motor_status_t>::size(ms, 4);
        ms.utime = utime;
        ms.failed[0] = 1;
        w.write("MOTOR_STATUS", utime, ms);
      }
    }
    ASSERT_TRUE(w.close());
  }
  lcmlog::ReplaySummary summary;
  std::ostringstream log;
  ASSERT_TRUE(lcmlog::replay_log(config, in, out, lcmlog::ReplayOptions{}, summary, log))
      << log.str();
  lcmlog::LogReader r(out);
  int descending = 0, no_attitude = 0, attitude_taken = 0;
  while (const lcmlog::LogEventView* ev = r.next()) {
    if (ev->channel != config.channels.status) continue;
    mixer_status_t s{};
    if (bus::decode_exact(ev->data.data(), ev->data.size(), s) != bus::Refusal::kNone) continue;
    descending += s.landing_state == mixer_status_t::LANDING_DESCENDING ? 1 : 0;
    no_attitude += s.landing_state == mixer_status_t::LANDING_NO_ATTITUDE ? 1 : 0;
    attitude_taken = std::max(attitude_taken, static_cast<int>(s.attitude_received));
  }
  EXPECT_GT(attitude_taken, 900) << "attitude_t not delivered to the loop";
  EXPECT_GT(descending, 0) << "the spin landing never took over; " << log.str() << " armed "
                           << summary.armed_s << " s, failed " << summary.failed_s << " s";
  EXPECT_EQ(no_attitude, 0) << "the landing was left without its attitude";
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace motormix
