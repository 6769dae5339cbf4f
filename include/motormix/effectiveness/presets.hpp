#pragma once
// Named vehicles: multirotor frames with the motor numbering and spin
// directions PX4 and ArduPilot use, the team quad's sign table, and wheeled
// bases. A preset is a Vehicle; everything downstream treats it like one
// described by hand.

#include <motormix/effectiveness/vehicle.hpp>

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace motormix {

struct PresetOptions {
  std::optional<double> arm_length;  // rotor distance from the centre (default 0.25)
  bool reverse_spin = false;         // every rotor spins the other way
  std::vector<int> motor_order;      // output i drives preset motor motor_order[i] (1-based)
};

std::optional<Vehicle> find_preset(std::string_view name, const PresetOptions& options = {});
std::vector<std::string> preset_names();

}  // namespace motormix
