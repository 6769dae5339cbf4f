#include "sim/period.hpp"

#include "sim/lockstep.hpp"

#include <cmath>

namespace motormix::sim {

SimulationPeriod::SimulationPeriod(double loop_rate_hz, double duration_s)
    : period_s(1.0 / loop_rate_hz),
      substeps(static_cast<int>(std::ceil(period_s / kMaxPhysicsStepS - kTimeToleranceS))),
      step_s(period_s / substeps),
      cycles(static_cast<std::int64_t>(std::floor(duration_s * loop_rate_hz + kTimeToleranceS))) {}

void SimulationPeriod::integrate(VehicleModel& vehicle, const MotorVector& outputs,
                                 const DirectionVector& direction, const MotorHealth& health,
                                 const ScenarioClock& clock, double t) const {
  for (int s = 0; s < substeps; ++s) {
    vehicle.step(outputs, direction, health, clock.environment(t + s * step_s), step_s);
  }
}

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
