#pragma once
// A lithium-polymer pack: open-circuit voltage from the state of charge
// (a piecewise-linear curve of a typical LiPo cell under light load), minus
// the drop across the pack's internal resistance; charge counted in
// ampere-hours. Voltage sag under current is what battery compensation is
// there to undo.

#include <motormix/config/vehicle_physics.hpp>

namespace motormix::sim {

class BatteryModel {
 public:
  explicit BatteryModel(const config::BatteryPhysics& p);
  // Draws `current_a` for dt seconds.
  void step(double current_a, double dt);
  double terminal_v() const { return terminal_v_; }
  double charge() const { return charge_; }  // 0..1
  double current_a() const { return current_a_; }
  const config::BatteryPhysics& physics() const { return p_; }

  // Open-circuit voltage of one cell at a state of charge 0..1.
  static double cell_ocv(double charge);

 private:
  config::BatteryPhysics p_;
  double charge_;
  double current_a_ = 0.0;
  double terminal_v_;
};

}  // namespace motormix::sim
