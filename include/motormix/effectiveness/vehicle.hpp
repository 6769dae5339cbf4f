#pragma once
// What a vehicle is, as far as mixing cares: either an effectiveness matrix
// (from a physical layout) from which the mixing matrix is derived, or a
// mixing table taken as it is; plus which axes it is commanded in.

#include <motormix/axes.hpp>
#include <motormix/effectiveness/effectiveness.hpp>
#include <motormix/effectiveness/geometry.hpp>
#include <motormix/effectiveness/mixing_matrix.hpp>

#include <optional>
#include <string>
#include <vector>

namespace motormix {

struct Vehicle {
  std::string name;
  std::string description;
  std::vector<std::string> motor_names;    // one per motor, output order
  std::vector<std::string> motor_details;  // e.g. "front right, CCW"; may be empty
  ThrustRange thrust_range = ThrustRange::kUnipolar;
  AxisMask controlled = kAllAxes;

  // Set when the vehicle was described rotor by rotor (presets included), in
  // output order: what other stacks' geometry formats are written from.
  std::vector<Rotor> rotors;

  // Exactly one of these is set.
  std::optional<EffectivenessMatrix> effectiveness;
  std::optional<MixingMatrix> mixing_table;

  int motors() const {
    return static_cast<int>(effectiveness ? effectiveness->cols() : mixing_table->rows());
  }
};

}  // namespace motormix
