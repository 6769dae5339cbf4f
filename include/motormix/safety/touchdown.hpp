#pragma once
// The touchdown rule both motor-loss descents (SpinningDescent on three
// rotors, TwoRotorDescent on two) land by: no vertical motion for the
// configured time once the descent has been flown, or the spin lost while
// still (in the air nothing takes the spin away: the rotors drive it and
// only the air brakes it). Pure; its state is three numbers.

#include <cmath>

namespace motormix {

class Touchdown {
 public:
  // Below this vertical speed (share of the descent rate) the vehicle is
  // not moving.
  static constexpr double kStillFraction = 0.25;
  // The descent has been flown once the vehicle went down at this share of
  // the descent rate for this long; before that, only a vehicle that does
  // not turn (a motor lost on the ground) can be still: right after the
  // takeover it may hover, but in the air the rotors' yaw torque turns it
  // within that time.
  static constexpr double kDescendingFraction = 0.5;
  static constexpr double kDescendedS = 1.0;
  static constexpr double kGroundedRateRadS = 0.5;
  // A spin once reached and now under this share of it is lost.
  static constexpr double kSpinLostShare = 0.3;

  void reset() {
    still_s_ = 0.0;
    descending_s_ = 0.0;
    descended_ = false;
  }

  // One update with a finite vertical speed (NED, m/s): `rate_rad_s` is
  // the measured body rate, `light` whether the thrust asked for leaves
  // the vehicle unable to be hovering (a descent that has no such test
  // passes true). Returns whether the vehicle is not moving vertically.
  bool update(double down_mps, double descent_rate_mps, double rate_rad_s, bool light, double dt) {
    const bool moving_down = down_mps > kDescendingFraction * descent_rate_mps;
    descending_s_ = moving_down ? descending_s_ + dt : 0.0;
    if (descending_s_ >= kDescendedS) descended_ = true;
    const bool not_moving = std::abs(down_mps) < kStillFraction * descent_rate_mps;
    const bool still = not_moving && (descended_ || rate_rad_s < kGroundedRateRadS) && light;
    still_s_ = still ? still_s_ + dt : 0.0;
    return not_moving;
  }

  // Landed: still for landed_after_s, or the spin lost while still.
  bool landed(double landed_after_s, bool spin_lost) const {
    return still_s_ >= landed_after_s || spin_lost;
  }
  bool descended() const { return descended_; }

 private:
  double still_s_ = 0.0;
  double descending_s_ = 0.0;  // moving down at the descent rate this long
  bool descended_ = false;     // the descent has been flown
};

}  // namespace motormix
