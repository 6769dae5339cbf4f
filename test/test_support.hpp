#pragma once

#include <cstdlib>
#include <string>
// Shared helpers for the tests: named tolerances and config loading.

#include "test_paths.hpp"

#include <motormix/config/build_mixer.hpp>
#include <motormix/config/load_config.hpp>

#include <cstdint>
#include <cstdio>
#include <random>
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

// The first seed of a closed-loop campaign: drawn fresh on every run, so that
// a campaign never settles on seeds it was tuned on, and printed once so that
// a failure can be replayed with MOTORMIX_SIM_SEED=N (which also pins it).
// Campaigns take seeds base, base + 1, ... (up to 10^6 beyond it).
inline std::uint64_t campaign_seed_base() {
  static const std::uint64_t base = [] {
    std::uint64_t b = 0;
    if (const char* v = std::getenv("MOTORMIX_SIM_SEED"); v != nullptr && *v != '\0') {
      b = std::strtoull(v, nullptr, 10);
    } else {
      std::random_device device;
      b = 1'000'000 + (static_cast<std::uint64_t>(device()) % 1'000'000'000ULL);
    }
    std::printf("closed-loop campaign seeds from %llu (replay: MOTORMIX_SIM_SEED=%llu)\n",
                static_cast<unsigned long long>(b), static_cast<unsigned long long>(b));
    std::fflush(stdout);
    return b;
  }();
  return base;
}

}  // namespace motormix::test
