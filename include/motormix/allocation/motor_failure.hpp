#pragma once
// Reallocation after motor failures. A failed motor is commanded to its stop
// value, and the healthy motors take over its share: the mixing matrix is
// derived again from the effectiveness without the failed columns, in the
// healthy vehicle's units (no normalization), so a demand means the same
// torque and thrust before and after, and controller gains keep their
// meaning. When the remaining motors cannot command every axis on its own
// (a quad with a motor out cannot hold yaw), axes are given up in reverse
// priority order (yaw, then thrust, then pitch, then roll) until the rest
// are independent, and the loss is reported, never hidden.
//
// Everything here runs at set-up: a switch of failure set in flight only
// selects a matrix computed before.

#include <motormix/allocation/allocation.hpp>
#include <motormix/axes.hpp>
#include <motormix/effectiveness/effectiveness.hpp>
#include <motormix/effectiveness/mixing_matrix.hpp>
#include <motormix/enum_names.hpp>
#include <motormix/motor_vector.hpp>

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

namespace motormix {

// How a failure set is being handled, as reported in mixer_status_t.
enum class FailureHandling : std::uint8_t {
  kNone = 0,         // no motor failed
  kReallocated = 1,  // failed motors stopped; the others hold every commanded axis
  kAxesLost = 2,     // failed motors stopped; some axis cannot be held (see held axes)
  kUnsupported = 3,  // more failures than were prepared (or a strategy without reallocation):
                     // failed motors stopped, the rest mixed as prepared, loss reported
};

inline constexpr EnumName<FailureHandling> kFailureHandlingNames[] = {
    {FailureHandling::kNone, "none"},
    {FailureHandling::kReallocated, "reallocated"},
    {FailureHandling::kAxesLost, "axes lost"},
    {FailureHandling::kUnsupported, "unsupported"},
};
inline const char* to_string(FailureHandling value) {
  return name_in(kFailureHandlingNames, value);
}

struct FailureMixing {
  MotorMask failed = 0;
  // Rows: motors (zero for failed ones); columns: axes (zero for axes given
  // up). Healthy units: effectiveness * mixing is the identity on `held`.
  MixingMatrix mixing;
  // The healthy normalized effectiveness with the failed motors' columns
  // zeroed: what the remaining motors really produce, for reporting.
  EffectivenessMatrix effectiveness;
  AxisMask held = 0;  // axes the remaining motors still command independently
  // For `prioritized`: roll, pitch and thrust in their least-norm mix with no
  // regard for yaw, and a yaw column that moves yaw alone. With motors out,
  // hovering with exactly the demanded yaw can leave no room at all for roll
  // or pitch (a hexa with alternating spins puts the opposite motor at zero),
  // while any other yaw leaves plenty: this is the basis on which yaw gives
  // way entirely. Set only when yaw is held and can be moved on its own.
  std::optional<MixingMatrix> yaw_free;
};

// `healthy`: the normalized effectiveness of the vehicle (effectiveness_of()
// of its mixing matrix); `controlled`: the axes it is commanded in.
FailureMixing derive_failure_mixing(const EffectivenessMatrix& healthy, AxisMask controlled,
                                    MotorMask failed);

// Number of motors in a mask.
int count_motors(MotorMask mask);

// One failure set prepared at set-up: the strategy rebuilt on the reduced
// matrix, and what that set leaves.
struct PreparedFailure {
  MotorMask failed = 0;
  std::unique_ptr<const Allocator> allocator;
  AxisMask held = 0;
  AxisVector authority = AxisVector::Zero();
};

// What the mixer needs to handle failures in flight without computing
// anything: the healthy effectiveness (to report what the working motors
// really produce) and every prepared failure set, sorted by mask.
struct FailurePlan {
  EffectivenessMatrix healthy_effectiveness;  // empty: no reallocation for this strategy
  AxisMask controlled = kAllAxes;
  CommandRange range;
  AxisVector healthy_authority = AxisVector::Zero();
  std::vector<PreparedFailure> prepared;
};

// Builds the strategy for one failure set from its derived matrices.
using FailureAllocatorFactory = std::function<std::unique_ptr<const Allocator>(
    const FailureMixing& failure, const MixingBasis& basis)>;

// Every single failure and every pair of `healthy_mixing`'s motors (at most
// 16 + 120 sets), each with its allocator from `make` (none when `make` is
// empty: the strategy has no reallocation) and the authority of its linear
// mix with torques measured at `base_thrust`.
FailurePlan prepare_failures(const MixingMatrix& healthy_mixing, CommandRange range,
                             double base_thrust, const FailureAllocatorFactory& make);

}  // namespace motormix
