#include "loop/physical_inputs.hpp"

#include "loop/esc_curve.hpp"

#include <motormix/config/hover_point.hpp>
#include <motormix/gravity.hpp>

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace motormix::loop {

namespace {

// The torque demands' step for the slope at hover: small against the range,
// large against rounding.
constexpr double kSlopeStep = 0.02;

// Body wrench (torque N m, FRD; upward thrust N) the vehicle's rotors give
// for a demand, through the mixer, its output stage and the ESCs' curve.
struct Chain {
  const config::Config& config;
  const Mixer& mixer;
  EscCurve curve;
  mutable MixerOutput out;

  Eigen::Vector4d wrench(const AxisVector& demand) const {
    mixer.mix(demand, out);
    Eigen::Vector4d w = Eigen::Vector4d::Zero();
    const auto& rotors = config.vehicle_model.rotors;
    for (std::size_t i = 0; i < rotors.size() && static_cast<Eigen::Index>(i) < out.output.size();
         ++i) {
      const double thrust_n =
          curve.thrust_of(i, out.output[static_cast<Eigen::Index>(i)]) * rotors[i].max_thrust_n;
      w.head<3>() += rotors[i].torque_per_newton() * thrust_n;
      w[3] += -rotors[i].axis.z() * thrust_n;
    }
    return w;
  }
};

}  // namespace

std::optional<PhysicalInputs> PhysicalInputs::build(const config::Config& config,
                                                    const Mixer& mixer) {
  const config::HoverPoint hover = config::hover_point(config);
  if (!hover.known) return std::nullopt;
  Chain chain{config, mixer, esc_curve_of(config), {}};
  PhysicalInputs p;
  for (int k = 0; k <= kTableSteps; ++k) {
    const double t = static_cast<double>(k) / kTableSteps;
    p.table_[static_cast<std::size_t>(k)] = chain.wrench(AxisVector(0.0, 0.0, 0.0, t))[3];
    // Monotonic by construction of a vehicle that lifts with throttle; a
    // flat stretch (idle, a clamp) keeps the lowest throttle that gives it.
    if (k > 0) {
      p.table_[static_cast<std::size_t>(k)] = std::max(p.table_[static_cast<std::size_t>(k)],
                                                       p.table_[static_cast<std::size_t>(k - 1)]);
    }
  }
  p.hover_thrust_n_ = config.vehicle_model.mass_kg * kStandardGravity;
  p.hover_throttle_ = p.throttle_for(p.hover_thrust_n_);
  for (int a = 0; a < 3; ++a) {
    AxisVector hi(0.0, 0.0, 0.0, p.hover_throttle_), lo = hi;
    hi[a] += kSlopeStep;
    lo[a] -= kSlopeStep;
    p.per_demand_.col(a) = (chain.wrench(hi) - chain.wrench(lo)).head<3>() / (2.0 * kSlopeStep);
  }
  const Eigen::FullPivLU<Eigen::Matrix3d> lu(p.per_demand_);
  if (!lu.isInvertible()) return std::nullopt;
  p.demand_per_nm_ = lu.inverse();
  return p;
}

double PhysicalInputs::throttle_for(double thrust_n) const {
  if (!(thrust_n > table_.front())) return 0.0;
  if (thrust_n >= table_.back()) return 1.0;
  const auto it = std::lower_bound(table_.begin(), table_.end(), thrust_n);
  const auto k = static_cast<double>(it - table_.begin());
  const double above = *it, below = *(it - 1);
  const double within = above > below ? (thrust_n - below) / (above - below) : 0.0;
  return (k - 1.0 + within) / kTableSteps;
}

Eigen::Vector3d PhysicalInputs::torques_for(const Eigen::Vector3d& torque_nm) const {
  return (demand_per_nm_ * torque_nm).cwiseMax(-1.0).cwiseMin(1.0);
}

}  // namespace motormix::loop
