#include "sim/period.hpp"

#include <algorithm>
#include <cmath>

namespace motormix::sim {

SimulationPeriod::SimulationPeriod(double loop_rate_hz, double duration_s, double sample_rate_hz)
    : period_s(1.0 / loop_rate_hz),
      substeps(static_cast<int>(std::ceil(
          period_s / std::min(kMaxPhysicsStepS, sample_rate_hz > 0 ? 1.0 / sample_rate_hz : 1.0) -
          kTimeToleranceS))),
      step_s(period_s / substeps),
      cycles(static_cast<std::int64_t>(std::floor(duration_s * loop_rate_hz + kTimeToleranceS))) {}

bool MessageSchedule::battery_due(double t) {
  if (!due(t, next_battery_)) return false;
  next_battery_ += kBatteryPeriodS;
  return true;
}

bool MessageSchedule::motor_status_due(double t, MotorMask detected) {
  if (detected == 0 || (detected == reported_ && !due(t, next_motor_status_))) return false;
  reported_ = detected;
  next_motor_status_ = t + kMotorStatusPeriodS;
  return true;
}

}  // namespace motormix::sim
