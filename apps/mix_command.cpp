// motormix mix: one set of demands through the configured mixer, printed
// (or as JSON), with a failed motor, a battery voltage or the output stage.
#include "commands.hpp"

#include <motormix/config/build_mixer.hpp>
#include <motormix/config/load_config.hpp>

#include <nlohmann/json.hpp>

#include <cmath>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>
#include <vector>

namespace motormix::app {

namespace {

bool check_range(const char* name, double value, double lo, double hi) {
  if (std::isfinite(value) && value >= lo && value <= hi) return true;
  std::cerr << "motormix mix: --" << name << " " << value << " is outside " << lo << ".." << hi
            << "\n";
  return false;
}

std::vector<int> motors_in(MotorMask mask, int motors) {
  std::vector<int> out;
  for (int i = 0; i < motors; ++i) {
    if ((mask >> i) & 1U) out.push_back(i);
  }
  return out;
}

}  // namespace

int mix(const MixCommand& cmd) {
  const auto config = load_vehicle(cmd.common, "mix");
  if (!config) return kExitUsage;
  const double throttle_low = thrust_floor(config->thrust_range());
  if (!check_range("throttle", cmd.throttle, throttle_low, 1.0) ||
      !check_range("roll", cmd.roll, -1.0, 1.0) || !check_range("pitch", cmd.pitch, -1.0, 1.0) ||
      !check_range("yaw", cmd.yaw, -1.0, 1.0)) {
    return kExitUsage;
  }
  // --failed goes through the loader's own checks, as mixer.failed_motors.
  std::optional<config::Config> failed_config;
  MotorMask failed = config->failed_motors;
  if (!cmd.failed.empty()) {
    CommonOptions with_failed = cmd.common;
    std::string list;
    for (const std::string& f : cmd.failed) list += (list.empty() ? "" : ",") + f;
    with_failed.overrides.push_back("mixer.failed_motors=[" + list + "]");
    failed_config = load_vehicle(with_failed, "mix");
    if (!failed_config) return kExitUsage;
    failed |= failed_config->failed_motors;
  }
  double gain = 1.0;
  if (cmd.battery_voltage) {
    if (!config->battery) {
      std::cerr << "motormix mix: --battery-voltage needs a 'battery' section in the configuration"
                << "\n";
      return kExitUsage;
    }
    if (!check_range("battery-voltage", *cmd.battery_voltage, config->battery->min_v,
                     config->battery->max_v)) {
      return kExitUsage;
    }
    gain = battery_gain(*config->battery, *cmd.battery_voltage);
  }
  if (cmd.parse_only) return kExitOk;
  const Mixer mixer = config::build_mixer(*config);
  const int n = mixer.motors();
  const auto names_of = [&](MotorMask mask) {
    std::vector<std::string> names;
    for (int i : motors_in(mask, n))
      names.push_back(config->motor_names()[static_cast<std::size_t>(i)]);
    return names;
  };
  MixerOutput out;
  const auto evaluate = [&](double roll, double pitch, double yaw, double throttle) {
    AxisVector demand;
    demand << roll, pitch, yaw, throttle * gain;
    const MixStatus status = mixer.mix(demand, out, 0.0, failed);
    nlohmann::json j;
    j["motors"] = config->motor_names();
    j["strategy"] = config::to_string(config->strategy);
    j["command"] = std::vector<double>(out.command.data(), out.command.data() + n);
    j["pwm"] = std::vector<double>(out.output.data(), out.output.data() + n);
    j["direction"] = std::vector<int>(out.direction.begin(), out.direction.begin() + n);
    j["saturated_motors"] = {{"upper", motors_in(out.allocation.saturated_upper, n)},
                             {"lower", motors_in(out.allocation.saturated_lower, n)}};
    nlohmann::json unallocated;
    for (int a = 0; a < kNumAxes; ++a) unallocated[kAxisNames[a]] = out.allocation.unallocated[a];
    j["unallocated"] = unallocated;
    j["demand_clamped"] = status == MixStatus::kDemandClamped;
    j["thrust_gain"] = gain;
    j["failed_motors"] = names_of(out.failed);
    j["failure_handling"] = to_string(out.failure);
    nlohmann::json held;
    nlohmann::json authority;
    for (int a = 0; a < kNumAxes; ++a) {
      held[kAxisNames[a]] = ((out.held >> a) & 1U) != 0;
      authority[kAxisNames[a]] = out.authority[a];
    }
    j["axes_held"] = held;
    j["authority"] = authority;
    j["iterations"] = out.allocation.iterations;
    return j;
  };

  if (cmd.batch) {
    // One demand per input line, "roll pitch yaw throttle"; one JSON object
    // per line out. A line that is not four numbers in range gets an
    // {"error": ...} line, and the exit status says so at the end.
    int bad = 0;
    long line_number = 0;
    for (std::string line; std::getline(std::cin, line);) {
      ++line_number;
      if (line.empty() || line[0] == '#') continue;
      std::istringstream in(line);
      double v[4];
      bool ok = static_cast<bool>(in >> v[0] >> v[1] >> v[2] >> v[3]);
      std::string rest;
      ok = ok && !(in >> rest);
      ok = ok && std::isfinite(v[0]) && std::abs(v[0]) <= 1.0 && std::isfinite(v[1]) &&
           std::abs(v[1]) <= 1.0 && std::isfinite(v[2]) && std::abs(v[2]) <= 1.0 &&
           std::isfinite(v[3]) && v[3] >= throttle_low && v[3] <= 1.0;
      if (!ok) {
        ++bad;
        std::cout << nlohmann::json{{"error", "line " + std::to_string(line_number) +
                                                  ": expected 'roll pitch yaw throttle' in range"}}
                         .dump()
                  << "\n";
        continue;
      }
      std::cout << evaluate(v[0], v[1], v[2], v[3]).dump() << "\n";
    }
    return bad == 0 ? kExitOk : kExitUsage;
  }
  const nlohmann::json j = evaluate(cmd.roll, cmd.pitch, cmd.yaw, cmd.throttle);
  if (cmd.json) {
    std::cout << j.dump() << "\n";
    return kExitOk;
  }
  std::cout << std::left << std::setw(8) << "motor" << std::setw(12) << "command"
            << "pwm\n";
  for (int i = 0; i < n; ++i) {
    std::cout << std::setw(8) << config->motor_names()[static_cast<std::size_t>(i)] << std::setw(12)
              << out.command[i] << out.output[i]
              << (((out.failed >> i) & 1U) ? "  failed (stopped)" : "") << "\n";
  }
  if (cmd.battery_voltage)
    std::cout << "thrust gain " << gain << " at " << *cmd.battery_voltage << " V\n";
  if (out.failed != 0) {
    std::cout << "failure handling: " << to_string(out.failure) << "; axes held:";
    for (int a = 0; a < kNumAxes; ++a) {
      if ((out.held >> a) & 1U) std::cout << " " << kAxisNames[a];
    }
    if (out.held == 0) std::cout << " none promised";
    std::cout << "\n";
  }
  if (out.allocation.axis_limited != 0) {
    std::cout << "not delivered (demanded minus produced):";
    for (int a = 0; a < kNumAxes; ++a) {
      if ((out.allocation.axis_limited >> a) & 1U) {
        std::cout << " " << kAxisNames[a] << " " << out.allocation.unallocated[a];
      }
    }
    std::cout << "\n";
  }
  return kExitOk;
}

}  // namespace motormix::app
