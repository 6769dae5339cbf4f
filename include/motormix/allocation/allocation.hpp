#pragma once
// The allocation step: one small interface, one class per strategy. Each call
// returns what it could not deliver, so an upstream controller can stop its
// integrators winding up against saturated motors.

#include <motormix/axes.hpp>
#include <motormix/effectiveness/mixing_matrix.hpp>
#include <motormix/motor_vector.hpp>

#include <cstdint>
#include <string_view>

namespace motormix {

struct AllocationResult {
  MotorMask saturated_upper = 0;  // bit i: motor i at its upper limit
  MotorMask saturated_lower = 0;  // bit i: motor i at its lower limit
  std::uint8_t axis_limited = 0;  // bit(Axis): demand on that axis not fully delivered
  AxisVector unallocated = AxisVector::Zero();  // target minus produced, per axis
  std::uint16_t iterations = 0;  // solver iterations (optimal); 0 for closed-form strategies
};

// Limits every strategy keeps motor commands within.
struct CommandRange {
  double lower = 0.0;
  double upper = 1.0;
};

class Allocator {
 public:
  virtual ~Allocator() = default;
  Allocator() = default;
  Allocator(const Allocator&) = delete;
  Allocator& operator=(const Allocator&) = delete;

  virtual std::string_view name() const = 0;
  virtual int motors() const = 0;

  // demand: finite, roll/pitch/yaw in -1..1 and thrust in its range (the Mixer
  // guarantees both). Resizes `commands` to motors() (no allocation: fixed
  // capacity) and fills it within the command range. Never throws.
  virtual AllocationResult allocate(const AxisVector& demand, MotorVector& commands) const = 0;
};

// What a matrix strategy works from: the mixing matrix it applies, the
// effectiveness it reports against, and the axes it answers for. From a
// mixing matrix alone (the healthy vehicle) the effectiveness is the matrix's
// pseudo-inverse and the axes are its non-zero columns; after a motor failure
// they are the healthy vehicle's effectiveness without the failed motors and
// the healthy axes, so whatever the failure costs is reported (see
// motor_failure.hpp).
struct MixingBasis {
  MixingBasis(const MixingMatrix& mixing);  // implicit on purpose: the healthy case
  MixingBasis(const MixingMatrix& mixing, const EffectivenessMatrix& effectiveness,
              AxisMask controlled);
  MixingMatrix mixing;
  EffectivenessMatrix effectiveness;
  AxisMask controlled;
};

// What every cycle clamps and reports with (the range, the saturation
// thresholds, the axis mask, the tolerances), prepared once per strategy as
// whole packets (each value twice): the baseline x86-64 target has no
// broadcasting load, so a scalar made a packet costs a load and a shuffle
// on every call, and the compiler does that even for constants.
struct alignas(16) CycleConstants {
  CycleConstants(CommandRange range, AxisMask controlled);
  double lower[2];  // the command range
  double upper[2];
  double at_upper[2];  // a command at or above this sits on the upper limit (twice: one packet)
  double at_lower[2];  // at or below this, on the lower limit
  // All bits set on a controlled axis, none elsewhere: an undelivered
  // demand is kept or zeroed by a bitwise and, never multiplied.
  std::uint64_t axis_kept[kNumAxes];
  double delivered[2];  // kDeliveredTolerance
  double sign[2];       // -0.0: the sign bit alone
};

// Shared state of the strategies that work from a mixing matrix: the matrix,
// its normalized effectiveness (for reporting) and the command range.
class MatrixAllocator : public Allocator {
 public:
  MatrixAllocator(const MixingBasis& basis, CommandRange range);
  int motors() const override { return static_cast<int>(mixing_.rows()); }
  const MixingMatrix& mixing() const { return mixing_; }
  CommandRange range() const { return range_; }

 protected:
  // Unconstrained mix: M * demand.
  void mix_linear(const AxisVector& demand, MotorVector& commands) const;
  // Clamps into the range and reports against `target`.
  AllocationResult finish(const AxisVector& target, MotorVector& commands) const;
  // E M = I within `tolerance` on the controlled axes: commands in range
  // deliver exactly what they were mixed from (true of the healthy vehicle;
  // after a failure the effectiveness is the healthy one's, and an axis
  // given up is not delivered).
  bool effectiveness_inverts_mixing(double tolerance) const;
  // Every motor the same positive share of thrust, within rounding
  // (symmetric multirotors with equal rotors).
  bool equal_thrust_shares() const;

  MixingMatrix mixing_;
  // The same matrix stored column by column (zero below the motor count),
  // for the per-cycle products.
  Eigen::Matrix<double, kMaxMotors, kNumAxes> mixing_by_column_;
  EffectivenessMatrix effectiveness_;
  CommandRange range_;
  AxisMask controlled_;
  CycleConstants cycle_constants_;
};

// The shifts k along a direction d for which every motor of u + k d is in
// range. Motors with d <= 0 cannot be moved by the shift: if one of them is
// out of range (by more than 1e-12), no shift helps and the interval is
// empty.
struct ShiftInterval {
  double lo;
  double hi;
  bool empty() const { return lo > hi; }
  // The smallest move that lands inside (0 when already inside).
  double smallest() const { return lo > 0.0 ? lo : (hi < 0.0 ? hi : 0.0); }
};
ShiftInterval feasible_shifts(const MotorVector& u, const MotorVector& d, CommandRange range);

// Fills saturation flags and the unallocated demand by comparing `target` with
// what `commands` produce through `effectiveness`. Shared by all strategies so
// they report alike.
// Axes outside `controlled` (roll and pitch of a wheeled vehicle) are not
// commanded at all: a demand there is ignored, not reported as undelivered.
AllocationResult describe_allocation(const EffectivenessMatrix& effectiveness,
                                     const AxisVector& target, const MotorVector& commands,
                                     CommandRange range, AxisMask controlled);
// The same with the range and the axis mask prepared once, for a caller that
// reports every cycle.
AllocationResult describe_allocation(const EffectivenessMatrix& effectiveness,
                                     const AxisVector& target, const MotorVector& commands,
                                     const CycleConstants& limits);

// Demand differences below this count as delivered (normalized units).
inline constexpr double kDeliveredTolerance = 1e-6;

}  // namespace motormix
