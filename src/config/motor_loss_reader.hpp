#pragma once
// Reads the `motor_loss:` section into config.motor_loss (see
// motor_loss.hpp). Needs the geometry, the outputs and the `vehicle:`
// section read first: the controller flies the vehicle described there.

#include "config/yaml_reader.hpp"

#include <motormix/config/config.hpp>

namespace motormix::config {

void read_motor_loss(MapReader section, Config& config);
// The model and equilibria from config.vehicle_model again, the settings
// kept (vehicle_derived.hpp).
void rederive_motor_loss(Config& config);

}  // namespace motormix::config
