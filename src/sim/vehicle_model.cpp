#include "sim/vehicle_model.hpp"

#include <motormix/angles.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace motormix::sim {

namespace {

constexpr double kTakenOffAltitudeM = 0.2;  // above this the vehicle has flown
// A rotor without its prop still has the bell's drag: a twentieth of the
// prop's (it then takes a few seconds to stop instead of for ever).
constexpr double kBellDragShare = 0.05;

// Exact discretization of a first-order lag over one step.
double lag(double value, double target, double alpha_up, double alpha_down) {
  return value + (target - value) * (std::abs(target) > std::abs(value) ? alpha_up : alpha_down);
}

}  // namespace

VehicleModel::VehicleModel(const config::Config& config)
    : p_(config.vehicle_model), battery_(config.vehicle_model.battery) {
  if (!p_.incomplete.empty()) throw std::invalid_argument(p_.incomplete);
  for (const OutputChannel& ch : config.outputs) modes_.push_back(ch.mode);
  speed_.assign(static_cast<std::size_t>(config.motors()), 0.0);
  rotor_speed_before_.assign(speed_.size(), 0.0);
  freewheel_.assign(speed_.size(), 0);
  prop_.assign(static_cast<std::size_t>(config.motors()), 1.0);
  mass_.mass_kg = p_.mass_kg;
  mass_.inertia = p_.inertia_kgm2;
  // Force (body) and torque of each rotor per newton of its thrust: along
  // its axis, about the centre of mass, and its drag against the spin.
  per_newton_.setZero(6, static_cast<Eigen::Index>(p_.rotors.size()));
  for (std::size_t i = 0; i < p_.rotors.size(); ++i) {
    const config::RotorPhysics& r = p_.rotors[i];
    const auto col = static_cast<Eigen::Index>(i);
    per_newton_.block<3, 1>(0, col) = r.axis;
    per_newton_.block<3, 1>(3, col) = r.torque_per_newton();
  }
}

void VehicleModel::set_body(const BodyState& body, bool landed) {
  body_ = body;
  landed_ = landed;
  taken_off_ = !landed;
}

double VehicleModel::driver_fraction(int i, double output, int direction) const {
  const auto k = static_cast<std::size_t>(i);
  const double lo = p_.esc_min[k], hi = p_.esc_max[k], mid = p_.esc_center[k];
  switch (modes_[k]) {
    case OutputMode::kUnipolar:
      return std::clamp((output - lo) / (hi - lo), 0.0, 1.0);
    case OutputMode::kCentered:
      return std::clamp(output >= mid ? (output - mid) / (hi - mid) : (output - mid) / (mid - lo),
                        -1.0, 1.0);
    case OutputMode::kMagnitudeDirection:
      return std::clamp((output - lo) / (hi - lo), 0.0, 1.0) * (direction > 0   ? 1.0
                                                                : direction < 0 ? -1.0
                                                                                : 0.0);
  }
  return 0.0;
}

Eigen::Matrix<double, 4, Eigen::Dynamic> VehicleModel::command_effect() const {
  Eigen::Matrix<double, 4, Eigen::Dynamic> e =
      Eigen::Matrix<double, 4, Eigen::Dynamic>::Zero(4, motors());
  for (int i = 0; i < motors(); ++i) {
    if (p_.wheeled) {
      const double side = i % 2 == 0 ? 1.0 : -1.0;  // even: left; left faster turns right (+yaw)
      const double wheel = p_.wheels.radius_m * p_.wheels.max_speed_rad_s / p_.wheels.per_side;
      e(2, i) = side * wheel / p_.wheels.track_m;
      e(3, i) = wheel / 2.0;
    } else {
      const config::RotorPhysics& r = p_.rotors[static_cast<std::size_t>(i)];
      const Eigen::Vector3d f = r.max_thrust_n * r.axis;
      const Eigen::Vector3d tau =
          r.position_m.cross(f) + static_cast<double>(r.spin) * r.torque_ratio_m * -f;
      e.block<3, 1>(0, i) = tau;
      e(3, i) = -f.z();
    }
  }
  return e;
}

double VehicleModel::ground_effect(int i) const {
  if (!p_.ground_effect) return 1.0;
  // Cheeseman and Bennett (1955): T / T_free = 1 / (1 - (R / 4z)^2) at a
  // height z of the rotor above the ground, R its radius; taken within one
  // diameter and no lower than R/2 (a third more thrust at most).
  const double radius = p_.prop_diameter_m / 2;
  const double z =
      -(body_.position + body_.attitude * p_.rotors[static_cast<std::size_t>(i)].position_m).z();
  if (z >= 2.0 * radius) return 1.0;
  const double q = radius / (4.0 * std::max(z, 0.5 * radius));
  return 1.0 / (1.0 - q * q);
}

