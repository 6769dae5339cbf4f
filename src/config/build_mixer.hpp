#pragma once
// Turns a validated Config into the core's Mixer. Set-up time only.

#include "config/config.hpp"

#include <motormix/mixer.hpp>

namespace motormix::config {

Mixer build_mixer(const Config& config);

}  // namespace motormix::config
