#pragma once
// YAML -> validated Config. Fails at start-up with a ConfigError that names
// the key path, the value and the allowed range; never later.

#include <motormix/config/config.hpp>

#include <string>
#include <vector>

namespace motormix::config {

// `overrides` are "key.path=value" strings applied on top of the file before
// validation (value parsed as YAML), e.g. "loop_rate_hz=1000".
Config load_config_file(const std::string& path, const std::vector<std::string>& overrides = {});
Config load_config_text(const std::string& yaml_text, const std::string& source_name,
                        const std::vector<std::string>& overrides = {});

}  // namespace motormix::config
