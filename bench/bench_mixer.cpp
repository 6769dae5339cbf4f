// Per-cycle cost of the mixing pipeline (allocation + output stage).

#include "config/build_mixer.hpp"
#include "config/load_config.hpp"

#include <benchmark/benchmark.h>

#include <random>

namespace {

void BM_MixTeamQuad(benchmark::State& state) {
  const auto config = motormix::config::load_config_file(MOTORMIX_CONFIG_DIR "/team_quad.yaml");
  const motormix::Mixer mixer = motormix::config::build_mixer(config);
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<motormix::AxisVector> demands(1024);
  for (auto& d : demands) d << unit(rng), unit(rng), unit(rng), (unit(rng) + 1.0) / 2.0;
  motormix::MixerOutput out;
  std::size_t i = 0;
  for (auto _ : state) {
    mixer.mix(demands[i++ & 1023U], out);
    benchmark::DoNotOptimize(out.output.data());
  }
}
BENCHMARK(BM_MixTeamQuad);

}  // namespace

BENCHMARK_MAIN();
