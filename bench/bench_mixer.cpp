// Per-cycle cost of the mixing pipeline (allocation + output stage), per
// strategy and vehicle, on a fixed set of seeded demands that includes
// saturating ones.

#include <motormix/config/build_mixer.hpp>
#include <motormix/config/load_config.hpp>

#include "reference/px4_sequential_desaturation.hpp"

#include <benchmark/benchmark.h>

#include <cmath>
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

// Demands a hovering vehicle sees most of the time: small torques (within
// 0.1) around mid thrust (0.4..0.6); the linear mix fits on every vehicle.
std::vector<motormix::AxisVector> unsaturated_demands() {
  std::mt19937 rng(43);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<motormix::AxisVector> d(1024);
  for (auto& v : d) v << 0.1 * unit(rng), 0.1 * unit(rng), 0.1 * unit(rng), 0.5 + 0.1 * unit(rng);
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

// The allocation step alone, as the prioritized strategy's cost is compared
// with other stacks': saturating demands in every axis (roll, pitch, yaw in
// -1..1, thrust 0..1) on the normalized matrix of PX4's normalization.
void allocate_yaml(benchmark::State& state, const std::string& yaml,
                   const std::vector<motormix::AxisVector>& inputs = demands()) {
  const auto config = motormix::config::load_config_text(yaml, "bench");
  const motormix::Mixer built = motormix::config::build_mixer(config);
  const motormix::Allocator& allocator = built.allocator();
  motormix::MotorVector commands;
  std::size_t i = 0;
  for (auto _ : state) {
    auto result = allocator.allocate(inputs[i++ & 1023U], commands);
    benchmark::DoNotOptimize(result);
    benchmark::DoNotOptimize(commands.data());
  }
}

void BM_Allocate(benchmark::State& state, const char* preset, const char* mixer) {
  allocate_yaml(state, "geometry: {preset: " + std::string(preset) +
                           ", normalization: px4}\nmixer: " + mixer + "\n");
}
#define MOTORMIX_ALLOCATE_BENCH(preset, label, mixer) \
  BENCHMARK_CAPTURE(BM_Allocate, preset##_##label, #preset, mixer)
#define MOTORMIX_ALLOCATE_PRESET(preset)                                                      \
  MOTORMIX_ALLOCATE_BENCH(preset, prioritized_off,                                            \
                          "{strategy: prioritized, prioritized: {airmode: off}}");            \
  MOTORMIX_ALLOCATE_BENCH(preset, prioritized_rp,                                             \
                          "{strategy: prioritized, prioritized: {airmode: roll_pitch}}");     \
  MOTORMIX_ALLOCATE_BENCH(preset, prioritized_rpy,                                            \
                          "{strategy: prioritized, prioritized: {airmode: roll_pitch_yaw}}"); \
  MOTORMIX_ALLOCATE_BENCH(preset, clip, "{strategy: clip}");                                  \
  MOTORMIX_ALLOCATE_BENCH(preset, shift, "{strategy: shift}");                                \
  MOTORMIX_ALLOCATE_BENCH(preset, optimal, "{strategy: optimal}")
// The PX4-style baselines (test/reference, float as PX4 runs it, clip and
// allocated-control report included) on the same matrix and demands: PX4's
// current rule (desaturation ignores entries below 0.2) and its older one
// (below float epsilon).
template <typename Px4>
void px4_loop(benchmark::State& state, const char* preset, motormix::reference::Px4Airmode mode,
              const std::vector<motormix::AxisVector>& demand_set) {
  const auto config = motormix::config::load_config_text(
      std::string("geometry: {preset: ") + preset + ", normalization: px4}\n", "bench");
  Px4 px4(config.mixing, mode);
  std::vector<std::array<float, 4>> inputs;
  for (const auto& d : demand_set) {
    inputs.push_back({static_cast<float>(d[0]), static_cast<float>(d[1]), static_cast<float>(d[2]),
                      static_cast<float>(d[3])});
  }
  std::size_t i = 0;
  for (auto _ : state) {
    px4.allocate(inputs[i++ & 1023U]);
    benchmark::DoNotOptimize(px4.allocated().data());
  }
}
void BM_Px4Baseline(benchmark::State& state, const char* preset,
                    motormix::reference::Px4Airmode mode) {
  px4_loop<motormix::reference::Px4SequentialDesaturation>(state, preset, mode, demands());
}
void BM_Px4EpsilonBaseline(benchmark::State& state, const char* preset,
                           motormix::reference::Px4Airmode mode) {
  px4_loop<motormix::reference::Px4EpsilonSequentialDesaturation>(state, preset, mode, demands());
}
#define MOTORMIX_PX4_CAPTURE(bench, preset)                                                    \
  BENCHMARK_CAPTURE(bench, preset##_off, #preset, motormix::reference::Px4Airmode::kDisabled); \
  BENCHMARK_CAPTURE(bench, preset##_rp, #preset, motormix::reference::Px4Airmode::kRollPitch); \
  BENCHMARK_CAPTURE(bench, preset##_rpy, #preset, motormix::reference::Px4Airmode::kRollPitchYaw)
#define MOTORMIX_PX4_PRESET(preset)             \
  MOTORMIX_PX4_CAPTURE(BM_Px4Baseline, preset); \
  MOTORMIX_PX4_CAPTURE(BM_Px4EpsilonBaseline, preset)
// The floor: a bare fixed-size matrix-vector product of the same size
// (motors x 4 times 4), what a mixer without limits or report would cost.
template <int N>
void BM_BareProduct(benchmark::State& state) {
  Eigen::Matrix<double, N, 4> m = Eigen::Matrix<double, N, 4>::Random();
  const auto inputs = demands();
  Eigen::Matrix<double, N, 1> u;
  std::size_t i = 0;
  for (auto _ : state) {
    u.noalias() = m * inputs[i++ & 1023U];
    benchmark::DoNotOptimize(u.data());
  }
}
BENCHMARK_TEMPLATE(BM_BareProduct, 4);
BENCHMARK_TEMPLATE(BM_BareProduct, 6);
BENCHMARK_TEMPLATE(BM_BareProduct, 8);

MOTORMIX_PX4_PRESET(quad_x);
MOTORMIX_PX4_PRESET(hexa_x);
MOTORMIX_PX4_PRESET(octo_x);

MOTORMIX_ALLOCATE_PRESET(quad_x);
MOTORMIX_ALLOCATE_PRESET(hexa_x);
MOTORMIX_ALLOCATE_PRESET(octo_x);

// Unsaturated demands: `prioritized` returns the linear mix after one check,
// where sequential desaturation runs its whole sequence regardless.
void BM_Unsaturated(benchmark::State& state, const char* preset, const char* airmode) {
  allocate_yaml(
      state,
      "geometry: {preset: " + std::string(preset) +
          ", normalization: px4}\nmixer: {strategy: prioritized, prioritized: {airmode: " +
          airmode + "}}\n",
      unsaturated_demands());
}
void BM_Px4Unsaturated(benchmark::State& state, const char* preset,
                       motormix::reference::Px4Airmode mode) {
  px4_loop<motormix::reference::Px4SequentialDesaturation>(state, preset, mode,
                                                           unsaturated_demands());
}
#define MOTORMIX_UNSATURATED_PRESET(preset)                                               \
  BENCHMARK_CAPTURE(BM_Unsaturated, preset##_prioritized_off, #preset, "off");            \
  BENCHMARK_CAPTURE(BM_Unsaturated, preset##_prioritized_rp, #preset, "roll_pitch");      \
  BENCHMARK_CAPTURE(BM_Unsaturated, preset##_prioritized_rpy, #preset, "roll_pitch_yaw"); \
  BENCHMARK_CAPTURE(BM_Px4Unsaturated, preset##_off, #preset,                             \
                    motormix::reference::Px4Airmode::kDisabled);                          \
  BENCHMARK_CAPTURE(BM_Px4Unsaturated, preset##_rp, #preset,                              \
                    motormix::reference::Px4Airmode::kRollPitch);                         \
  BENCHMARK_CAPTURE(BM_Px4Unsaturated, preset##_rpy, #preset,                             \
                    motormix::reference::Px4Airmode::kRollPitchYaw)
MOTORMIX_UNSATURATED_PRESET(quad_x);
MOTORMIX_UNSATURATED_PRESET(hexa_x);
MOTORMIX_UNSATURATED_PRESET(octo_x);

// Scaling: the allocation step against motor count, 4 to 16, for every
// strategy, on a ring of rotors with alternating spin (a quad X at 4).
std::string ring_yaml(int n) {
  std::string y = "geometry:\n  normalization: px4\n  rotors:\n";
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * 3.141592653589793 * (i + 0.5) / n;
    y += "    - {position: [" + std::to_string(std::cos(a)) + ", " + std::to_string(std::sin(a)) +
         "], spin: " + (i % 2 ? "cw" : "ccw") + "}\n";
  }
  return y;
}

void BM_Scaling(benchmark::State& state, const std::string& strategy, int motors) {
  allocate_yaml(state, ring_yaml(motors) + "mixer: {strategy: " + strategy + "}\n");
}

const bool kScalingRegistered = [] {
  for (const char* strategy : {"clip", "shift", "prioritized", "optimal"}) {
    for (int n = 4; n <= 16; n += 2) {
      benchmark::RegisterBenchmark(
          ("BM_Scaling/" + std::string(strategy) + "/" + std::to_string(n)).c_str(),
          [strategy, n](benchmark::State& st) { BM_Scaling(st, strategy, n); });
    }
  }
  return true;
}();
BENCHMARK_TEMPLATE(BM_BareProduct, 10);
BENCHMARK_TEMPLATE(BM_BareProduct, 12);
BENCHMARK_TEMPLATE(BM_BareProduct, 14);
BENCHMARK_TEMPLATE(BM_BareProduct, 16);

}  // namespace

BENCHMARK_MAIN();
