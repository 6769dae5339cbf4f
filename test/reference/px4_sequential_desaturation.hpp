#pragma once
// A restatement of PX4's sequential desaturation (ControlAllocationSequential-
// Desaturation in src/lib/control_allocation, from its published source), in
// float as PX4 runs it, with its final clip and its "allocated control"
// report (effectiveness times the clipped setpoint). It is the baseline that
// motormix's `prioritized` strategy is benchmarked and compared against; it
// is not part of motormix.
//
// Conventions are motormix's: columns roll, pitch, yaw, thrust, with a
// positive thrust column (PX4 mixes a negative z thrust; the arithmetic is
// the same with the sign folded in), commands in [0, 1].
//
// The scalar type is a parameter: float for benchmarks (what PX4 runs), double
// for comparing delivered demands with motormix without float noise.
//
// Two rules for which motors a desaturation step may use, both kept because
// both have flown: PX4's current computeDesaturationGain skips every motor
// whose entry in the desaturation vector is below 0.2 in magnitude ("do not
// try to desaturate using an actuator with weak effectiveness to avoid large
// desaturation gains"); the older multirotor mixer skipped only entries
// below FLT_EPSILON.

#include <motormix/effectiveness/mixing_matrix.hpp>

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>

namespace motormix::reference {

enum class Px4Airmode { kDisabled = 0, kRollPitch = 1, kRollPitchYaw = 2 };

// Which desaturation-vector entries a step ignores (see above).
enum class Px4WeakEntryRule { kCurrent, kEpsilon };

template <typename Scalar, Px4WeakEntryRule kRule = Px4WeakEntryRule::kCurrent>
class SequentialDesaturation {
 public:
  using Airmode = Px4Airmode;
  using Vec = Scalar[kMaxMotors];
  static constexpr int kMax = kMaxMotors;
  static constexpr Scalar kMinimumYawMargin = Scalar(0.15);  // PX4's MINIMUM_YAW_MARGIN
  // A compile-time constant, as in PX4's source.
  static constexpr Scalar kWeak =
      kRule == Px4WeakEntryRule::kCurrent ? Scalar(0.2) : Scalar(FLT_EPSILON);

  SequentialDesaturation(const MixingMatrix& mixing, Airmode airmode)
      : n_(static_cast<int>(mixing.rows())), airmode_(airmode) {
    const EffectivenessMatrix e = effectiveness_of(mixing);
    for (int i = 0; i < n_; ++i) {
      for (int a = 0; a < 4; ++a) {
        mix_[static_cast<std::size_t>(a)][static_cast<std::size_t>(i)] =
            static_cast<Scalar>(mixing(i, a));
        eff_[static_cast<std::size_t>(a)][static_cast<std::size_t>(i)] =
            static_cast<Scalar>(e(a, i));
      }
    }
  }

  // control_sp: roll, pitch, yaw, thrust (normalized).
  void allocate(const std::array<Scalar, 4>& control_sp) {
    sp_ = control_sp;
    switch (airmode_) {
      case Airmode::kRollPitch:
        mix_airmode_rp();
        break;
      case Airmode::kRollPitchYaw:
        mix_airmode_rpy();
        break;
      default:
        mix_airmode_disabled();
        break;
    }
    // Clip, then report what the clipped setpoint produces.
    for (int i = 0; i < n_; ++i) act_[i] = std::min(std::max(act_[i], Scalar(0)), Scalar(1));
    for (std::size_t a = 0; a < 4; ++a) {
      Scalar sum = 0;
      for (int i = 0; i < n_; ++i) sum += eff_[a][static_cast<std::size_t>(i)] * act_[i];
      allocated_[a] = sum;
    }
  }

  int motors() const { return n_; }
  Scalar actuator(int i) const { return act_[i]; }
  const std::array<Scalar, 4>& allocated() const { return allocated_; }

 private:
  const Scalar* col(int a) const { return mix_[static_cast<std::size_t>(a)].data(); }

  Scalar desaturation_gain(const Scalar* v, const Scalar* u) const {
    Scalar k_min = 0;
    Scalar k_max = 0;
    for (int i = 0; i < n_; ++i) {
      if (std::abs(v[i]) < kWeak) continue;
      if (u[i] < act_min_) {
        const Scalar k = (act_min_ - u[i]) / v[i];
        if (k < k_min) k_min = k;
        if (k > k_max) k_max = k;
      }
      if (u[i] > act_max_) {
        const Scalar k = (act_max_ - u[i]) / v[i];
        if (k < k_min) k_min = k;
        if (k > k_max) k_max = k;
      }
    }
    return k_min + k_max;
  }

  // decrease_only: thrust may only go down (PX4's "increase_only" flag, whose
  // sign convention is that of its negative z thrust).
  void desaturate(Scalar* u, const Scalar* v, bool decrease_only = false) {
    Scalar gain = desaturation_gain(v, u);
    if (decrease_only && gain > 0) return;
    for (int i = 0; i < n_; ++i) u[i] += gain * v[i];
    gain = Scalar(0.5) * desaturation_gain(v, u);
    for (int i = 0; i < n_; ++i) u[i] += gain * v[i];
  }

  void mix(bool with_yaw) {
    for (int i = 0; i < n_; ++i) {
      act_[i] = col(0)[i] * sp_[0] + col(1)[i] * sp_[1] + col(3)[i] * sp_[3] +
                (with_yaw ? col(2)[i] * sp_[2] : Scalar(0));
    }
  }

  void mix_yaw() {
    for (int i = 0; i < n_; ++i) act_[i] += col(2)[i] * sp_[2];
    const Scalar max_prev = act_max_;
    act_max_ += (act_max_ - act_min_) * kMinimumYawMargin;
    desaturate(act_, col(2));
    act_max_ = max_prev;
    desaturate(act_, col(3), true);
  }

  void mix_airmode_rp() {
    mix(false);
    desaturate(act_, col(3));
    mix_yaw();
  }

  void mix_airmode_rpy() {
    mix(true);
    desaturate(act_, col(3));
    desaturate(act_, col(2));
  }

  void mix_airmode_disabled() {
    mix(false);
    desaturate(act_, col(3), true);
    desaturate(act_, col(0));
    desaturate(act_, col(1));
    mix_yaw();
  }

  int n_;
  Airmode airmode_;
  std::array<std::array<Scalar, kMax>, 4> mix_{};
  std::array<std::array<Scalar, kMax>, 4> eff_{};
  std::array<Scalar, 4> sp_{};
  Vec act_{};
  Scalar act_min_ = 0;
  Scalar act_max_ = 1;
  std::array<Scalar, 4> allocated_{};
};

// As PX4 runs it today, and as its older mixer did.
using Px4SequentialDesaturation = SequentialDesaturation<float>;
using Px4EpsilonSequentialDesaturation = SequentialDesaturation<float, Px4WeakEntryRule::kEpsilon>;

}  // namespace motormix::reference
