// A log recorded by lcm-logger off a live bus (with its own receive
// timestamps, and whatever else was on the bus) works like a generated one:
// `motormix replay` over the recording gives, for the same inputs, the same
// outputs as the golden replay of the original flight.

#include "integration/process.hpp"
#include "test_support.hpp"

#include <motormix/motor_pwm_t.hpp>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <csignal>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

namespace motormix::test {
namespace {

using namespace std::chrono_literals;

// Golden PWM is written to 0.001.
constexpr double kGoldenPwm = 1e-3;
// Reception jitter can move a staleness boundary by a cycle: at most this
// share of armed outputs may name inputs the golden replay never armed.
constexpr double kBoundaryShare = 0.01;

std::map<std::pair<std::int64_t, std::int64_t>, std::vector<double>> read_golden(
    const std::string& path) {
  std::map<std::pair<std::int64_t, std::int64_t>, std::vector<double>> g;
  std::ifstream f(path);
  for (std::string line; std::getline(f, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::stringstream s(line);
    std::string cell;
    std::vector<double> v;
    while (std::getline(s, cell, ',')) v.push_back(std::stod(cell));
    g[{static_cast<std::int64_t>(v[0]), static_cast<std::int64_t>(v[1])}] =
        std::vector<double>(v.begin() + 2, v.end());
  }
  return g;
}

TEST(RecordedLog, ReplaysLikeTheOriginal) {
  const char* flag = std::getenv("MOTORMIX_PRIVATE_BUS");
  ASSERT_TRUE(flag && std::string(flag) == "1") << "run through scripts/private-bus";
  const std::string dir = ::testing::TempDir();
  const std::string recorded = dir + "/recorded_dropout.lcmlog";
  std::remove(recorded.c_str());

  ChildProcess logger({"lcm-logger", "--quiet", "--force", recorded});
  ASSERT_TRUE(logger.started());
  // The logger is up once its file exists (bounded wait on the file, not a
  // fixed sleep).
  for (int i = 0; i < 200 && !std::ifstream(recorded).good(); ++i)
    std::this_thread::sleep_for(10ms);
  ChildProcess player({"lcm-logplayer", source_path("test/data/flights/dropout.lcmlog")});
  ASSERT_EQ(player.wait_for(60s), 0);
  logger.signal(SIGINT);
  ASSERT_TRUE(logger.wait_for(10s).has_value());

  const std::string out = dir + "/recorded_dropout.out.lcmlog";
  const std::string cmd = std::string(motormix_binary()) + " replay --every-input --config " +
                          source_path("config/quad_x.yaml") +
                          " --set inputs.yaw_source=setpoint --set output.spool_up_s=0 " +
                          recorded + " " + out + " > /dev/null 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;

  const auto golden = read_golden(source_path("test/data/golden/dropout__quad_x_prioritized.csv"));
  ASSERT_FALSE(golden.empty());
  std::size_t armed = 0;
  std::size_t unmatched = 0;
  lcm::LogFile file(out, "r");
  while (const lcm::LogEvent* ev = file.readNextEvent()) {
    if (ev->channel != "MOTOR_PWM") continue;
    motor_pwm_t m{};
    ASSERT_GT(m.decode(ev->data, 0, static_cast<int>(ev->datalen)), 0);
    if (!m.armed) continue;
    ++armed;
    const auto g = golden.find({m.setpoint_utime, m.pid_utime});
    if (g == golden.end()) {
      ++unmatched;
      continue;
    }
    for (std::size_t i = 0; i < m.pwm.size(); ++i) ASSERT_NEAR(m.pwm[i], g->second[i], kGoldenPwm);
  }
  EXPECT_GT(armed, 1000U);
  EXPECT_LE(static_cast<double>(unmatched), kBoundaryShare * static_cast<double>(armed));
}

}  // namespace
}  // namespace motormix::test
