// The relaxed hover of a quad with one motor stopped (Mueller & D'Andrea):
// the three thrusts and the body rates at which the rotors' torques balance
// the gyroscopic and drag torques, solved by Newton's method at start-up
// (see spinning_descent.hpp).

#include <motormix/safety/spinning_descent.hpp>

#include "spin_dynamics.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace motormix {

namespace {

using detail::holding_torque;
using detail::kDegPerRad;
using detail::planar;
using detail::rotor_momentum;

constexpr int kNewtonIterations = 100;
constexpr double kNewtonTolerance = 1e-10;
// Largest share of a motor's thrust the equilibrium may use: the rest is
// what the controller has to tilt the spin axis with.
constexpr double kEquilibriumHeadroom = 0.92;

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

struct Layout {
  std::array<int, 3> working{};
  int opposite = 0;                 // index into working: the motor across from the dead one
  std::array<int, 2> neighbours{};  // indices into working: the two beside it
};

Layout layout(const SpinningDescentModel& m, int failed) {
  Layout l;
  int n = 0;
  for (int k = 0; k < 4; ++k) {
    if (k != failed) l.working[static_cast<std::size_t>(n++)] = k;
  }
  // The torque per newton across the thrust axis is the arm turned by 90
  // degrees, so distances between those are distances between the rotors.
  const Eigen::Vector2d dead = planar(m.torque_per_newton[static_cast<std::size_t>(failed)]);
  double far = -1.0;
  for (int j = 0; j < 3; ++j) {
    const auto k = static_cast<std::size_t>(l.working[static_cast<std::size_t>(j)]);
    const double d = (planar(m.torque_per_newton[k]) - dead).norm();
    if (d > far) {
      far = d;
      l.opposite = j;
    }
  }
  int b = 0;
  for (int j = 0; j < 3; ++j) {
    if (j != l.opposite) l.neighbours[static_cast<std::size_t>(b++)] = j;
  }
  return l;
}

// Force and torque of the working motors' thrusts f (body).
Eigen::Vector3d force_of(const SpinningDescentModel& m, const Layout& l, const Eigen::Vector3d& f) {
  Eigen::Vector3d F = Eigen::Vector3d::Zero();
  for (std::size_t j = 0; j < 3; ++j)
    F += m.axis[static_cast<std::size_t>(l.working[j])] * f[static_cast<Eigen::Index>(j)];
  return F;
}

Eigen::Vector3d torque_of(const SpinningDescentModel& m, const Layout& l,
                          const Eigen::Vector3d& f) {
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  for (std::size_t j = 0; j < 3; ++j)
    t += m.torque_per_newton[static_cast<std::size_t>(l.working[j])] *
         f[static_cast<Eigen::Index>(j)];
  return t;
}

// The spin axis, pointing the way the thrust pushes.
Eigen::Vector3d up_axis(const Eigen::Vector3d& w, const Eigen::Vector3d& force) {
  const double norm = w.norm();
  if (norm <= 0.0) return -Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d n = w / norm;
  return n.dot(force) >= 0.0 ? n : Eigen::Vector3d(-n);
}

constexpr int kMomentumSteps = 8;

Vector6d residual(const SpinningDescentModel& m, const Layout& l, double spin, const Vector6d& x) {
  const Eigen::Vector3d f = x.head<3>();
  const Eigen::Vector3d w = x.tail<3>();
  const Eigen::Vector3d F = force_of(m, l, f);
  Vector6d r;
  r.head<3>() = torque_of(m, l, f) - holding_torque(m, w, rotor_momentum(m, l.working, f));
  r[3] = (up_axis(w, F).dot(F) - m.mass_kg * kStandardGravity) / (m.mass_kg * kStandardGravity);
  r[4] = (w.norm() - spin) / spin;
  r[5] = (f[l.neighbours[0]] - f[l.neighbours[1]]) / (m.mass_kg * kStandardGravity);
  return r;
}

// Newton's method with a halving line search from x; returns the last
// residual's norm.
double newton(const SpinningDescentModel& m, const Layout& l, double spin_rate, Vector6d& x) {
  Vector6d r = residual(m, l, spin_rate, x);
  for (int it = 0; it < kNewtonIterations && r.norm() > kNewtonTolerance; ++it) {
    Matrix6d jac;
    for (int c = 0; c < 6; ++c) {
      Vector6d xh = x;
      const double h = 1e-7 * std::max(1.0, std::abs(x[c]));
      xh[c] += h;
      jac.col(c) = (residual(m, l, spin_rate, xh) - r) / h;
    }
    const Vector6d step = jac.fullPivLu().solve(-r);
    double scale = 1.0;
    Vector6d next = x + step;
    Vector6d rn = residual(m, l, spin_rate, next);
    for (int half = 0; half < 30 && !(rn.norm() < r.norm()); ++half) {
      scale /= 2.0;
      next = x + scale * step;
      rn = residual(m, l, spin_rate, next);
    }
    if (!(rn.norm() < r.norm())) break;
    x = next;
    r = rn;
  }
  return r.norm();
}

}  // namespace

