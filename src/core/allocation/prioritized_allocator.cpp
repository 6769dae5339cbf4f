#include <motormix/allocation/prioritized_allocator.hpp>

#include "fitting_scale.hpp"
#include "fixed_size.hpp"
#include "priority_order.hpp"
#include "report_kernel.hpp"
#include "shift_kernel.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace motormix {

namespace {

// Column entries smaller than this do not move a motor (the sequence's
// gains ignore them rather than divide by them).
constexpr double kNegligibleEntry = std::numeric_limits<float>::epsilon();
constexpr double kInf = std::numeric_limits<double>::infinity();

using detail::closer_in_order;
using detail::prefer_repair;
using detail::roll_pitch_norm;
using detail::roll_pitch_square;
using detail::roll_pitch_verdict;
using detail::RollPitchVerdict;

}  // namespace

PrioritizedAllocator::InRangeGains PrioritizedAllocator::in_range_gains(const MotorVector& v,
                                                                        CommandRange range) {
  InRangeGains g{MotorVector(v.size()), MotorVector(v.size()), MotorVector(v.size())};
  for (Eigen::Index i = 0; i < v.size(); ++i) {
    if (std::abs(v[i]) < kNegligibleEntry) {
      g.inverse[i] = 0.0;
      g.lowest[i] = -kInf;
      g.highest[i] = kInf;
      continue;
    }
    // Motor i reaches bound b at the gain (b - u_i) / v_i; which bound
    // comes first depends on the entry's sign.
    g.inverse[i] = 1.0 / v[i];
    const double at_lower = range.lower * g.inverse[i];
    const double at_upper = range.upper * g.inverse[i];
    g.lowest[i] = std::min(at_lower, at_upper);
    g.highest[i] = std::max(at_lower, at_upper);
  }
  return g;
}

PrioritizedAllocator::PrioritizedAllocator(const MixingBasis& basis, CommandRange range,
                                           AirmodeLimits airmode, double yaw_headroom,
                                           double tie_tolerance)
    : MatrixAllocator(basis, range),
      yaw_headroom_(yaw_headroom),
      // NaN or negative would make every comparison a loss for the repair
      // or none a tie: neither is a tolerance.
      tie_tolerance_(tie_tolerance >= 0.0 ? tie_tolerance : 0.0),
      gain_that_counts_(std::min(tie_tolerance_, kGainThatCounts)) {
  for (int a = 0; a < kNumAxes; ++a) {
    gains_[static_cast<std::size_t>(a)] = in_range_gains(mixing_.col(a), range_);
  }
  CommandRange widened = range_;
  widened.upper += (range_.upper - range_.lower) * yaw_headroom_;
  const MotorVector yaw = mixing_.col(index(Axis::kYaw));
  const MotorVector thrust = mixing_.col(index(Axis::kThrust));
  yaw_gains_with_headroom_ = in_range_gains(yaw, widened);
  lift_inverse_ = detail::positive_inverse(thrust);
  all_motors_lift_ = thrust.size() == 0 || thrust.minCoeff() > 0.0;
  constexpr double kInverts = 1e-9;  // far below the delivered tolerance's effect
  effectiveness_inverts_mixing_ = effectiveness_inverts_mixing(kInverts);
  if (yaw.size() > 1) {
    const double scale = yaw.cwiseAbs().maxCoeff();
    const double same = 1e-12 * scale;  // equal within rounding
    const double a = yaw[0];
    double b = a;
    for (Eigen::Index i = 0; i < yaw.size(); ++i) {
      if (std::abs(yaw[i] - a) > same) b = yaw[i];
    }
    bool two = scale > 0.0 && std::abs(b - a) > same;
    yaw_pad_a_.resize(yaw.size());
    yaw_pad_b_.resize(yaw.size());
    for (Eigen::Index i = 0; i < yaw.size() && two; ++i) {
      const bool in_a = std::abs(yaw[i] - a) <= same;
      two = in_a || std::abs(yaw[i] - b) <= same;
      yaw_pad_a_[i] = in_a ? 0.0 : kInf;
      yaw_pad_b_[i] = in_a ? kInf : 0.0;
    }
    yaw_two_groups_ = two;
    yaw_value_a_ = a;
    yaw_value_b_ = b;
  }
  // Equal within rounding: the repair's shift still uses the column itself.
  equal_lift_ = equal_thrust_shares();

  // Out of [0, 1] (or NaN) is no limit a configuration passes: the nearest
  // end, NaN as none.
  const auto share = [](double x) { return x >= 0.0 ? std::min(x, 1.0) : 0.0; };
  airmode.roll_pitch = share(airmode.roll_pitch);
  airmode.yaw = share(airmode.yaw);
  const std::optional<Airmode> named = named_airmode(airmode);
  sequence_ = !named                          ? Sequence::kLimited
              : *named == Airmode::kOff       ? Sequence::kOff
              : *named == Airmode::kRollPitch ? Sequence::kRollPitch
                                              : Sequence::kRollPitchYaw;
  // A share of the range, as a gain along the thrust column: no motor
  // rises by more than that share of its range. 1 is no cap at all.
  const double top_share = thrust.size() > 0 ? thrust.cwiseAbs().maxCoeff() : 0.0;
  const double room = range_.upper - range_.lower;
  const auto cap = [&](double limit) {
    if (limit >= 1.0) return kInf;
    return limit > 0.0 && top_share > 0.0 ? limit * room / top_share : 0.0;
  };
  rp_rise_cap_ = cap(airmode.roll_pitch);
  yaw_rise_cap_ = cap(airmode.yaw);
  rp_rise_command_ = airmode.roll_pitch >= 1.0 ? kInf : airmode.roll_pitch * room;
}

