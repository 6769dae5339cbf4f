// Battery-voltage compensation: the gain law, the filter, and every way a
// voltage can be unusable.

#include "test_support.hpp"

#include <motormix/output/battery_compensation.hpp>

#include <gtest/gtest.h>

#include <cmath>

namespace motormix::test {
namespace {

// The gain is the power law itself: the same arithmetic, to the last bits.
constexpr double kGainExact = kExact;
// A first-order step response sampled at 1 kHz against its exponential.
constexpr double kFilterStep = 2e-3;

BatterySettings settings() {
  BatterySettings s;
  s.nominal_v = 16.8;
  s.exponent = 1.0;
  s.max_gain = 1.5;
  s.filter_hz = 2.0;
  s.timeout_s = 0.5;
  s.min_v = 8.4;
  s.max_v = 21.0;
  return s;
}

TEST(BatteryGain, PowerLawKeptBetweenOneAndMaxGain) {
  const BatterySettings s = settings();
  EXPECT_NEAR(battery_gain(s, 16.8), 1.0, kGainExact);
  EXPECT_NEAR(battery_gain(s, 14.0), 16.8 / 14.0, kGainExact);
  EXPECT_NEAR(battery_gain(s, 17.5), 1.0, kGainExact) << "a pack above nominal is not turned down";
  EXPECT_NEAR(battery_gain(s, 9.0), 1.5, kGainExact) << "capped at max_gain";
  BatterySettings squared = s;
  squared.exponent = 2.0;
  EXPECT_NEAR(battery_gain(squared, 14.0), std::pow(16.8 / 14.0, 2.0), kGainExact);
  EXPECT_EQ(battery_gain(s, std::nan("")), 1.0);
  EXPECT_EQ(battery_gain(s, 0.0), 1.0);
  EXPECT_EQ(battery_gain(s, -3.0), 1.0);
}

TEST(BatteryFilter, FirstOrderStepResponse) {
  BatteryCompensation b(settings());
  ASSERT_EQ(b.add(16.0, 0), BatteryCompensation::Reading::kAccepted);
  EXPECT_EQ(b.filtered_v(), 16.0) << "the first reading initializes the filter";
  // A step to 14 V sampled at 1 kHz for one time constant 1/(2 pi f).
  const double tau_s = 1.0 / (2.0 * M_PI * 2.0);
  const int steps = static_cast<int>(std::lround(tau_s * 1000.0));
  for (int k = 1; k <= steps; ++k) b.add(14.0, k * kMs);
  const double expected = 14.0 + 2.0 * std::exp(-static_cast<double>(steps) / 1000.0 / tau_s);
  EXPECT_NEAR(b.filtered_v(), expected, kFilterStep);
  EXPECT_EQ(b.state(steps * kMs), BatteryState::kOk);
  EXPECT_NEAR(b.gain(steps * kMs), 16.8 / b.filtered_v(), kGainExact);
}

TEST(BatteryFilter, StaleMissingAndImplausibleMeanNoCompensation) {
  BatteryCompensation b(settings());
  EXPECT_EQ(b.state(0), BatteryState::kMissing);
  EXPECT_EQ(b.gain(0), 1.0);
  b.add(14.0, 0);
  EXPECT_EQ(b.state(500 * kMs), BatteryState::kOk);
  EXPECT_EQ(b.state(501 * kMs), BatteryState::kStale);
  EXPECT_EQ(b.gain(501 * kMs), 1.0);
  // An implausible reading is refused and says so; the filter keeps its value.
  EXPECT_EQ(b.add(3.0, 510 * kMs), BatteryCompensation::Reading::kImplausible);
  EXPECT_EQ(b.state(510 * kMs), BatteryState::kImplausible);
  EXPECT_EQ(b.gain(510 * kMs), 1.0);
  EXPECT_EQ(b.add(std::nan(""), 511 * kMs), BatteryCompensation::Reading::kNonFinite);
  EXPECT_EQ(b.add(40.0, 512 * kMs), BatteryCompensation::Reading::kImplausible);
  EXPECT_EQ(b.filtered_v(), 14.0);
  // After a gap longer than the timeout the filter restarts from the new reading.
  EXPECT_EQ(b.add(15.0, 2000 * kMs), BatteryCompensation::Reading::kAccepted);
  EXPECT_EQ(b.filtered_v(), 15.0);
  EXPECT_EQ(b.state(2000 * kMs), BatteryState::kOk);
}

}  // namespace
}  // namespace motormix::test
