#pragma once
// The one exception a configuration throws: at start-up, naming the key path,
// the value found and what is allowed. Its own header, so a reader of YAML
// (src/config/include/config/yaml_reader.hpp) needs no configuration.

#include <stdexcept>

namespace motormix::config {

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace motormix::config
