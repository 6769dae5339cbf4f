#pragma once

#include <cstdlib>
#include <string>
// Shared helpers for the tests: named tolerances and config loading.

#include "test_paths.hpp"

#include <motormix/config/build_mixer.hpp>
#include <motormix/config/load_config.hpp>

#include <cstdint>
#include <string>

namespace motormix::test {

// Same arithmetic in the same order: results agree to the last bits.
inline constexpr double kExact = 1e-12;
// Float32 message fields against double references (PWM microseconds).
inline constexpr double kFloatPwmUs = 1e-3;
// Float32 normalized commands against double references.
inline constexpr double kFloatCommand = 1e-6;

// The control loop's clocks in its unit tests, in microseconds: one
// millisecond, and this host's wall clock, ahead of every utime used.
inline constexpr std::int64_t kMs = 1000;
inline constexpr std::int64_t kWall = 1'800'000'000'000'000;

inline std::string source_path(const std::string& relative) {
  return std::string(source_dir()) + "/" + relative;
}

inline config::Config team_quad_config() {
  return config::load_config_file(source_path("config/team_quad.yaml"));
}

// MOTORMIX_SIM_REDUCED=1 (set for the sanitizer build): the closed-loop
// simulation tests fly a reduced grid, the first and the last motor on one
// seed (and fewer vehicles and strategies), so their assertions, the right
// motor named among them, run under the sanitizers within minutes.
inline bool reduced_sim_grid() {
  const char* v = std::getenv("MOTORMIX_SIM_REDUCED");
  return v != nullptr && std::string(v) == "1";
}
inline bool in_sim_grid(int motor, int motors) {
  return !reduced_sim_grid() || motor == 0 || motor == motors - 1;
}
inline int sim_grid_seeds(int full) { return reduced_sim_grid() ? 1 : full; }

}  // namespace motormix::test