double VehicleModel::rotor_speed_rad_s(int i) const {
  // Its speed grows as the square root of its thrust fraction.
  return p_.max_rotor_speed_rad_s * std::sqrt(std::max(speed_[static_cast<std::size_t>(i)], 0.0));
}

double VehicleModel::freewheel(int i, double dt) const {
  // Nothing drives the rotor and nothing brakes it: its air drag Q = k T,
  // with T = T_max (w / w_max)^2, slows it alone, I dw/dt = -c w^2, whose
  // exact step is w / (1 + c w dt). A 10-inch rotor from hover keeps half
  // its thrust for about a quarter of a second.
  const auto k = static_cast<std::size_t>(i);
  const config::RotorPhysics& r = p_.rotors[k];
  const double w_max = p_.max_rotor_speed_rad_s;
  const double c = r.torque_ratio_m * r.max_thrust_n * std::max(prop_[k], kBellDragShare) /
                   (p_.rotor_inertia_kgm2 * w_max * w_max);
  const double w = rotor_speed_rad_s(i);
  const double next = w / (1.0 + c * w * dt);
  return (next / w_max) * (next / w_max);
}

void VehicleModel::sum_rotors(double dt) {
  MotorVector thrust(motors());
  for (int i = 0; i < motors(); ++i) thrust[i] = thrust_n(i) * ground_effect(i);
  Eigen::Matrix<double, 6, 1> w;
  w.noalias() = per_newton_ * thrust;
  rotor_force_ = w.head<3>();
  rotor_torque_ = w.tail<3>();
  rotor_momentum_.setZero();
  if (p_.rotor_inertia_kgm2 > 0.0) {
    for (std::size_t i = 0; i < p_.rotors.size(); ++i) {
      // A counter-clockwise rotor (seen from above) spins about its thrust
      // axis. Its momentum turns the body gyroscopically (-w x h, in
      // wrench()); speeding it up over this step pushed the body the other
      // way about its axis (held over the step, as the thrust is).
      const config::RotorPhysics& r = p_.rotors[i];
      const double speed = rotor_speed_rad_s(static_cast<int>(i));
      const Eigen::Vector3d h_axis = static_cast<double>(r.spin) * p_.rotor_inertia_kgm2 * r.axis;
      rotor_momentum_ += speed * h_axis;
      if (freewheel_[i] != 0) {
        // No motor torque: the body feels neither the rotor's drag nor its
        // slowing (both act between the rotor and the air).
        rotor_torque_ -= static_cast<double>(r.spin) * r.torque_ratio_m *
                         -thrust[static_cast<Eigen::Index>(i)] * r.axis;
      } else {
        rotor_torque_ -= (speed - rotor_speed_before_[i]) / dt * h_axis;
      }
    }
  }
}

Wrench VehicleModel::wrench(const BodyState& s, const Environment& env) const {
  Wrench w;
  w.force_world = s.attitude * rotor_force_ + Eigen::Vector3d(0, 0, mass_.mass_kg * kGravity) -
                  p_.drag_linear_n_per_mps * (s.velocity - env.wind_ned) + env.force_world;
  w.torque_body = rotor_torque_ - p_.drag_rotational_nm_per_radps * s.rates + env.torque_body -
                  s.rates.cross(rotor_momentum_);
  return w;
}

void VehicleModel::step(const MotorVector& outputs, const DirectionVector& direction,
                        MotorMask stopped, const Environment& env, double dt) {
  MotorHealth health = MotorHealth::healthy(motors());
  for (int i = 0; i < motors(); ++i) {
    if (((stopped >> i) & 1U) != 0) health.drive[i] = 0.0;
  }
  step(outputs, direction, health, env, dt);
}

