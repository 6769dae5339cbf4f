#pragma once
// What every fuzz target insists on, whatever the input: outputs finite and
// within their configured range (the disarmed value when disarmed). A
// violation aborts, so libFuzzer keeps the input as a crash.

#include <motormix/mixer.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace motormix::fuzz {

[[noreturn]] inline void violation(const char* what, int motor, double value) {
  std::fprintf(stderr, "fuzz invariant violated: %s (motor %d, value %.17g)\n", what, motor, value);
  std::abort();
}

inline void check_outputs(const Mixer& mixer, const MixerOutput& out) {
  for (int i = 0; i < mixer.motors(); ++i) {
    const OutputChannel& ch = mixer.output_stage().channel(i);
    const double v = out.output[i];
    if (!std::isfinite(v)) violation("output not finite", i, v);
    if (out.armed && ((out.failed >> i) & 1U)) {
      if (v != ch.disarmed) violation("failed motor not at its disarmed (stop) value", i, v);
      if (out.command[i] != 0.0) violation("failed motor commanded", i, out.command[i]);
    } else if (out.armed) {
      if (v < std::fmin(ch.min, ch.max) || v > std::fmax(ch.min, ch.max)) {
        violation("armed output outside [min, max]", i, v);
      }
      if (!std::isfinite(out.command[i]) || std::abs(out.command[i]) > 1.0) {
        violation("command outside -1..1", i, out.command[i]);
      }
    } else if (v != ch.disarmed) {
      violation("disarmed output is not the disarmed value", i, v);
    }
  }
}

}  // namespace motormix::fuzz
