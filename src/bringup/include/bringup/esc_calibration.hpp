#pragma once
// The ESC calibration sequence (`motormix esc-calibrate`), with time passed
// in: PWM ESCs learn their throttle range from the maximum at power-up and
// then the minimum. Every motor runs at full command while it does, so the
// sequence refuses to start when anything else may drive the outputs, and
// ends at the disarmed values whatever happens:
//
//   listening (nothing published) -- a mixer heard --> refused (nothing published)
//       | listen time over
//   maximum, armed -- Enter --> minimum, armed -- min_seconds --> disarmed (done)
//       | timeout, end of input, interrupt, a mixer heard: disarmed (aborted)
//
// The disarmed values are published for kDisarmedHoldS after the end, then
// the sequence is over.

#include <motormix/config/config.hpp>

#include <string>
#include <vector>

namespace motormix::bringup {

// Why the configuration cannot be calibrated (outputs that are not PWM ESCs
// learning a range); empty when it can.
std::string calibration_refusal(const config::Config& config);

struct EscCalibrationTiming {
  double listen_s = 1.0;     // listening for a running mixer first
  double timeout_s = 30.0;   // at the maximum, waiting for Enter
  double min_seconds = 4.0;  // at the minimum before disarming
};

class EscCalibration {
 public:
  enum class Phase { kListening, kMaximum, kMinimum, kDisarming, kDone, kRefused };
  enum class Outcome { kRunning, kCalibrated, kAborted, kRefused };
  static constexpr double kDisarmedHoldS = 0.5;

  EscCalibration(const config::Config& config, const EscCalibrationTiming& timing, double now_s);

  // What happened since the last step.
  void on_mixer_heard() { mixer_heard_ = true; }
  void on_enter() { enter_ = true; }
  void on_end_of_input() { end_of_input_ = true; }
  void on_interrupt() { interrupted_ = true; }

  // What to publish now, if anything: one value per output, and whether the
  // message says armed (the maximum and minimum do: the ESCs must see them).
  struct Output {
    bool publish = false;
    const std::vector<double>* pwm = nullptr;
    double command = 0.0;
    bool armed = false;
  };
  Output step(double now_s);

  Phase phase() const { return phase_; }
  Outcome outcome() const;
  // Why it was refused or aborted; empty otherwise.
  const std::string& reason() const { return reason_; }
  // Where the phase just entered, for the user's dialogue.
  bool phase_changed() const { return changed_; }
  const std::vector<double>& maximum() const { return high_; }
  const std::vector<double>& minimum() const { return low_; }

 private:
  void enter(Phase phase, double now_s);
  void abort(const std::string& why, double now_s);
  // While the motors run: an interrupt or a mixer on the bus aborts to
  // disarmed (true when it did).
  bool must_stop(double now_s);

  EscCalibrationTiming timing_;
  std::vector<double> high_, low_, disarmed_;
  Phase phase_ = Phase::kListening;
  double since_s_;
  bool calibrated_ = false;
  bool changed_ = true;
  std::string reason_;
  bool mixer_heard_ = false;
  bool enter_ = false;
  bool end_of_input_ = false;
  bool interrupted_ = false;
};

}  // namespace motormix::bringup
