#pragma once
// `prioritized` for a vehicle with motors out. Sequential desaturation on the
// reduced matrix keeps its rules, but scaling yaw toward zero is not always
// enough any more: with motors out, zero yaw itself can sit on the edge of
// what the working motors can do, so roll and pitch would be cut although a
// different yaw would leave room for them. When the reduced matrix does not
// deliver roll, pitch and thrust, this allocator mixes roll, pitch and thrust
// with yaw left free (their least-norm mix, desaturated in the same priority
// order), then adds as much of the demanded yaw as the range allows along the
// direction that moves yaw alone. It keeps whichever of the two delivers the
// demand better in priority order: roll and pitch, then thrust, then yaw.

#include <motormix/allocation.hpp>
#include <motormix/prioritized_allocator.hpp>

#include <memory>

namespace motormix {

class YawYieldingAllocator final : public Allocator {
 public:
  // `reduced`: the failure's mixing basis; `yaw_free`: the same failure's
  // yaw-free mixing (FailureMixing::yaw_free).
  YawYieldingAllocator(const MixingBasis& reduced, const MixingMatrix& yaw_free, CommandRange range,
                       Airmode airmode, double yaw_headroom);
  std::string_view name() const override { return "prioritized"; }
  int motors() const override { return full_.motors(); }
  AllocationResult allocate(const AxisVector& demand, MotorVector& commands) const override;

 private:
  PrioritizedAllocator full_;
  PrioritizedAllocator yaw_free_;
  MotorVector yaw_alone_;  // command change per unit of yaw, nothing else
  EffectivenessMatrix effectiveness_;
  CommandRange range_;
  AxisMask controlled_;
};

}  // namespace motormix
