// The monitor's screen, drawn from messages without a bus.

#include "bringup/monitor.hpp"

#include <motormix/output_status_t.hpp>

#include <gtest/gtest.h>

namespace motormix::test {
namespace {

bool has(const std::string& text, const std::string& needle) {
  return text.find(needle) != std::string::npos;
}

TEST(MonitorView, ShowsStateFailuresMotorsAndCounters) {
  mixer_status_t st{};
  st.state = mixer_status_t::STATE_FAILSAFE;
  st.failsafe_reason = mixer_status_t::REASON_PID_STALE;
  st.num_motors = 3;
  st.failed_motors = 0b010;
  st.failure_handling = mixer_status_t::FAILURE_AXES_LOST;
  st.axis_held[0] = st.axis_held[1] = st.axis_held[3] = 1;
  st.saturated_upper = 0b001;
  st.axis_limited[2] = 1;
  st.unallocated[2] = -0.25F;
  st.input_age_ms[0] = 4.0F;
  st.input_age_ms[1] = 150.0F;
  st.input_age_ms[2] = -1.0F;
  st.input_age_ms[3] = 20.0F;
  st.pid_stale = 1;
  st.battery_state = mixer_status_t::BATTERY_OK;
  st.battery_voltage = 14.5F;
  st.thrust_gain = 1.158F;
  st.rejected_size = 7;
  st.arming_refused = 3;
  st.arming_refused_not_disarmed_first = 3;
  st.arming_refusal = mixer_status_t::ARMING_REFUSAL_NOT_DISARMED_FIRST;
  st.rejected_bad_length = 3;
  st.rejected_wrong_type = 2;
  st.overruns = 2;
  motor_pwm_t pwm{};
  pwm.num_motors = 3;
  pwm.command = {1.0F, 0.0F, 0.5F};
  pwm.pwm = {2000.0F, 1000.0F, 1500.0F};
  pwm.direction = {0, 0, 0};
  pwm.armed = 1;
  bringup::MonitorSnapshot snap{st, pwm, 0.05, 0.01, {}, std::nullopt, 0.0};
  bringup::MonitorOptions o;
  o.motor_names = {"FL", "FR", "RR"};
  const std::string view = bringup::render_monitor(snap, o, 10);
  EXPECT_TRUE(has(view, "FAILSAFE (pid stale)")) << view;
  EXPECT_TRUE(has(view, "pid 150 ms STALE")) << view;
  EXPECT_TRUE(has(view, "battery never")) << view;
  EXPECT_TRUE(has(view, "FR failed: AXES LOST; held: roll pitch thrust")) << view;
  EXPECT_TRUE(has(view, "FL      [##########] 2000.0 us  SAT-HIGH")) << view;
  EXPECT_TRUE(has(view, "RR      [#####.....] 1500.0 us")) << view;
  EXPECT_TRUE(has(view, "1000.0 us  FAILED")) << view;
  EXPECT_TRUE(has(view, "yaw -0.250!")) << view;
  EXPECT_TRUE(has(view, "14.50 V, thrust x1.158")) << view;
  EXPECT_TRUE(has(view, "array size 7")) << view;
  EXPECT_TRUE(has(view, "arming refused 3 (throttle 0, not disarmed first 3)")) << view;
  EXPECT_TRUE(has(view, "ARMING REFUSED: no setpoint with armed false came first")) << view;
  EXPECT_TRUE(has(view, "wrong type 2   bad length 3")) << view;
  EXPECT_TRUE(has(view, "overruns 2")) << view;
  EXPECT_FALSE(has(view, "\x1b")) << "no escape codes in the view itself";
}

TEST(MonitorView, SaysWhenNothingOrOldStatusArrived) {
  bringup::MonitorOptions o;
  EXPECT_TRUE(has(bringup::render_monitor(bringup::MonitorSnapshot{}, o), "no mixer_status"));
  mixer_status_t st{};
  st.num_motors = 1;
  bringup::MonitorSnapshot old{st, std::nullopt, 4.0, 0.0, {}, std::nullopt, 0.0};
  const std::string view = bringup::render_monitor(old, o);
  EXPECT_TRUE(has(view, "STATUS STALE")) << view;
  EXPECT_TRUE(has(view, "m1")) << view;
  EXPECT_TRUE(has(view, "no outputs seen")) << view;
}

// Whether failure detection and the spin landing are fed: a detector that is
// on with nothing arriving says so, and nothing is said when both are off.
TEST(MonitorView, ShowsWhatTheDetectorAndTheLandingAreFed) {
  bringup::MonitorOptions o;
  mixer_status_t st{};
  st.num_motors = 4;
  st.attitude_age_ms = -1.0F;
  st.esc_telemetry_age_ms = -1.0F;
  const std::string off =
      bringup::render_monitor({st, std::nullopt, 0.0, 0.0, {}, std::nullopt, 0.0}, o);
  EXPECT_FALSE(has(off, "feeds")) << off;

  st.detector_sources = mixer_status_t::DETECTOR_TELEMETRY | mixer_status_t::DETECTOR_RATES;
  st.motor_loss_on = 1;
  st.attitude_age_ms = 3.0F;
  const std::string unfed =
      bringup::render_monitor({st, std::nullopt, 0.0, 0.0, {}, std::nullopt, 0.0}, o);
  EXPECT_TRUE(has(unfed, "detection telemetry rates   spin landing on")) << unfed;
  EXPECT_TRUE(has(unfed, "esc_telemetry never NOT FED")) << unfed;
  EXPECT_TRUE(has(unfed, "attitude 3 ms\n")) << unfed;

  st.detector_sources = 0;
  st.esc_telemetry_age_ms = 12.0F;
  st.attitude_age_ms = -1.0F;
  const std::string landing_only =
      bringup::render_monitor({st, std::nullopt, 0.0, 0.0, {}, std::nullopt, 0.0}, o);
  EXPECT_TRUE(has(landing_only, "detection off   spin landing on   attitude never NOT FED"))
      << landing_only;
  EXPECT_FALSE(has(landing_only, "esc_telemetry 12")) << "telemetry is not read without detection";
}

// motormix output's state (output_status_t): its pins, its counts and the
// chip's report; a configuration that drives pins says when none is heard.
TEST(MonitorView, ShowsTheOutputProcessAndItsFirmware) {
  bringup::MonitorOptions o;
  mixer_status_t st{};
  st.num_motors = 4;
  bringup::MonitorSnapshot snap{st, std::nullopt, 0.0, 0.0, {}, std::nullopt, 0.0};
  EXPECT_FALSE(has(bringup::render_monitor(snap, o), "output ")) << "no driver, no line";
  o.expect_output = true;
  EXPECT_TRUE(has(bringup::render_monitor(snap, o), "output    NOT HEARD on OUTPUT_STATUS"));

  output_status_t out{};
  out.driver = output_status_t::DRIVER_SERIAL;
  out.pins = output_status_t::PINS_STALE;
  out.num_motors = 4;
  out.taken = 1200;
  out.refused_malformed = 3;
  out.refused_out_of_range = 2;
  out.device_open = false;
  out.device_reopened = 2;
  out.firmware_report = true;
  out.firmware_flags = output_status_t::FIRMWARE_CONFIGURED | output_status_t::FIRMWARE_TIMED_OUT;
  out.firmware_crc_errors = 5;
  out.firmware_link_timeouts = 1;
  out.firmware_watchdog_resets = 2;
  snap.output = out;
  snap.output_age_s = 0.1;
  const std::string view = bringup::render_monitor(snap, o);
  EXPECT_TRUE(has(view, "output    serial   pins disarmed (motor_pwm_t STALE)   age 100 ms"))
      << view;
  EXPECT_TRUE(has(view, "taken 1200   refused: signature 0   malformed 3")) << view;
  EXPECT_TRUE(has(view, "range 2")) << view;
  EXPECT_TRUE(has(view, "DEVICE LOST (reopening)   reopened 2")) << view;
  EXPECT_TRUE(has(view, "firmware  configured, disarmed (LINK TIMED OUT)")) << view;
  EXPECT_TRUE(has(view, "crc errors 5")) << view;
  EXPECT_TRUE(has(view, "link timeouts 1   watchdog resets 2")) << view;
  EXPECT_FALSE(bringup::monitor_shows(output_status_t{})) << "0 motors: refused";
}

}  // namespace
}  // namespace motormix::test
