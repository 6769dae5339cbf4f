#include <motormix/mixer.hpp>

#include <algorithm>
#include <utility>

namespace motormix {

Mixer::Mixer(std::unique_ptr<const Allocator> allocator, OutputStage output_stage,
             ThrustRange thrust_range, FailurePlan failures)
    : allocator_(std::move(allocator)),
      output_stage_(std::move(output_stage)),
      thrust_range_(thrust_range),
      failures_(std::move(failures)) {
  std::sort(failures_.prepared.begin(), failures_.prepared.end(),
            [](const PreparedFailure& a, const PreparedFailure& b) { return a.failed < b.failed; });
}

Mixer::FailureReport Mixer::failure_report(MotorMask failed) const {
  return failure_report(failed, failed == 0 ? nullptr : prepared(failed));
}

Mixer::FailureReport Mixer::failure_report(MotorMask failed, const PreparedFailure* exact) const {
  FailureReport r;
  r.held = failures_.controlled;
  r.authority = failures_.healthy_authority;
  if (failed == 0) return r;
  if (const PreparedFailure* p = exact) {
    r.handling = p->held == failures_.controlled ? FailureHandling::kReallocated
                                                 : FailureHandling::kAxesLost;
    r.held = p->held;
    r.authority = p->authority;
  } else {
    // No promise is made for a set that was not prepared.
    r.handling = FailureHandling::kUnsupported;
    r.held = 0;
    r.authority.setZero();
  }
  return r;
}

const Allocator& Mixer::allocator_for(MotorMask failed, const PreparedFailure* exact) const {
  if (failed == 0) return *allocator_;
  if (exact != nullptr) return *exact->allocator;
  // Not prepared: the set of its two lowest motors, if that one was.
  const MotorMask first = failed & (~failed + 1);
  const MotorMask rest = failed & ~first;
  if (const PreparedFailure* pair = prepared(first | (rest & (~rest + 1)))) return *pair->allocator;
  return *allocator_;
}

const PreparedFailure* Mixer::prepared(MotorMask failed) const {
  const auto it =
      std::lower_bound(failures_.prepared.begin(), failures_.prepared.end(), failed,
                       [](const PreparedFailure& p, MotorMask mask) { return p.failed < mask; });
  return it != failures_.prepared.end() && it->failed == failed ? &*it : nullptr;
}

MixStatus Mixer::mix(const AxisVector& demand, MixerOutput& out, double dt_s,
                     MotorMask failed) const {
  if (!demand.allFinite()) {
    disarm(out);
    return MixStatus::kNonFiniteDemand;
  }
  const double thrust_low = thrust_floor(thrust_range_);
  AxisVector clamped;
  clamped << std::clamp(demand[index(Axis::kRoll)], -1.0, 1.0),
      std::clamp(demand[index(Axis::kPitch)], -1.0, 1.0),
      std::clamp(demand[index(Axis::kYaw)], -1.0, 1.0),
      std::clamp(demand[index(Axis::kThrust)], thrust_low, 1.0);
  const MotorMask all = motors() >= 32 ? ~MotorMask{0} : (MotorMask{1} << motors()) - 1;
  failed &= all;
  const PreparedFailure* exact = failed == 0 ? nullptr : prepared(failed);
  const Allocator* allocator = &allocator_for(failed, exact);
  const FailureReport report = failure_report(failed, exact);
  out.failed = failed;
  out.failure = report.handling;
  out.held = report.held;
  out.authority = report.authority;
  out.allocation = allocator->allocate(clamped, out.command);
  if (failed != 0) {
    for (int i = 0; i < motors(); ++i) {
      if ((failed >> i) & 1U) out.command[i] = 0.0;  // stopped
    }
    if (out.failure == FailureHandling::kUnsupported) {
      // What the working motors really produce, now that every failed one
      // is stopped.
      if (failures_.healthy_effectiveness.cols() == motors()) {
        EffectivenessMatrix working = failures_.healthy_effectiveness;
        for (int i = 0; i < motors(); ++i) {
          if ((failed >> i) & 1U) working.col(i).setZero();
        }
        out.allocation = describe_allocation(working, clamped, out.command, failures_.range,
                                             failures_.controlled);
      } else {
        out.allocation.axis_limited = kAllAxes;  // nothing to tell what is delivered
      }
    }
    out.allocation.saturated_upper &= ~failed;
    out.allocation.saturated_lower &= ~failed;
  }
  output_stage_.armed(out.command, out.output, out.direction, dt_s, out.armed, failed);
  out.armed = true;
  return clamped == demand ? MixStatus::kOk : MixStatus::kDemandClamped;
}

void Mixer::disarm(MixerOutput& out) const {
  out.armed = false;
  out.command.setZero(motors());
  out.allocation = AllocationResult{};
  out.failed = 0;
  out.failure = FailureHandling::kNone;
  out.held = failures_.controlled;
  out.authority = failures_.healthy_authority;
  output_stage_.disarmed(out.output, out.direction);
}

}  // namespace motormix
