// The `motor_loss:` section (documented in docs/motor-loss-landing.md).

#include "motor_loss_reader.hpp"

#include <motormix/angles.hpp>
#include <motormix/enum_names.hpp>
#include <motormix/safety/two_rotor_descent.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

namespace motormix::config {

namespace {

// The equilibrium spin may use at most this share of the gyro's range: the
// transient after the failure and gusts swing the rates above it.
constexpr double kSpinShareOfGyroRange = 0.7;
// The spin rate when the configuration names none and the vehicle has an
// equilibrium there.
constexpr double kDefaultSpinRate = 20.0;

// Why the vehicle cannot land spinning, or "" when it can.
std::string unsupported(const Config& config) {
  const VehiclePhysics& v = config.vehicle_model;
  if (config.thrust_range() == ThrustRange::kBipolar) return "a ground vehicle has no spin landing";
  if (config.motors() != 4) {
    return "spin landing is for four rotors; this vehicle has " + std::to_string(config.motors()) +
           " (more rotors keep flying on the ones left)";
  }
  if (!v.incomplete.empty()) return v.incomplete;
  for (const RotorPhysics& r : v.rotors) {
    if (r.axis.z() > -0.9) return "spin landing needs rotors that push up (axis near [0, 0, -1])";
  }
  for (const OutputChannel& ch : config.outputs) {
    if (ch.mode != OutputMode::kUnipolar) return "spin landing needs unipolar ESC outputs";
  }
  return "";
}

SpinningDescentModel model_of(const Config& config) {
  const VehiclePhysics& v = config.vehicle_model;
  SpinningDescentModel m;
  m.mass_kg = v.mass_kg;
  m.inertia_kgm2 = v.inertia_kgm2;
  m.rotational_drag = v.drag_rotational_nm_per_radps;
  m.time_constant_s = 0.5 * (v.time_constant_up_s + v.time_constant_down_s);
  m.rate_delay_s = v.imu.rate_delay_s();
  for (std::size_t i = 0; i < 4; ++i) {
    const RotorPhysics& r = v.rotors[i];
    m.axis[i] = r.axis;
    m.torque_per_newton[i] = r.torque_per_newton();
    m.max_thrust_n[i] = r.max_thrust_n;
    // The ESC's floor, not the idle: in the first half second the motor across
    // from the dead one must stop pushing the vehicle over (its idle thrust
    // alone tips a default quad), and a brief stop is the lesser risk.
    m.min_thrust_n[i] = 0.0;
    m.spin[i] = static_cast<double>(r.spin);
  }
  m.rotor_inertia_kgm2 = v.rotor_inertia_kgm2;
  m.max_rotor_speed_rad_s = v.max_rotor_speed_rad_s;
  return m;
}

// The model and equilibria of `ml` from the configuration; "" when every
// motor has one, else why not.
std::string derive(const Config& config, MotorLoss& ml) {
  std::string why = unsupported(config);
  if (why.empty()) {
    ml.model = model_of(config);
    ml.model.gyro_range_rad_s = ml.gyro_range_rad_s;
    ml.equilibria = solve_spin_equilibria(ml.model, ml.settings.spin_rate_rad_s);
    for (const SpinEquilibrium& eq : ml.equilibria) {
      if (!eq.found && why.empty()) why = eq.why;
    }
  }
  return why;
}

// The spin rates (whole rad/s from kSpinRateMin up to the gyro's share)
// at which every motor of the vehicle has an equilibrium, in order.
constexpr double kSpinRateMin = 3.0;
constexpr double kSpinRateMax = 100.0;
std::vector<double> working_spin_rates(const Config& config, const MotorLoss& base) {
  std::vector<double> rates;
  const double top = std::min(kSpinRateMax, kSpinShareOfGyroRange * base.gyro_range_rad_s);
  for (double w = kSpinRateMin; w <= top + 1e-9; w += 1.0) {
    MotorLoss trial = base;
    trial.settings.spin_rate_rad_s = w;
    if (derive(config, trial).empty()) rates.push_back(w);
  }
  return rates;
}

// The middle of the widest run of working rates (ties: the run nearest
// `wanted`): away from both edges, where the rotors' yaw torque is too weak
// to hold the spin (slow) or the motor across from the lost one leaves its
// range (fast).
double middle_of_widest_run(const std::vector<double>& rates, double wanted) {
  double best = rates.front(), best_width = -1.0;
  for (std::size_t i = 0; i < rates.size();) {
    std::size_t j = i;
    while (j + 1 < rates.size() && rates[j + 1] - rates[j] < 1.5) ++j;
    const double width = rates[j] - rates[i];
    const double middle = 0.5 * (rates[i] + rates[j]);
    if (width > best_width ||
        (width == best_width && std::abs(middle - wanted) < std::abs(best - wanted))) {
      best = middle;
      best_width = width;
    }
    i = j + 1;
  }
  return best;
}

// "13-18 rad/s" (or "13-15 and 20-22 rad/s"): the rates found, in order.
std::string describe_rates(const std::vector<double>& rates) {
  std::ostringstream s;
  for (std::size_t i = 0; i < rates.size();) {
    std::size_t j = i;
    while (j + 1 < rates.size() && rates[j + 1] - rates[j] < 1.5) ++j;
    if (i > 0) s << (j + 1 == rates.size() ? " and " : ", ");
    s << rates[i];
    if (j > i) s << "-" << rates[j];
    i = j + 1;
  }
  s << " rad/s";
  return s.str();
}

// What `run --check` says of two motors lost: the pairs the two-rotor
// landing covers, or why none.
std::string two_rotor_summary(const SpinningDescentModel& model) {
  std::ostringstream s;
  std::string why;
  int found = 0;
  s.precision(3);
  for (int a = 0; a < 4; ++a) {
    for (int b = a + 1; b < 4; ++b) {
      const TwoRotorPlan p = plan_two_rotor_descent(model, a, b);
      if (p.found) {
        s << (found++ == 0 ? "; two opposite motors lost: " : ", ") << p.failed[0] + 1 << "+"
          << p.failed[1] + 1 << " lands on " << p.working[0] + 1 << "+" << p.working[1] + 1 << " ("
          << p.weight_share * 100 << " % of the weight carried)";
      } else if (why.empty() && p.why.find("not opposite") == std::string::npos) {
        why = p.why;
      }
    }
  }
  if (found == 0)
    return "; two opposite motors lost: no landing (" + (why.empty() ? "none opposite" : why) + ")";
  return s.str();
}

}  // namespace

void rederive_motor_loss(Config& config) {
  if (!config.motor_loss) return;
  MotorLoss ml = *config.motor_loss;
  const std::string why = derive(config, ml);
  if (why.empty()) {
    config.motor_loss = ml;
  } else {
    config.motor_loss.reset();
    config.motor_loss_off = why;
  }
}

namespace {

// motor_loss.mode: landing on what is left when it can (auto), required
// (spin_landing: a configuration that cannot is refused), or never.
enum class MotorLossMode : std::uint8_t { kAuto, kSpinLanding, kOff };
constexpr EnumName<MotorLossMode> kMotorLossModeNames[] = {
    {MotorLossMode::kAuto, "auto"},
    {MotorLossMode::kSpinLanding, "spin_landing"},
    {MotorLossMode::kOff, "off"},
};

}  // namespace

void read_motor_loss(MapReader section, Config& config) {
  const MotorLossMode mode = section.choice("mode", MotorLossMode::kAuto, kMotorLossModeNames);
  MotorLoss ml;
  SpinningDescentSettings& s = ml.settings;
  ml.gyro_range_rad_s = section.number("gyro_range_dps", 2000.0, 100.0, 10000.0) * kRadPerDeg;
  const bool rate_named = section.has("spin_rate_rad_s");
  s.spin_rate_rad_s =
      section.number("spin_rate_rad_s", kDefaultSpinRate, kSpinRateMin, kSpinRateMax);
  s.descent_rate_mps = section.number("descent_rate_mps", 1.0, 0.2, 3.0);
  s.max_tilt_deg = section.number("max_tilt_deg", 8.0, 0.0, 20.0);
  s.spin_up_raise = section.boolean("spin_up_raise", true);
  ml.attitude_timeout_s = section.number("attitude_timeout_ms", 50.0, 5.0, 1000.0) / 1e3;
  if (s.spin_rate_rad_s > kSpinShareOfGyroRange * ml.gyro_range_rad_s) {
    std::ostringstream found, allowed;
    found << s.spin_rate_rad_s << " with gyro_range_dps " << ml.gyro_range_rad_s / kRadPerDeg;
    allowed << "at most " << kSpinShareOfGyroRange * 100
            << " % of the gyro's range (the transient swings above the equilibrium)";
    fail(section.path_of("spin_rate_rad_s"), found.str(), allowed.str());
  }
  section.finish();
  config.motor_loss.reset();
  config.motor_loss_off = "";
  if (mode == MotorLossMode::kOff) {
    config.motor_loss_off = "motor_loss.mode is off";
    return;
  }
  std::string why = derive(config, ml);
  if (!why.empty() && unsupported(config).empty()) {
    // This vehicle has no equilibrium at this rate: the rates it has one
    // at. Unnamed, the default gives way to the middle of the widest run
    // of them; named, the configuration's rate stands and the message says
    // which would do.
    const std::vector<double> rates = working_spin_rates(config, ml);
    if (!rates.empty() && !rate_named) {
      const double rate = middle_of_widest_run(rates, kDefaultSpinRate);
      std::ostringstream chosen;
      chosen << "spin_rate_rad_s " << rate << " chosen: the default " << kDefaultSpinRate
             << " has no equilibrium for this vehicle (" << why << "); it has one at "
             << describe_rates(rates);
      ml.settings.spin_rate_rad_s = rate;
      why = derive(config, ml);
      ml.spin_rate_chosen = chosen.str();
    } else if (!rates.empty()) {
      std::ostringstream more;
      more << why << " at spin_rate_rad_s " << s.spin_rate_rad_s << "; this vehicle has one at "
           << describe_rates(rates);
      why = more.str();
    } else {
      std::ostringstream none;
      none.precision(3);
      none << why << "; none at any spin rate from " << kSpinRateMin << " to "
           << std::min(kSpinRateMax, kSpinShareOfGyroRange * ml.gyro_range_rad_s)
           << " rad/s either (" << kSpinShareOfGyroRange * 100 << " % of the gyro's range)";
      why = none.str();
    }
  }
  if (!why.empty()) {
    if (mode == MotorLossMode::kSpinLanding)
      fail(section.path_of("mode"), name_in(kMotorLossModeNames, mode), "auto or off: " + why);
    config.motor_loss_off = why;
    return;
  }
  config.motor_loss = ml;
}

std::string Config::motor_loss_summary() const {
  if (motor_loss) {
    std::ostringstream s;
    s << "motor loss: spin landing (" << motor_loss->settings.spin_rate_rad_s << " rad/s, down at "
      << motor_loss->settings.descent_rate_mps << " m/s); needs attitude_t on " << channels.attitude
      << " (with velocity, or it follows the throttle); without a fresh one it mixes as before";
    if (!motor_loss->spin_rate_chosen.empty()) s << "; " << motor_loss->spin_rate_chosen;
    s << two_rotor_summary(motor_loss->model);
    return s.str();
  }
  if (motors() == 4 && thrust_range() != ThrustRange::kBipolar) {
    return "motor loss: no spin landing (" + motor_loss_off + ")";
  }
  return "";
}

}  // namespace motormix::config
