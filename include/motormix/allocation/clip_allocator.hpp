#pragma once
// Strategy `clip`: mix linearly, clip each motor to its range. The baseline
// every other strategy is compared with: whatever saturates is simply lost,
// and the attitude error lands wherever the clipping puts it.

#include <motormix/allocation/allocation.hpp>

namespace motormix {

class ClipAllocator final : public MatrixAllocator {
 public:
  using MatrixAllocator::MatrixAllocator;
  std::string_view name() const override { return "clip"; }
  AllocationResult allocate(const AxisVector& demand, MotorVector& commands) const override;
};

}  // namespace motormix
