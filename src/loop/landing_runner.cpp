#include "loop/landing_runner.hpp"

#include "loop/durations.hpp"

#include <algorithm>
#include <cmath>

namespace motormix::loop {

namespace {

// The one motor of `failed`, or -1 when it is none or several.
int single_motor(MotorMask failed) {
  if (failed == 0 || (failed & (failed - 1)) != 0) return -1;
  int m = 0;
  while (((failed >> m) & 1U) == 0) ++m;
  return m;
}

}  // namespace

LandingRunner::LandingRunner(const config::Config& config)
    : descent_(config.motor_loss->model, config.motor_loss->settings,
               config.motor_loss->equilibria),
      attitude_timeout_us_(seconds_to_us(config.motor_loss->attitude_timeout_s)),
      curve_{config.vehicle_model.esc_min, config.vehicle_model.esc_max,
             config.vehicle_model.thrust_expo} {}

void LandingRunner::disarmed() {
  descent_.stop();
  if (report_.state != DescentPhase::kLanded) report_ = LandingReport{};
}

void LandingRunner::armed() {
  if (report_.state == DescentPhase::kLanded) report_ = LandingReport{};
}

bool LandingRunner::cycle(const Inputs& in, std::int64_t now_us, const OutputStage& stage,
                          MixerOutput& out) {
  const int motor = in.flying ? single_motor(in.failed) : -1;
  const bool fresh = in.attitude->fresh(now_us, attitude_timeout_us_);
  // A failsafe (the controller's stream lost) keeps a landing going; it
  // never starts one: the motors may have stopped on the ground.
  const bool allowed = descent_.running() ? descent_.failed() == motor : in.may_start;
  if (motor < 0 || !fresh || !allowed) {
    descent_.stop();
    report_ = LandingReport{};
    if (motor >= 0 && !fresh) {  // what keeps it from landing: say so
      report_.state = DescentPhase::kNoAttitude;
      report_.motor = motor;
    }
    return false;
  }
  if (!descent_.running()) descent_.start(motor, now_us, out.command);
  const AttitudeSample& a = in.attitude->sample();
  DescentInput d;
  if (std::isfinite(a.q[0])) {
    d.attitude = Eigen::Quaterniond(a.q[0], a.q[1], a.q[2], a.q[3]);
  } else {
    // Rates only: no direction to point the spin axis at. Not enough.
    descent_.stop();
    report_ = LandingReport{DescentPhase::kNoAttitude, motor, 0.0, 0.0};
    return false;
  }
  d.rates = {a.rates[0], a.rates[1], a.rates[2]};
  d.velocity = {a.velocity[0], a.velocity[1], a.velocity[2]};
  d.throttle = in.throttle;
  const DescentCommand& c = descent_.update(d, now_us);
  report_.motor = motor;
  report_.measured_rate_rad_s = c.measured_rate_rad_s;
  report_.axis_error_deg = c.axis_error_deg;
  report_.state =
      c.phase == DescentPhase::kLanded ? DescentPhase::kLanded : DescentPhase::kDescending;
  for (int i = 0; i < stage.outputs(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    const OutputChannel& ch = stage.channel(i);
    const double value = curve_.output_of(k, c.thrust_fraction[i]);
    out.output[i] = i == motor
                        ? ch.disarmed
                        : std::clamp(value, std::min(ch.min, ch.max), std::max(ch.min, ch.max));
    out.command[i] = i == motor ? 0.0 : c.thrust_fraction[i];
    out.direction[k] = 0;
  }
  out.armed = true;
  // Yaw is given up; the rest is the descent's own business.
  out.allocation.axis_limited = static_cast<std::uint8_t>(1U << index(Axis::kYaw));
  out.allocation.unallocated.setZero();
  out.allocation.saturated_upper = 0;
  out.allocation.saturated_lower = 0;
  return true;
}

}  // namespace motormix::loop
