// What motormix's failure detector adds to a control cycle: two control
// loops on the octo X (8 motors), one without failure_detection and one with
// every source (telemetry, rates, outputs), fed the same inputs each cycle
// (a setpoint, a pid, one ESC reading per motor, an attitude sample) and
// cycled alternately, so a noisy spell of the machine lands on both. Prints
// the per-cycle percentiles of each and of their difference as a markdown
// table.
//
//   detector_cost SOURCE_DIR [--cycles N] [--passes N]

#include "loop/control_loop.hpp"

#include <motormix/config/build_mixer.hpp>
#include <motormix/config/load_config.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace {

using motormix::loop::AttitudeSample;
using motormix::loop::ControlLoop;
using motormix::loop::EscTelemetrySample;
using motormix::loop::PidSample;
using motormix::loop::SetpointSample;

constexpr std::int64_t kPeriodUs = 2500;
constexpr std::int64_t kEpochUs = 1'700'000'000'000'000;

double percentile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(p * static_cast<double>(v.size() - 1))];
}

// Feeds one cycle's inputs (armed, hovering, gently rolling) and returns
// the time cycle() took, in nanoseconds.
double one_cycle(ControlLoop& loop, std::int64_t k) {
  const std::int64_t now = kEpochUs + k * kPeriodUs;
  const double phase = static_cast<double>(k) * 0.01;
  loop.on_setpoint(SetpointSample{now, k < 10 ? 0.0 : 0.55, 0.0, k >= 5}, now, now);
  loop.on_pid(PidSample{now, 0.1 * std::sin(phase), 0.05 * std::cos(phase), 0.0}, now, now);
  EscTelemetrySample esc;
  esc.utime = now;
  esc.count = 8;
  for (int i = 0; i < 8; ++i) {
    esc.readings[static_cast<std::size_t>(i)] = {i + 1, 9000.0 + 10.0 * i, NAN, 8.0, 15.5, 40.0,
                                                 NAN};
  }
  loop.on_esc_telemetry(esc, now, now);
  loop.on_attitude(AttitudeSample{now, {1, 0, 0, 0}, {0.01 * std::sin(phase), 0.0, 0.0}}, now, now);
  const auto start = std::chrono::steady_clock::now();
  const auto& r = loop.cycle(now);
  const auto end = std::chrono::steady_clock::now();
  if (r.mix.output.size() == 0) std::abort();  // keeps the call
  return static_cast<double>(
      std::chrono::duration_cast<std::chrono::nanoseconds>(end - start).count());
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: detector_cost SOURCE_DIR [--cycles N] [--passes N]\n");
    return 2;
  }
  const std::string config_path = std::string(argv[1]) + "/config/octo_x.yaml";
  std::int64_t cycles = 200000;
  int passes = 3;
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--cycles") cycles = std::atoll(argv[i + 1]);
    if (flag == "--passes") passes = std::atoi(argv[i + 1]);
  }
  const std::vector<std::string> common = {"inputs.arm_max_throttle=1", "output.spool_up_s=0"};
  std::vector<std::string> with = common;
  with.push_back("failure_detection.sources=[telemetry, rates, outputs]");
  const motormix::config::Config c_off = motormix::config::load_config_file(config_path, common);
  const motormix::config::Config c_on = motormix::config::load_config_file(config_path, with);
  std::printf(
      "| pass | cycles | without detector p50 / p99 ns | with detector p50 / p99 ns "
      "| added p50 / p99 ns | declared |\n|---|---|---|---|---|---|\n");
  for (int pass = 1; pass <= passes; ++pass) {
    ControlLoop off(c_off, motormix::config::build_mixer(c_off));
    ControlLoop on(c_on, motormix::config::build_mixer(c_on));
    std::vector<double> t_off, t_on;
    t_off.reserve(static_cast<std::size_t>(cycles));
    t_on.reserve(static_cast<std::size_t>(cycles));
    for (std::int64_t k = 0; k < cycles; ++k) {
      // Alternate which loop goes first, so neither always finds the cache warm.
      double a, b;
      if (k % 2 == 0) {
        a = one_cycle(off, k);
        b = one_cycle(on, k);
      } else {
        b = one_cycle(on, k);
        a = one_cycle(off, k);
      }
      t_off.push_back(a);
      t_on.push_back(b);
    }
    std::printf("| %d | %lld | %.0f / %.0f | %.0f / %.0f | %.0f / %.0f | %s |\n", pass,
                static_cast<long long>(cycles), percentile(t_off, 0.5), percentile(t_off, 0.99),
                percentile(t_on, 0.5), percentile(t_on, 0.99),
                percentile(t_on, 0.5) - percentile(t_off, 0.5),
                percentile(t_on, 0.99) - percentile(t_off, 0.99),
                on.last().detection.failed != 0 ? "yes (bench invalid)" : "none");
  }
  return 0;
}
