#pragma once
// The settings a configuration derives from its `vehicle:` section (the
// failure detector's motor lag, the spin landing's model and equilibria),
// derived again after the vehicle was changed in code: the simulator's
// realism switches take the rotors' inertia or the slower spin-down away,
// and motormix must then see the vehicle as flown.

#include <motormix/config/config.hpp>

namespace motormix::config {

// When the spin landing no longer has an equilibrium for every motor, it is
// switched off and motor_loss_off says why (as at load time with `auto`).
void rederive_from_vehicle(Config& config);

}  // namespace motormix::config
