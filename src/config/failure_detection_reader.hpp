#pragma once
// Reads the `failure_detection:` section into config.failure_detection
// (see failure_detection.hpp). Needs the geometry, the outputs and the
// `vehicle:` section read first: the rates source takes its scale from it.

#include "config/yaml_reader.hpp"

#include <motormix/config/config.hpp>

namespace motormix::config {

// present: the document has the section (absent means off).
void read_failure_detection(MapReader section, bool present, Config& config);

}  // namespace motormix::config
