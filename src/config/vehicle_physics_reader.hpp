#pragma once
// Reads the `vehicle:` section into config.vehicle_model (see vehicle_physics.hpp).
// Needs the geometry and the outputs read first: defaults come from them.

#include "config/yaml_reader.hpp"

#include <motormix/config/config.hpp>

namespace motormix::config {

void read_vehicle_physics(MapReader vehicle, Config& config);

}  // namespace motormix::config
