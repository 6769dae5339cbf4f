// mixer: (the strategy and its settings, motors stopped from the start) and
// battery:.

#include "section_readers.hpp"
#include "strategies.hpp"

#include <motormix/allocation/motor_failure.hpp>

#include <cmath>
#include <sstream>

namespace motormix::config::reading {

namespace {

// mixer.failed_motors: motors stopped from the start, by number as `motormix
// matrix` prints them (m3 is 3) or by name.
void read_failed_motors(MapReader& mixer, Config& config) {
  const YAML::Node list = mixer.raw("failed_motors");
  if (!list.IsDefined() || list.IsNull()) return;
  const std::string path = mixer.path_of("failed_motors");
  const int n = config.motors();
  const std::string allowed = "a list of motor numbers 1.." + std::to_string(n) +
                              " (as motormix matrix prints them) or motor names (" +
                              join(config.motor_names()) + ")";
  if (!list.IsSequence()) fail(path, describe(list), allowed);
  if (!strategy_entry(config.strategy).reallocates && list.size() > 0) {
    fail(path, describe(list) + " with strategy " + to_string(config.strategy),
         "failed motors only with strategy " + reallocating_strategies() +
             " (the budget strategies have no reallocation)");
  }
  MotorMask mask = 0;
  for (std::size_t k = 0; k < list.size(); ++k) {
    const std::string item_path = path + "[" + std::to_string(k) + "]";
    const YAML::Node& item = list[k];
    if (!item.IsScalar()) fail(item_path, describe(item), allowed);
    const int motor = config.motor_index(item.Scalar());
    if (motor < 0) fail(item_path, describe(item), allowed);
    const MotorMask b = MotorMask{1} << motor;
    if (mask & b) fail(item_path, describe(item) + ", listed twice", "each motor once");
    mask |= b;
  }
  if (count_motors(mask) >= n) {
    fail(path, describe(list), "at least one working motor");
  }
  config.failed_motors = mask;
}

}  // namespace

void read_battery(MapReader battery, Config& config) {
  if (!battery.has("nominal_v")) {
    fail(battery.path_of("nominal_v"), "nothing",
         "the pack voltage at which no compensation is applied, 1 to 100 V (required when "
         "'battery' is present)");
  }
  BatterySettings b;
  b.nominal_v = battery.required_number("nominal_v", 1.0, 100.0);
  b.exponent = battery.number("exponent", 1.0, 0.0, 3.0);
  b.max_gain = battery.number("max_gain", 1.5, 1.0, 3.0);
  b.filter_hz = battery.number("filter_hz", 2.0, 0.01, config.loop_rate_hz / 2.0);
  b.timeout_s = battery.number("timeout_ms", 500.0, 1.0, 10000.0) / 1e3;
  b.min_v = battery.number("min_v", 0.5 * b.nominal_v, 0.0, 100.0);
  b.max_v = battery.number("max_v", 1.25 * b.nominal_v, 0.0, 150.0);
  if (!(b.min_v < b.nominal_v && b.nominal_v <= b.max_v)) {
    std::ostringstream found;
    found << "min_v " << b.min_v << ", nominal_v " << b.nominal_v << ", max_v " << b.max_v;
    fail(battery.path_of("min_v"), found.str(), "min_v < nominal_v <= max_v");
  }
  battery.finish();
  config.battery = b;
}

void read_mixer(MapReader mixer, Config& config) {
  // Default: sequential desaturation for aircraft, shifting for wheels.
  const Strategy fallback =
      config.thrust_range() == ThrustRange::kBipolar ? Strategy::kShift : Strategy::kPrioritized;
  config.strategy = mixer.choice("strategy", fallback, kStrategyNames);
  const std::string strategy = to_string(config.strategy);
  if (!strategy_entry(config.strategy).reallocates &&
      config.thrust_range() == ThrustRange::kBipolar) {
    fail(mixer.path_of("strategy"), "'" + strategy + "' for a wheeled vehicle",
         reallocating_strategies() + " (budgets assume motors that only push)");
  }

  MapReader budgets = mixer.map("legacy_budget");
  config.legacy_budgets.throttle = budgets.number("throttle", 0.60, 0.0, 1.0);
  config.legacy_budgets.roll_pitch = budgets.number("roll_pitch", 0.25, 0.0, 1.0);
  config.legacy_budgets.yaw = budgets.number("yaw", 0.15, 0.0, 1.0);
  const double sum =
      config.legacy_budgets.throttle + config.legacy_budgets.roll_pitch + config.legacy_budgets.yaw;
  if (sum > 1.0 + kBudgetSumTolerance) {
    std::ostringstream found;
    found << "throttle + roll_pitch + yaw = " << sum;
    fail(mixer.path_of("legacy_budget"), found.str(), "a sum of at most 1 (full power)");
  }
  budgets.finish();

  MapReader prioritized = mixer.map("prioritized");
  // A named mode, or the continuous limits (its corners are the names).
  config.airmode = limits_of(prioritized.choice("airmode", Airmode::kOff, kAirmodeNames));
  MapReader limits = prioritized.map("airmode_limits");
  const AirmodeLimits asked{limits.number("roll_pitch", 0.0, 0.0, 1.0),
                            limits.number("yaw", 0.0, 0.0, 1.0)};
  limits.finish();
  if (prioritized.has("airmode_limits")) {
    if (prioritized.has("airmode")) {
      fail(prioritized.path_of("airmode_limits"), "both airmode and airmode_limits",
           "one of the two: a named mode, or the limits (off is {roll_pitch: 0, yaw: 0}, "
           "roll_pitch {1, 0}, roll_pitch_yaw {1, 1})");
    }
    config.airmode = asked;
  }
  config.yaw_headroom = prioritized.number("yaw_headroom", 0.15, 0.0, 1.0);
  config.tie_tolerance = prioritized.number("tie_tolerance", config.tie_tolerance, 0.0, 0.1);
  prioritized.finish();

  MapReader optimal = mixer.map("optimal");
  MapReader weights = optimal.map("weights");
  for (int a = 0; a < kNumAxes; ++a) {
    config.optimal.weights[a] = weights.number(kAxisNames[static_cast<std::size_t>(a)],
                                               config.optimal.weights[a], 0.0, 1e3);
  }
  weights.finish();
  config.optimal.max_iterations = static_cast<int>(optimal.number("max_iterations", 100, 1, 1000));
  optimal.finish();
  read_failed_motors(mixer, config);
  mixer.finish();
}

}  // namespace motormix::config::reading
