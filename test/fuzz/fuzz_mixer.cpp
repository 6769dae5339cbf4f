// The allocation strategies and the output stage on random vehicles: a
// random mixing table (1 to 16 motors), strategy, output mode and limits,
// written as a configuration. It loads into a mixer or is refused with a
// ConfigError; every mixer is then driven with random demands (NaN and
// infinities included) and must stay finite and in range.

#include "fuzz_checks.hpp"

#include <motormix/config/build_mixer.hpp>
#include <motormix/config/load_config.hpp>

#include <fuzzer/FuzzedDataProvider.h>

#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>

namespace {

std::string number(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

double demand_value(FuzzedDataProvider& in) {
  switch (in.ConsumeIntegralInRange<int>(0, 9)) {
    case 0:
      return std::numeric_limits<double>::quiet_NaN();
    case 1:
      return std::numeric_limits<double>::infinity();
    case 2:
      return in.ConsumeFloatingPoint<double>();
    default:
      return in.ConsumeFloatingPointInRange<double>(-1.2, 1.2);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace motormix;
  FuzzedDataProvider in(data, size);
  const int motors = in.ConsumeIntegralInRange<int>(1, kMaxMotors);
  static const char* strategies[] = {"legacy_budget", "budget",      "shift",
                                     "clip",          "prioritized", "optimal"};
  static const char* airmodes[] = {"off", "roll_pitch", "roll_pitch_yaw"};
  const bool wheels = in.ConsumeBool();
  std::string yaml = "geometry:\n  mixing:\n";
  for (int i = 0; i < motors; ++i) {
    yaml += "    - [";
    for (int a = 0; a < kNumAxes; ++a) {
      const double v = in.ConsumeBool()
                           ? in.ConsumeFloatingPointInRange<double>(-2.0, 2.0)
                           : static_cast<double>(in.ConsumeIntegralInRange<int>(-1, 1));
      yaml += (a ? ", " : "") + number(v);
    }
    yaml += "]\n";
  }
  yaml += "mixer:\n  strategy: " + std::string(strategies[in.ConsumeIntegralInRange<int>(0, 5)]) +
          "\n  prioritized: {airmode: " + airmodes[in.ConsumeIntegralInRange<int>(0, 2)] +
          ", yaw_headroom: " + number(in.ConsumeFloatingPointInRange<double>(0.0, 0.5)) + "}\n" +
          "  optimal: {max_iterations: " + std::to_string(in.ConsumeIntegralInRange<int>(1, 200)) +
          "}\n";
  const double lo = in.ConsumeFloatingPointInRange<double>(-3000.0, 3000.0);
  const double hi = in.ConsumeFloatingPointInRange<double>(-3000.0, 3000.0);
  const char* mode = wheels ? (in.ConsumeBool() ? "centered" : "magnitude_direction") : "unipolar";
  yaml += "output: {mode: " + std::string(mode) + ", min: " + number(lo) + ", max: " + number(hi) +
          ", center: " + number((lo + hi) / 2) + ", disarmed: " + number(lo) +
          ", idle: " + number(in.ConsumeFloatingPointInRange<double>(0.0, 0.3)) +
          ", thrust_model_factor: " + number(in.ConsumeFloatingPointInRange<double>(0.0, 1.0)) +
          ", slew_per_s: " + number(in.ConsumeFloatingPointInRange<double>(0.0, 1e5)) + "}\n";
  try {
    const config::Config c = config::load_config_text(yaml, "fuzz");
    const Mixer mixer = config::build_mixer(c);
    MixerOutput out;
    mixer.disarm(out);
    while (in.remaining_bytes() > 0) {
      AxisVector d;
      for (int a = 0; a < kNumAxes; ++a) d[a] = demand_value(in);
      const double dt = in.ConsumeFloatingPointInRange<double>(0.0, 0.01);
      // Any failure set, prepared or not, including bits beyond the motors.
      const MotorMask failed = in.ConsumeBool() ? in.ConsumeIntegral<std::uint32_t>() : 0;
      mixer.mix(d, out, dt, failed);
      motormix::fuzz::check_outputs(mixer, out);
    }
  } catch (const config::ConfigError&) {
  }
  return 0;
}
