#include <motormix/safety/failure_detector.hpp>

#include <motormix/angles.hpp>

#include <algorithm>
#include <cmath>

namespace motormix {

namespace {

// A rates sample further than this after the previous one starts the
// angular acceleration afresh: a difference across a gap is no derivative.
constexpr double kMaxRatesGapS = 0.05;
// Along-the-column fraction above which a residual is more than one motor's
// whole thrust can explain, even with the scale off by this much.
constexpr double kMaxLoss = 2.0;
// The learned torque scale's bounds: beyond, the vehicle section is wrong.
constexpr double kMinScale = 0.7, kMaxScale = 1.3;
// rpm in thousands for the load (current / krpm^3): keeps the cube in range.
constexpr double kLoadRpmScale = 1000.0;
// A motor whose thrust is at least this share of the most it had in the
// latency window is not being slowed: its load is judged.
constexpr double kSteadyShare = 0.9;
// Below this thrust share a motor's current is too small against an ESC's
// current offset and noise (a few tenths of an ampere) to weigh its prop.
constexpr double kLoadMinThrust = 0.25;

// The reporting interval's running mean: its gain per reading, how many
// times the mean one gap may count, and the largest first gap taken.
constexpr double kIntervalGain = 0.1;
constexpr double kMaxGapShare = 3.0;
constexpr double kMaxIntervalS = 1.0;

// Median of the first n values (n >= 1) of a scratch array (reordered).
double median(std::array<double, kMaxMotors>& v, int n) {
  const auto mid = v.begin() + n / 2;
  std::nth_element(v.begin(), mid, v.begin() + n);
  if (n % 2 == 1) return *mid;
  return 0.5 * (*mid + *std::max_element(v.begin(), mid));
}

double low_pass_alpha(double dt, double time_constant) {
  return time_constant > 0 ? 1.0 - std::exp(-dt / time_constant) : 1.0;
}

bool has(MotorMask mask, int i) { return ((mask >> i) & 1U) != 0; }

}  // namespace

FailureDetector::FailureDetector(const FailureDetectorSettings& settings) : s_(settings) {
  lagged_.setZero(s_.motors);
  output_filtered_.setZero(s_.motors);
  if (s_.torque_per_thrust.cols() != s_.motors) s_.torque_per_thrust.setZero(3, s_.motors);
  reset();
}

void FailureDetector::reset() {
  detection_ = Detection{};
  lagged_.setZero(s_.motors);
  speed_lagged_.fill(0.0);
  lag_count_ = 0;
  rotor_speed_.fill(0.0);
  output_filtered_.setZero(s_.motors);
  telemetry_suspicion_.fill(0.0);
  silent_suspicion_.fill(0.0);
  rates_suspicion_.fill(0.0);
  outputs_suspicion_.fill(0.0);
  telemetry_healthy_.fill(false);
  accel_filtered_.setZero();
  rotor_torque_filtered_.setZero();
  rest_torque_filtered_.setZero();
  // The model's own scale as the prior, worth one time constant of
  // manoeuvring at the smallest judged torque.
  scale_ = 1.0;
  scale_xy_ = scale_xx_ = s_.min_residual_nm * s_.min_residual_nm;
  residual_.setZero();
  filters_primed_ = false;
  updated_ = false;
}

void FailureDetector::on_telemetry(int motor, double rpm, double current_a, std::int64_t now_us) {
  if (motor < 0 || motor >= s_.motors) return;
  EscState& e = esc_[static_cast<std::size_t>(motor)];
  // Its reporting interval: a running mean of the gaps between its readings
  // (several in one message make no gap), each gap counted at most
  // kMaxGapShare times the mean so that one long pause (a lost stretch, a
  // silence that ended) does not teach it. The first gap is taken as it is,
  // up to kMaxIntervalS.
  if (e.any && now_us > e.received_us) {
    const double gap = static_cast<double>(now_us - e.received_us) / 1e6;
    e.interval_s =
        e.interval_s > 0.0
            ? e.interval_s +
                  kIntervalGain * (std::min(gap, kMaxGapShare * e.interval_s) - e.interval_s)
            : std::min(gap, kMaxIntervalS);
  }
  e.rpm = rpm;
  e.current = current_a;
  e.received_us = now_us;
  e.any = true;
}

void FailureDetector::on_rates(const Eigen::Vector3d& rates, std::int64_t sample_us,
                               std::int64_t now_us) {
  const double dt = static_cast<double>(sample_us - rates_sample_us_) / 1e6;
  if (rates_any_ && dt > 0.0 && dt <= kMaxRatesGapS) {
    accel_raw_ = (rates - rates_) / dt;
    accel_any_ = true;
  } else if (!rates_any_ || dt > kMaxRatesGapS) {
    accel_any_ = false;  // nothing to differentiate against yet
  }
  if (dt > 0.0 || !rates_any_) {
    rates_ = rates;
    rates_sample_us_ = sample_us;
  }
  rates_received_us_ = now_us;
  rates_any_ = true;
}

bool FailureDetector::silent(std::size_t i, std::int64_t now_us) const {
  const EscState& e = esc_[i];
  // Not before its interval is known (a second reading): an ESC asked in
  // turn with others may not have had its next turn yet.
  if (!e.any || e.interval_s <= 0.0) return false;
  const double quiet_s = std::max(s_.telemetry_timeout_s, kSilentIntervals * e.interval_s);
  return static_cast<double>(now_us - e.received_us) > quiet_s * 1e6;
}

bool FailureDetector::accumulate(double& suspicion, bool evidence, double dt, double persist) {
  suspicion = evidence ? suspicion + dt : std::max(0.0, suspicion - 2.0 * dt);
  return evidence && suspicion >= persist;
}

double FailureDetector::suspicion_s(DetectionSource source, int motor) const {
  if (motor < 0 || motor >= s_.motors) return 0.0;
  const auto k = static_cast<std::size_t>(motor);
  switch (source) {
    case DetectionSource::kTelemetry:
      return telemetry_suspicion_[k];
    case DetectionSource::kTelemetrySilent:
      return silent_suspicion_[k];
    case DetectionSource::kRates:
      return rates_suspicion_[k];
    case DetectionSource::kOutputs:
      return outputs_suspicion_[k];
    case DetectionSource::kNone:
      break;
  }
  return 0.0;
}

void FailureDetector::declare(int motor, DetectionSource source, std::int64_t now_us) {
  detection_.failed |= MotorMask{1} << motor;
  detection_.source = source;
  detection_.motor = motor;
  detection_.at_us = now_us;
  // What the other motors looked like included this one's loss: their
  // suspicions start again from the vehicle as it now is.
  telemetry_suspicion_.fill(0.0);
  silent_suspicion_.fill(0.0);
  rates_suspicion_.fill(0.0);
  outputs_suspicion_.fill(0.0);
}

const Detection& FailureDetector::update(const MotorVector& thrust, MotorMask excluded,
                                         bool allowed, std::int64_t now_us) {
  const double dt =
      updated_ ? std::max(0.0, static_cast<double>(now_us - last_update_us_) / 1e6) : 0.0;
  updated_ = true;
  last_update_us_ = now_us;
  excluded |= detection_.failed;

  // The filters' factors, computed again only when the period changes (a
  // loop's period rarely does: five exponentials a cycle saved).
  if (dt != alpha_dt_) {
    alpha_dt_ = dt;
    alpha_.up = low_pass_alpha(dt, s_.time_constant_up_s);
    alpha_.down = low_pass_alpha(dt, s_.time_constant_down_s);
    alpha_.rates = low_pass_alpha(dt, 1.0 / (kTwoPi * s_.rates_filter_hz));
    alpha_.scale = low_pass_alpha(dt, s_.scale_time_constant_s);
    alpha_.outputs = low_pass_alpha(dt, s_.outputs_filter_s);
  }
  const double up = alpha_.up;
  const double down = alpha_.down;
  const int n = std::min<int>(s_.motors, static_cast<int>(thrust.size()));
  for (int i = 0; i < n; ++i) {
    const double target = has(excluded, i) ? 0.0 : std::clamp(thrust[i], 0.0, 1.0);
    lagged_[i] += (target - lagged_[i]) * (target > lagged_[i] ? up : down);
    // The same lag on the rotor's speed instead of its thrust (how most
    // simulators and many motors have it): its thrust, the speed squared,
    // is never above the thrust lag's from a steady start.
    double& speed = speed_lagged_[static_cast<std::size_t>(i)];
    const double target_speed = std::sqrt(target);
    speed += (target_speed - speed) * (target_speed > speed ? up : down);
  }
  // The rotors' momentum, and the reaction torque of its change since the
  // last update (the rotor speeds follow the lagged thrusts as their square
  // roots).
  rotor_reaction_.setZero();
  rotor_momentum_.setZero();
  const bool spinning_mass = s_.max_rotor_speed_rad_s > 0.0 && s_.momentum_per_speed.cols() >= n;
  for (int i = 0; spinning_mass && i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const double speed = s_.max_rotor_speed_rad_s * std::sqrt(std::max(lagged_[i], 0.0));
    rotor_momentum_ += speed * s_.momentum_per_speed.col(i);
    if (dt > 0.0) rotor_reaction_ -= (speed - rotor_speed_[k]) / dt * s_.momentum_per_speed.col(i);
    rotor_speed_[k] = speed;
  }
  lag_head_ = (lag_head_ + 1) % kLagHistory;
  lag_count_ = std::min(lag_count_ + 1, kLagHistory);
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const auto slot = static_cast<std::size_t>(lag_head_);
    lag_history_[slot][k] = lagged_[i];
    lag_low_history_[slot][k] = std::min(lagged_[i], speed_lagged_[k] * speed_lagged_[k]);
  }
  lag_history_us_[static_cast<std::size_t>(lag_head_)] = now_us;

