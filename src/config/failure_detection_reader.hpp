#pragma once
// Reads the `failure_detection:` section into config.failure_detection
// (see failure_detection.hpp). Needs the geometry, the outputs and the
// `vehicle:` section read first: the rates source takes its scale from it.

#include "config/yaml_reader.hpp"

#include <motormix/config/config.hpp>

namespace motormix::config {

// present: the document has the section (absent means off).
void read_failure_detection(MapReader section, bool present, Config& config);
// The rates source's model of the rotors' own angular momentum, from the
// vehicle (also after the simulator changed it: vehicle_derived.hpp).
void rotor_momentum_model(const VehiclePhysics& v, FailureDetectorSettings& s);

}  // namespace motormix::config
