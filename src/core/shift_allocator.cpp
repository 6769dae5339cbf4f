#include <motormix/shift_allocator.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace motormix {

namespace {

// The interval of shifts k for which lo <= u + k d <= hi holds for every
// motor; empty when lo > hi.
struct Interval {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool empty() const { return lo > hi; }
};

Interval feasible_shifts(const MotorVector& u, const MotorVector& d, CommandRange r) {
  Interval k;
  for (Eigen::Index i = 0; i < u.size(); ++i) {
    if (d[i] <= 0.0) continue;  // such a motor cannot be moved by a shift
    k.lo = std::max(k.lo, (r.lower - u[i]) / d[i]);
    k.hi = std::min(k.hi, (r.upper - u[i]) / d[i]);
  }
  return k;
}

}  // namespace

ShiftAllocator::ShiftAllocator(const MixingMatrix& mixing, CommandRange range)
    : MatrixAllocator(mixing, range) {
  direction_ = mixing.col(index(Axis::kThrust));
  const double peak = direction_.cwiseAbs().maxCoeff();
  if (peak > 0.0 && direction_.minCoeff() > 0.0) {
    direction_ /= peak;
  } else {
    direction_.setOnes(mixing.rows());
  }
}

AllocationResult ShiftAllocator::allocate(const AxisVector& demand, MotorVector& commands) const {
  mix_linear(demand, commands);
  Interval k = feasible_shifts(commands, direction_, range_);
  if (k.empty()) {
    // The spread alone does not fit: shrink the part that is not along the
    // shift direction about the mean, just enough, then shift.
    const double mean = commands.mean();
    MotorVector spread = commands - MotorVector::Constant(commands.size(), mean);
    const double width = spread.maxCoeff() - spread.minCoeff();
    const double room = range_.upper - range_.lower;
    if (width > room) spread *= room / width;
    commands = MotorVector::Constant(commands.size(), mean) + spread;
    k = feasible_shifts(commands, direction_, range_);
  }
  // The smallest shift that lands inside (0 when already inside).
  const double shift = k.empty() ? 0.0 : std::clamp(0.0, k.lo, k.hi);
  commands += shift * direction_;
  return finish(demand, commands);
}

}  // namespace motormix
