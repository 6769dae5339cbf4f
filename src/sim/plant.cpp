#include "sim/plant.hpp"

#include "sim/scenario_clock.hpp"

namespace motormix::sim {

Plant::Plant(const config::Config& flown, const Scenario& scenario, const Realism& realism,
             std::uint64_t seed)
    : vehicle_(truth_config(flown, realism.truth)),
      imu_(vehicle_.physics(), scenario.noise.gyro_rad_s, realism.imu, seed),
      sensors_(scenario.noise, seed),
      attitude_sensor_(seed),
      esc_telemetry_(flown.motors(), seed, realism.esc_latency) {}

void Plant::integrate(const SimulationPeriod& period, const MotorVector& outputs,
                      const DirectionVector& direction, const MotorHealth& health,
                      const ScenarioClock& clock, double t) {
  for (int s = 0; s < period.substeps; ++s) {
    vehicle_.step(outputs, direction, health, clock.environment(t + s * period.step_s),
                  period.step_s);
    imu_.sample(vehicle_, period.step_s);
  }
}

}  // namespace motormix::sim