SpinEquilibrium solve_spin_equilibrium(const SpinningDescentModel& m, int failed,
                                       double spin_rate) {
  SpinEquilibrium eq;
  eq.failed = failed;
  const Layout l = layout(m, failed);
  eq.working = l.working;
  const double weight = m.mass_kg * kStandardGravity;
  // Start level, spinning the way the two neighbours' drag turns the body.
  Vector6d x;
  x.head<3>().setConstant(weight / 3.0);
  double yaw = 0.0;
  for (int b : l.neighbours)
    yaw +=
        m.torque_per_newton[static_cast<std::size_t>(l.working[static_cast<std::size_t>(b)])].z();
  x.tail<3>() = Eigen::Vector3d(0.0, 0.0, yaw >= 0.0 ? spin_rate : -spin_rate);
  // The rotors' momentum moves the solution far from that start: solve
  // without it first, then add it in steps, each starting from the last
  // solution (continuation).
  SpinningDescentModel stepped = m;
  for (int k = 0; k <= kMomentumSteps; ++k) {
    stepped.rotor_inertia_kgm2 = m.rotor_inertia_kgm2 * k / kMomentumSteps;
    newton(stepped, l, spin_rate, x);
    if (m.rotor_inertia_kgm2 <= 0.0) break;
  }
  const Vector6d r = residual(m, l, spin_rate, x);
  std::ostringstream why;
  if (!(r.norm() <= 1e-8)) {
    why << "no relaxed hover at " << spin_rate << " rad/s with motor " << failed + 1
        << " stopped (the equations did not converge)";
    eq.why = why.str();
    return eq;
  }
  eq.thrust_n = x.head<3>();
  eq.rates = x.tail<3>();
  const Eigen::Vector3d F = force_of(m, l, eq.thrust_n);
  eq.up = up_axis(eq.rates, F);
  eq.axis_tilt_deg = std::acos(std::clamp(eq.up.dot(F.normalized()), -1.0, 1.0)) * kDegPerRad;
  for (std::size_t j = 0; j < 3; ++j) {
    const auto k = static_cast<std::size_t>(l.working[j]);
    const double f = eq.thrust_n[static_cast<Eigen::Index>(j)];
    if (f > kEquilibriumHeadroom * m.max_thrust_n[k] || f < m.min_thrust_n[k]) {
      why.precision(3);
      why << "with motor " << failed + 1 << " stopped, spinning at " << spin_rate
          << " rad/s needs motor " << k + 1 << " at " << f << " N, outside " << m.min_thrust_n[k]
          << ".." << kEquilibriumHeadroom * m.max_thrust_n[k] << " N (its idle to "
          << kEquilibriumHeadroom * 100 << " % of its thrust)";
      eq.why = why.str();
      return eq;
    }
  }
  eq.found = true;
  return eq;
}

SpinEquilibria solve_spin_equilibria(const SpinningDescentModel& model, double spin_rate_rad_s) {
  SpinEquilibria equilibria;
  for (int failed = 0; failed < 4; ++failed) {
    equilibria[static_cast<std::size_t>(failed)] =
        solve_spin_equilibrium(model, failed, spin_rate_rad_s);
  }
  return equilibria;
}

}  // namespace motormix
