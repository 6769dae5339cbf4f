// `motormix import px4-params` on arbitrary bytes (a .params text or a
// ULog): parameters and a configuration, or a std::runtime_error naming
// what is wrong; never a crash, a hang or another exception. A ULog's
// topics are read through the same reader (formats, nested types, data).
// What the import writes either loads or is refused by the loader with a
// ConfigError (a value out of motormix's ranges), as the CLI reports it.
// `motormix import ulog` on the same ULog: events in time order, each of
// which decodes, with inputs inside motormix's ranges; or a refusal.

#include <motormix/config/load_config.hpp>
#include <motormix/config/px4_import.hpp>
#include <motormix/config/ulog.hpp>
#include <motormix/pid_t.hpp>
#include <motormix/setpoint_t.hpp>
#include "fuzz_checks.hpp"
#include "log/ulog_import.hpp"

#include <cmath>

#include <cstdint>
#include <stdexcept>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace motormix;
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  const auto check = [](bool ok, const char* what) {
    if (!ok) fuzz::violation(what, 0, 0.0);
  };
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
    try {
      lcmlog::UlogImportSummary summary;
      const auto events = lcmlog::ulog_events(log, {}, summary);
      for (std::size_t i = 0; i < events.size(); ++i) {
        const lcmlog::ImportedEvent& e = events[i];
        if (i > 0) check(events[i - 1].t <= e.t, "events out of time order");
        const int n = static_cast<int>(e.bytes.size());
        if (e.channel == "PID") {
          motormix::pid_t m;
          check(m.decode(e.bytes.data(), 0, n) == n, "an imported message does not decode");
          for (float v : {m.roll, m.pitch, m.yaw}) check(std::abs(v) <= 1.0F, "pid outside -1..1");
        } else if (e.channel == "SETPOINT") {
          motormix::setpoint_t m;
          check(m.decode(e.bytes.data(), 0, n) == n, "an imported message does not decode");
          check(m.throttle >= 0.0F && m.throttle <= 1.0F, "throttle outside 0..1");
        }
      }
    } catch (const std::runtime_error&) {
      // no mixing inputs: refused
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
