#pragma once
// The configuration's signing policy for one process, or a clear error.
// Every process reads the key the same way at start-up (a missing key or one
// open to others stops it there, never mid-flight) and reports it with its
// own name: "motormix output: security.key_file: ...".

#include <motormix/config/config.hpp>
#include <motormix/signing_policy.hpp>

#include <optional>
#include <ostream>

namespace motormix::bus {

// `who` names the process in the error ("output", "monitor"); `link_offset`
// gives a process a link id of its own (the simulator's).
std::optional<signing::Policy> policy_or_error(const config::Config& config, const char* who,
                                               std::ostream& err, int link_offset = 0);

}  // namespace motormix::bus
