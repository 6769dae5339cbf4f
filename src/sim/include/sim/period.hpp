#pragma once
// One simulation period, written once for the lockstep and the live run:
// how long a period is, how many physics substeps it takes (each at most
// 1 ms, and at most one gyro sample long), how many periods a run has, and when the simulated
// vehicle's own messages are due (battery at 50 Hz; motor_status at 10 Hz once a failure is
// reported, and at once when the reported set changes).

#include "sim/motor_health.hpp"
#include "sim/scenario.hpp"
#include "sim/vehicle_model.hpp"

#include <motormix/mixer.hpp>

#include <cstdint>

namespace motormix::sim {

// Simulated times are sums of periods in floating point: an event due at t
// counts as due from t - kTimeToleranceS on, so rounding never moves it to
// the next period.
inline constexpr double kTimeToleranceS = 1e-9;
inline bool due(double t, double at) { return t + kTimeToleranceS >= at; }

inline constexpr double kMaxPhysicsStepS = 1e-3;
inline constexpr double kBatteryPeriodS = 0.02;  // battery_t at 50 Hz
inline constexpr double kMotorStatusPeriodS =
    0.1;  // motor_status_t at 10 Hz once a failure is seen

struct SimulationPeriod {
  double period_s;      // one loop period
  int substeps;         // physics steps per period
  double step_s;        // period_s / substeps, at most kMaxPhysicsStepS
  std::int64_t cycles;  // periods in a run of duration_s

  // Each step also at most 1 / sample_rate_hz long (the gyro is sampled
  // once per step).
  SimulationPeriod(double loop_rate_hz, double duration_s, double sample_rate_hz = 0.0);
  double start_of(std::int64_t k) const { return static_cast<double>(k) * period_s; }
};

// When the simulated vehicle's own messages are due.
class MessageSchedule {
 public:
  // A battery reading is due at t (and the next one is scheduled).
  bool battery_due(double t);
  // A motor_status reporting `detected` is due at t: when some failure is
  // detected and either the set changed or its period came round.
  bool motor_status_due(double t, MotorMask detected);

 private:
  double next_battery_ = 0.0;
  double next_motor_status_ = 0.0;
  MotorMask reported_ = 0;
};

}  // namespace motormix::sim
