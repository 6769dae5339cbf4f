#pragma once
// Reads the `hardware:` section into config.hardware (see hardware.hpp).
// Needs the outputs read first: every motor's range and disarmed value must
// be a pulse the driver can make.

#include "config/yaml_reader.hpp"

#include <motormix/config/config.hpp>

namespace motormix::config {

void read_hardware(MapReader section, Config& config);

}  // namespace motormix::config
