#pragma once
// What a simulated run is judged by (SimResult), accumulated cycle by cycle:
// how well it flew (Scorer) and what the detector declared against the
// failures that really happened (DetectionScorer). Lockstep and live runs
// score the same way.

#include "loop/control_loop.hpp"
#include "sim/controller.hpp"
#include "sim/scenario.hpp"
#include "sim/vehicle_model.hpp"

#include <motormix/config/config.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace motormix::sim {

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
  double altitude_loss_m = 0.0;  // largest drop below the commanded altitude, once reached
  // Aircraft: the largest tilt error in the kFailureWindowS (detection and recovery) after the
  // first failure (what the failure and its handling cost, apart from the
  // scenario's own steps); 0 without failures.
  double failure_attitude_error_max_deg = 0.0;
  // A run that never arms or never climbs scores no loss and no error: these
  // say whether it flew at all.
  double armed_s = 0.0;           // simulated time the mixer spent armed, the whole run
  bool reached_altitude = false;  // aircraft: came within 0.1 m of a commanded altitude
  double altitude_error_max_m =
      0.0;  // aircraft: largest |commanded - flown| altitude, scored window
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
    // Where the vehicle was: height of its centre above the ground (m), and
    // whether it had crashed. Near the ground, ground effect and contact push
    // the body with torques no flying model holds.
    double height_m = 0.0;
    bool crashed = false;
  };
  std::vector<Declaration> declarations;
  double sim_seconds = 0.0;
  double wall_seconds = 0.0;
};

// After period k's physics (ending at t_end): the battery's low point, the
// cycle count, and a crash, which ends the run (returns true).
bool end_of_period(SimResult& r, const VehicleModel& vehicle, std::int64_t k, double t_end);

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
  // A cycle's result at time t, with the vehicle then.
  void add(double t, const loop::CycleResult& cycle, const VehicleModel& vehicle) {
    add(t, cycle.detection.failed, cycle.detection.source, vehicle);
  }
  // What the detector has declared by time t (0 after disarming), and the
  // source of its latest declaration: from a cycle, or from the mixer's
  // status over the bus.
  void add(double t, MotorMask declared, DetectionSource source, const VehicleModel& vehicle);
  void finish(SimResult& r) const;

 private:
  std::vector<FailureOutcome> outcomes_;
  std::vector<SimResult::Declaration> declarations_;
  MotorMask seen_ = 0;
  int false_detections_ = 0;
};

}  // namespace motormix::sim
