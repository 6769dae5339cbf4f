#include <motormix/safety/two_rotor_descent.hpp>

#include "descent_collective.hpp"
#include "spin_dynamics.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace motormix {

namespace {

using detail::kDegPerRad;
using detail::planar;
// The two rotors left must push through the centre of mass from opposite
// sides: their arms within this angle of opposite.
constexpr double kOppositeToleranceDeg = 15.0;
// Largest share of a motor's thrust the collective is planned with: the
// rest is the differential that steers.
constexpr double kHeadroom = 0.92;
// The two must carry at least this share of the weight with that room left.
// Below it the vehicle falls too fast to land; above it and below 1 it comes
// down faster than the descent rate, the air's drag limiting the speed (a
// default quad, thrust twice its weight, carries 92 %).
constexpr double kMinWeightShare = 0.9;
// The regulator's weights (Bryson's rule: each state at its largest
// acceptable value costs as much as the input at its largest). The thrust
// axis 0.1 rad (6 degrees) off, 3 rad/s across it, a quarter of a motor's
// thrust in differential.
constexpr double kAxisErrorScaleRad = 0.1;
constexpr double kRateScaleRadS = 3.0;
constexpr double kDifferentialShare = 0.25;
// The model is sampled at this period for the regulator (the loop's default
// rate; at other rates the gain is that of the same continuous design).
constexpr double kDesignPeriodS = 0.0025;
constexpr int kDoublingIterations = 80;
// The gyro is trusted up to this share of its range; beyond, the model.
constexpr double kGyroTrustShare = 0.9;
// Landing (Touchdown): a spin lost is one that peaked at this at least.
constexpr double kSpinReachedRadS = 5.0;

using StateMatrix = Eigen::Matrix<double, TwoRotorDescent::kStates, TwoRotorDescent::kStates>;
using InputVector = Eigen::Matrix<double, TwoRotorDescent::kStates, 1>;
constexpr int kAugmented = TwoRotorDescent::kStates + 1;
using AugmentedMatrix = Eigen::Matrix<double, kAugmented, kAugmented>;

constexpr std::array<std::array<int, 2>, 6> kPairs{
    {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}}};

// exp(M) by scaling and squaring of its Taylor series (start-up only).
AugmentedMatrix exponential(const AugmentedMatrix& m) {
  const double norm = m.cwiseAbs().rowwise().sum().maxCoeff();
  int squarings = 0;
  while (norm / std::ldexp(1.0, squarings) > 0.5 && squarings < 40) ++squarings;
  const AugmentedMatrix a = m / std::ldexp(1.0, squarings);
  AugmentedMatrix term = AugmentedMatrix::Identity();
  AugmentedMatrix sum = AugmentedMatrix::Identity();
  for (int k = 1; k <= 16; ++k) {
    term = term * a / static_cast<double>(k);
    sum += term;
  }
  for (int i = 0; i < squarings; ++i) sum = sum * sum;
  return sum;
}

// The discrete linear-quadratic regulator's gain for x+ = A x + B u, cost
// sum x'Qx + r u^2: the Riccati solution by the structure-preserving
// doubling algorithm (quadratic convergence). Non-finite when the pair is
// not stabilizable.
TwoRotorDescent::Gain lqr(const StateMatrix& a, const InputVector& b, const StateMatrix& q,
                          double r) {
  StateMatrix ak = a;
  StateMatrix g = b * b.transpose() / r;
  StateMatrix h = q;
  const StateMatrix identity = StateMatrix::Identity();
  for (int k = 0; k < kDoublingIterations; ++k) {
    const StateMatrix w = (identity + g * h).inverse();
    const StateMatrix a_next = ak * w * ak;
    const StateMatrix g_next = g + ak * w * g * ak.transpose();
    const StateMatrix h_next = h + ak.transpose() * h * w * ak;
    const double change = (h_next - h).norm();
    ak = a_next;
    g = g_next;
    h = h_next;
    if (!h.allFinite()) break;
    if (change <= 1e-12 * std::max(1.0, h.norm())) break;
  }
  const double denominator = r + (b.transpose() * h * b)(0, 0);
  return (b.transpose() * h * a) / denominator;
}

