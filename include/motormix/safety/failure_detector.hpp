#pragma once
// Finds a motor that stopped producing thrust when nobody reports it, from
// ESC telemetry, body rates or the controller's outputs, each source with
// hysteresis. Pure: time is passed in, nothing is allocated after
// construction, no I/O. How each source decides and what it cannot tell
// apart: docs/failure-detection.md, "How each source decides".

#include <motormix/enum_names.hpp>
#include <motormix/motor_vector.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products

#include <array>
#include <cstdint>

namespace motormix {

// An ESC is silent after this many of its own reporting intervals without a
// reading (and at least telemetry_timeout_s): with 3 % of frames lost, six
// in a row are lost about once in a billion intervals.
inline constexpr double kSilentIntervals = 6.0;

enum class DetectionSource : std::uint8_t {
  kNone = 0,
  kTelemetry = 1,        // rpm or current implausible for the command
  kTelemetrySilent = 2,  // the ESC stopped reporting while the others kept on
  kRates = 3,            // body-rate residual names the motor
  kOutputs = 4,          // the controller drove the motor to full for long
};

inline constexpr EnumName<DetectionSource> kDetectionSourceNames[] = {
    {DetectionSource::kNone, "none"},
    {DetectionSource::kTelemetry, "telemetry"},
    {DetectionSource::kTelemetrySilent, "telemetry_silent"},
    {DetectionSource::kRates, "rates"},
    {DetectionSource::kOutputs, "outputs"},
};
inline const char* to_string(DetectionSource value) {
  return name_in(kDetectionSourceNames, value);
}

// Which sources run (bit per source).
enum class DetectorSources : std::uint8_t {
  kTelemetry = 1,
  kRates = 2,
  kOutputs = 4,
};
inline constexpr EnumName<DetectorSources> kDetectorSourcesNames[] = {
    {DetectorSources::kTelemetry, "telemetry"},
    {DetectorSources::kRates, "rates"},
    {DetectorSources::kOutputs, "outputs"},
};

struct FailureDetectorSettings {
  int motors = 0;
  std::uint8_t sources = 0;  // DetectorSources bits

  // Thrust-fraction lag of the motors (first order, up and down).
  double time_constant_up_s = 0.03;
  double time_constant_down_s = 0.05;
  // Below this commanded thrust fraction a motor is not judged by the
  // telemetry or rates ratios (its rpm is near idle noise).
  double min_motor_thrust = 0.08;

  // Telemetry.
  // A reading older than this is not judged. An ESC is silent once its
  // last reading is older than this and than kSilentIntervals of its own
  // reporting interval (learned from its readings): an ESC asked in turn
  // with seven others reports a few times a second, and its pauses are no
  // silence.
  double telemetry_timeout_s = 0.1;
  double telemetry_persist_s = 0.01;  // a suspicion held this long is declared
  // How late a reading may arrive after its ESC measured it (serial
  // telemetry's frame, the ESC's averaging, the request round-robin): a
  // motor's rpm is judged against the least its thrust was since this long
  // before the reading arrived, so a reading taken while the motor was
  // still speeding up (or an old one, the frames after it lost) is not "too
  // slow".
  double telemetry_latency_s = 0.02;
  double rpm_ratio = 0.6;        // rpm below this fraction of the median ratio: suspect
  double rpm_high_ratio = 1.25;  // or above this multiple of it (a prop thrown): suspect
  double current_ratio = 0.35;   // current below this fraction of the median ratio: suspect
  // With rpm and current both read: a motor's current per rpm^3 (its
  // prop's load) below this fraction of the median is a prop thrown or
  // broken, whatever its command (0: not judged). Judged only while the
  // motor is not being slowed: a braking ESC draws little or regenerates.
  double load_ratio = 0.6;
  int min_reporting = 3;  // motors with fresh telemetry needed for a median
  // Whether an ESC that goes silent while most others report is declared
  // on that alone (without the rates source). The configuration sets it
  // for six rotors or more; a quad never stops a motor for a silent wire.
  bool silence_declares = false;

