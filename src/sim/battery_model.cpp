#include "sim/battery_model.hpp"

#include <algorithm>
#include <array>
#include <cstddef>

namespace motormix::sim {

BatteryModel::BatteryModel(const config::BatteryPhysics& p)
    : p_(p), charge_(p.initial_charge), terminal_v_(p.cells * cell_ocv(p.initial_charge)) {}

double BatteryModel::cell_ocv(double charge) {
  static constexpr std::array<double, 9> kCharge = {0.0, 0.05, 0.1, 0.2, 0.4, 0.6, 0.8, 0.9, 1.0};
  static constexpr std::array<double, 9> kVolts = {3.27, 3.50, 3.60, 3.70, 3.78,
                                                   3.87, 3.97, 4.06, 4.20};
  const double c = std::clamp(charge, 0.0, 1.0);
  std::size_t i = 1;
  while (i + 1 < kCharge.size() && c > kCharge[i]) ++i;
  const double f = (c - kCharge[i - 1]) / (kCharge[i] - kCharge[i - 1]);
  return kVolts[i - 1] + f * (kVolts[i] - kVolts[i - 1]);
}

void BatteryModel::step(double current_a, double dt) {
  current_a_ = std::max(0.0, current_a);
  charge_ = std::max(0.0, charge_ - current_a_ * dt / 3600.0 / (p_.capacity_mah / 1000.0));
  terminal_v_ =
      std::max(0.0, p_.cells * cell_ocv(charge_) - current_a_ * p_.internal_resistance_ohm);
}

}  // namespace motormix::sim
