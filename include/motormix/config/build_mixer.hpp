#pragma once
// Turns a validated Config into the core's Mixer. Set-up time only.

#include <motormix/config/config.hpp>

#include <motormix/mixer.hpp>

namespace motormix::config {

// Motor command range: 0..1 for motors that only push, -1..1 for wheels.
CommandRange command_range(const Config& config);

Mixer build_mixer(const Config& config);

}  // namespace motormix::config
