#pragma once
// Reads the `security:` section into config.security (see security.hpp).

#include "config/yaml_reader.hpp"

#include <motormix/config/config.hpp>

#include <string>

namespace motormix::config {

// base_dir: the configuration file's directory, for a relative key_file.
void read_security(MapReader section, const std::string& base_dir, Config& config);

}  // namespace motormix::config
