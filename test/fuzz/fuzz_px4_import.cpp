// `motormix import px4-params` on arbitrary bytes (a .params text or a
// ULog): parameters and a configuration, or a std::runtime_error naming
// what is wrong; never a crash, a hang or another exception. A ULog's
// topics are read through the same reader (formats, nested types, data).
// What the import writes either loads or is refused by the loader with a
// ConfigError (a value out of motormix's ranges), as the CLI reports it.

#include <motormix/config/load_config.hpp>
#include <motormix/config/px4_import.hpp>
#include <motormix/config/ulog.hpp>

#include <cstdint>
#include <stdexcept>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace motormix;
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  if (config::Ulog::is_ulog(bytes)) {
    const config::Ulog log = config::Ulog::parse(bytes, "fuzz");
    for (const char* topic : {"actuator_motors", "vehicle_torque_setpoint", "esc_status"}) {
      try {
        (void)log.samples(topic, {"timestamp"});
        (void)log.samples(topic, {"esc[0].esc_rpm", "xyz[2]"});
      } catch (const std::runtime_error&) {
        // not logged, or no such field: a clean refusal
      }
    }
  }
  try {
    const config::Px4Parameters p = config::parse_px4_parameters(bytes, "fuzz");
    const config::Px4Import imported = config::import_px4(p, "fuzz");
    config::load_config_text(imported.yaml, "imported");
  } catch (const config::ConfigError&) {
  } catch (const std::runtime_error&) {
  }
  return 0;
}
