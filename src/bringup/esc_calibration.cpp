#include "bringup/esc_calibration.hpp"

namespace motormix::bringup {

std::string calibration_refusal(const config::Config& config) {
  for (const OutputChannel& ch : config.outputs) {
    if (ch.mode != OutputMode::kUnipolar) {
      return std::string("the outputs are ") +
             (ch.mode == OutputMode::kCentered ? "centered (reversible drives)"
                                               : "duty plus direction pin (H-bridges)") +
             "; calibration is for PWM ESCs that learn their throttle range (output.mode "
             "unipolar)";
    }
  }
  return "";
}

EscCalibration::EscCalibration(const config::Config& config, const EscCalibrationTiming& timing,
                               double now_s)
    : timing_(timing), since_s_(now_s) {
  for (const OutputChannel& ch : config.outputs) {
    high_.push_back(ch.reversed ? ch.min : ch.max);
    low_.push_back(ch.reversed ? ch.max : ch.min);
    disarmed_.push_back(ch.disarmed);
  }
}

void EscCalibration::enter(Phase phase, double now_s) {
  phase_ = phase;
  since_s_ = now_s;
  changed_ = true;
}

void EscCalibration::abort(const std::string& why, double now_s) {
  reason_ = why;
  enter(Phase::kDisarming, now_s);
}

bool EscCalibration::must_stop(double now_s) {
  if (interrupted_) {
    abort("interrupted", now_s);
  } else if (mixer_heard_) {
    abort("a mixer started on the bus", now_s);
  } else {
    return false;
  }
  return true;
}

EscCalibration::Outcome EscCalibration::outcome() const {
  switch (phase_) {
    case Phase::kRefused:
      return Outcome::kRefused;
    case Phase::kDone:
      return calibrated_ ? Outcome::kCalibrated : Outcome::kAborted;
    default:
      return Outcome::kRunning;
  }
}

EscCalibration::Output EscCalibration::step(double now_s) {
  changed_ = false;
  const double in_phase = now_s - since_s_;
  switch (phase_) {
    case Phase::kListening:
      if (mixer_heard_) {
        reason_ = "a mixer is running on the bus: stop it first";
        enter(Phase::kRefused, now_s);
      } else if (interrupted_) {
        reason_ = "interrupted";
        enter(Phase::kRefused, now_s);
      } else if (in_phase >= timing_.listen_s) {
        enter(Phase::kMaximum, now_s);
      }
      break;
    case Phase::kMaximum:
      // Checked in order of what must stop the motors first.
      if (must_stop(now_s)) {
        // disarming
      } else if (enter_) {
        enter(Phase::kMinimum, now_s);
      } else if (end_of_input_) {
        abort("no confirmation (end of input)", now_s);
      } else if (in_phase >= timing_.timeout_s) {
        abort("no confirmation within the timeout", now_s);
      }
      break;
    case Phase::kMinimum:
      if (must_stop(now_s)) {
        // disarming
      } else if (in_phase >= timing_.min_seconds) {
        calibrated_ = true;
        enter(Phase::kDisarming, now_s);
      }
      break;
    case Phase::kDisarming:
      if (in_phase >= kDisarmedHoldS) enter(Phase::kDone, now_s);
      break;
    case Phase::kDone:
    case Phase::kRefused:
      break;
  }
  Output out;
  switch (phase_) {
    case Phase::kMaximum:
      out = {true, &high_, 1.0, true};
      break;
    case Phase::kMinimum:
      out = {true, &low_, 0.0, true};
      break;
    case Phase::kDisarming:
      out = {true, &disarmed_, 0.0, false};
      break;
    default:
      break;  // listening, refused, done: nothing on the bus
  }
  return out;
}

}  // namespace motormix::bringup
