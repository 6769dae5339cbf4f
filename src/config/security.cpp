// The `security:` section's reader and the policy it configures.

#include "security_reader.hpp"

#include <motormix/signing.hpp>

#include <cmath>

namespace motormix::config {

void read_security(MapReader section, const std::string& base_dir, Config& config) {
  Security& s = config.security;
  s.mode = section.choice("mode", signing::Mode::kOff, signing::kModeNames);
  s.key_file = section.text("key_file", "");
  if (!s.key_file.empty() && s.key_file.front() != '/' && !base_dir.empty()) {
    s.key_file = base_dir + "/" + s.key_file;
  }
  const double link_id = section.number("link_id", 1, 0, 255);
  if (link_id != std::floor(link_id)) {
    fail(section.path_of("link_id"), describe(section.raw("link_id")), "a whole number 0..255");
  }
  s.link_id = static_cast<int>(link_id);
  s.max_skew_s = section.number("max_skew_s", 60.0, 1.0, 3600.0);
  if (s.mode != signing::Mode::kOff && s.key_file.empty()) {
    fail(section.path_of("key_file"), "nothing",
         std::string("a key file (motormix keygen makes one) with security.mode ") +
             to_string(s.mode));
  }
  section.finish();
}

std::string describe(const Security& s) {
  const std::string where = " (key " + s.key_file + ", link id " + std::to_string(s.link_id) + ")";
  switch (s.mode) {
    case signing::Mode::kOff:
      return "security: off: nothing signed or verified (anyone who reaches the bus can drive "
             "it; see docs/signing-the-bus.md)";
    case signing::Mode::kSign:
      return "security: sign" + where +
             ": outputs signed; signed inputs verified, unsigned inputs still taken";
    case signing::Mode::kRequire:
      return "security: require" + where +
             ": outputs signed; only inputs whose signature verifies are taken";
  }
  return "security: ?";
}

signing::Policy signing_policy(const Config& config, int link_id_offset) {
  const Security& s = config.security;
  if (s.mode == signing::Mode::kOff) return signing::Policy();
  try {
    return signing::Policy(s.mode, signing::load_key(s.key_file),
                           static_cast<std::uint8_t>((s.link_id + link_id_offset) & 0xFF),
                           s.max_skew_s);
  } catch (const signing::KeyError& e) {
    throw ConfigError(std::string("security.key_file: ") + e.what());
  }
}

}  // namespace motormix::config
