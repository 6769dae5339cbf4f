#pragma once
// The simulated world below the controller, assembled once for the lockstep
// and the live run: the vehicle as it really is (the configuration with the
// realism's model error), its gyro, the controller's other sensors, the
// estimator's attitude_t and the ESCs' telemetry, all from one seed.
//
// The configuration passed in is the one flown (scenario_config: the
// scenario's battery and the realism's switches applied); the controller
// and motormix see it, the physics runs on truth_config of it.

#include "sim/attitude_sensor.hpp"
#include "sim/esc_telemetry_model.hpp"
#include "sim/imu.hpp"
#include "sim/period.hpp"
#include "sim/realism.hpp"
#include "sim/scenario_clock.hpp"
#include "sim/sensors.hpp"
#include "sim/vehicle_model.hpp"

#include <cstdint>

namespace motormix::sim {

class Plant {
 public:
  Plant(const config::Config& flown, const Scenario& scenario, const Realism& realism,
        std::uint64_t seed);

  const VehicleModel& vehicle() const { return vehicle_; }
  // What the built-in controller measures now.
  BodyState measured() { return sensors_.measure(vehicle_.body(), imu_.rates()); }
  double measured_speed() { return sensors_.speed(vehicle_.forward_speed()); }
  // The flight controller's attitude_t now.
  loop::AttitudeSample attitude(std::int64_t utime) {
    return attitude_sensor_.sample(vehicle_.body(), imu_.rates(), utime);
  }
  // The ESC telemetry arriving by t (count 0: none).
  const loop::EscTelemetrySample& esc_telemetry(double t, std::int64_t utime,
                                                const MotorHealth& health) {
    return esc_telemetry_.sample(t, utime, vehicle_, health);
  }
  // One loop period of physics from t, the gyro sampled at every step.
  void integrate(const SimulationPeriod& period, const MotorVector& outputs,
                 const DirectionVector& direction, const MotorHealth& health,
                 const ScenarioClock& clock, double t);

 private:
  VehicleModel vehicle_;
  Imu imu_;
  Sensors sensors_;
  AttitudeSensor attitude_sensor_;
  EscTelemetryModel esc_telemetry_;
};

}  // namespace motormix::sim