// One allocation at N motors, every per-motor vector a local of fixed size.
template <int N>
class PrioritizedAllocator::Kernel {
 public:
  using Motors = detail::LocalMotors<N>;
  using View = detail::ConstMotorsView<N>;

  explicit Kernel(const PrioritizedAllocator& a) : a_(a), n_(a.mixing_.rows()), range_(a.range_) {}

  AllocationResult allocate(const AxisVector& demand, MotorVector& commands) const {
    Motors u(n_);
    u.noalias() = mixing() * demand;
    const double lowest = u.minCoeff();
    const double highest = u.maxCoeff();
    if (lowest >= range_.lower && highest <= range_.upper) {
      return deliver(demand, u, commands);  // nothing saturates: nothing to prioritize
    }
    const double yaw = demand[index(Axis::kYaw)];
    AxisVector effective = demand;
    effective[index(Axis::kYaw)] = 0.0;
    switch (a_.sequence_) {
      case Sequence::kOff:
        u -= yaw * column(Axis::kYaw);  // the mix without yaw
        desaturate(u, effective, Axis::kThrust, kNoRise);
        desaturate(u, effective, Axis::kRoll);
        desaturate(u, effective, Axis::kPitch);
        mix_yaw(yaw, u, effective);
        break;
      case Sequence::kRollPitch:
        u -= yaw * column(Axis::kYaw);  // the mix without yaw
        desaturate(u, effective, Axis::kThrust);
        mix_yaw(yaw, u, effective);
        break;
      case Sequence::kLimited:
        // off and roll_pitch with the thrust's rise capped: what the rise
        // cannot fix comes from roll and pitch (under a whole share).
        u -= yaw * column(Axis::kYaw);
        desaturate(u, effective, Axis::kThrust, a_.rp_rise_cap_);
        if (!a_.keeps_roll_pitch()) {
          desaturate(u, effective, Axis::kRoll);
          desaturate(u, effective, Axis::kPitch);
        }
        mix_yaw(yaw, u, effective, a_.yaw_rise_cap_);
        break;
      case Sequence::kRollPitchYaw:
        effective = demand;  // u is already the mix of the whole demand
        if (a_.equal_lift_) {
          // Thrust moves every motor alike: the extremes just taken give
          // its step, with no second pass.
          desaturate_equal_lift(u, effective, lowest, highest);
        } else {
          desaturate(u, effective, Axis::kThrust);
        }
        {
          // desaturate() inlined: the one step between the mix and the range
          // check here, and where the compiler keeps desaturate_along out of
          // line (hexa, octo) a call passed the motors through memory both
          // ways (a fifth of the octo's time).
          const Needs needs = needs_along(u, a_.gains_[index(Axis::kYaw)]);
          step(u, effective, Axis::kYaw, needs.up, needs.down, kInf);
        }
        break;
    }
    constexpr double kRangeSlack = 1e-12;  // the sequence's own rounding
    if (u.minCoeff() >= range_.lower - kRangeSlack && u.maxCoeff() <= range_.upper + kRangeSlack) {
      return deliver(demand, u, commands);
    }
    // Two ways to bring the sequence's result into range: the repair (scale
    // yaw, then roll and pitch, along their demanded directions, with the
    // best thrust shift), or clipping each motor as sequential desaturation
    // does elsewhere. Clipping can change the direction of the delivered
    // torque yet land closer to the demand. The clip stays unless the
    // repair delivers the demand better in priority order (roll and pitch,
    // then thrust, then yaw) without losing more than the tie tolerance on
    // any key (prefer_repair). The demand's roll/pitch error is needed only by the shortcut below
    // with airmode, and from the demand alone: taken before the clip and the scales, its root is
    // ready when they are.
    const double demanded = a_.effectiveness_inverts_mixing_ && a_.keeps_roll_pitch()
                                ? demanded_roll_pitch(demand)
                                : 0.0;
    Motors clipped = u;
    clamp(clipped);
    const AxisVector clip_left = undelivered(demand, clipped);
    const Repair r = repair_scales(effective);
    // When the effectiveness inverts the mixing matrix, the repair's roll
    // and pitch error is known from its scales alone: in range, its
    // commands deliver exactly the scaled effective demand. With a margin
    // far above the rounding of that shortcut, it often decides the first
    // key of the order without the repaired commands' report: the clip is
    // closer (no repaired commands needed), or the repair is (no
    // comparison of the two reports needed). Squared norms keep a root
    // off the chain that the decision waits for.
    RollPitchVerdict verdict = RollPitchVerdict::kUndecided;
    if (a_.effectiveness_inverts_mixing_) {
      verdict = roll_pitch_verdict(roll_pitch_square(clip_left),
                                   repair_roll_pitch_error(demand, effective, r, demanded),
                                   a_.gain_that_counts_, a_.tie_tolerance_);
      if (verdict == RollPitchVerdict::kClipCloser) {
        store(clipped, commands);
        return detail::describe_with<N>(clip_left, clipped.data(), n_, a_.cycle_constants_);
      }
    }
    const bool repair_fits = apply(r, effective, u);
    clamp(u);
    const AxisVector repair_left = undelivered(demand, u);
    // The shortcut holds only for repaired commands in range.
    const bool repair_closer = verdict == RollPitchVerdict::kRepairCloser && repair_fits;
    if (!repair_closer &&
        !prefer_repair(repair_left, clip_left, a_.gain_that_counts_, a_.tie_tolerance_)) {
      store(clipped, commands);
      return detail::describe_with<N>(clip_left, clipped.data(), n_, a_.cycle_constants_);
    }
    store(u, commands);
    return detail::describe_with<N>(repair_left, u.data(), n_, a_.cycle_constants_);
  }

