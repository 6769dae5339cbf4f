#include "sim/scoring.hpp"

#include <motormix/angles.hpp>

#include <algorithm>
#include <cmath>

namespace motormix::sim {

namespace {

constexpr double kReachedM = 0.1;  // within this of the commanded altitude: arrived

double wrap(double angle) { return std::remainder(angle, 2 * kPi); }

}  // namespace

DetectionScorer::DetectionScorer(const std::vector<MotorFailure>& failures) {
  for (const MotorFailure& f : failures) outcomes_.push_back({f, -1.0, -1, DetectionSource::kNone});
}

void DetectionScorer::add(double t, MotorMask declared, DetectionSource source,
                          const VehicleModel& vehicle) {
  const MotorMask fresh = declared & ~seen_;
  seen_ |= declared;
  if (declared == 0) seen_ = 0;  // disarmed: a new flight
  for (int m = 0; fresh >> m != 0; ++m) {
    if (((fresh >> m) & 1U) == 0) continue;
    declarations_.push_back({t, m, source, -vehicle.body().position.z(), vehicle.crashed()});
    // The earliest undetected thrust-losing failure of this motor; else the
    // earliest undetected one of any motor (named wrong).
    FailureOutcome* match = nullptr;
    FailureOutcome* other = nullptr;
    for (FailureOutcome& o : outcomes_) {
      if (o.detected_at_s >= 0 || !loses_thrust(o.failure.kind) || o.failure.at_s > t) continue;
      if (o.failure.motor == m && match == nullptr) match = &o;
      if (other == nullptr) other = &o;
    }
    FailureOutcome* o = match != nullptr ? match : other;
    if (o != nullptr) {
      o->detected_at_s = t;
      o->detected_motor = m;
      o->detected_by = source;
    }
    if (match == nullptr) ++false_detections_;
  }
}

void DetectionScorer::finish(SimResult& r) const {
  r.failures = outcomes_;
  r.false_detections = false_detections_;
  r.declarations = declarations_;
}

bool end_of_period(SimResult& r, const VehicleModel& vehicle, std::int64_t k, double t_end) {
  r.min_battery_v = std::min(r.min_battery_v, vehicle.battery().terminal_v());
  r.cycles = k + 1;
  if (!vehicle.crashed()) return false;
  r.crashed = true;
  r.crash_reason = vehicle.crash_reason();
  r.crash_time_s = t_end;
  return true;
}

Scorer::Scorer(const Scenario& scenario, const config::Config& config)
    : from_s_(scenario.score_from_s),
      to_s_(scenario.score_to_s),
      wheeled_(config.thrust_range() == ThrustRange::kBipolar),
      controlled_(config.geometry.controlled),
      period_s_(1.0 / config.loop_rate_hz) {}

void Scorer::add_flight(double t, const VehicleModel& vehicle) {
  const BodyState& b = vehicle.body();
  const Eigen::Vector2d here(b.position.x(), b.position.y());
  if (!drift_from_set_ && failure_s_ >= 0 && t >= failure_s_) {
    drift_from_ = here;
    drift_from_set_ = true;
  }
  const bool landed = vehicle.landed();
  if (touchdown_s_ < 0) drift_to_ = here;
  if (landed && !was_landed_ && vehicle.taken_off() && touchdown_s_ < 0) {
    touchdown_s_ = t;
    touchdown_speed_ = vehicle.touchdown_speed();
  }
  was_landed_ = landed;
  if (!landed && vehicle.taken_off()) {
    max_rate_ = std::max(max_rate_, b.rates.norm());
    max_tilt_ = std::max(max_tilt_, tilt(b.attitude) / kRadPerDeg);
  }
  if (failure_s_ >= 0 && t >= failure_s_ && touchdown_s_ < 0 && !landed) {
    Settle s;
    s.t = t;
    s.rate = b.rates.norm();
    for (int i = 0; i < vehicle.motors(); ++i) s.thrust.push_back(vehicle.thrust_n(i));
    settle_.push_back(std::move(s));
    while (settle_begin_ < settle_.size() && settle_[settle_begin_].t < t - kSettleWindowS) {
      ++settle_begin_;
    }
    if (settle_begin_ > 4096) {  // long runs: keep only the window
      settle_.erase(settle_.begin(), settle_.begin() + static_cast<std::ptrdiff_t>(settle_begin_));
      settle_begin_ = 0;
    }
  }
}

void Scorer::add(double t, const Reference& ref, const ControllerCommand& cmd,
                 const VehicleModel& vehicle, bool armed, std::uint8_t axis_limited) {
  if (armed) ++armed_cycles_;
  if (!wheeled_) add_flight(t, vehicle);
  if (!wheeled_ && ref.altitude_m > 0 &&
      std::abs(ref.altitude_m + vehicle.body().position.z()) < kReachedM) {
    ever_reached_ = true;
  }
  if (t < from_s_ || t > to_s_) return;
  ++scored_;
  const BodyState& b = vehicle.body();
  if (wheeled_) {
    const double ds = ref.speed_mps - vehicle.forward_speed();
    const double dr = (ref.yaw_rate - b.rates.z()) / kRadPerDeg;
    speed_sq_ += ds * ds;
    rate_sq_ += dr * dr;
  } else {
    const Eigen::Vector3d z = b.attitude * Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d z_sp = cmd.attitude_sp * Eigen::Vector3d::UnitZ();
    const double att = std::acos(std::clamp(z.dot(z_sp), -1.0, 1.0)) / kRadPerDeg;
    const double yaw = wrap(ref.yaw - heading(b.attitude)) / kRadPerDeg;
    att_sq_ += att * att;
    yaw_sq_ += yaw * yaw;
    att_max_ = std::max(att_max_, att);
    if (failure_s_ >= 0 && t >= failure_s_ && t <= failure_s_ + kFailureWindowS) {
      failure_att_max_ = std::max(failure_att_max_, att);
    }
    // A drop counts once the vehicle has reached the commanded altitude
    // (within kReachedM) since the command last changed: a climb still on
    // its way is not a loss.
    const double below = ref.altitude_m + b.position.z();
    if (ref.altitude_m != commanded_altitude_) {
      commanded_altitude_ = ref.altitude_m;
      reached_ = false;
    }
    if (below < kReachedM) reached_ = true;
    if (reached_) altitude_loss_ = std::max(altitude_loss_, below);
    altitude_error_max_ = std::max(altitude_error_max_, std::abs(below));
  }
  if (armed && (axis_limited & controlled_) != 0) ++saturated_;
}

void Scorer::finish(SimResult& r) const {
  r.attitude_error_max_deg = att_max_;
  r.failure_attitude_error_max_deg = failure_att_max_;
  r.altitude_loss_m = altitude_loss_;
  r.armed_s = static_cast<double>(armed_cycles_) * period_s_;
  r.reached_altitude = ever_reached_;
  r.altitude_error_max_m = altitude_error_max_;
  r.touchdown_speed_mps = touchdown_speed_;
  r.touchdown_time_s = touchdown_s_;
  r.drift_m = (drift_to_ - drift_from_).norm();
  r.max_spin_rate_rad_s = max_rate_;
  r.max_thrust_axis_tilt_deg = max_tilt_;
  if (settle_begin_ < settle_.size()) {
    const auto n = static_cast<double>(settle_.size() - settle_begin_);
    r.settled_thrust_n.assign(settle_.back().thrust.size(), 0.0);
    for (std::size_t k = settle_begin_; k < settle_.size(); ++k) {
      r.settled_spin_rate_rad_s += settle_[k].rate / n;
      for (std::size_t i = 0; i < r.settled_thrust_n.size(); ++i)
        r.settled_thrust_n[i] += settle_[k].thrust[i] / n;
    }
  }
  if (scored_ == 0) return;
  const auto n = static_cast<double>(scored_);
  r.attitude_error_rms_deg = std::sqrt(att_sq_ / n);
  r.yaw_error_rms_deg = std::sqrt(yaw_sq_ / n);
  r.speed_error_rms_mps = std::sqrt(speed_sq_ / n);
  r.yaw_rate_error_rms_dps = std::sqrt(rate_sq_ / n);
  r.saturated_fraction = static_cast<double>(saturated_) / n;
}

}  // namespace motormix::sim
