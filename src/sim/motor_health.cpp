#include "sim/motor_health.hpp"

#include <algorithm>
#include <cmath>

namespace motormix::sim {

std::optional<FailureKind> failure_kind(const std::string& name) {
  return parse_in(kFailureKindNames, name);
}

bool reported_outside(FailureKind kind) {
  return kind == FailureKind::kStop || kind == FailureKind::kDesync;
}

bool loses_thrust(FailureKind kind) { return kind != FailureKind::kTelemetry; }

void MotorHealth::apply(const MotorFailure& f, double t) {
  const double since = t - f.at_s;
  const int i = f.motor;
  switch (f.kind) {
    case FailureKind::kStop:
      drive[i] = 0.0;
      break;
    case FailureKind::kHalfThrust:
      prop[i] *= 0.5;
      break;
    case FailureKind::kIntermittent:
      if (std::fmod(since, kIntermittentPeriodS) < kIntermittentOffS) drive[i] = 0.0;
      break;
    case FailureKind::kDesync:
      drive[i] *= std::clamp(1.0 - since / kDesyncSpinDownS, 0.0, 1.0);
      break;
    case FailureKind::kTelemetry:
      telemetry_dead |= MotorMask{1} << i;
      break;
    case FailureKind::kPropLost:
      drive[i] *= kPropLostSpeedUp;
      prop[i] = 0.0;
      lag[i] = kPropLostLag;
      break;
    case FailureKind::kPropDamaged:
      drive[i] *= kPropDamagedSpeedUp;
      prop[i] *= kPropDamagedThrust;
      break;
  }
}

}  // namespace motormix::sim
