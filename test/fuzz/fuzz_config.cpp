// The configuration loader on arbitrary text: a Config and a working mixer,
// or a ConfigError; never a crash, a hang or another exception. Every mixer
// it builds is driven with extreme demands and must stay in range.

#include "fuzz_checks.hpp"

#include <motormix/config/build_mixer.hpp>
#include <motormix/config/load_config.hpp>

#include <cstdint>
#include <limits>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace motormix;
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const config::Config c = config::load_config_text(text, "fuzz");
    const Mixer mixer = config::build_mixer(c);
    MixerOutput out;
    const double inf = std::numeric_limits<double>::infinity();
    const AxisVector demands[] = {
        {0, 0, 0, 0},          {1, 1, 1, 1},
        {-1, -1, -1, 1},       {1, -1, 1, 0},
        {0.3, -0.2, 0.9, 0.5}, {5, -5, 5, 5},
        {inf, 0, 0, 0.5},      {std::numeric_limits<double>::quiet_NaN(), 0, 0, 0.5}};
    for (const AxisVector& d : demands) {
      mixer.mix(d, out, 0.0025);
      motormix::fuzz::check_outputs(mixer, out);
    }
    mixer.disarm(out);
    motormix::fuzz::check_outputs(mixer, out);
  } catch (const config::ConfigError&) {
    // A clean refusal is a correct answer.
  }
  return 0;
}
