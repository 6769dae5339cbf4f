#include "loop/landing_runner.hpp"

#include "loop/durations.hpp"

#include <algorithm>
#include <cmath>

namespace motormix::loop {

LandingRunner::LandingRunner(const config::Config& config)
    : descent_(config.motor_loss->model, config.motor_loss->settings,
               config.motor_loss->equilibria),
      two_rotor_(config.motor_loss->model, config.motor_loss->settings),
      attitude_timeout_us_(seconds_to_us(config.motor_loss->attitude_timeout_s)),
      curve_(esc_curve_of(config)) {}

void LandingRunner::stop() {
  descent_.stop();
  two_rotor_.stop();
}

void LandingRunner::disarmed() {
  stop();
  if (report_.state != DescentPhase::kLanded) report_ = LandingReport{};
}

void LandingRunner::armed() {
  if (report_.state == DescentPhase::kLanded) report_ = LandingReport{};
}

namespace {

int first_motor(MotorMask failed) {
  if (failed == 0) return -1;
  int m = 0;
  while (((failed >> m) & 1U) == 0) ++m;
  return m;
}

// Rates only: no direction to point the spin axis at.
bool to_descent_input(const AttitudeSample& a, double throttle, DescentInput& d) {
  if (!std::isfinite(a.q[0])) return false;
  d.attitude = Eigen::Quaterniond(a.q[0], a.q[1], a.q[2], a.q[3]);
  d.rates = {a.rates[0], a.rates[1], a.rates[2]};
  d.velocity = {a.velocity[0], a.velocity[1], a.velocity[2]};
  d.throttle = throttle;
  return true;
}

}  // namespace

void LandingRunner::drive(const DescentCommand& c, MotorMask failed, const OutputStage& stage,
                          MixerOutput& out) {
  report_.motor = first_motor(failed);
  report_.failed = failed;
  report_.measured_rate_rad_s = c.measured_rate_rad_s;
  report_.axis_error_deg = c.axis_error_deg;
  report_.state =
      c.phase == DescentPhase::kLanded ? DescentPhase::kLanded : DescentPhase::kDescending;
  for (int i = 0; i < stage.outputs(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    const OutputChannel& ch = stage.channel(i);
    const bool dead = ((failed >> i) & 1U) != 0;
    const double value = curve_.output_of(k, c.thrust_fraction[i]);
    out.output[i] =
        dead ? ch.disarmed : std::clamp(value, std::min(ch.min, ch.max), std::max(ch.min, ch.max));
    out.command[i] = dead ? 0.0 : c.thrust_fraction[i];
    out.direction[k] = 0;
  }
  out.armed = true;
  // Yaw is given up; the rest is the descent's own business.
  out.allocation.axis_limited = static_cast<std::uint8_t>(1U << index(Axis::kYaw));
  out.allocation.unallocated.setZero();
  out.allocation.saturated_upper = 0;
  out.allocation.saturated_lower = 0;
}

bool LandingRunner::two_rotor_cycle(const Inputs& in, std::int64_t now_us, const OutputStage& stage,
                                    MixerOutput& out) {
  const TwoRotorPlan* plan = in.flying ? two_rotor_.plan(in.failed) : nullptr;
  const bool fresh = in.attitude->fresh(now_us, attitude_timeout_us_);
  const bool allowed = two_rotor_.running() ? two_rotor_.failed() == in.failed : in.may_start;
  DescentInput d;
  if (plan == nullptr || !plan->found || !fresh || !allowed ||
      !to_descent_input(in.attitude->sample(), in.throttle, d)) {
    stop();
    report_ = LandingReport{};
    if (plan != nullptr && plan->found && allowed) {  // what keeps it from landing: say so
      report_.state = DescentPhase::kNoAttitude;
      report_.motor = first_motor(in.failed);
      report_.failed = in.failed;
    }
    return false;
  }
  if (!two_rotor_.running()) two_rotor_.start(in.failed, now_us, out.command);
  drive(two_rotor_.update(d, now_us), in.failed, stage, out);
  return true;
}

bool LandingRunner::cycle(const Inputs& in, std::int64_t now_us, const OutputStage& stage,
                          MixerOutput& out) {
  if (in.flying && in.failed != 0 && (in.failed & (in.failed - 1)) != 0) {
    descent_.stop();
    return two_rotor_cycle(in, now_us, stage, out);
  }
  two_rotor_.stop();
  const int motor = in.flying ? first_motor(in.failed) : -1;
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
      report_.failed = in.failed;
    }
    return false;
  }
  DescentInput d;
  if (!to_descent_input(in.attitude->sample(), in.throttle, d)) {
    descent_.stop();
    report_ = LandingReport{};
    report_.state = DescentPhase::kNoAttitude;
    report_.motor = motor;
    report_.failed = in.failed;
    return false;
  }
  if (!descent_.running()) descent_.start(motor, now_us, out.command);
  drive(descent_.update(d, now_us), in.failed, stage, out);
  return true;
}

}  // namespace motormix::loop