 private:
  // A step along thrust that may only lower it.
  static constexpr double kNoRise = 0.0;

  detail::ConstMixingColumnsView<N> mixing() const {
    return detail::ConstMixingColumnsView<N>(a_.mixing_by_column_.data(), n_, kNumAxes);
  }
  // A column of the mixing matrix: contiguous in MatrixAllocator's
  // column-major copy.
  View column(Axis axis) const { return View(a_.mixing_by_column_.col(index(axis)).data(), n_); }

  // Into the range; NaN (which finite inputs cannot produce) to the safe end.
  void clamp(Motors& u) const { detail::clamp_into_range<N>(u, a_.cycle_constants_); }
  void store(const Motors& u, MotorVector& commands) const {
    commands.resize(n_);
    detail::MotorsView<N>(commands.data(), n_) = u;
  }
  AxisVector undelivered(const AxisVector& target, const Motors& u) const {
    return detail::undelivered<N>(a_.effectiveness_, target, u.data(), n_, a_.cycle_constants_);
  }
  AllocationResult report(const AxisVector& target, const Motors& u) const {
    return detail::describe_fixed<N>(a_.effectiveness_, target, u.data(), n_, a_.cycle_constants_);
  }
  AllocationResult deliver(const AxisVector& target, Motors& u, MotorVector& commands) const {
    clamp(u);
    store(u, commands);
    return report(target, u);
  }

