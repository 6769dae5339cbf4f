#pragma once
// The motors treated as failed, and how the mixer handles that set. Three
// sources add up: the configuration (mixer.failed_motors, always), the
// latest accepted motor_status message, which stands until the next one
// says otherwise (a failure detector that falls silent does not bring a
// motor back), and motormix's own detector, whose declarations stand until
// the loop disarms.

#include <motormix/mixer.hpp>

#include <optional>

namespace motormix::loop {

class FailureSet {
 public:
  FailureSet(MotorMask configured, int motors)
      : configured_(configured), all_((MotorMask{1} << motors) - 1) {}

  void set_reported(MotorMask reported) { reported_ = reported; }
  void set_detected(MotorMask detected) { detected_ = detected; }

  MotorMask in_force() const { return (configured_ | reported_ | detected_) & all_; }
  MotorMask detected() const { return detected_ & all_; }

  // How `mixer` handles the set in force, looked up again only when the set
  // changes (Mixer::mix looks the set up for itself every cycle).
  const Mixer::FailureReport& report(const Mixer& mixer) {
    const MotorMask set = in_force();
    if (!report_for_ || *report_for_ != set) {
      report_ = mixer.failure_report(set);
      report_for_ = set;
    }
    return report_;
  }

 private:
  MotorMask configured_;
  MotorMask all_;
  MotorMask reported_ = 0;
  MotorMask detected_ = 0;
  std::optional<MotorMask> report_for_;
  Mixer::FailureReport report_;
};

}  // namespace motormix::loop
