#include "sim/controller.hpp"

#include <motormix/angles.hpp>

#include <algorithm>
#include <cmath>

namespace motormix::sim {

namespace {

constexpr double kStep = 0.02;  // demand step of the linearization
constexpr double kMaxRateDps = 400.0;
constexpr double kMaxYawRateDps = 200.0;
constexpr double kMaxDescent = 1.5;          // m/s
constexpr double kRateIntegralLimit = 0.5;   // rad: integral term at most rate_i x this
constexpr double kClimbIntegralLimit = 2.0;  // m/s
constexpr double kMinTiltCosine = 0.5;       // thrust is tilt-compensated up to 60 degrees
// Less than this of an axis undelivered is rounding, not saturation (the
// mixer's own kDeliveredTolerance is 1e-6; mixer_status_t carries floats).
constexpr double kUndelivered = 1e-5;

// d command / d demand around `at`, motor by motor (columns: axes).
Eigen::MatrixXd mixer_slope(const Mixer& mixer, const AxisVector& at, int motors) {
  Eigen::MatrixXd d(motors, kNumAxes);
  MixerOutput out;
  for (int a = 0; a < kNumAxes; ++a) {
    AxisVector hi = at, lo = at;
    hi[a] += kStep;
    lo[a] -= kStep;
    mixer.mix(hi, out);
    const Eigen::VectorXd up = out.command.head(motors);
    mixer.mix(lo, out);
    d.col(a) = (up - out.command.head(motors)) / (2 * kStep);
  }
  return d;
}

}  // namespace

Controller::Controller(const config::Config& config, const Mixer& mixer,
                       const Eigen::Matrix<double, 4, Eigen::Dynamic>& command_effect,
                       double mass_kg, const Eigen::Vector3d& inertia, double time_constant_s)
    : wheeled_(config.thrust_range() == ThrustRange::kBipolar),
      mass_kg_(mass_kg),
      inertia_(inertia) {
  const int n = config.motors();
  AxisVector at = AxisVector::Zero();
  if (!wheeled_) {
    // Linearize around hover: the thrust demand that holds the weight, found
    // by a few fixed-point steps (the mix is linear in thrust away from the
    // limits, so two suffice).
    at[index(Axis::kThrust)] = 0.5;
    for (int k = 0; k < 3; ++k) {
      const Eigen::MatrixXd d = mixer_slope(mixer, at, n);
      const double per_demand = (command_effect.row(3) * d.col(index(Axis::kThrust)))(0);
      if (per_demand > 0) {
        at[index(Axis::kThrust)] = std::clamp(mass_kg * kGravity / per_demand, 0.05, 0.95);
      }
    }
  }
  g_ = command_effect * mixer_slope(mixer, at, n);
  g_inv_ = g_.completeOrthogonalDecomposition().pseudoInverse();
  gains_.hover_thrust = at[index(Axis::kThrust)];

  const double tau = time_constant_s + 1.0 / config.loop_rate_hz;
  gains_.rate_p = 0.5 / tau;
  gains_.rate_i = gains_.rate_p * gains_.rate_p / 5.0;
  gains_.attitude_p = gains_.rate_p / 4.0;
  gains_.yaw_p = gains_.rate_p / 8.0;
  gains_.max_rate = kMaxRateDps * kPi / 180.0;
  gains_.max_yaw_rate = kMaxYawRateDps * kPi / 180.0;
}

bool Controller::winds_up(Axis axis, double error, const AxisVector& unallocated) const {
  const int a = index(axis);
  // A positive error raises the physical command on its axis (torque,
  // thrust, speed, turn rate); g_inv_ maps that onto the demand, whatever
  // sign the mixing table gives the axis.
  const double demand_change = g_inv_(a, a) * error;
  return std::abs(unallocated[a]) > kUndelivered && unallocated[a] * demand_change > 0.0;
}

void Controller::reset() {
  rate_integral_.setZero();
  climb_integral_ = 0.0;
  speed_integral_ = 0.0;
  yaw_rate_integral_ = 0.0;
}

ControllerCommand Controller::update(const Reference& ref, const BodyState& m, double forward_speed,
                                     bool mixer_armed, bool on_ground,
                                     const AxisVector& unallocated, double dt) {
  ControllerCommand c;
  c.armed = ref.armed;
  if (ref.roll != sp_euler_.x() || ref.pitch != sp_euler_.y() || ref.yaw != sp_euler_.z()) {
    sp_euler_ = {ref.roll, ref.pitch, ref.yaw};
    attitude_sp_ = from_euler(ref.roll, ref.pitch, ref.yaw);
  }
  c.attitude_sp = attitude_sp_;
  if (!ref.armed || !mixer_armed) {
    // Zero throttle until the mixer has accepted the arming.
    reset();
    return c;
  }
  Eigen::Vector4d want = Eigen::Vector4d::Zero();
  if (wheeled_) {
    const double speed_error = ref.speed_mps - forward_speed;
    const double rate_error = ref.yaw_rate - m.rates.z();
    if (!winds_up(Axis::kThrust, speed_error, unallocated)) speed_integral_ += speed_error * dt;
    if (!winds_up(Axis::kYaw, rate_error, unallocated)) yaw_rate_integral_ += rate_error * dt;
    want[2] = ref.yaw_rate + gains_.speed_p * rate_error + gains_.speed_i * yaw_rate_integral_;
    want[3] = ref.speed_mps + gains_.speed_p * speed_error + gains_.speed_i * speed_integral_;
  } else {
    Eigen::Quaterniond err = m.attitude.conjugate() * c.attitude_sp;
    if (err.w() < 0) err.coeffs() *= -1.0;
    const Eigen::Vector3d e = 2.0 * err.vec();
    Eigen::Vector3d rate_sp(gains_.attitude_p * e.x(), gains_.attitude_p * e.y(),
                            gains_.yaw_p * e.z());
    const double tilt_rate = rate_sp.head<2>().norm();
    if (tilt_rate > gains_.max_rate) rate_sp.head<2>() *= gains_.max_rate / tilt_rate;
    rate_sp.z() = std::clamp(rate_sp.z(), -gains_.max_yaw_rate, gains_.max_yaw_rate);
    const Eigen::Vector3d rate_error = rate_sp - m.rates;
    if (on_ground) {
      reset();
    } else {
      Eigen::Vector3d integrating;
      for (int a = 0; a < 3; ++a) {
        integrating[a] = winds_up(static_cast<Axis>(a), rate_error[a], unallocated) ? 0.0 : 1.0;
      }
      rate_integral_ = (rate_integral_ + integrating.cwiseProduct(rate_error) * dt)
                           .cwiseMax(-kRateIntegralLimit)
                           .cwiseMin(kRateIntegralLimit);
    }
    const Eigen::Vector3d accel = gains_.rate_p * rate_error + gains_.rate_i * rate_integral_;
    want.head<3>() = inertia_.cwiseProduct(accel) + m.rates.cross(inertia_.cwiseProduct(m.rates));

    const double altitude = -m.position.z();
    const double climb_sp =
        std::clamp(gains_.altitude_p * (ref.altitude_m - altitude), -kMaxDescent, gains_.max_climb);
    const double climb_error = climb_sp - (-m.velocity.z());
    if (!on_ground) {
      if (!winds_up(Axis::kThrust, climb_error, unallocated)) {
        climb_integral_ = std::clamp(climb_integral_ + climb_error * dt, -kClimbIntegralLimit,
                                     kClimbIntegralLimit);
      }
    }
    const double up_accel = gains_.climb_p * climb_error + gains_.climb_i * climb_integral_;
    const double cos_tilt = std::max((m.attitude * Eigen::Vector3d::UnitZ()).z(), kMinTiltCosine);
    want[3] = std::max(0.0, mass_kg_ * (kGravity + up_accel) / cos_tilt);
  }
  const Eigen::Vector4d d = g_inv_ * want;
  c.roll = std::clamp(d[0], -1.0, 1.0);
  c.pitch = std::clamp(d[1], -1.0, 1.0);
  c.yaw = std::clamp(d[2], -1.0, 1.0);
  c.thrust = std::clamp(d[3], wheeled_ ? -1.0 : 0.0, 1.0);
  return c;
}

Controller Controller::for_vehicle(const config::Config& config, const Mixer& mixer,
                                   const VehicleModel& vehicle) {
  const auto& v = config.vehicle_model;
  const double tau = (v.time_constant_up_s + v.time_constant_down_s) / 2;
  return Controller(config, mixer, vehicle.command_effect(), v.mass_kg, v.inertia_kgm2, tau);
}

}  // namespace motormix::sim