  // Rates.
  // Torque (N m, body FRD) of each motor at full thrust fraction: column i.
  Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::ColMajor, 3, kMaxMotors> torque_per_thrust;
  Eigen::Vector3d inertia_kgm2 = Eigen::Vector3d::Ones();  // principal moments
  double rotational_drag = 0.0;                            // N m per rad/s
  // The rotors' own angular momentum per rad/s of each (spin x inertia x
  // axis; zero: massless rotors) and their speed at full thrust: their
  // gyroscopic torque and the reaction of speeding them up or down are part
  // of what the rates show without any failure.
  Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::ColMajor, 3, kMaxMotors> momentum_per_speed;
  double max_rotor_speed_rad_s = 0.0;
  double rates_timeout_s = 0.02;  // no rates sample within this: stale
  double rates_filter_hz = 15.0;  // low-pass on both sides of the residual
  double rates_persist_s = 0.06;
  double min_loss = 0.75;     // residual along the column: at least this fraction of the thrust
  double max_off_axis = 0.3;  // residual across the column: at most this fraction of the along part
  // A residual smaller than this (N m) is never a failure, whatever it lines
  // up with: model error and gusts live below it.
  double min_residual_nm = 0.0;
  // How fast the learned torque scale follows (battery sag, ESC curve).
  double scale_time_constant_s = 3.0;

  // Outputs.
  double outputs_filter_s = 0.5;
  double outputs_persist_s = 1.0;
  double outputs_high = 0.9;     // low-passed command at least this
  double outputs_margin = 0.35;  // and at least this above the median's
};

// What the detector has declared, latched until reset().
struct Detection {
  MotorMask failed = 0;  // every motor declared, by any source
  // The latest declaration: which source, which motor (0-based; -1 none), when.
  DetectionSource source = DetectionSource::kNone;
  int motor = -1;
  std::int64_t at_us = 0;
  // Motors whose telemetry is stale while others report (declared only with
  // silence_declares and without the rates source): for the status.
  MotorMask telemetry_silent = 0;
};

class FailureDetector {
 public:
  explicit FailureDetector(const FailureDetectorSettings& settings);

  const FailureDetectorSettings& settings() const { return s_; }
  bool uses(DetectorSources source) const {
    return (s_.sources & static_cast<std::uint8_t>(source)) != 0;
  }

  // Forgets every suspicion, filter and declaration (on disarming).
  void reset();

  // One ESC reading, accepted by the caller's checks, arrived at now_us. rpm
  // mechanical; NaN when the ESC does not report it (likewise current).
  void on_telemetry(int motor, double rpm, double current_a, std::int64_t now_us);
  // One body-rates sample (rad/s, FRD), stamped by its publisher (sample_us)
  // and arrived at now_us: the angular acceleration is taken between
  // consecutive publisher stamps.
  void on_rates(const Eigen::Vector3d& rates, std::int64_t sample_us, std::int64_t now_us);

  // One control cycle. `thrust`: each motor's commanded thrust fraction
  // (0..1) in this cycle; `excluded`: motors already treated as failed;
  // `allowed`: false while disarmed, spooling up, testing a motor or at low
  // throttle (filters keep running, suspicions are dropped).
  const Detection& update(const MotorVector& thrust, MotorMask excluded, bool allowed,
                          std::int64_t now_us);

  const Detection& detection() const { return detection_; }
  // For tests and diagnostics: the rates residual (N m), the learned torque
  // scale, each source's suspicion time per motor.
  const Eigen::Vector3d& rates_residual() const { return residual_; }
  double torque_scale() const { return scale_; }
  double suspicion_s(DetectionSource source, int motor) const;

