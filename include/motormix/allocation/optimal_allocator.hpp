#pragma once
// Strategy `optimal`: bounded weighted least squares (active-set method, as
// in Harkegard's WLS allocation). It finds motor commands within their
// limits that minimize
//     gamma * |W (E u - d)|^2 + |u - u_p|^2
// where E is the normalized effectiveness, d the demand, W the per-axis
// weights from config, u_p the plain linear mix clipped to the limits, and
// gamma large (attitude error dominates; the second term only picks among
// equally good answers). Every iterate stays within the limits, so stopping
// at the iteration cap still returns a feasible answer, never a worse one
// than where it started. No heap: all matrices have fixed capacity.

#include <motormix/allocation/allocation.hpp>
#include <motormix/allocation/allocation_settings.hpp>

namespace motormix {

class OptimalAllocator final : public MatrixAllocator {
 public:
  OptimalAllocator(const MixingBasis& basis, CommandRange range, OptimalSettings settings);
  std::string_view name() const override { return "optimal"; }
  AllocationResult allocate(const AxisVector& demand, MotorVector& commands) const override;

 private:
  // allocate() at N motors (Eigen::Dynamic: a count without its own
  // instantiation, see src/core/allocation/fixed_size.hpp).
  template <int N>
  AllocationResult solve(const AxisVector& demand, double* out, Eigen::Index n) const;

  OptimalSettings settings_;
  EffectivenessMatrix weighted_;  // W E: the effectiveness with each axis row weighted
};

// The weighted squared error |W (E u - d)|^2 that `optimal` minimizes, for
// comparing strategies.
double weighted_error(const EffectivenessMatrix& effectiveness, const AxisVector& weights,
                      const AxisVector& demand, const MotorVector& commands);

}  // namespace motormix