// The rotors' angular momentum along body z with the plan's collective.
double momentum_z(const SpinningDescentModel& m, const TwoRotorPlan& p, double collective) {
  double h = 0.0;
  for (std::size_t j = 0; j < 2; ++j) {
    const auto k = static_cast<std::size_t>(p.working[j]);
    const double share = std::clamp(p.share[j] * collective / m.max_thrust_n[k], 0.0, 1.0);
    h += m.spin[k] * m.rotor_inertia_kgm2 * m.max_rotor_speed_rad_s * std::sqrt(share) *
         m.axis[k].z();
  }
  return h;
}

// The gain at spin rate `spin` (signed about body z).
TwoRotorDescent::Gain gain_at(const SpinningDescentModel& m, const TwoRotorPlan& p, double spin) {
  const double weight = m.mass_kg * kStandardGravity;
  const double collective = std::min(weight, p.weight_share * weight);
  const double hz = momentum_z(m, p, collective);
  const Eigen::Vector3d& inertia = m.inertia_kgm2;
  const double drag = m.rotational_drag;
  const double lag = std::max(m.time_constant_s, 1e-3);
  const auto ka = static_cast<std::size_t>(p.working[0]);
  const auto kb = static_cast<std::size_t>(p.working[1]);
  const Eigen::Vector2d d = 0.5 * planar(m.torque_per_newton[ka] - m.torque_per_newton[kb]);
  // x = [axis error x, y; rates across x, y; differential through the lag]
  StateMatrix a = StateMatrix::Zero();
  a(0, 1) = spin;
  a(0, 3) = 1.0;
  a(1, 0) = -spin;
  a(1, 2) = -1.0;
  a(2, 2) = -drag / inertia.x();
  a(2, 3) = -(spin * (inertia.z() - inertia.y()) + hz) / inertia.x();
  a(2, 4) = d.x() / inertia.x();
  a(3, 2) = (spin * (inertia.z() - inertia.x()) + hz) / inertia.y();
  a(3, 3) = -drag / inertia.y();
  a(3, 4) = d.y() / inertia.y();
  a(4, 4) = -1.0 / lag;
  InputVector b = InputVector::Zero();
  b(4) = 1.0 / lag;
  AugmentedMatrix continuous = AugmentedMatrix::Zero();
  continuous.topLeftCorner<TwoRotorDescent::kStates, TwoRotorDescent::kStates>() =
      a * kDesignPeriodS;
  continuous.topRightCorner<TwoRotorDescent::kStates, 1>() = b * kDesignPeriodS;
  const AugmentedMatrix discrete = exponential(continuous);
  StateMatrix q = StateMatrix::Zero();
  q(0, 0) = q(1, 1) = 1.0 / (kAxisErrorScaleRad * kAxisErrorScaleRad);
  q(2, 2) = q(3, 3) = 1.0 / (kRateScaleRadS * kRateScaleRadS);
  const double u_scale = kDifferentialShare * 0.5 * (m.max_thrust_n[ka] + m.max_thrust_n[kb]);
  return lqr(discrete.topLeftCorner<TwoRotorDescent::kStates, TwoRotorDescent::kStates>(),
             discrete.topRightCorner<TwoRotorDescent::kStates, 1>(), q, 1.0 / (u_scale * u_scale));
}

}  // namespace

