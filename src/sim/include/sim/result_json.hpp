#pragma once
// A simulated flight's results as JSON, written once for `motormix sim
// --json` and the scorecard (test/sim/scorecard.cpp, which renders SIM.md
// from it), so the two cannot name or compute a metric differently.

#include "sim/lockstep.hpp"

#include <motormix/config/config.hpp>

#include <nlohmann/json.hpp>

#include <vector>

namespace motormix::sim {

// What went wrong in flight: crashed (with why and when), attitude, yaw and
// altitude errors, saturation; speed and yaw-rate errors for ground
// vehicles. What the scorecard keeps per cell (the worst over its seeds).
nlohmann::json flight_errors_json(const SimResult& r, bool wheeled);

// The whole run: flight_errors_json and everything else SimResult holds.
nlohmann::json result_json(const SimResult& r, bool wheeled);

// Each failure: which motor, when, what kind, whether something outside
// motormix reported it, and what motormix's own detector made of it.
nlohmann::json failures_json(const std::vector<FailureOutcome>& outcomes,
                             const config::Config& config, bool undetected);

// What motormix's own detector declared: working motors stopped, and every
// declaration (live: as its status reported them).
void add_detections(nlohmann::json& j, const SimResult& r, const config::Config& config);

// A quad that lost one motor: the spin and thrusts it settled at before
// touchdown, next to the relaxed-hover equilibrium of the same vehicle.
void add_spin(nlohmann::json& j, const SimResult& r, const config::Config& config,
              const std::vector<FailureOutcome>& outcomes);

}  // namespace motormix::sim
