#pragma once
// Turns a validated Config into the core's Mixer. Set-up time only.

#include <motormix/config/config.hpp>

#include <motormix/mixer.hpp>

namespace motormix::config {

// Motor command range: 0..1 for motors that only push, -1..1 for wheels.
CommandRange command_range(const Config& config);

// Per axis, the largest pure demand that `mixing`'s linear mix delivers
// within the command range, torques measured from half thrust (aircraft) or
// standstill (wheels).
AxisVector authority_at_half_thrust(const Config& config, const MixingMatrix& mixing);

// The healthy effectiveness and a reallocation for every single and double
// motor failure (none for the budget strategies, which have none).
FailurePlan failure_plan(const Config& config);

// The configured mixer, with every failure plan prepared.
Mixer build_mixer(const Config& config);

}  // namespace motormix::config