TwoRotorPlan plan_two_rotor_descent(const SpinningDescentModel& m, int first, int second) {
  TwoRotorPlan p;
  p.failed = {std::min(first, second), std::max(first, second)};
  int n = 0;
  for (int k = 0; k < 4; ++k) {
    if (k != first && k != second && n < 2) p.working[static_cast<std::size_t>(n++)] = k;
  }
  std::ostringstream why;
  why.precision(3);
  const auto ka = static_cast<std::size_t>(p.working[0]);
  const auto kb = static_cast<std::size_t>(p.working[1]);
  if (first == second || n != 2) {
    p.why = "not two different motors";
    return p;
  }
  // The torque per newton across the thrust axis is the arm turned by 90
  // degrees: opposite arms, opposite torques.
  const Eigen::Vector2d ta = planar(m.torque_per_newton[ka]);
  const Eigen::Vector2d tb = planar(m.torque_per_newton[kb]);
  const double cross = ta.x() * tb.y() - ta.y() * tb.x();
  const double angle =
      std::atan2(std::abs(cross), -ta.dot(tb)) * kDegPerRad;  // 0 when exactly opposite
  if (ta.norm() <= 0.0 || tb.norm() <= 0.0 || angle > kOppositeToleranceDeg) {
    why << "motors " << ka + 1 << " and " << kb + 1
        << " are not opposite each other: their thrusts tip the vehicle over";
    p.why = why.str();
    return p;
  }
  if (m.spin[ka] != m.spin[kb]) {
    why << "motors " << ka + 1 << " and " << kb + 1
        << " spin opposite ways: nothing spins the body to steer it";
    p.why = why.str();
    return p;
  }
  p.share = {tb.norm() / (ta.norm() + tb.norm()), ta.norm() / (ta.norm() + tb.norm())};
  const double weight = m.mass_kg * kStandardGravity;
  const double most = std::min(kHeadroom * m.max_thrust_n[ka] / p.share[0],
                               kHeadroom * m.max_thrust_n[kb] / p.share[1]);
  const double up = -0.5 * (m.axis[ka].z() + m.axis[kb].z());
  p.weight_share = most * up / weight;
  if (p.weight_share < kMinWeightShare) {
    why << "motors " << ka + 1 << " and " << kb + 1 << " carry " << p.weight_share * 100
        << " % of the weight with room to steer; a two-rotor landing needs "
        << kMinWeightShare * 100 << " %";
    p.why = why.str();
    return p;
  }
  const double yaw = p.share[0] * m.torque_per_newton[ka].z() +
                     p.share[1] * m.torque_per_newton[kb].z();  // per newton of collective
  p.spin_sign = yaw >= 0.0 ? 1.0 : -1.0;
  const double collective = std::min(weight, most) / up;
  p.settled_spin_rad_s = m.rotational_drag > 0.0 ? std::abs(yaw) * collective / m.rotational_drag
                                                 : TwoRotorDescent::kGridTopRadS;
  p.found = true;
  return p;
}

int TwoRotorDescent::pair_index(unsigned failed) {
  for (std::size_t i = 0; i < kPairs.size(); ++i) {
    if (failed == ((1U << kPairs[i][0]) | (1U << kPairs[i][1]))) return static_cast<int>(i);
  }
  return -1;
}

TwoRotorDescent::TwoRotorDescent(const SpinningDescentModel& model,
                                 const SpinningDescentSettings& settings)
    : m_(model), s_(settings) {
  for (std::size_t i = 0; i < kPairs.size(); ++i) {
    plans_[i] = plan_two_rotor_descent(m_, kPairs[i][0], kPairs[i][1]);
    if (!plans_[i].found) continue;
    // From the top down: where the spin is too slow for the coupling to
    // steer (no rotor momentum and no spin), the next faster gain stands.
    for (int g = kGridPoints - 1; g >= 0; --g) {
      const double spin = plans_[i].spin_sign * kGridTopRadS * g / (kGridPoints - 1);
      Gain k = gain_at(m_, plans_[i], spin);
      const auto gi = static_cast<std::size_t>(g);
      if (!k.allFinite() || k.norm() > 1e6) {
        k = g + 1 < kGridPoints ? gains_[i][gi + 1] : Gain::Zero();
      }
      gains_[i][gi] = k;
    }
    if (gains_[i].back().isZero()) {
      plans_[i].found = false;
      plans_[i].why = "no stabilizing gain for the two-rotor model";
    }
  }
  cmd_.thrust_fraction.setZero(4);
}

