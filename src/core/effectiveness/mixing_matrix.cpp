#include <motormix/effectiveness/mixing_matrix.hpp>

#include <Eigen/QR>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <limits>

namespace motormix {

namespace {
// Singular values below this fraction of the largest are treated as zero.
constexpr double kRankRelativeTolerance = 1e-9;
// Entries below this magnitude count as zero when counting motors that act
// on an axis (PX4's normalization counts them the same way).
constexpr double kNonZeroEntry = 1e-3;

Eigen::MatrixXd pinv(const Eigen::MatrixXd& m) {
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(m);
  cod.setThreshold(kRankRelativeTolerance);
  return cod.pseudoInverse();
}

int rank(const Eigen::MatrixXd& m) {
  if (m.size() == 0) return 0;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(m);
  svd.setThreshold(kRankRelativeTolerance);
  return static_cast<int>(svd.rank());
}

AxisVector axis_max_scale(const Eigen::MatrixXd& raw) {
  AxisVector s;
  for (int a = 0; a < kNumAxes; ++a) s[a] = raw.col(a).cwiseAbs().maxCoeff();
  return s;
}

AxisVector px4_scale(const Eigen::MatrixXd& raw) {
  AxisVector s = AxisVector::Ones();
  const auto rms_scale = [&](int a) {
    const double nonzero = static_cast<double>((raw.col(a).array().abs() > kNonZeroEntry).count());
    return nonzero > 0 ? std::sqrt(raw.col(a).squaredNorm() / (nonzero / 2.0)) : 0.0;
  };
  const double roll_pitch = std::max(rms_scale(index(Axis::kRoll)), rms_scale(index(Axis::kPitch)));
  s[index(Axis::kRoll)] = roll_pitch;
  s[index(Axis::kPitch)] = roll_pitch;
  s[index(Axis::kYaw)] = raw.col(index(Axis::kYaw)).maxCoeff();
  const auto thrust = raw.col(index(Axis::kThrust)).array().abs();
  const double nonzero =
      static_cast<double>((thrust > std::numeric_limits<double>::epsilon()).count());
  s[index(Axis::kThrust)] = nonzero > 0 ? thrust.sum() / nonzero : 0.0;
  return s;
}

}  // namespace

MixingDerivation derive_mixing(const EffectivenessMatrix& effectiveness, AxisMask controlled,
                               Normalization normalization) {
  const Eigen::Index n = effectiveness.cols();
  Eigen::MatrixXd e = effectiveness;
  for (int a = 0; a < kNumAxes; ++a) {
    if (!((controlled >> a) & 1U)) e.row(a).setZero();
  }
  MixingDerivation d;
  d.rank = rank(e);
  // An axis is uncontrollable when its row adds nothing to the others: the
  // motors cannot produce it without also producing something else.
  for (int a = 0; a < kNumAxes; ++a) {
    if (!((controlled >> a) & 1U)) continue;
    Eigen::MatrixXd without = e;
    without.row(a).setZero();
    if (e.row(a).norm() == 0.0 || rank(without) == d.rank) {
      d.uncontrollable |= static_cast<AxisMask>(1U << a);
    }
  }
  const Eigen::MatrixXd raw = pinv(e);  // n x 4; zero columns for zero rows
  switch (normalization) {
    case Normalization::kAxisMax:
      d.scale = axis_max_scale(raw);
      break;
    case Normalization::kPx4:
      d.scale = px4_scale(raw);
      break;
    case Normalization::kNone:
      d.scale = AxisVector::Ones();
      // Thrust is still scaled by its mean, so full thrust means full
      // command on identical rotors (PX4 does the same without rpy scaling).
      d.scale[index(Axis::kThrust)] = px4_scale(raw)[index(Axis::kThrust)];
      break;
  }
  d.mixing.resize(n, kNumAxes);
  for (int a = 0; a < kNumAxes; ++a) {
    const bool usable = ((controlled >> a) & 1U) && d.scale[a] > 0.0;
    if (!usable) d.scale[a] = 1.0;
    d.mixing.col(a) = usable ? (raw.col(a) / d.scale[a]).eval() : Eigen::VectorXd::Zero(n);
  }
  return d;
}

EffectivenessMatrix effectiveness_of(const MixingMatrix& mixing) {
  return pinv(Eigen::MatrixXd(mixing));
}

int rank_of(const MixingMatrix& mixing) { return rank(Eigen::MatrixXd(mixing)); }

AxisMask controlled_axes(const MixingMatrix& mixing) {
  AxisMask mask = 0;
  for (int a = 0; a < kNumAxes; ++a) {
    if (mixing.col(a).cwiseAbs().maxCoeff() > 0.0) mask |= static_cast<AxisMask>(1U << a);
  }
  return mask;
}

AxisVector authority_of(const MixingMatrix& mixing, double base_thrust, double lower,
                        double upper) {
  AxisVector authority;
  for (int a = 0; a < kNumAxes; ++a) {
    const bool thrust_axis = a == index(Axis::kThrust);
    double best = std::numeric_limits<double>::infinity();
    bool acts = false;
    for (Eigen::Index i = 0; i < mixing.rows(); ++i) {
      const double base = thrust_axis ? 0.0 : mixing(i, index(Axis::kThrust)) * base_thrust;
      const double c = mixing(i, a);
      if (std::abs(c) < 1e-12) continue;
      acts = true;
      best = std::min(best, c > 0 ? (upper - base) / c : (lower - base) / c);
    }
    authority[a] = acts ? std::max(0.0, best) : 0.0;
  }
  return authority;
}

}  // namespace motormix
