// `motormix import ulog` and the replay's comparison with PX4 (issue 50), on
// the shared PX4 SITL flight: the flight becomes an LCM log, the replay of
// it with the imported configuration matches PX4's own actuator_motors,
// and motormix's failure detector, fed the flight's rates and ESC reports,
// declares nothing, while a copy with one ESC reporting its motor stopped
// is found.

#include <motormix/config/px4_import.hpp>
#include <motormix/esc_telemetry_t.hpp>
#include <motormix/mixer_status_t.hpp>
#include <motormix/motor_pwm_t.hpp>
#include <motormix/setpoint_t.hpp>
#include "log/log_reader.hpp"
#include "log/log_replay.hpp"
#include "log/ulog_import.hpp"
#include "messages/log_writer.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <unistd.h>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace motormix::test {
namespace {

const std::string kSharedFlight = "test/data/px4/sample_px4_events.ulg";
// Issue 50: the replay of the shared flight fails below a 1e-5 match with
// PX4 (measured: 1.19e-7, float32 messages).
constexpr double kReplayPx4Tolerance = 1e-5;
// Of the flight's 313 actuator_motors, those while PX4 was armed.
constexpr std::int64_t kArmedPx4SamplesMin = 150;

std::string scratch(const std::string& name) {
  return "/tmp/motormix-ulog-" + std::to_string(::getpid()) + "-" + name;
}

config::Config imported_config(const std::vector<std::string>& overrides = {}) {
  const std::string path = source_path(kSharedFlight);
  return config::load_config_text(config::import_px4(config::read_px4_parameters(path), path).yaml,
                                  "imported", overrides);
}

lcmlog::UlogImportSummary import_shared(const std::string& out) {
  lcmlog::UlogImportSummary s;
  std::ostringstream log;
  EXPECT_TRUE(lcmlog::import_ulog(source_path(kSharedFlight), out, {}, s, log)) << log.str();
  return s;
}

lcmlog::ReplaySummary replay(const config::Config& c, const std::string& in,
                             const std::string& out) {
  lcmlog::ReplaySummary s;
  std::ostringstream log;
  EXPECT_TRUE(lcmlog::replay_log(c, in, out, {}, s, log)) << log.str();
  return s;
}

TEST(UlogImport, TheSharedFlightBecomesMotormixsInputsAndPx4sOutputs) {
  const std::string out = scratch("flight.lcmlog");
  const lcmlog::UlogImportSummary s = import_shared(out);
  EXPECT_EQ(s.events.at("SETPOINT"), 1558);  // one per logged torque setpoint
  EXPECT_EQ(s.events.at("PID"), 1558);
  EXPECT_EQ(s.events.at("ATTITUDE"), 1558);
  EXPECT_EQ(s.events.at("ESC_TELEMETRY"), 126);
  EXPECT_EQ(s.events.at(lcmlog::kPx4ReferenceChannel), 313);
  EXPECT_EQ(s.clamped, 0);
  EXPECT_EQ(s.skipped, 0);
  EXPECT_NEAR(s.duration_s, 31.1, 0.1);

  lcmlog::LogReader in(out);
  std::int64_t previous = 0, armed = 0, telemetry = 0;
  double max_throttle = 0.0;
  while (const lcmlog::LogEventView* ev = in.next()) {
    EXPECT_GE(ev->timestamp, previous);  // in time order
    previous = ev->timestamp;
    const int size = static_cast<int>(ev->data.size());
    if (ev->channel == "SETPOINT") {
      setpoint_t sp{};
      ASSERT_EQ(sp.decode(ev->data.data(), 0, size), size);
      EXPECT_EQ(sp.utime, ev->timestamp);
      armed += sp.armed ? 1 : 0;
      max_throttle = std::max(max_throttle, static_cast<double>(sp.throttle));
    } else if (ev->channel == "ESC_TELEMETRY") {
      esc_telemetry_t m{};
      ASSERT_EQ(m.decode(ev->data.data(), 0, size), size);
      // The SITL reports six ESCs, two of them on outputs that are not
      // motors (functions 45, 46): only the four motors are kept.
      ASSERT_EQ(m.count, 4);
      for (int i = 0; i < m.count; ++i) EXPECT_EQ(m.motor[static_cast<std::size_t>(i)], i + 1);
      ++telemetry;
    }
  }
  EXPECT_TRUE(in.skipped().empty());
  EXPECT_GT(armed, 0);
  EXPECT_LT(armed, 1558);        // the flight starts and ends disarmed
  EXPECT_GT(max_throttle, 0.4);  // -vehicle_thrust_setpoint.z in flight
  EXPECT_EQ(telemetry, 126);
  std::remove(out.c_str());
}

// The whole round trip: import, replay with the imported configuration,
// comparison. motormix's own spool-up ramp (output.spool_up_s) is the one
// difference, and the replay names it.
TEST(UlogImport, TheReplayMatchesPx4AndSaysWhereItDiffers) {
  const std::string in = scratch("flight2.lcmlog"), out = scratch("replayed2.lcmlog");
  import_shared(in);
  const lcmlog::ReplaySummary exact = replay(imported_config({"output.spool_up_s=0"}), in, out);
  const lcmlog::ReferenceComparison& c = exact.reference;
  ASSERT_TRUE(c.present());
  EXPECT_EQ(c.references, 313);
  EXPECT_GE(c.compared, kArmedPx4SamplesMin);
  EXPECT_EQ(c.compared + c.reference_disarmed, c.references);
  EXPECT_EQ(c.unpaired, 0);
  EXPECT_EQ(c.motormix_disarmed, 0);  // armed exactly when PX4 was
  ASSERT_EQ(c.max_difference.size(), 4U);
  for (std::size_t m = 0; m < 4; ++m) {
    EXPECT_LE(c.max_difference[m], kReplayPx4Tolerance) << "motor " << m + 1;
    EXPECT_LE(c.p99_difference[m], c.max_difference[m]);
  }
  EXPECT_EQ(c.differing_spool_up + c.differing_saturated + c.differing_limited + c.differing_other,
            0);
  std::printf("replay vs PX4: %lld commands compared, largest difference %.3g\n",
              static_cast<long long>(c.compared), c.worst);

  // motormix's default ramp after arming: PX4's first commands after arming
  // differ, and only those, each said to be the ramp.
  const lcmlog::ReplaySummary ramped = replay(imported_config(), in, out);
  EXPECT_GT(ramped.reference.worst, kReplayPx4Tolerance);
  EXPECT_GT(ramped.reference.differing_spool_up, 0);
  EXPECT_EQ(ramped.reference.differing_saturated + ramped.reference.differing_limited +
                ramped.reference.differing_other,
            0);

  // Another channel, or none: no comparison, and no cycles after every input.
  lcmlog::ReplayOptions none;
  none.reference_channel.clear();
  lcmlog::ReplaySummary plain;
  std::ostringstream log;
  ASSERT_TRUE(lcmlog::replay_log(imported_config(), in, out, none, plain, log));
  EXPECT_FALSE(plain.reference.present());
  EXPECT_LT(plain.outputs, exact.outputs);
  std::remove(in.c_str());
  std::remove(out.c_str());
}

// The failure detector over the flight's rates and ESC reports: nothing
// declared. The same flight with motor 3's ESC reporting it stopped from
// 20 s (a mid-air failure, as telemetry would show it) is found: the
// detector was judging.
TEST(UlogImport, TheDetectorOverTheFlightDeclaresNothingAndFindsAStoppedMotor) {
  const std::string in = scratch("flight3.lcmlog"), out = scratch("replayed3.lcmlog");
  import_shared(in);
  const config::Config c = imported_config(
      {"failure_detection.enabled=true", "failure_detection.sources=[telemetry, rates]"});
  const lcmlog::ReplaySummary healthy = replay(c, in, out);
  EXPECT_EQ(healthy.detections, 0);
  EXPECT_EQ(healthy.rejected, 0);
  // Both sources were fed while armed (the status says so).
  std::uint8_t sources = 0;
  std::int64_t fed = 0;
  {
    lcmlog::LogReader r(out);
    while (const lcmlog::LogEventView* ev = r.next()) {
      if (ev->channel != "MIXER_STATUS") continue;
      mixer_status_t st{};
      const int size = static_cast<int>(ev->data.size());
      ASSERT_EQ(st.decode(ev->data.data(), 0, size), size);
      sources |= static_cast<std::uint8_t>(st.detector_sources);
      if (st.state == mixer_status_t::STATE_ARMED && st.esc_telemetry_age_ms >= 0 &&
          st.esc_telemetry_age_ms < 200 && st.attitude_age_ms >= 0 && st.attitude_age_ms < 50)
        ++fed;
    }
  }
  EXPECT_EQ(sources, mixer_status_t::DETECTOR_TELEMETRY | mixer_status_t::DETECTOR_RATES);
  EXPECT_GT(fed, 0);

  // The copy: motor 3 reports 0 rpm from 20 s into the flight.
  const std::string stopped = scratch("stopped3.lcmlog");
  {
    lcmlog::LogReader r(in);
    messages::LogWriter w(stopped);
    std::int64_t first = -1;
    while (const lcmlog::LogEventView* ev = r.next()) {
      if (first < 0) first = ev->timestamp;
      esc_telemetry_t m{};
      const int size = static_cast<int>(ev->data.size());
      if (ev->channel == "ESC_TELEMETRY" && ev->timestamp - first > 20'000'000 &&
          m.decode(ev->data.data(), 0, size) == size) {
        m.rpm[2] = 0.0F;
        w.write(ev->channel, ev->timestamp, m);
      } else {
        w.raw(ev->channel, ev->timestamp, ev->data.data(), size);
      }
    }
    ASSERT_TRUE(w.close());
  }
  const lcmlog::ReplaySummary failed = replay(c, stopped, out);
  EXPECT_EQ(failed.detections, 1);
  bool motor3 = false;
  {
    lcmlog::LogReader r(out);
    while (const lcmlog::LogEventView* ev = r.next()) {
      motor_pwm_t p{};
      const int size = static_cast<int>(ev->data.size());
      if (ev->channel == "MOTOR_PWM" && p.decode(ev->data.data(), 0, size) == size)
        motor3 = motor3 || p.failed_motors == (1 << 2);
    }
  }
  EXPECT_TRUE(motor3) << "the failed set named motor 3 alone";
  for (const std::string& f : {in, out, stopped}) std::remove(f.c_str());
}

TEST(UlogImport, DamagedOrForeignInputIsRefusedWithTheReason) {
  const auto refused = [](const std::string& path, const std::string& why) {
    lcmlog::UlogImportSummary s;
    std::ostringstream log;
    EXPECT_FALSE(lcmlog::import_ulog(path, scratch("refused.lcmlog"), {}, s, log));
    EXPECT_NE(log.str().find(why), std::string::npos) << log.str();
  };
  refused("/nonexistent.ulg", "cannot open");
  refused(source_path("config/quad_x.yaml"), "not a ULog");
  // The flight cut after its definitions and parameters: a ULog, with
  // nothing to mix.
  std::ifstream whole(source_path(kSharedFlight), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(whole)),
                          std::istreambuf_iterator<char>());
  const std::string cut = scratch("cut.ulg");
  { std::ofstream(cut, std::ios::binary) << bytes.substr(0, 4096); }
  refused(cut, "no mixing inputs");
  // Cut halfway: what came before the cut is imported.
  { std::ofstream(cut, std::ios::binary) << bytes.substr(0, bytes.size() / 2); }
  lcmlog::UlogImportSummary half;
  std::ostringstream log;
  EXPECT_TRUE(lcmlog::import_ulog(cut, scratch("half.lcmlog"), {}, half, log)) << log.str();
  EXPECT_GT(half.events["PID"], 0);
  EXPECT_LT(half.events["PID"], 1558);
  std::remove(cut.c_str());
  std::remove(scratch("half.lcmlog").c_str());
}

}  // namespace
}  // namespace motormix::test
