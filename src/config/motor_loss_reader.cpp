// The `motor_loss:` section (documented in docs/motor-loss-landing.md).

#include "motor_loss_reader.hpp"

#include <motormix/angles.hpp>
#include <motormix/enum_names.hpp>
#include <motormix/safety/two_rotor_descent.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace motormix::config {

namespace {

// The equilibrium spin may use at most this share of the gyro's range: the
// transient after the failure and gusts swing the rates above it.
constexpr double kSpinShareOfGyroRange = 0.7;

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
  s.spin_rate_rad_s = section.number("spin_rate_rad_s", 20.0, 3.0, 100.0);
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
  const std::string why = derive(config, ml);
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
    s << two_rotor_summary(motor_loss->model);
    return s.str();
  }
  if (motors() == 4 && thrust_range() != ThrustRange::kBipolar) {
    return "motor loss: no spin landing (" + motor_loss_off + ")";
  }
  return "";
}

}  // namespace motormix::config
