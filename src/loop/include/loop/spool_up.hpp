#pragma once
// Spool-up: after each disarmed -> armed transition (so after any disarm or
// failsafe too) the outputs rise over output.spool_up_s. The demand is
// scaled by the ramp r = time armed / spool_up_s, and each output is its
// disarmed value (taken into [min, max]: output.min for an ESC whose
// disarmed value is below it) plus r times the way to its mixed value, so
// it rises from stopped through idle, never overshoots what it is mixed to
// and never leaves the output range.

#include <motormix/mixer.hpp>

#include <cstdint>

namespace motormix::loop {

class SpoolUp {
 public:
  explicit SpoolUp(std::int64_t spool_up_us) : spool_up_us_(spool_up_us) {}

  // The ramp 0..1 after armed_for_us armed; 1 once done (and with no
  // spool-up configured).
  double ramp(std::int64_t armed_for_us) const {
    return armed_for_us >= spool_up_us_
               ? 1.0
               : static_cast<double>(armed_for_us) / static_cast<double>(spool_up_us_);
  }

  // Moves each mixed output from its disarmed value toward what it was
  // mixed to, by `ramp`. Failed motors keep their stop value.
  static void blend(const OutputStage& stage, double ramp, MixerOutput& out);

 private:
  std::int64_t spool_up_us_;
};

}  // namespace motormix::loop