const TwoRotorPlan* TwoRotorDescent::plan(unsigned failed) const {
  const int i = pair_index(failed);
  return i < 0 ? nullptr : &plans_[static_cast<std::size_t>(i)];
}

TwoRotorDescent::Gain TwoRotorDescent::gain(unsigned failed, double spin) const {
  const int i = pair_index(failed);
  if (i < 0) return Gain::Zero();
  const auto& grid = gains_[static_cast<std::size_t>(i)];
  const double x = std::clamp(std::abs(spin) / kGridTopRadS, 0.0, 1.0) * (kGridPoints - 1);
  const int lo = std::min(static_cast<int>(x), kGridPoints - 2);
  const double t = x - lo;
  return (1.0 - t) * grid[static_cast<std::size_t>(lo)] +
         t * grid[static_cast<std::size_t>(lo + 1)];
}

void TwoRotorDescent::start(unsigned failed, std::int64_t now_us,
                            const MotorVector& thrust_fraction) {
  stop();
  const int i = pair_index(failed);
  if (i < 0 || !plans_[static_cast<std::size_t>(i)].found) return;
  pair_ = i;
  failed_ = failed;
  const TwoRotorPlan& p = plans_[static_cast<std::size_t>(i)];
  for (std::size_t j = 0; j < 2; ++j) {
    const auto k = static_cast<std::size_t>(p.working[j]);
    const double x = static_cast<Eigen::Index>(k) < thrust_fraction.size()
                         ? thrust_fraction[static_cast<Eigen::Index>(k)]
                         : 0.0;
    lagged_n_[static_cast<Eigen::Index>(j)] =
        std::isfinite(x) ? std::clamp(x, 0.0, 1.0) * m_.max_thrust_n[k] : 0.0;
  }
  const double collective = lagged_n_.sum();
  lagged_differential_ = lagged_n_[0] - lagged_n_[1] - (p.share[0] - p.share[1]) * collective;
  last_us_ = now_us;
  velocity_integral_ = 0.0;
  up_force_ = 0.0;
  spin_ = 0.0;
  peak_spin_ = 0.0;
  touchdown_.reset();
  cmd_ = DescentCommand{};
  cmd_.thrust_fraction.setZero(4);
  cmd_.phase = DescentPhase::kDescending;
}

void TwoRotorDescent::stop() {
  pair_ = -1;
  failed_ = 0;
  cmd_.phase = DescentPhase::kOff;
  cmd_.thrust_fraction.setZero(4);
}