 private:
  void declare(int motor, DetectionSource source, std::int64_t now_us);
  void judge_telemetry(MotorMask excluded, bool allowed, double dt, std::int64_t now_us);
  void judge_rates(MotorMask excluded, bool allowed, double dt, std::int64_t now_us);
  void judge_outputs(const MotorVector& thrust, MotorMask excluded, bool allowed, double dt,
                     std::int64_t now_us);
  // Hysteresis: time accumulates while `evidence`, drains twice as fast otherwise.
  static bool accumulate(double& suspicion, bool evidence, double dt, double persist);

  struct EscState {
    double rpm = 0.0, current = 0.0;
    std::int64_t received_us = 0;
    double interval_s = 0.0;  // its reporting interval, learned (0: not yet)
    bool any = false;
  };
  // Whether motor i's ESC has gone silent by now_us (see telemetry_timeout_s).
  bool silent(std::size_t i, std::int64_t now_us) const;

  FailureDetectorSettings s_;
  Detection detection_;
  std::array<EscState, kMaxMotors> esc_{};
  MotorVector lagged_;  // each motor's thrust through the motor lag
  // lagged_ over the last cycles (a ring, newest at lag_head_), for the
  // telemetry's latency window.
  static constexpr int kLagHistory = 64;
  std::array<std::array<double, kMaxMotors>, kLagHistory> lag_history_{};
  // Each motor's speed fraction (the square root of its thrust fraction)
  // through the same lag, and over the last cycles the lesser of the two
  // lags' thrusts: a motor slowing (or speeding up) as either lag has it
  // follows its command, and is not too slow.
  std::array<double, kMaxMotors> speed_lagged_{};
  std::array<std::array<double, kMaxMotors>, kLagHistory> lag_low_history_{};
  std::array<std::int64_t, kLagHistory> lag_history_us_{};
  int lag_head_ = 0, lag_count_ = 0;
  // Each rotor's speed (rad/s) from lagged_ at the previous update.
  std::array<double, kMaxMotors> rotor_speed_{};
  Eigen::Vector3d rotor_reaction_ = Eigen::Vector3d::Zero();  // N m, this update
  Eigen::Vector3d rotor_momentum_ = Eigen::Vector3d::Zero();  // N m s
  MotorVector output_filtered_;                               // outputs source: low-passed commands
  std::array<double, kMaxMotors> telemetry_suspicion_{};
  // Fresh telemetry shows the motor spinning as commanded (rates then do
  // not declare it).
  std::array<bool, kMaxMotors> telemetry_healthy_{};
  std::array<double, kMaxMotors> silent_suspicion_{};
  std::array<double, kMaxMotors> rates_suspicion_{};
  std::array<double, kMaxMotors> outputs_suspicion_{};
  // Rates: latest sample, its stamp, the raw angular acceleration it gave.
  Eigen::Vector3d rates_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_raw_ = Eigen::Vector3d::Zero();
  std::int64_t rates_sample_us_ = 0;
  std::int64_t rates_received_us_ = 0;
  bool rates_any_ = false, accel_any_ = false;
  Eigen::Vector3d accel_stage_ = Eigen::Vector3d::Zero();  // first stages of the filters
  Eigen::Vector3d rotor_torque_stage_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d rest_torque_stage_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_filtered_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d rotor_torque_filtered_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d rest_torque_filtered_ = Eigen::Vector3d::Zero();
  // Learned torque scale: exponentially forgotten sums of x.y and x.x.
  double scale_ = 1.0, scale_xy_ = 0.0, scale_xx_ = 0.0;
  Eigen::Vector3d residual_ = Eigen::Vector3d::Zero();
  bool filters_primed_ = false;
  std::int64_t last_update_us_ = 0;
  // Filter factors for the period alpha_dt_ (see update()).
  double alpha_dt_ = -1.0;
  struct {
    double up = 0, down = 0, rates = 0, scale = 0, outputs = 0;
  } alpha_;
  bool updated_ = false;
};

}  // namespace motormix
