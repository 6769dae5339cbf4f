#pragma once
// Named vehicles whose mixing tables are known by heart.

#include <motormix/mixing_matrix.hpp>

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace motormix {

struct Preset {
  std::string name;
  std::string description;
  std::vector<std::string> motor_names;  // in motor order
  MixingMatrix mixing;                   // rows: motors; columns: roll, pitch, yaw, thrust
};

std::optional<Preset> find_preset(std::string_view name);
std::vector<std::string> preset_names();

}  // namespace motormix
