#include "bus/policy_or_error.hpp"

#include <motormix/config/security.hpp>

namespace motormix::bus {

std::optional<signing::Policy> policy_or_error(const config::Config& config, const char* who,
                                               std::ostream& err, int link_offset) {
  try {
    return config::signing_policy(config, link_offset);
  } catch (const std::exception& e) {  // ConfigError, KeyError: both name the key and why
    err << "motormix " << who << ": " << e.what() << "\n";
    return std::nullopt;
  }
}

}  // namespace motormix::bus