  if (uses(DetectorSources::kTelemetry)) judge_telemetry(excluded, allowed, dt, now_us);
  if (uses(DetectorSources::kRates)) judge_rates(excluded, allowed, dt, now_us);
  if (uses(DetectorSources::kOutputs)) judge_outputs(thrust, excluded, allowed, dt, now_us);
  return detection_;
}

void FailureDetector::judge_telemetry(MotorMask excluded, bool allowed, double dt,
                                      std::int64_t now_us) {
  const auto timeout_us = static_cast<std::int64_t>(s_.telemetry_timeout_s * 1e6);
  const auto latency_us = static_cast<std::int64_t>(s_.telemetry_latency_s * 1e6);
  // What a motor's thrust was while its reading can have been measured:
  // from the latency before it arrived until now. `least` is the least of it
  // (the kindest thrust to judge a slow rpm by), `mid` the thrust half the
  // latency before it arrived (the likeliest; the ring holds kLagHistory
  // cycles, at most that far back).
  struct Window {
    double least, mid, most;
  };
  const auto window = [&](std::size_t k, std::int64_t received_us) {
    const double now = lagged_[static_cast<Eigen::Index>(k)];
    const double low_now = std::min(now, speed_lagged_[k] * speed_lagged_[k]);
    Window w{low_now, now, now};
    const std::int64_t mid_us = received_us - latency_us / 2;
    for (int back = 1; back < lag_count_; ++back) {
      const auto slot = static_cast<std::size_t>((lag_head_ - back + kLagHistory) % kLagHistory);
      if (lag_history_us_[slot] < received_us - latency_us) break;
      w.least = std::min(w.least, lag_low_history_[slot][k]);
      w.most = std::max(w.most, lag_history_[slot][k]);
      if (lag_history_us_[slot] >= mid_us) w.mid = lag_history_[slot][k];
    }
    return w;
  };
  // Each judged motor's ratio of rpm (or current) to what its thrust should
  // give, up to a common scale: at its likeliest thrust (ratio: current
  // only), at the kindest to a slow motor (best: the least thrust) and to a
  // fast one (fastest: the most); kind: 1 rpm, 2 current, 0 not judged.
  std::array<double, kMaxMotors> ratio{}, best{}, fastest{}, load{};
  std::array<std::uint8_t, kMaxMotors> kind{};
  // Whether load[k] was measured: a thrown prop's current is noise around
  // zero, so a load at or below zero is the most unloaded, not "none".
  std::array<bool, kMaxMotors> has_load{};
  std::array<double, kMaxMotors> rpm_ratios{}, current_ratios{}, loads{};
  int n_rpm = 0, n_current = 0, n_load = 0, fresh = 0;
  for (int i = 0; i < s_.motors; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const EscState& e = esc_[k];
    if (!e.any || silent(k, now_us)) continue;
    ++fresh;
    // Too old to judge (a slow ESC between two of its readings).
    if (now_us - e.received_us > timeout_us) continue;
    if (has(excluded, i) || lagged_[i] < s_.min_motor_thrust) continue;
    // Below min_motor_thrust at any time its reading can come from, it is
    // not judged (near idle, rpm says little).
    const Window w = window(k, e.received_us);
    if (w.least < s_.min_motor_thrust) continue;
    const double mid = w.mid, least = w.least;
    if (std::isfinite(e.rpm)) {
      best[k] = e.rpm / std::sqrt(least);
      fastest[k] = e.rpm / std::sqrt(w.most);
      kind[k] = 1;
      // A slow motor is judged against each motor at its least kind: a
      // reading fresher than the assumed latency on motors spinning up fast
      // (the spin landing's raise) would lift the median of likeliest
      // ratios and make the motor slowed beside them look dead.
      rpm_ratios[static_cast<std::size_t>(n_rpm++)] = fastest[k];
      // The prop's load: battery current grows as the cube of the rpm for a
      // given prop. Not while the motor is being slowed (a braking ESC's
      // current says nothing of its prop).
      const double krpm = e.rpm / kLoadRpmScale;
      if (s_.load_ratio > 0.0 && std::isfinite(e.current) && krpm > 0.0 &&
          w.least >= kLoadMinThrust && lagged_[i] >= kSteadyShare * w.most) {
        load[k] = e.current / (krpm * krpm * krpm);
        has_load[k] = true;
        loads[static_cast<std::size_t>(n_load++)] = load[k];
      }
    } else if (std::isfinite(e.current)) {
      ratio[k] = e.current / (mid * std::sqrt(mid));
      best[k] = e.current / (least * std::sqrt(least));
      kind[k] = 2;
      current_ratios[static_cast<std::size_t>(n_current++)] = ratio[k];
    }
  }
  const double rpm_median = n_rpm >= s_.min_reporting ? median(rpm_ratios, n_rpm) : 0.0;
  const double current_median =
      n_current >= s_.min_reporting ? median(current_ratios, n_current) : 0.0;
  const double load_median = n_load >= s_.min_reporting ? median(loads, n_load) : 0.0;
  const auto unloaded = [&](std::size_t k) {
    return load_median > 0.0 && has_load[k] && load[k] < s_.load_ratio * load_median;
  };
  // A fast motor is judged against the motors that are not too slow: two
  // motors stopped on a quad put the median halfway to zero, and the two
  // healthy ones would look twice too fast. Each at its kindest to the one
  // judged, for the same reason as above, the other way round.
  std::array<double, kMaxMotors> spinning{};
  int n_spinning = 0;
  for (int i = 0; i < s_.motors && rpm_median > 0.0; ++i) {
    const auto k = static_cast<std::size_t>(i);
    if (kind[k] == 1 && best[k] >= s_.rpm_ratio * rpm_median)
      spinning[static_cast<std::size_t>(n_spinning++)] = best[k];
  }
  const double fast_median = n_spinning >= s_.min_reporting ? median(spinning, n_spinning) : 0.0;
  const auto too_fast = [&](std::size_t k) {
    return fast_median > 0.0 && fastest[k] > s_.rpm_high_ratio * fast_median;
  };

  detection_.telemetry_silent = 0;
  for (int i = 0; i < s_.motors; ++i) {
    const auto k = static_cast<std::size_t>(i);
    telemetry_healthy_[k] =
        (kind[k] == 1 && rpm_median > 0 && best[k] >= s_.rpm_ratio * rpm_median && !too_fast(k) &&
         !unloaded(k)) ||
        (kind[k] == 2 && current_median > 0 && best[k] >= s_.current_ratio * current_median);
  }
  // Silence alone stops a motor only where that costs nothing the vehicle
  // needs, and never when the rates can tell a dead motor from a dead wire.
  const bool silence_declares = s_.silence_declares && !uses(DetectorSources::kRates);
  for (int i = 0; i < s_.motors; ++i) {
    const auto k = static_cast<std::size_t>(i);
    if (has(excluded, i)) continue;
    // Silent: it reported before, it no longer does, and most others do.
    const bool silent = this->silent(k, now_us) && 2 * fresh >= s_.motors;
    if (silent) detection_.telemetry_silent |= MotorMask{1} << i;
    // Too slow for its command (stopped, desynced), or too fast: a prop
    // thrown or broken unloads the motor, which then outruns its command.
    const bool low =
        (kind[k] == 1 && rpm_median > 0 &&
         (best[k] < s_.rpm_ratio * rpm_median || too_fast(k) || unloaded(k))) ||
        (kind[k] == 2 && current_median > 0 && best[k] < s_.current_ratio * current_median);
    if (!allowed) {
      telemetry_suspicion_[k] = 0.0;
      silent_suspicion_[k] = 0.0;
      continue;
    }
    if (accumulate(telemetry_suspicion_[k], low, dt, s_.telemetry_persist_s)) {
      declare(i, DetectionSource::kTelemetry, now_us);
      return;
    }
    if (accumulate(silent_suspicion_[k], silent && silence_declares, dt, s_.telemetry_persist_s)) {
      declare(i, DetectionSource::kTelemetrySilent, now_us);
      return;
    }
  }
}

