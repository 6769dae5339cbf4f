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

#include <motormix/axes.hpp>
#include <motormix/effectiveness.hpp>
#include <motormix/mixing_matrix.hpp>
#include <motormix/motor_vector.hpp>

#include <cstdint>

namespace motormix {

// How a failure set is being handled, as reported in mixer_status_t.
enum class FailureHandling : std::uint8_t {
  kNone = 0,         // no motor failed
  kReallocated = 1,  // failed motors stopped; the others hold every commanded axis
  kAxesLost = 2,     // failed motors stopped; some axis cannot be held (see held axes)
  kUnsupported = 3,  // more failures than were prepared (or a strategy without reallocation):
                     // failed motors stopped, the rest mixed as prepared, loss reported
};

const char* to_string(FailureHandling handling);

struct FailureMixing {
  MotorMask failed = 0;
  // Rows: motors (zero for failed ones); columns: axes (zero for axes given
  // up). Healthy units: effectiveness * mixing is the identity on `held`.
  MixingMatrix mixing;
  // The healthy normalized effectiveness with the failed motors' columns
  // zeroed: what the remaining motors really produce, for reporting.
  EffectivenessMatrix effectiveness;
  AxisMask held = 0;  // axes the remaining motors still command independently
};

// `healthy`: the normalized effectiveness of the vehicle (effectiveness_of()
// of its mixing matrix); `controlled`: the axes it is commanded in.
FailureMixing derive_failure_mixing(const EffectivenessMatrix& healthy, AxisMask controlled,
                                    MotorMask failed);

// Number of motors in a mask.
int count_motors(MotorMask mask);

}  // namespace motormix
