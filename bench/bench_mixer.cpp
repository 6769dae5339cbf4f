// Per-cycle cost of the mixing pipeline (allocation + output stage), per
// strategy and vehicle, on a fixed set of seeded demands that includes
// saturating ones.

#include <motormix/config/build_mixer.hpp>
#include <motormix/config/load_config.hpp>

#include <benchmark/benchmark.h>

#include <random>
#include <string>
#include <vector>

namespace {

std::vector<motormix::AxisVector> demands() {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<motormix::AxisVector> d(1024);
  for (auto& v : d) v << unit(rng), unit(rng), unit(rng), (unit(rng) + 1.0) / 2.0;
  return d;
}

void mix_loop(benchmark::State& state, const std::string& yaml) {
  const auto config = motormix::config::load_config_text(yaml, "bench.yaml");
  const motormix::Mixer mixer = motormix::config::build_mixer(config);
  const auto inputs = demands();
  motormix::MixerOutput out;
  std::size_t i = 0;
  for (auto _ : state) {
    mixer.mix(inputs[i++ & 1023U], out, 0.0025);
    benchmark::DoNotOptimize(out.output.data());
  }
}

void BM_TeamQuadLegacy(benchmark::State& state) {
  mix_loop(state, "geometry: {preset: team_quad}\nmixer: {strategy: legacy_budget}\n");
}
BENCHMARK(BM_TeamQuadLegacy);

void BM_QuadX(benchmark::State& state, const char* strategy) {
  mix_loop(state, std::string("geometry: {preset: quad_x}\nmixer: {strategy: ") + strategy + "}\n");
}
BENCHMARK_CAPTURE(BM_QuadX, clip, "clip");
BENCHMARK_CAPTURE(BM_QuadX, shift, "shift");
BENCHMARK_CAPTURE(BM_QuadX, prioritized, "prioritized");
BENCHMARK_CAPTURE(BM_QuadX, optimal, "optimal");

void BM_Octo(benchmark::State& state, const char* strategy) {
  mix_loop(state, std::string("geometry: {preset: octo_x}\nmixer: {strategy: ") + strategy + "}\n");
}
BENCHMARK_CAPTURE(BM_Octo, prioritized, "prioritized");
BENCHMARK_CAPTURE(BM_Octo, optimal, "optimal");

}  // namespace

BENCHMARK_MAIN();