  // Moves u along the column of `axis` (and the effective demand with it)
  // by the gain that removes as much of the range violation as possible:
  // the smallest and largest gains that each bring one violating motor back
  // to its limit, summed. The sum moves the worst violations symmetrically
  // when both limits are exceeded, and fully when only one is. Then a second,
  // half step balances what remains between the two limits.
  //
  // Every motor keeps to the range for the gains in an interval
  // [a_i, b_i] (in_range_gains); motor i asks for max(a_i, 0) upward or
  // min(b_i, 0) downward, so the step is max(0, max a) + min(0, min b). A
  // step g moves every interval by -g, so the second step comes from the
  // same two extremes: one pass over the motors for both steps.
  void desaturate(Motors& u, AxisVector& effective, Axis axis, double rise_cap = kInf) const {
    desaturate_along(u, effective, axis, a_.gains_[index(axis)], rise_cap);
  }
  void desaturate_along(Motors& u, AxisVector& effective, Axis axis, const InRangeGains& g,
                        double rise_cap) const {
    const Needs needs = needs_along(u, g);
    step(u, effective, axis, needs.up, needs.down, rise_cap);
  }
  struct Needs {
    double up;    // max a_i
    double down;  // min b_i
  };
  MOTORMIX_ALWAYS_INLINE Needs needs_along(const Motors& u, const InRangeGains& g) const {
    const Motors position = u.cwiseProduct(View(g.inverse.data(), n_));
    return {(View(g.lowest.data(), n_) - position).maxCoeff(),
            (View(g.highest.data(), n_) - position).minCoeff()};
  }
  // The same for thrust when every motor has the same share of it (1 / c
  // in every entry of its gains): max a_i and min b_i are the lowest and
  // highest command's.
  void desaturate_equal_lift(Motors& u, AxisVector& effective, double lowest,
                             double highest) const {
    const InRangeGains& g = a_.gains_[index(Axis::kThrust)];
    step(u, effective, Axis::kThrust, g.lowest[0] - lowest * g.inverse[0],
         g.highest[0] - highest * g.inverse[0], kInf);
  }
  // A step rises by `rise_cap` at most (a gain): the whole step (with its
  // balancing half) is taken, then cut to the cap, so a capped step never
  // rises further than the uncapped one. A first step up never ends at or
  // below zero, so with a cap of 0 it is not taken at all (airmode off).
  void step(Motors& u, AxisVector& effective, Axis axis, double need_up, double need_down,
            double rise_cap) const {
    double gain = std::max(0.0, need_up) + std::min(0.0, need_down);
    if (rise_cap <= 0.0 && gain > 0.0) return;
    gain += 0.5 * (std::max(0.0, need_up - gain) + std::min(0.0, need_down - gain));
    if (gain > rise_cap) gain = rise_cap;
    u += gain * column(axis);
    effective[index(axis)] += gain;
  }