const DescentCommand& TwoRotorDescent::update(const DescentInput& in, std::int64_t now_us) {
  if (pair_ < 0 || cmd_.phase != DescentPhase::kDescending) return cmd_;
  const double dt = std::clamp(static_cast<double>(now_us - last_us_) / 1e6, 0.0, detail::kMaxDtS);
  last_us_ = now_us;
  // Non-finite inputs are kept out by the loop's checks; should one arrive
  // anyway, the previous command stands (it is inside the motors' range).
  if (!in.attitude.coeffs().allFinite() || in.attitude.norm() < 0.5 || !in.rates.allFinite()) {
    return cmd_;
  }
  const TwoRotorPlan& p = plans_[static_cast<std::size_t>(pair_)];
  const auto ka = static_cast<std::size_t>(p.working[0]);
  const auto kb = static_cast<std::size_t>(p.working[1]);
  const Eigen::Matrix3d rot = in.attitude.normalized().toRotationMatrix();  // body -> NED
  const Eigen::Vector3d w = in.rates.cwiseMax(-detail::kMaxRateRadS).cwiseMin(detail::kMaxRateRadS);
  cmd_.measured_rate_rad_s = w.norm();

  // The spin: the gyro's inside its range; at the rail, the rotors' yaw
  // torque against the drag carries it on from there.
  const double yaw_torque =
      m_.torque_per_newton[ka].z() * lagged_n_[0] + m_.torque_per_newton[kb].z() * lagged_n_[1];
  const double modelled =
      spin_ + dt * (yaw_torque - m_.rotational_drag * spin_) / m_.inertia_kgm2.z();
  if (m_.gyro_range_rad_s <= 0.0 || std::abs(w.z()) < kGyroTrustShare * m_.gyro_range_rad_s) {
    spin_ = w.z();
  } else {
    spin_ = std::copysign(std::max(std::abs(modelled), std::abs(w.z())), w.z());
  }
  peak_spin_ = std::max(peak_spin_, std::abs(spin_));

  // Where the thrust axis should point (the world's up, tilted against the
  // horizontal velocity), seen from the body.
  const Eigen::Vector3d desired = detail::wanted_up_body(s_, in, rot);
  cmd_.axis_error_deg = std::acos(std::clamp(-desired.z(), -1.0, 1.0)) * kDegPerRad;

  Eigen::Matrix<double, kStates, 1> x;
  x << desired.x(), desired.y(), w.x(), w.y(), lagged_differential_;
  const double u_limit = std::min(m_.max_thrust_n[ka], m_.max_thrust_n[kb]);
  const double asked = -(gain(failed_, spin_) * x)(0, 0);
  double u = std::clamp(asked, -u_limit, u_limit);
  if (!std::isfinite(u)) u = 0.0;

  const Eigen::Vector3d up_body = rot.transpose() * Eigen::Vector3d(0.0, 0.0, -1.0);
  detail::CollectiveState state{velocity_integral_, up_force_};
  const double wanted = detail::descent_collective(m_, s_, in, up_body, dt, state);
  velocity_integral_ = state.velocity_integral;
  up_force_ = state.up_force;
  // The differential first: the collective in what the motors have left.
  const double hi = std::min((m_.max_thrust_n[ka] - 0.5 * u) / p.share[0],
                             (m_.max_thrust_n[kb] + 0.5 * u) / p.share[1]);
  const double lo = std::max((m_.min_thrust_n[ka] - 0.5 * u) / p.share[0],
                             (m_.min_thrust_n[kb] + 0.5 * u) / p.share[1]);
  const double collective = lo <= hi ? std::clamp(wanted, lo, hi) : 0.5 * (lo + hi);
  cmd_.saturated = collective != wanted || u != asked;
  Eigen::Vector2d f(p.share[0] * collective + 0.5 * u, p.share[1] * collective - 0.5 * u);

  // Landing: still once the descent has been flown (or never turning: two
  // motors lost on the ground), or the spin lost while still.
  if (std::isfinite(in.velocity.z())) {
    const bool not_moving =
        touchdown_.update(in.velocity.z(), s_.descent_rate_mps, cmd_.measured_rate_rad_s, true, dt);
    const bool spin_lost = not_moving && touchdown_.descended() && peak_spin_ >= kSpinReachedRadS &&
                           std::abs(spin_) < Touchdown::kSpinLostShare * peak_spin_;
    if (touchdown_.landed(s_.landed_after_s, spin_lost)) cmd_.phase = DescentPhase::kLanded;
  }
  cmd_.thrust_fraction.setZero(4);
  const double alpha = detail::command_working<2>(
      m_, p.working, cmd_.phase == DescentPhase::kLanded, dt, f, cmd_.thrust_fraction, lagged_n_);
  cmd_.thrust_n.setZero();
  cmd_.thrust_n.head<2>() = f;
  const double applied = f[0] - f[1] - (p.share[0] - p.share[1]) * (f[0] + f[1]);
  lagged_differential_ += alpha * (applied - lagged_differential_);
  return cmd_;
}

}  // namespace motormix
