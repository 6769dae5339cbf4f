#include <motormix/clip_allocator.hpp>

#include "fixed_size.hpp"
#include "report_kernel.hpp"

namespace motormix {

// The mix, the clamp and the report in one pass at the motor count's fixed
// size, in this function itself (no further call: at four motors the call
// overhead is a good part of the cost).
AllocationResult ClipAllocator::allocate(const AxisVector& demand, MotorVector& commands) const {
  const Eigen::Index n = mixing_.rows();
  commands.resize(n);
  const CommandRange range = range_;
  return detail::with_motor_count(n, [&](auto size) {
    constexpr int N = decltype(size)::value;
    detail::LocalMotors<N> u(n);
    u.noalias() = detail::ConstMixingColumnsView<N>(mixing_by_column_.data(), n, kNumAxes) * demand;
    // Finite demand and matrix give finite commands (the Mixer guarantees
    // the demand): a plain clamp.
    u = u.cwiseMax(range.lower).cwiseMin(range.upper);
    detail::MotorsView<N>(commands.data(), n) = u;
    return detail::describe_fixed<N>(effectiveness_, demand, u.data(), n, range, controlled_);
  });
}

}  // namespace motormix