  void mix_yaw(double yaw, Motors& u, AxisVector& effective, double yaw_rise_cap = 0.0) const {
    u += yaw * column(Axis::kYaw);
    effective[index(Axis::kYaw)] = yaw;
    // Limited airmode for yaw: first the thrust rises (only rises, by at
    // most its cap, and only into room the top motors have) to lift the
    // motors yaw pushed under the bottom.
    if (yaw_rise_cap > 0.0) {
      const Needs needs = needs_along(u, a_.gains_[index(Axis::kThrust)]);
      const double rise =
          std::min({std::max(0.0, needs.up), std::max(0.0, needs.down), yaw_rise_cap});
      if (rise > 0.0) {
        u += rise * column(Axis::kThrust);
        effective[index(Axis::kThrust)] += rise;
      }
    }
    // Yaw gives way on its own axis (roll and pitch untouched), with some
    // room above the top so that full thrust still leaves yaw authority...
    desaturate_along(u, effective, Axis::kYaw, a_.yaw_gains_with_headroom_, kInf);
    // ...which thrust then pays for, only downward.
    desaturate(u, effective, Axis::kThrust, kNoRise);
  }

  // Largest s in [0, 1] for which base + s * part fits after a thrust shift
  // (rising by rp_rise_cap_ at most); -1 when none (fitting_scale.hpp).
  double largest_fitting_scale(const Motors& base, const Motors& part) const {
    return detail::largest_fitting_scale<N>(base, part, View(a_.lift_inverse_.data(), n_),
                                            a_.all_motors_lift_, n_, range_, a_.rp_rise_cap_);
  }

  // The repair keeps the promise of the priorities exactly: thrust moves
  // first (rising within the roll/pitch limit), then yaw is scaled down, and
  // roll and pitch only when yaw alone cannot make room. First the scales...
  struct Repair {
    Motors rp_part;
    double yaw_scale = 0.0;
    double rp_scale = 1.0;
  };
  Repair repair_scales(const AxisVector& effective) const {
    Repair r{column(Axis::kRoll) * effective[index(Axis::kRoll)] +
             column(Axis::kPitch) * effective[index(Axis::kPitch)]};
    // Yaw gives way first: the largest share of it that fits with all of
    // roll and pitch. Only when none fits do roll and pitch give way,
    // without yaw.
    const double thrust = effective[index(Axis::kThrust)];
    if (a_.equal_lift_) {
      // Thrust is the same on every motor: an offset, and for thrust alone
      // the scale is closed form.
      const double offset = column(Axis::kThrust)[0] * thrust;
      double rp_low = 0.0;
      double rp_high = 0.0;
      if (a_.yaw_two_groups_) {
        // Yaw moves each spin direction's motors alike: closed form too.
        const View pad_a(a_.yaw_pad_a_.data(), n_);
        const View pad_b(a_.yaw_pad_b_.data(), n_);
        const detail::GroupExtremes e{
            (r.rp_part - pad_a).maxCoeff(), (r.rp_part + pad_a).minCoeff(),
            (r.rp_part - pad_b).maxCoeff(), (r.rp_part + pad_b).minCoeff()};
        const double yaw = effective[index(Axis::kYaw)];
        r.yaw_scale = detail::largest_fitting_scale_two_groups(
            offset, e, yaw * a_.yaw_value_a_, yaw * a_.yaw_value_b_, range_, a_.rp_rise_command_);
        rp_low = std::min(e.low_a, e.low_b);
        rp_high = std::max(e.high_a, e.high_b);
      } else {
        const Motors yaw_part = column(Axis::kYaw) * effective[index(Axis::kYaw)];
        const Motors base = (r.rp_part.array() + offset).matrix();
        r.yaw_scale = largest_fitting_scale(base, yaw_part);
        rp_low = r.rp_part.minCoeff();
        rp_high = r.rp_part.maxCoeff();
      }
      if (r.yaw_scale < 0.0) {
        r.yaw_scale = 0.0;
        r.rp_scale = std::max(0.0, detail::largest_fitting_scale_uniform_base(
                                       offset, rp_low, rp_high, range_, a_.rp_rise_command_));
      }
      return r;
    }
    const Motors thrust_part = column(Axis::kThrust) * thrust;
    const Motors yaw_part = column(Axis::kYaw) * effective[index(Axis::kYaw)];
    r.yaw_scale = largest_fitting_scale(thrust_part + r.rp_part, yaw_part);
    if (r.yaw_scale < 0.0) {
      r.yaw_scale = 0.0;
      r.rp_scale = std::max(0.0, largest_fitting_scale(thrust_part, r.rp_part));
    }
    return r;
  }

