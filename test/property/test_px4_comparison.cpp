// prioritized against a PX4-style sequential desaturation (test/reference,
// the same algorithm in double so that float noise is not mistaken for a
// difference of priorities), on the same normalized matrix (normalization:
// px4) and seeded random demands that saturate in every axis. Compared
// lexicographically in priority order: the delivered roll/pitch error first
// (Euclidean), then thrust, then yaw, with the tolerance the allocator uses.
// motormix must be at least as good on every demand; the shares of identical
// outputs, ties and demands motormix delivers better are printed (the
// README's table comes from them).

#include "reference/px4_sequential_desaturation.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>

namespace motormix::test {
namespace {

// Errors closer than this are ties: the allocator's own tolerance.
constexpr double kTie = kDeliveredTolerance;

long cases() {
  const char* env = std::getenv("MOTORMIX_PROPERTY_CASES");
  return env ? std::max(1L, std::atol(env)) : 100000L;
}

struct Errors {
  double roll_pitch, thrust, yaw;
};

Errors errors_of(const AxisVector& demand, const AxisVector& produced) {
  const AxisVector e = demand - produced;
  return {std::hypot(e[0], e[1]), std::abs(e[3]), std::abs(e[2])};
}

// -1: a better than b in priority order, 0: tie, +1: worse.
int compare(const Errors& a, const Errors& b) {
  for (const auto& [x, y] : {std::pair{a.roll_pitch, b.roll_pitch}, std::pair{a.thrust, b.thrust},
                             std::pair{a.yaw, b.yaw}}) {
    if (x < y - kTie) return -1;
    if (x > y + kTie) return 1;
  }
  return 0;
}

struct Tally {
  long same = 0, better = 0, worse = 0, identical_outputs = 0;
  long better_linear_fits = 0;  // better where the plain linear mix was in range
};

class Px4Comparison : public ::testing::TestWithParam<std::tuple<std::string, std::string>> {};

TEST_P(Px4Comparison, NeverWorseInPriorityOrder) {
  const auto& [preset, airmode] = GetParam();
  const config::Config c = config::load_config_text(
      "geometry: {preset: " + preset + ", normalization: px4}\nmixer: {strategy: prioritized, "
      "prioritized: {airmode: " + airmode + "}}\n",
      "px4-comparison");
  const Mixer mixer = config::build_mixer(c);
  const Allocator& ours = mixer.allocator();
  const EffectivenessMatrix e = effectiveness_of(c.mixing);
  reference::SequentialDesaturation<double> px4(
      c.mixing, airmode == "off"          ? reference::Px4Airmode::kDisabled
                : airmode == "roll_pitch" ? reference::Px4Airmode::kRollPitch
                                          : reference::Px4Airmode::kRollPitchYaw);
  std::mt19937_64 rng(std::hash<std::string>{}(preset + airmode) ^ 0x5eedULL);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Tally t;
  MotorVector u;
  long reported = 0;
  for (long k = 0; k < cases(); ++k) {
    const AxisVector d(unit(rng), unit(rng), unit(rng), 0.5 * (unit(rng) + 1.0));
    ours.allocate(d, u);
    px4.allocate({d[0], d[1], d[2], d[3]});
    AxisVector theirs;
    for (int a = 0; a < 4; ++a) theirs[a] = px4.allocated()[static_cast<std::size_t>(a)];
    const int order = compare(errors_of(d, e * u), errors_of(d, theirs));
    bool same_outputs = true;
    for (int i = 0; i < px4.motors(); ++i) same_outputs &= std::abs(u[i] - px4.actuator(i)) < 1e-9;
    t.identical_outputs += same_outputs;
    if (order < 0) {
      ++t.better;
      const MotorVector linear = c.mixing * d;
      t.better_linear_fits += linear.minCoeff() >= 0.0 && linear.maxCoeff() <= 1.0;
    }
    if (order == 0) ++t.same;
    if (order > 0) {
      ++t.worse;
      if (reported++ < 5) {
        const Errors a = errors_of(d, e * u), b = errors_of(d, theirs);
        ADD_FAILURE() << preset << " airmode " << airmode << ": demand " << d.transpose()
                      << "\n  motormix errors rp " << a.roll_pitch << " thrust " << a.thrust
                      << " yaw " << a.yaw << "; px4 rp " << b.roll_pitch << " thrust " << b.thrust
                      << " yaw " << b.yaw;
      }
    }
  }
  const auto share = [](long part) { return 100.0 * static_cast<double>(part) / static_cast<double>(cases()); };
  std::printf("| %s | %s | %ld | %.2f %% | %.2f %% | %.2f %% (linear mix fits: %.2f %%) | %ld |\n",
              preset.c_str(), airmode.c_str(), cases(), share(t.identical_outputs), share(t.same),
              share(t.better), share(t.better_linear_fits), t.worse);
  EXPECT_EQ(t.worse, 0);
}

INSTANTIATE_TEST_SUITE_P(Presets, Px4Comparison,
                         ::testing::Combine(::testing::Values("quad_x", "hexa_x", "octo_x"),
                                            ::testing::Values("off", "roll_pitch",
                                                              "roll_pitch_yaw")));

}  // namespace
}  // namespace motormix::test