void FailureDetector::judge_rates(MotorMask excluded, bool allowed, double dt,
                                  std::int64_t now_us) {
  const auto timeout_us = static_cast<std::int64_t>(s_.rates_timeout_s * 1e6);
  const bool fresh = rates_any_ && accel_any_ && now_us - rates_received_us_ <= timeout_us;
  if (!fresh) {
    filters_primed_ = false;
    rates_suspicion_.fill(0.0);
    residual_.setZero();
    return;
  }
  const Eigen::Vector3d& w = rates_;
  const Eigen::Vector3d iw = s_.inertia_kgm2.cwiseProduct(w);
  Eigen::Vector3d rotors;
  rotors.noalias() = s_.torque_per_thrust * lagged_;
  const Eigen::Vector3d rest =
      -s_.rotational_drag * w - w.cross(iw + rotor_momentum_) + rotor_reaction_;
  // Both sides through the same second-order low-pass (two first-order
  // stages): differentiating the rates lifts the frame's vibration by its
  // frequency, and a second stage takes it back down where a first leaves
  // it as large as a failure's torque.
  if (!filters_primed_) {
    accel_stage_ = accel_filtered_ = accel_raw_;
    rotor_torque_stage_ = rotor_torque_filtered_ = rotors;
    rest_torque_stage_ = rest_torque_filtered_ = rest;
    filters_primed_ = true;
  } else {
    const double a = alpha_.rates;
    accel_stage_ += a * (accel_raw_ - accel_stage_);
    rotor_torque_stage_ += a * (rotors - rotor_torque_stage_);
    rest_torque_stage_ += a * (rest - rest_torque_stage_);
    accel_filtered_ += a * (accel_stage_ - accel_filtered_);
    rotor_torque_filtered_ += a * (rotor_torque_stage_ - rotor_torque_filtered_);
    rest_torque_filtered_ += a * (rest_torque_stage_ - rest_torque_filtered_);
  }
  // What the rotors' torque did, measured: inertia times acceleration, less
  // drag and the gyroscopic term.
  const Eigen::Vector3d measured =
      s_.inertia_kgm2.cwiseProduct(accel_filtered_) - rest_torque_filtered_;
  // The rotors' torque per unit of the modelled one, learned while the
  // vehicle flies healthy and manoeuvres (battery sag, ESC curve, prop
  // wear): the modelled torque is scaled by it. Not while anything is
  // suspected (a failure must not teach it), nor without excitation.
  const double excitation = rotor_torque_filtered_.squaredNorm();
  bool suspected = false;
  for (int i = 0; i < s_.motors; ++i) {
    suspected = suspected || rates_suspicion_[static_cast<std::size_t>(i)] > 0.0;
  }
  // Only what a scale explains teaches it: the residual before this update
  // must lie along the modelled torque (an outside torque, a gust, mostly
  // does not until the controller has answered it, and by then it is
  // suspected or small).
  const Eigen::Vector3d across =
      residual_ - (excitation > 0.0 ? residual_.dot(rotor_torque_filtered_) / excitation : 0.0) *
                      rotor_torque_filtered_;
  // And only a residual a scale inside its range can explain: a motor that
  // loses its thrust over a few hundred milliseconds (a freewheeling rotor)
  // leaves one along the modelled torque too, but larger than that, and
  // learning it would shrink the loss below min_loss.
  const bool scale_explains =
      residual_.norm() <= (kMaxScale - 1.0) * std::sqrt(excitation) + 0.5 * s_.min_residual_nm;
  if (allowed && !suspected && excitation >= s_.min_residual_nm * s_.min_residual_nm &&
      across.norm() < 0.5 * s_.min_residual_nm && scale_explains) {
    const double forget = alpha_.scale;
    scale_xy_ += forget * (rotor_torque_filtered_.dot(measured) - scale_xy_);
    scale_xx_ += forget * (excitation - scale_xx_);
    if (scale_xx_ > 0.0) scale_ = std::clamp(scale_xy_ / scale_xx_, kMinScale, kMaxScale);
  }
  residual_ = measured - scale_ * rotor_torque_filtered_;

  // The motor whose loss explains the residual best, if any does.
  int best = -1;
  double best_off = s_.max_off_axis;
  const double residual_norm = residual_.norm();
  if (allowed && residual_norm >= s_.min_residual_nm) {
    for (int i = 0; i < s_.motors; ++i) {
      if (has(excluded, i) || lagged_[i] < s_.min_motor_thrust) continue;
      // An ESC reporting the speed its command asks for is spinning: an
      // outside torque is pushing, not this motor failing.
      if (telemetry_healthy_[static_cast<std::size_t>(i)]) continue;
      const Eigen::Vector3d loss = s_.torque_per_thrust.col(i) * lagged_[i];
      const double loss_sq = loss.squaredNorm();
      if (loss_sq <= 0.0) continue;
      const double along = -residual_.dot(loss) / loss_sq;
      if (along < s_.min_loss || along > kMaxLoss) continue;
      const double off = (residual_ + along * loss).norm() / (along * std::sqrt(loss_sq));
      if (off <= best_off) {
        best_off = off;
        best = i;
      }
    }
  }
  for (int i = 0; i < s_.motors; ++i) {
    const auto k = static_cast<std::size_t>(i);
    if (!allowed) {
      rates_suspicion_[k] = 0.0;
      continue;
    }
    if (accumulate(rates_suspicion_[k], i == best, dt, s_.rates_persist_s)) {
      declare(i, DetectionSource::kRates, now_us);
      return;
    }
  }
}

