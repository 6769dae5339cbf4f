#include "loop/spool_up.hpp"

#include <algorithm>

namespace motormix::loop {

void SpoolUp::blend(const OutputStage& stage, double ramp, MixerOutput& out) {
  for (int i = 0; i < stage.outputs(); ++i) {
    if ((out.failed >> i) & 1U) continue;
    const OutputChannel& ch = stage.channel(i);
    const double off = std::clamp(ch.disarmed, std::min(ch.min, ch.max), std::max(ch.min, ch.max));
    out.output[i] = off + ramp * (out.output[i] - off);
  }
}

}  // namespace motormix::loop
