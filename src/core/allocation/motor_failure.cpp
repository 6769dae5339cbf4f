#include <motormix/allocation/motor_failure.hpp>

#include <Eigen/QR>

#include <array>

namespace motormix {

namespace {
// Singular values below this fraction of the largest count as zero (as for
// the healthy derivation).
constexpr double kRankRelativeTolerance = 1e-9;

// Axes in the order they are given up when the remaining motors cannot
// command them all: yaw first, roll last.
constexpr std::array<Axis, kNumAxes> kGiveUpOrder = {Axis::kYaw, Axis::kThrust, Axis::kPitch,
                                                     Axis::kRoll};

// Rows `axes` of `e`, columns of the motors that still work.
Eigen::MatrixXd reduced(const EffectivenessMatrix& e, AxisMask axes, MotorMask failed) {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(kNumAxes, e.cols());
  for (int a = 0; a < kNumAxes; ++a) {
    if (!((axes >> a) & 1U)) continue;
    for (Eigen::Index i = 0; i < e.cols(); ++i) {
      if (!((failed >> i) & 1U)) out(a, i) = e(a, i);
    }
  }
  return out;
}

int count_axes(AxisMask mask) {
  int n = 0;
  for (int a = 0; a < kNumAxes; ++a) n += (mask >> a) & 1U;
  return n;
}

}  // namespace

int count_motors(MotorMask mask) {
  int n = 0;
  for (; mask != 0; mask &= mask - 1) ++n;
  return n;
}

FailureMixing derive_failure_mixing(const EffectivenessMatrix& healthy, AxisMask controlled,
                                    MotorMask failed) {
  FailureMixing f;
  f.failed = failed;
  f.effectiveness = healthy;
  for (Eigen::Index i = 0; i < healthy.cols(); ++i) {
    if ((failed >> i) & 1U) f.effectiveness.col(i).setZero();
  }
  // Give axes up, lowest priority first, until the rows left are
  // independent: then the pseudo-inverse delivers each of them exactly.
  AxisMask held = controlled;
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod;
  cod.setThreshold(kRankRelativeTolerance);
  for (Axis axis : kGiveUpOrder) {
    cod.compute(reduced(f.effectiveness, held, failed));
    if (cod.rank() == count_axes(held)) break;
    held = static_cast<AxisMask>(held & ~bit(axis));
  }
  cod.compute(reduced(f.effectiveness, held, failed));
  if (cod.rank() != count_axes(held)) held = 0;  // nothing independent is left
  f.held = held;
  f.mixing.setZero(healthy.cols(), kNumAxes);
  if (held != 0) {
    const Eigen::MatrixXd inverse = cod.pseudoInverse();  // motors x axes
    for (int a = 0; a < kNumAxes; ++a) {
      if ((held >> a) & 1U) f.mixing.col(a) = inverse.col(a);
    }
  }
  if ((held & bit(Axis::kYaw)) && failed != 0) {
    const AxisMask others = static_cast<AxisMask>(held & ~bit(Axis::kYaw));
    const Eigen::MatrixXd a = reduced(f.effectiveness, others, failed);
    cod.compute(a);
    const Eigen::MatrixXd least_norm = cod.pseudoInverse();  // motors x axes, yaw column zero
    // The part of the yaw row that roll, pitch and thrust do not see: moving
    // along it changes yaw and nothing else.
    const Eigen::VectorXd yaw_row =
        reduced(f.effectiveness, bit(Axis::kYaw), failed).row(index(Axis::kYaw)).transpose();
    const Eigen::VectorXd alone = yaw_row - least_norm * (a * yaw_row);
    const double per_unit = yaw_row.dot(alone);
    if (per_unit > kRankRelativeTolerance * yaw_row.squaredNorm()) {
      MixingMatrix m = MixingMatrix::Zero(healthy.cols(), kNumAxes);
      for (int ax = 0; ax < kNumAxes; ++ax) {
        if ((others >> ax) & 1U) m.col(ax) = least_norm.col(ax);
      }
      m.col(index(Axis::kYaw)) = alone / per_unit;
      f.yaw_free = m;
    }
  }
  return f;
}

FailurePlan prepare_failures(const MixingMatrix& healthy_mixing, CommandRange range,
                             double base_thrust, const FailureAllocatorFactory& make) {
  FailurePlan plan;
  plan.healthy_effectiveness = effectiveness_of(healthy_mixing);
  plan.controlled = controlled_axes(healthy_mixing);
  plan.range = range;
  plan.healthy_authority = authority_of(healthy_mixing, base_thrust, range.lower, range.upper);
  if (!make) return plan;
  const int n = static_cast<int>(healthy_mixing.rows());
  const auto prepare = [&](MotorMask failed) {
    const FailureMixing f =
        derive_failure_mixing(plan.healthy_effectiveness, plan.controlled, failed);
    PreparedFailure p;
    p.failed = failed;
    p.allocator = make(f, MixingBasis(f.mixing, f.effectiveness, plan.controlled));
    p.held = f.held;
    p.authority = authority_of(f.mixing, base_thrust, range.lower, range.upper);
    plan.prepared.push_back(std::move(p));
  };
  for (int i = 0; i < n; ++i) {
    if (n > 1) prepare(MotorMask{1} << i);
    for (int j = i + 1; j < n && n > 2; ++j) prepare((MotorMask{1} << i) | (MotorMask{1} << j));
  }
  return plan;
}

}  // namespace motormix
