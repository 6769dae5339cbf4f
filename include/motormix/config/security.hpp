#pragma once
// The `security:` section: whether motormix signs what it publishes and
// verifies what it reads (docs/signing-the-bus.md). Validated with the rest
// of the configuration; the key itself is read by signing_policy(), at
// start-up of a process that needs it, so that commands that never touch
// the bus (matrix, mix, check) run without access to the key.

#include <motormix/signing_policy.hpp>

#include <cstdint>
#include <string>

namespace motormix::config {

struct Config;

struct Security {
  signing::Mode mode = signing::Mode::kOff;
  // 64 hexadecimal digits, readable by its owner only (`motormix keygen`);
  // a relative path is relative to the configuration file's directory.
  std::string key_file;
  // This process's link id in its signatures. Receivers keep timestamps per
  // link and channel, so processes that publish on the same channel with
  // one key need link ids of their own.
  int link_id = 1;
  // A link's first message on a channel is refused when its timestamp is
  // further than this from the receiver's clock.
  double max_skew_s = 60.0;
};

// One line for logs and `--check`: the mode and what it means (the key
// file's path, never the key).
std::string describe(const Security& security);

// The policy of config.security, its key read from the key file. Throws
// ConfigError naming security.key_file and what is wrong with the file
// (never the key). Mode off: a policy without a key (no file is read).
// link_id_offset is added to security.link_id (mod 256): a second kind of
// publisher under the same configuration (the simulated vehicle beside the
// mixer, both publishing motor_status_t) signs as a link of its own.
signing::Policy signing_policy(const Config& config, int link_id_offset = 0);

// The link id the simulator on the bus signs as: security.link_id + 128.
constexpr int kSimulatorLinkOffset = 128;

}  // namespace motormix::config
