#include <motormix/safety/spinning_descent.hpp>

#include <motormix/angles.hpp>

#include "descent_collective.hpp"
#include "spin_dynamics.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>

namespace motormix {

namespace {

// Landed (Touchdown) only while the thrust asked for is below this share
// of the weight: in the air that much less would have the vehicle moving
// down within a fraction of landed_after_s.
constexpr double kLandedThrustShare = 0.8;
// The spin is reached at this share of the equilibrium rate; lost below
// Touchdown's share of it.
constexpr double kSpinReachedShare = 0.6;
// The rate loop crosses over where the motors' lag and the rates' delay
// together cost this much phase (45 degrees left); the attitude loop runs
// this many times slower than the rate loop.
constexpr double kRateLoopLagRad = kPi / 4.0;
constexpr double kLoopSeparation = 2.5;
constexpr double kThrustWeight = 0.3;
// Null-direction entries smaller than this are zero (a motor the raise leaves alone).
constexpr double kNullEpsilon = 1e-12;
// The spin-up's raise lasts at most this many times the spin-up the model
// gives at the raise's most (see the constructor).
constexpr double kSpinUpAllowance = 2.0;

// The rate at which a first-order lag T and a delay d cost kRateLoopLagRad
// of phase: atan(w T) + w d = kRateLoopLagRad, increasing in w (bisection).
double lag_limited_gain(double lag_s, double delay_s) {
  double lo = 0.0, hi = 1e4;
  for (int i = 0; i < 60; ++i) {
    const double w = 0.5 * (lo + hi);
    (std::atan(w * lag_s) + w * delay_s > kRateLoopLagRad ? hi : lo) = w;
  }
  return lo;
}

}  // namespace

Eigen::Vector3d SpinningDescent::allocate(const SpinEquilibrium& eq,
                                          const Eigen::Vector3d& demand) const {
  const auto fk = static_cast<std::size_t>(eq.failed);
  const Eigen::Matrix3d& a = allocation_[fk];
  Eigen::Vector3d lo, hi;
  for (Eigen::Index j = 0; j < 3; ++j) {
    const auto k = static_cast<std::size_t>(eq.working[static_cast<std::size_t>(j)]);
    lo[j] = m_.min_thrust_n[k];
    hi[j] = m_.max_thrust_n[k];
  }
  const Eigen::Vector3d exact = allocation_inverse_[fk] * demand;
  if ((exact.array() >= lo.array()).all() && (exact.array() <= hi.array()).all()) return exact;
  // Weighted least squares on the box: every pattern of motors held at a
  // bound, the others solved freely; the best one inside the box is the
  // optimum (the problem is convex, and the optimum has some such pattern).
  const Eigen::Vector3d w(thrust_weight_, 1.0, 1.0);
  const Eigen::Matrix3d wa = w.asDiagonal() * a;
  const Eigen::Vector3d wd = w.cwiseProduct(demand);
  Eigen::Vector3d best = exact.cwiseMax(lo).cwiseMin(hi);
  double best_cost = (wa * best - wd).squaredNorm();
  for (int pattern = 0; pattern < 27; ++pattern) {
    Eigen::Vector3d f;
    std::array<int, 3> state{pattern % 3, (pattern / 3) % 3, pattern / 9};  // 0 free, 1 lo, 2 hi
    int free = 0;
    for (Eigen::Index j = 0; j < 3; ++j) {
      const int st = state[static_cast<std::size_t>(j)];
      f[j] = st == 1 ? lo[j] : st == 2 ? hi[j] : 0.0;
      if (st == 0) ++free;
    }
    if (free > 0) {
      // Normal equations on the free motors; a held motor's row and column
      // are the identity (its correction 0). The allocation matrix is
      // invertible, so any set of its columns is independent and this is
      // positive definite.
      Eigen::Matrix3d normal = wa.transpose() * wa;
      Eigen::Vector3d rhs = wa.transpose() * (wd - wa * f);
      for (Eigen::Index j = 0; j < 3; ++j) {
        if (state[static_cast<std::size_t>(j)] == 0) continue;
        normal.row(j).setZero();
        normal.col(j).setZero();
        normal(j, j) = 1.0;
        rhs[j] = 0.0;
      }
      f += normal.inverse() * rhs;
    }
    if ((f.array() < lo.array() - 1e-9).any() || (f.array() > hi.array() + 1e-9).any()) continue;
    const double cost = (wa * f - wd).squaredNorm();
    if (cost < best_cost) {
      best_cost = cost;
      best = f;
    }
  }
  return best;
}

SpinningDescent::SpinningDescent(const SpinningDescentModel& model,
                                 const SpinningDescentSettings& settings)
    : SpinningDescent(model, settings, solve_spin_equilibria(model, settings.spin_rate_rad_s)) {}

SpinningDescent::SpinningDescent(const SpinningDescentModel& model,
                                 const SpinningDescentSettings& settings,
                                 const SpinEquilibria& equilibria)
    : m_(model), s_(settings), equilibria_(equilibria) {
  for (int failed = 0; failed < 4; ++failed) {
    const auto k = static_cast<std::size_t>(failed);
    Eigen::Matrix3d a;
    for (Eigen::Index j = 0; j < 3; ++j) {
      const auto motor =
          static_cast<std::size_t>(equilibria_[k].working[static_cast<std::size_t>(j)]);
      a(0, j) = -m_.axis[motor].z();
      a(1, j) = m_.torque_per_newton[motor].x();
      a(2, j) = m_.torque_per_newton[motor].y();
    }
    allocation_[k] = a;
    allocation_inverse_[k] = a.inverse();
    // The spin-up's direction: the torque rows' null direction, the way
    // that raises the thrust.
    Eigen::Vector3d n = Eigen::Vector3d(a.row(1)).cross(Eigen::Vector3d(a.row(2)));
    if (a.row(0).dot(n) < 0.0) n = -n;
    spin_up_direction_[k] = n;
    // How long the spin-up takes at most: the yaw acceleration with the
    // raised motors at full thrust and the other at its least brings the
    // body to the spin that counts as reached in this long; the raise is
    // given twice that (the model can be wrong, a gust can hold the spin
    // back) and then ends, whatever the spin, so that a vehicle whose spin
    // falls short of it (lighter or draggier than configured) still comes
    // down.
    double yaw = 0.0;
    for (Eigen::Index j = 0; j < 3; ++j) {
      const auto motor =
          static_cast<std::size_t>(equilibria_[k].working[static_cast<std::size_t>(j)]);
      const double thrust =
          std::abs(n[j]) > kNullEpsilon ? m_.max_thrust_n[motor] : m_.min_thrust_n[motor];
      yaw += m_.torque_per_newton[motor].z() * thrust;
    }
    const double reach = kSpinReachedShare * equilibria_[k].rates.norm();
    spin_up_s_[k] = std::abs(yaw) > 0.0 && std::isfinite(reach)
                        ? kSpinUpAllowance * m_.inertia_kgm2.z() * reach / std::abs(yaw)
                        : 0.0;
  }
  cmd_.thrust_fraction.setZero(4);
  // Thrust counts for this much of a torque error of its newton times the
  // mean arm: height can be lost for a moment, the attitude cannot.
  double arm = 0.0;
  for (const Eigen::Vector3d& t : m_.torque_per_newton) arm += detail::planar(t).norm() / 4.0;
  thrust_weight_ = kThrustWeight * arm;
  // A rate loop faster than its lag allows rings: with a 40 ms motor lag and
  // the 5.6 ms of a 40 Hz gyro filter, 30/s leaves 30 degrees of phase and
  // the spin goes into a limit cycle that saturates the motors.
  rate_gain_ = std::min(s_.rate_gain, lag_limited_gain(std::max(m_.time_constant_s, 0.0),
                                                       std::max(m_.rate_delay_s, 0.0)));
  attitude_gain_ = std::min(s_.attitude_gain, rate_gain_ / kLoopSeparation);
}

void SpinningDescent::start(int failed, std::int64_t now_us, const MotorVector& thrust_fraction) {
  failed_ = failed;
  const SpinEquilibrium& eq = equilibria_[static_cast<std::size_t>(failed)];
  for (Eigen::Index j = 0; j < 3; ++j) {
    const auto k = static_cast<std::size_t>(eq.working[static_cast<std::size_t>(j)]);
    const double x = static_cast<Eigen::Index>(k) < thrust_fraction.size()
                         ? thrust_fraction[static_cast<Eigen::Index>(k)]
                         : 0.0;
    lagged_n_[j] = std::isfinite(x) ? std::clamp(x, 0.0, 1.0) * m_.max_thrust_n[k] : 0.0;
  }
  last_us_ = now_us;
  velocity_integral_ = 0.0;
  up_force_ = 0.0;
  since_start_s_ = 0.0;
  touchdown_.reset();
  spin_reached_ = false;
  cmd_ = DescentCommand{};
  cmd_.thrust_fraction.setZero(4);
  cmd_.phase = DescentPhase::kDescending;
}

void SpinningDescent::stop() {
  failed_ = -1;
  cmd_.phase = DescentPhase::kOff;
  cmd_.thrust_fraction.setZero(4);
}

double SpinningDescent::collective(const DescentInput& in, const Eigen::Vector3d& up_body,
                                   double dt) {
  detail::CollectiveState state{velocity_integral_, up_force_};
  const double thrust = detail::descent_collective(m_, s_, in, up_body, dt, state);
  velocity_integral_ = state.velocity_integral;
  up_force_ = state.up_force;
  return thrust;
}

// The spin-up, before the spin is reached: the body has no gyroscopic
// stiffness yet, and how soon it has it depends on the yaw torque alone,
// which is largest with the two motors beside the dead one at full thrust.
// So the thrusts the demands asked for are raised along the one direction
// that changes neither tilting torque (the torque rows' null direction: the
// two motors beside the dead one together, for a quad), as far as the
// motors' ranges allow. Its cost is a climb, bounded: the raise fades out as
// the vehicle climbs toward descent_rate_mps (as fast up as it will come
// down), there is none without a velocity, and it ends after spin_up_s_
// (twice the spin-up the model gives) whatever the spin.
Eigen::Vector3d SpinningDescent::spin_up(const SpinEquilibrium& eq, const Eigen::Vector3d& f,
                                         const DescentInput& in) const {
  if (!std::isfinite(in.velocity.z()) || std::abs(in.velocity.z()) >= detail::kMaxSpeedMps ||
      s_.descent_rate_mps <= 0.0) {
    return f;
  }
  const auto fk = static_cast<std::size_t>(eq.failed);
  if (since_start_s_ >= spin_up_s_[fk]) return f;
  const Eigen::Vector3d& n = spin_up_direction_[fk];
  double most = std::numeric_limits<double>::infinity();
  for (Eigen::Index j = 0; j < 3; ++j) {
    const auto k = static_cast<std::size_t>(eq.working[static_cast<std::size_t>(j)]);
    if (n[j] > kNullEpsilon) most = std::min(most, (m_.max_thrust_n[k] - f[j]) / n[j]);
    if (n[j] < -kNullEpsilon) most = std::min(most, (f[j] - m_.min_thrust_n[k]) / -n[j]);
  }
  if (!std::isfinite(most) || most <= 0.0) return f;
  // NED: velocity.z is negative climbing; at -descent_rate the raise is gone.
  const double share =
      std::clamp((in.velocity.z() + s_.descent_rate_mps) / s_.descent_rate_mps, 0.0, 1.0);
  return f + share * most * n;
}

const DescentCommand& SpinningDescent::update(const DescentInput& in, std::int64_t now_us) {
  if (failed_ < 0 || cmd_.phase != DescentPhase::kDescending) return cmd_;
  const double dt = std::clamp(static_cast<double>(now_us - last_us_) / 1e6, 0.0, detail::kMaxDtS);
  last_us_ = now_us;
  since_start_s_ += dt;
  // The loop's checks keep non-finite inputs out; should one arrive anyway,
  // the previous command stands (it is inside the motors' range).
  if (!in.attitude.coeffs().allFinite() || in.attitude.norm() < 0.5 || !in.rates.allFinite()) {
    return cmd_;
  }
  const auto fk = static_cast<std::size_t>(failed_);
  const SpinEquilibrium& eq = equilibria_[fk];
  const Eigen::Matrix3d rot = in.attitude.normalized().toRotationMatrix();  // body -> NED
  const Eigen::Vector3d w = in.rates.cwiseMax(-detail::kMaxRateRadS).cwiseMin(detail::kMaxRateRadS);
  cmd_.measured_rate_rad_s = w.norm();

  // Where the spin axis should point: up, tilted against the horizontal
  // velocity (at most max_tilt) once the spin is reached. Before that the
  // vehicle has no gyroscopic stiffness and one of its tilting torques
  // only one sign (the dead motor's side cannot push up): every bit of
  // authority goes to holding the axis up, and the drift waits.
  if (cmd_.measured_rate_rad_s >= kSpinReachedShare * eq.rates.norm()) spin_reached_ = true;
  SpinningDescentSettings braking = s_;
  if (!spin_reached_) braking.max_tilt_deg = 0.0;
  const Eigen::Vector3d desired = detail::wanted_up_body(braking, in, rot);
  const Eigen::Vector3d& axis = eq.up;
  cmd_.axis_error_deg = std::acos(std::clamp(axis.dot(desired), -1.0, 1.0)) * detail::kDegPerRad;

  // Reduced attitude: rates across the axis turn it toward `desired`; the
  // rate about it is whatever it is.
  const Eigen::Vector3d rates_wanted = attitude_gain_ * axis.cross(desired) + w.dot(axis) * axis;
  Eigen::Vector3d accel = rate_gain_ * (rates_wanted - w);
  accel -= accel.dot(axis) * axis;
  Eigen::Vector3d feedback = m_.inertia_kgm2.cwiseProduct(accel);
  // The feedback turns with the body at the spin rate: lead it by the motor
  // lag, (1 + T s) for a vector turning at -spin about the axis.
  const double spin = w.dot(axis);
  feedback -= m_.time_constant_s * spin * axis.cross(feedback);
  const Eigen::Vector3d hold =
      detail::holding_torque(m_, w, detail::rotor_momentum(m_, eq.working, lagged_n_));

  const Eigen::Vector3d up_body = rot.transpose() * Eigen::Vector3d(0.0, 0.0, -1.0);
  const double thrust = collective(in, up_body, dt);

  // Three motors, three demands: the thrusts closest to them within each
  // motor's range (least squares, thrust weighted below the torques: the
  // vehicle can lose some height, not its attitude).
  const Eigen::Vector3d demand(thrust, hold.x() + feedback.x(), hold.y() + feedback.y());
  Eigen::Vector3d f = allocate(eq, demand);
  const Eigen::Vector3d got = allocation_[fk] * f;
  cmd_.saturated = (got - demand).cwiseAbs().maxCoeff() > 1e-6;
  if (s_.spin_up_raise && !spin_reached_ && !cmd_.saturated) f = spin_up(eq, f, in);

  // Landing: no vertical motion for landed_after_s while the velocity loop
  // asks for well under the weight (in the air that much less thrust would
  // have the vehicle moving down within a fraction of that time).
  if (std::isfinite(in.velocity.z())) {
    const bool not_moving =
        touchdown_.update(in.velocity.z(), s_.descent_rate_mps, cmd_.measured_rate_rad_s,
                          up_force_ < kLandedThrustShare * m_.mass_kg * kStandardGravity, dt);
    const bool spin_lost = not_moving && spin_reached_ &&
                           cmd_.measured_rate_rad_s < Touchdown::kSpinLostShare * eq.rates.norm();
    if (touchdown_.landed(s_.landed_after_s, spin_lost)) {
      cmd_.phase = DescentPhase::kLanded;
      f.setZero();
    }
  }
  cmd_.thrust_fraction.setZero(4);
  detail::command_working<3>(m_, eq.working, cmd_.phase == DescentPhase::kLanded, dt, f,
                             cmd_.thrust_fraction, lagged_n_);
  cmd_.thrust_n = f;
  return cmd_;
}

}  // namespace motormix
