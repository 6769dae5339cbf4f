#pragma once
// What a configuration makes `motormix run` do, in the words the start-up
// banner (each line behind "motormix: ") and `motormix run --check` both
// print, so the two cannot say different things: the vehicle and strategy,
// the inputs and their timeouts, the outputs and rates, the failure
// detector's sources and channels, what a failed motor makes it do, and
// the signing mode. The mixing matrix follows in both (export_matrix).
// The detector's line reads the detector the loop runs (its sources and
// gates), not the configuration it was built from: the banner says what
// runs.

#include "loop/control_loop.hpp"

#include <motormix/config/config.hpp>

#include <string>
#include <vector>

namespace motormix::node {

std::vector<std::string> describe_run(const config::Config& config, const loop::ControlLoop& loop);

}  // namespace motormix::node