void FailureDetector::judge_outputs(const MotorVector& thrust, MotorMask excluded, bool allowed,
                                    double dt, std::int64_t now_us) {
  const double a = alpha_.outputs;
  // Only the first failure: once a motor is out, the others' commands are
  // uneven by design and say nothing about a second.
  allowed = allowed && excluded == 0;
  std::array<double, kMaxMotors> working{};
  int n = 0, top = -1;
  for (int i = 0; i < s_.motors; ++i) {
    const double target = has(excluded, i) ? 0.0 : std::clamp(thrust[i], 0.0, 1.0);
    output_filtered_[i] += a * (target - output_filtered_[i]);
    if (has(excluded, i)) continue;
    working[static_cast<std::size_t>(n++)] = output_filtered_[i];
    if (top < 0 || output_filtered_[i] > output_filtered_[top]) top = i;
  }
  if (n < 2) return;
  const double mid = median(working, n);
  for (int i = 0; i < s_.motors; ++i) {
    const auto k = static_cast<std::size_t>(i);
    if (!allowed) {
      outputs_suspicion_[k] = 0.0;
      continue;
    }
    const bool evidence = i == top && output_filtered_[i] >= s_.outputs_high &&
                          output_filtered_[i] - mid >= s_.outputs_margin;
    if (accumulate(outputs_suspicion_[k], evidence, dt, s_.outputs_persist_s)) {
      declare(i, DetectionSource::kOutputs, now_us);
      return;
    }
  }
}

}  // namespace motormix