void VehicleModel::step(const MotorVector& outputs, const DirectionVector& direction,
                        const MotorHealth& health, const Environment& env, double dt) {
  if (crashed_) return;
  if (dt != lag_dt_) {
    lag_dt_ = dt;
    alpha_up_ = 1.0 - std::exp(-dt / p_.time_constant_up_s);
    alpha_down_ = 1.0 - std::exp(-dt / p_.time_constant_down_s);
  }
  const double v = battery_.terminal_v() / battery_.physics().reference_v;
  double current = battery_.physics().avionics_current_a;
  for (int i = 0; i < motors(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    double target = 0.0;
    prop_[k] = health.prop[i];
    if (health.drive[i] > 0.0) {
      const double x = driver_fraction(i, outputs[i], direction[k]);
      if (p_.wheeled) {
        target = x * p_.wheels.max_speed_rad_s * v;
      } else {
        const double e = p_.thrust_expo;
        target = ((1 - e) * v + e * v * v) * OutputStage::thrust_of(x, e);
      }
      target *= health.drive[i];
    }
    rotor_speed_before_[k] = rotor_speed_rad_s(i);
    freewheel_[k] = !p_.wheeled && health.drive[i] <= 0.0 && p_.rotor_inertia_kgm2 > 0.0;
    if (freewheel_[k]) {
      speed_[k] = freewheel(i, dt);
    } else {
      double up = alpha_up_, down = alpha_down_;
      if (health.lag.size() > i && health.lag[i] != 1.0) {
        // A rotor that lost its prop: only the bell to turn.
        const double f = health.lag[i];
        up = 1.0 - std::exp(-dt / (f * p_.time_constant_up_s));
        down = 1.0 - std::exp(-dt / (f * p_.time_constant_down_s));
      }
      if (p_.motor_lag == config::MotorLag::kSpeed && !p_.wheeled) {
        // The lag on the rotor's speed, the square root of the thrust
        // fraction (signed: a reversed rotor's is negative).
        const auto root = [](double x) { return std::copysign(std::sqrt(std::abs(x)), x); };
        const double w = lag(root(speed_[k]), root(target), up, down);
        speed_[k] = std::copysign(w * w, w);
      } else {
        speed_[k] = lag(speed_[k], target, up, down);
      }
    }
    // Electrical power grows with thrust^1.5 (momentum theory); a wheel
    // motor's current with its speed.
    const double s = std::max(speed_[k] * prop_[k], 0.0);
    const double load =
        p_.wheeled ? std::abs(speed_[k]) / p_.wheels.max_speed_rad_s : s * std::sqrt(s);
    current += battery_.physics().full_throttle_current_a * load;
  }
  battery_.step(current, dt);
  if (p_.wheeled) {
    step_wheels(dt);
  } else {
    step_aircraft(env, dt);
  }
}

void VehicleModel::step_aircraft(const Environment& env, double dt) {
  sum_rotors(dt);
  if (landed_) {
    // Resting on the ground: lift off once the net force points up.
    if (wrench(body_, env).force_world.z() >= 0.0) return;
    landed_ = false;
  }
  body_ = rk4_step(
      body_, mass_, [&](const BodyState& s) { return wrench(s, env); }, dt);
  if (!taken_off_ && body_.position.z() < -kTakenOffAltitudeM) taken_off_ = true;
  if (body_.position.z() >= 0.0) {
    const double impact = body_.velocity.z();
    if (taken_off_) touchdown_speed_ = impact;
    if (taken_off_ && impact > kCrashSpeedMps) {
      std::ostringstream why;
      why.precision(3);
      why << "hit the ground at " << impact << " m/s";
      crashed_ = true;
      crash_reason_ = why.str();
    }
    // On the ground: at rest, level, heading kept.
    body_.position.z() = 0.0;
    body_.velocity.setZero();
    body_.rates.setZero();
    body_.attitude = from_euler(0.0, 0.0, euler(body_.attitude).z());
    landed_ = true;
    return;
  }
  if (taken_off_ && tilt(body_.attitude) > kPi / 2) {
    crashed_ = true;
    crash_reason_ = "tilted past 90 degrees";
  }
}

void VehicleModel::step_wheels(double dt) {
  double left = 0.0, right = 0.0;
  for (int i = 0; i < motors(); ++i)
    (i % 2 == 0 ? left : right) += speed_[static_cast<std::size_t>(i)];
  left /= p_.wheels.per_side;
  right /= p_.wheels.per_side;
  forward_speed_ = p_.wheels.radius_m * (left + right) / 2.0;
  const double yaw_rate = p_.wheels.radius_m * (left - right) / p_.wheels.track_m;
  double yaw = euler(body_.attitude).z() + yaw_rate * dt;
  body_.velocity = {forward_speed_ * std::cos(yaw), forward_speed_ * std::sin(yaw), 0.0};
  body_.position += body_.velocity * dt;
  body_.attitude = from_euler(0.0, 0.0, yaw);
  body_.rates = {0.0, 0.0, yaw_rate};
  landed_ = true;
}

}  // namespace motormix::sim
