#pragma once
// One simulated run in lockstep: the scenario, the built-in controller, the
// real control loop (loop::ControlLoop: arming, staleness, battery
// compensation, motor_status handling) around the real Mixer and output
// stage, and the vehicle model, all on the simulated clock. Nothing waits
// on a wall clock, so a run is as fast as the CPU and the same inputs and
// seed give the same results, bit for bit.
//
// Each loop period: the scenario's events due are applied; the controller
// reads the (noisy) state and sends a setpoint and a pid; a battery reading
// (50 Hz) and a motor_status (from the failure's detection on, 10 Hz) are
// delivered when due; the control loop cycles; the vehicle integrates the
// outputs over the period in steps of at most 1 ms.

#include "loop/control_loop.hpp"
#include "sim/controller.hpp"
#include "sim/sensors.hpp"
#include "sim/scenario.hpp"
#include "sim/vehicle_model.hpp"

#include <motormix/config/config.hpp>
#include <motormix/mixer.hpp>

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace motormix::sim {

inline constexpr std::int64_t kEpochUs = 1700000000000000;  // utime of simulated time 0

struct SimOptions {
  std::vector<MotorFailure> failures;  // on top of the scenario's
  bool undetected = false;             // never report the failures on motor_status
  std::uint64_t seed = 1;
  double duration_s = 0.0;  // > 0: instead of the scenario's
};

// After a failure, how long its attitude transient is watched.
inline constexpr double kFailureWindowS = 1.0;
// The spin and thrusts a spin landing settles at: averaged over this long
// before touchdown.
inline constexpr double kSettleWindowS = 2.0;

// One failure of a run and what motormix's own detector made of it.
struct FailureOutcome {
  MotorFailure failure;
  double detected_at_s = -1.0;  // when a motor was first declared after it; -1: never
  int detected_motor = -1;      // which (0-based); not failure.motor: the wrong one
  DetectionSource detected_by = DetectionSource::kNone;
};

// The metrics of one run, over the scenario's scored window (armed cycles).
struct SimResult {
  bool crashed = false;
  std::string crash_reason;
  double crash_time_s = -1.0;
  double attitude_error_rms_deg = 0.0;  // tilt between the attitude asked and flown
  double attitude_error_max_deg = 0.0;
  double yaw_error_rms_deg = 0.0;
  double altitude_loss_m = 0.0;         // largest drop below the commanded altitude, once reached
  // Aircraft: the largest tilt error in the kFailureWindowS (detection and recovery) after the
  // first failure (what the failure and its handling cost, apart from the
  // scenario's own steps); 0 without failures.
  double failure_attitude_error_max_deg = 0.0;
  // A run that never arms or never climbs scores no loss and no error: these
  // say whether it flew at all.
  double armed_s = 0.0;             // simulated time the mixer spent armed, the whole run
  bool reached_altitude = false;    // aircraft: came within 0.1 m of a commanded altitude
  double altitude_error_max_m = 0.0;  // aircraft: largest |commanded - flown| altitude, scored window
  // Aircraft, the whole run: the first touchdown after flying (vertical
  // speed, down positive, and when; -1 if none), how far from where the
  // first failure happened (or the start) it came down (horizontal; the end
  // position without a touchdown), and the largest body rate and thrust-axis
  // tilt while flying.
  double touchdown_speed_mps = -1.0;
  double touchdown_time_s = -1.0;
  double drift_m = 0.0;
  double max_spin_rate_rad_s = 0.0;
  double max_thrust_axis_tilt_deg = 0.0;
  // Over the kSettleWindowS before touchdown (or the end), once a failure
  // happened: the mean body rate and each motor's mean thrust (N), for the
  // comparison with the relaxed-hover equilibrium (empty without a failure).
  double settled_spin_rate_rad_s = 0.0;
  std::vector<double> settled_thrust_n;
  double saturated_fraction = 0.0;      // cycles with some axis not fully delivered
  double speed_error_rms_mps = 0.0;     // ground vehicles
  double yaw_rate_error_rms_dps = 0.0;  // ground vehicles
  double min_battery_v = 0.0;
  double final_charge = 0.0;
  std::int64_t cycles = 0;
  std::int64_t failsafe_events = 0;
  std::vector<FailureOutcome> failures;  // in time order
  // Motors motormix's detector declared that were working (none of the
  // run's thrust-losing failures explains them): each stopped a good motor.
  int false_detections = 0;
  // Every declaration of the detector: when, which motor, by which source.
  struct Declaration {
    double at_s = 0.0;
    int motor = -1;
    DetectionSource source = DetectionSource::kNone;
  };
  std::vector<Declaration> declarations;
  double sim_seconds = 0.0;
  double wall_seconds = 0.0;
};

// Everything one loop period produced, for logs and plots.
struct SimFrame {
  std::int64_t utime = 0;
  const loop::SetpointSample* setpoint = nullptr;
  const loop::PidSample* pid = nullptr;
  const loop::CycleResult* cycle = nullptr;
  const VehicleModel* vehicle = nullptr;
  const loop::BatterySample* battery = nullptr;           // when one was sent this period
  const loop::MotorStatusSample* motor_status = nullptr;  // when one was sent this period
  const Reference* reference = nullptr;
  const ControllerCommand* command = nullptr;  // what the controller sent
  const loop::Counters* counters = nullptr;
};
using FrameObserver = std::function<void(const SimFrame&)>;

// After period k's physics (ending at t_end): the battery's low point, the
// cycle count, and a crash, which ends the run (returns true).
bool end_of_period(SimResult& r, const VehicleModel& vehicle, std::int64_t k, double t_end);

// The configuration as the scenario flies it (its battery settings applied).
// Throws config::ConfigError when the scenario is for the other kind of
// vehicle.
config::Config scenario_config(const config::Config& config, const Scenario& scenario);

// `mixer` is what the control loop flies with (build_mixer(config), or a
// comparison allocator); the controller linearizes it.
SimResult run_lockstep(const config::Config& config, Mixer mixer, const Scenario& scenario,
                       const SimOptions& options, const FrameObserver& observer = {});

// The metrics of SimResult, accumulated cycle by cycle (lockstep and live).
class Scorer {
 public:
  Scorer(const Scenario& scenario, const config::Config& config);
  // One cycle at time t: what was asked, what the vehicle did, whether the
  // mixer was armed and which axes it could not deliver.
  void add(double t, const Reference& ref, const ControllerCommand& cmd,
           const VehicleModel& vehicle, bool armed, std::uint8_t axis_limited);
  void finish(SimResult& r) const;
  // The first failure's time (for failure_attitude_error_max_deg).
  void failure_at(double t) { failure_s_ = t; }

 private:
  // Touchdown, drift, largest rate and tilt, settled spin (every cycle).
  void add_flight(double t, const VehicleModel& vehicle);
  struct Settle {
    double t = 0.0, rate = 0.0;
    std::vector<double> thrust;
  };
  double from_s_, to_s_;
  double failure_s_ = -1.0;
  double failure_att_max_ = 0.0;
  bool wheeled_;
  AxisMask controlled_;
  double att_sq_ = 0, yaw_sq_ = 0, speed_sq_ = 0, rate_sq_ = 0;
  double att_max_ = 0, altitude_loss_ = 0, altitude_error_max_ = 0;
  double period_s_;
  std::int64_t armed_cycles_ = 0;
  bool ever_reached_ = false;
  double commanded_altitude_ = -1.0;
  bool reached_ = false;
  std::int64_t scored_ = 0, saturated_ = 0;
  double touchdown_speed_ = -1.0, touchdown_s_ = -1.0, max_rate_ = 0.0, max_tilt_ = 0.0;
  Eigen::Vector2d drift_from_ = Eigen::Vector2d::Zero(), drift_to_ = Eigen::Vector2d::Zero();
  bool drift_from_set_ = false;
  bool was_landed_ = true;
  std::vector<Settle> settle_;  // per cycle since the failure, trimmed to the window
  std::size_t settle_begin_ = 0;
};

// Matches what motormix's detector declares with the failures of the run.
class DetectionScorer {
 public:
  explicit DetectionScorer(const std::vector<MotorFailure>& failures);
  // A cycle's result at time t.
  void add(double t, const loop::CycleResult& cycle) {
    add(t, cycle.detection.failed, cycle.detection.source);
  }
  // What the detector has declared by time t (0 after disarming), and the
  // source of its latest declaration: from a cycle, or from the mixer's
  // status over the bus.
  void add(double t, MotorMask declared, DetectionSource source);
  void finish(SimResult& r) const;

 private:
  std::vector<FailureOutcome> outcomes_;
  std::vector<SimResult::Declaration> declarations_;
  MotorMask seen_ = 0;
  int false_detections_ = 0;
};

// The scenario's references at time t, and what the events due change.
class ScenarioClock {
 public:
  ScenarioClock(const Scenario& scenario, const config::Config& config,
                const std::vector<MotorFailure>& extra_failures);
  // Applies every event due at t.
  void advance(double t);
  const Reference& reference() const { return ref_; }
  // What each motor can do at t, after the failures due by then.
  const MotorHealth& health(double t);
  Environment environment(double t) const;
  // Failed motors something outside motormix would have reported by t,
  // detection_s after each failure (motor_health.hpp: reported_outside).
  MotorMask detected(double t, double detection_s) const;
  const std::vector<MotorFailure>& failures() const { return failures_; }  // sorted by at_s

 private:
  const Scenario& scenario_;
  std::vector<MotorFailure> failures_;
  std::size_t next_ = 0;
  Reference ref_;
  MotorHealth health_;
  Eigen::Vector3d wind_ = Eigen::Vector3d::Zero();
  std::vector<std::pair<double, Gust>> gusts_;  // (start, gust)
};

}  // namespace motormix::sim
