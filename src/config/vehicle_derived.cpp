#include <motormix/config/vehicle_derived.hpp>

#include "failure_detection_reader.hpp"
#include "motor_loss_reader.hpp"

namespace motormix::config {

void rederive_from_vehicle(Config& config) {
  const VehiclePhysics& v = config.vehicle_model;
  if (config.failure_detection) {
    config.failure_detection->detector.time_constant_up_s = v.time_constant_up_s;
    config.failure_detection->detector.time_constant_down_s = v.time_constant_down_s;
    rotor_momentum_model(v, config.failure_detection->detector);
  }
  if (config.motor_loss) rederive_motor_loss(config);
}

}  // namespace motormix::config
