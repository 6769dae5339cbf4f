#include <motormix/allocation/clip_allocator.hpp>

#include "fixed_size.hpp"
#include "report_kernel.hpp"

namespace motormix {

// The mix, the clamp and the report in one pass at the motor count's fixed
// size, in this function itself (no further call: at four motors the call
// overhead is a good part of the cost).
AllocationResult ClipAllocator::allocate(const AxisVector& demand, MotorVector& commands) const {
  const Eigen::Index n = mixing_.rows();
  commands.resize(n);
  return detail::with_motor_count<detail::FixedCounts::kUpTo16>(
      n,
      [](auto size, const ClipAllocator& self, const AxisVector& target, double* out,
         Eigen::Index motors) MOTORMIX_INLINE_LAMBDA {
        constexpr int N = decltype(size)::value;
        detail::LocalMotors<N> u(motors);
        u.noalias() =
            detail::ConstMixingColumnsView<N>(self.mixing_by_column_.data(), motors, kNumAxes) *
            target;
        detail::clamp_into_range<N>(u, self.cycle_constants_);
        detail::MotorsView<N>(out, motors) = u;
        return detail::describe_fixed<N>(self.effectiveness_, target, u.data(), motors,
                                         self.cycle_constants_);
      },
      *this, demand, commands.data(), n);
}

}  // namespace motormix