  // ...then the commands: the scaled parts with the best thrust shift;
  // false when no shift brings them into range (rounding aside, the
  // scales rule that out).
  bool apply(const Repair& r, AxisVector& effective, Motors& u) const {
    const View thrust = column(Axis::kThrust);
    u = thrust * effective[index(Axis::kThrust)] +
        (r.yaw_scale * effective[index(Axis::kYaw)]) * column(Axis::kYaw) + r.rp_scale * r.rp_part;
    ShiftInterval k = detail::shifts_that_fit<N>(u, View(a_.lift_inverse_.data(), n_), n_, range_,
                                                 a_.all_motors_lift_);
    if (a_.rp_rise_cap_ < kInf) k.hi = std::min(k.hi, a_.rp_rise_cap_);
    // At the largest scale some motor sits exactly on its limit: rounding
    // may leave the interval a few ulps wide of empty.
    constexpr double kRounding = 1e-12;
    if (k.empty() && k.lo - k.hi < kRounding) k.lo = k.hi = 0.5 * (k.lo + k.hi);
    const bool fits = !k.empty();
    if (fits) {
      const double shift = k.smallest();
      u += shift * thrust;
      effective[index(Axis::kThrust)] += shift;
    }
    effective[index(Axis::kYaw)] *= r.yaw_scale;
    effective[index(Axis::kRoll)] *= r.rp_scale;
    effective[index(Axis::kPitch)] *= r.rp_scale;
    return fits;
  }

  // The roll/pitch error the repair will leave, known from its scales
  // alone: in range, the commands deliver exactly the scaled effective
  // demand (when the effectiveness inverts the mixing matrix). With
  // airmode, the sequence leaves roll and pitch as demanded, so the error
  // is the share the scale drops of the demand's own roll/pitch error,
  // whose root (`demanded`) waits on nothing.
  double repair_roll_pitch_error(const AxisVector& demand, const AxisVector& effective,
                                 const Repair& r, double demanded) const {
    if (a_.keeps_roll_pitch()) return (1.0 - r.rp_scale) * demanded;
    // Scalar on purpose: `effective` was just written element by element,
    // and a packet load of it would stall on store forwarding.
    const auto left = [&](Axis axis) {
      const int a = index(axis);
      return ((a_.controlled_ >> a) & 1U) ? demand[a] - r.rp_scale * effective[a] : 0.0;
    };
    const double roll = left(Axis::kRoll);
    const double pitch = left(Axis::kPitch);
    return std::sqrt(roll * roll + pitch * pitch);
  }
  // The roll/pitch error of delivering nothing: the demand's, on the
  // commanded axes.
  double demanded_roll_pitch(const AxisVector& demand) const {
    return roll_pitch_norm(detail::on_controlled_axes(demand, a_.cycle_constants_));
  }

  const PrioritizedAllocator& a_;
  Eigen::Index n_;
  CommandRange range_;
};

bool PrioritizedAllocator::closer_in_priority_order(const AxisVector& error_a,
                                                    const AxisVector& error_b, double tolerance) {
  return closer_in_order(error_a, error_b, tolerance);
}

AllocationResult PrioritizedAllocator::allocate(const AxisVector& demand,
                                                MotorVector& commands) const {
  return detail::with_motor_count(
      mixing_.rows(),
      [](auto size, const PrioritizedAllocator& self, const AxisVector& target, MotorVector& out)
          MOTORMIX_INLINE_LAMBDA {
            return Kernel<decltype(size)::value>(self).allocate(target, out);
          },
      *this, demand, commands);
}

}  // namespace motormix
