// Each allocation strategy against its reference: sequential desaturation
// against the published PX4 unit tests, shift against the differential-drive
// document, budget against the team quad document's "possible improvement".

#include "test_support.hpp"

#include <motormix/allocation/clip_allocator.hpp>
#include <motormix/allocation/optimal_allocator.hpp>
#include <motormix/allocation/shift_allocator.hpp>

#include <gtest/gtest.h>

#include <random>

namespace motormix::test {
namespace {

// Sums of a few exact binary fractions: equality up to rounding.
constexpr double kAllocation = 1e-9;

using Motors4 = std::array<double, 4>;

// The quad of PX4's ControlAllocationSequentialDesaturationTest
// (src/lib/control_allocation/control_allocation/): rotors at (+-1, +-1)
// numbered clockwise from front right, moment ratio +1/-1, no roll/pitch/yaw
// normalization, thrust normalized.
std::string px4_test_quad(const std::string& airmode) {
  return "geometry:\n"
         "  rotors:\n"
         "    - {position: [1, 1], spin: ccw, torque_ratio: 1}\n"
         "    - {position: [-1, 1], spin: cw, torque_ratio: 1}\n"
         "    - {position: [-1, -1], spin: ccw, torque_ratio: 1}\n"
         "    - {position: [1, -1], spin: cw, torque_ratio: 1}\n"
         "  normalization: none\n"
         "mixer: {strategy: prioritized, prioritized: {airmode: " +
         airmode + ", yaw_headroom: 0.15}}\n";
}

class Px4SequentialDesaturation : public ::testing::Test {
 protected:
  void use(const std::string& airmode) {
    config_ = config::load_config_text(px4_test_quad(airmode), "px4.yaml");
    mixer_ = std::make_unique<Mixer>(config::build_mixer(config_));
  }
  // PX4's allocate(roll, pitch, yaw, thrust) with thrust positive up. The
  // allocator is called directly: some published cases command more than
  // full thrust, which the Mixer would clamp first.
  Motors4 allocate(double roll, double pitch, double yaw, double thrust) {
    MotorVector u;
    mixer_->allocator().allocate(AxisVector(roll, pitch, yaw, thrust), u);
    return {u[0], u[1], u[2], u[3]};
  }
  void expect(double roll, double pitch, double yaw, double thrust, Motors4 want) {
    const Motors4 got = allocate(roll, pitch, yaw, thrust);
    for (std::size_t i = 0; i < 4; ++i) {
      EXPECT_NEAR(got[i], want[i], kAllocation) << "motor " << i << " for (" << roll << ", "
                                                << pitch << ", " << yaw << ", " << thrust << ")";
    }
  }
  config::Config config_;
  std::unique_ptr<Mixer> mixer_;
};

// TEST_F(..., Zero), CollectiveThrust, AirmodeDisabledThrustZ
TEST_F(Px4SequentialDesaturation, ZeroAndCollectiveThrust) {
  use("off");
  expect(0, 0, 0, 0, {0, 0, 0, 0});
  for (int k = 0; k <= 10; ++k) {
    const double t = k / 10.0;
    expect(0, 0, 0, t, {t, t, t, t});
  }
}

// TEST_F(..., RollPitchYaw)
TEST_F(Px4SequentialDesaturation, RollPitchYawAtHalfThrust) {
  use("off");
  expect(1, 0, 0, .5, {.25, .25, .75, .75});
  expect(-1, 0, 0, .5, {.75, .75, .25, .25});
  expect(0, 1, 0, .5, {.75, .25, .25, .75});
  expect(0, -1, 0, .5, {.25, .75, .75, .25});
  expect(0, 0, 1, .5, {.75, .25, .75, .25});
  expect(0, 0, -1, .5, {.25, .75, .25, .75});
}

// TEST_F(..., RollPitchYawFullThrust): yaw keeps 30 % authority at full thrust.
TEST_F(Px4SequentialDesaturation, RollPitchYawAtFullThrust) {
  use("off");
  expect(1, 0, 0, 1, {.5, .5, 1, 1});
  expect(-1, 0, 0, 1, {1, 1, .5, .5});
  expect(0, 1, 0, 1, {1, .5, .5, 1});
  expect(0, -1, 0, 1, {.5, 1, 1, .5});
  expect(0, 0, 1, 1, {1, .7, 1, .7});
  expect(0, 0, -1, 1, {.7, 1, .7, 1});
}

// TEST_F(..., RollPitchYawZeroThrust): without airmode nothing is allocated.
TEST_F(Px4SequentialDesaturation, ZeroThrustWithoutAirmode) {
  use("off");
  for (const auto& d : {AxisVector(1, 0, 0, 0), AxisVector(-1, 0, 0, 0), AxisVector(0, 1, 0, 0),
                        AxisVector(0, -1, 0, 0), AxisVector(0, 0, 1, 0), AxisVector(0, 0, -1, 0)}) {
    expect(d[0], d[1], d[2], d[3], {0, 0, 0, 0});
  }
}

// TEST_F(..., RollPitchYawZeroThrustAirmodeRP)
TEST_F(Px4SequentialDesaturation, ZeroThrustAirmodeRollPitch) {
  use("roll_pitch");
  expect(1, 0, 0, 0, {0, 0, .5, .5});
  expect(-1, 0, 0, 0, {.5, .5, 0, 0});
  expect(0, 1, 0, 0, {.5, 0, 0, .5});
  expect(0, -1, 0, 0, {0, .5, .5, 0});
  expect(0, 0, 1, 0, {0, 0, 0, 0});
  expect(0, 0, -1, 0, {0, 0, 0, 0});
}

// TEST_F(..., RollPitchYawZeroThrustAirmodeRPY), AirmodeLimOneAndYawMatchRPY
TEST_F(Px4SequentialDesaturation, ZeroThrustAirmodeRollPitchYaw) {
  use("roll_pitch_yaw");
  expect(1, 0, 0, 0, {0, 0, .5, .5});
  expect(-1, 0, 0, 0, {.5, .5, 0, 0});
  expect(0, 1, 0, 0, {.5, 0, 0, .5});
  expect(0, -1, 0, 0, {0, .5, .5, 0});
  expect(0, 0, 1, 0, {.5, 0, .5, 0});
  expect(0, 0, -1, 0, {0, .5, 0, .5});
  expect(1, 1, -1, 0, {0, 0, 0, 1});
}

// TEST_F(..., AirmodeDisabledThrustAndYaw), ...ThrustAndSaturatedYaw,
// ...ThrustAndPitch, ...ReducedThrustAndYaw, ...ReducedThrustAndPitch
TEST_F(Px4SequentialDesaturation, AirmodeDisabledThrustWithYawAndPitch) {
  use("off");
  const double t = 0.75;
  expect(0, 0, 0.02, t, {t + .005, t - .005, t + .005, t - .005});
  expect(0, 0, 1, t, {t + .25, t - .25, t + .25, t - .25});
  expect(0, 0.1, 0, t, {t + .025, t - .025, t - .025, t + .025});
  expect(0, 0, 1, 3.2, {1, 1 - 2 * 0.15, 1, 1 - 2 * 0.15});
  expect(0, 2, 0, 3, {1, 0, 0, 1});
}

// The differential-drive document's two saturating turns, with its numbers
// (wheel radius 5, track 10, max wheel speed 1: forward 5, turn 1 at full
// command). move(1.0, 0.9) -> wheels (-0.8, 1.0); move(-1.0, 0.9) -> (-1.0, 0.8).
TEST(ShiftStrategy, Seed002DesaturationKeepsTheTurn) {
  const auto c = config::load_config_text(
      "geometry: {differential_drive: {wheel_radius: 5, track_width: 10, max_wheel_speed: 1}}\n"
      "mixer: {strategy: shift}\n",
      "drive.yaml");
  const Mixer mixer = config::build_mixer(c);
  MixerOutput out;
  mixer.mix(AxisVector(0, 0, 0.9, 1.0 / 5.0), out);
  EXPECT_NEAR(out.command[0], -0.8, kAllocation);
  EXPECT_NEAR(out.command[1], 1.0, kAllocation);
  EXPECT_NEAR(out.command[1] - out.command[0], 1.8, kAllocation);  // the turn is kept
  EXPECT_NEAR(out.allocation.unallocated[index(Axis::kYaw)], 0.0, kAllocation);
  EXPECT_GT(std::abs(out.allocation.unallocated[index(Axis::kThrust)]), 0.05);  // speed gave way
  mixer.mix(AxisVector(0, 0, 0.9, -1.0 / 5.0), out);
  EXPECT_NEAR(out.command[0], -1.0, kAllocation);
  EXPECT_NEAR(out.command[1], 0.8, kAllocation);
  // A spread wider than the range: the turn itself is scaled, and says so.
  mixer.mix(AxisVector(0, 0, 1.0, 0.5), out);
  EXPECT_NEAR(out.command[0], -1.0, kAllocation);
  EXPECT_NEAR(out.command[1], 1.0, kAllocation);
}

TEST(ShiftStrategy, WheelsIgnoreRollAndPitch) {
  const auto c = config::load_config_text("geometry: {preset: differential_drive}\n", "w.yaml");
  const Mixer mixer = config::build_mixer(c);
  MixerOutput with;
  MixerOutput without;
  mixer.mix(AxisVector(0.5, -0.5, 0.2, 0.3), with);
  mixer.mix(AxisVector(0.0, 0.0, 0.2, 0.3), without);
  EXPECT_EQ(with.command, without.command);
  EXPECT_EQ(with.allocation.axis_limited, 0);  // not commanded, so not "undelivered"
  EXPECT_EQ(with.allocation.unallocated[index(Axis::kRoll)], 0.0);
}

TEST(ShiftStrategy, AircraftKeepTorquesAndGiveUpThrust) {
  const auto c =
      config::load_config_text("geometry: {preset: quad_x}\nmixer: {strategy: shift}\n", "q.yaml");
  const Mixer mixer = config::build_mixer(c);
  MixerOutput out;
  mixer.mix(AxisVector(0.3, 0.0, 0.0, 0.95), out);  // 0.95 +- 0.3 overflows by 0.25
  EXPECT_NEAR(out.command.maxCoeff(), 1.0, kAllocation);
  EXPECT_NEAR(out.allocation.unallocated[index(Axis::kRoll)], 0.0, kAllocation);
  EXPECT_NEAR(out.allocation.unallocated[index(Axis::kThrust)], 0.25, kAllocation);
}

// Motors that share thrust alike take shift's one-pass path; a thrust column
// one part in 10^9 off uniform takes the general one. Both must deliver the
// same commands, on saturating and fitting demands, aircraft and wheels.
TEST(ShiftStrategy, OnePassPathAgreesWithTheGeneralOne) {
  constexpr double kPaths = 1e-6;  // the perturbation's effect, with margin
  // The one-pass path reports from its scalars, not from E u: against the
  // report recomputed from its commands it may differ by rounding only.
  constexpr double kReportRounding = 1e-12;
  for (const char* geometry : {"preset: quad_x", "preset: octo_x",
                               "differential_drive: {wheel_radius: 5, track_width: 10, "
                               "max_wheel_speed: 1}"}) {
    const auto c = config::load_config_text(std::string("geometry: {") + geometry + "}\n", "s");
    const CommandRange range{c.mixing.col(index(Axis::kThrust)).minCoeff() > 0.0 &&
                                     std::string(geometry).find("differential") == std::string::npos
                                 ? 0.0
                                 : -1.0,
                             1.0};
    MixingMatrix nudged = c.mixing;
    nudged(0, index(Axis::kThrust)) *= 1.0 + 1e-9;
    const MixingBasis basis(c.mixing);
    const ShiftAllocator alike(basis, range);
    const ShiftAllocator general(MixingBasis(nudged), range);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    MotorVector a;
    MotorVector b;
    for (int k = 0; k < 20000; ++k) {
      const double scale = k % 2 == 0 ? 1.0 : 0.2;  // saturating, and mostly fitting
      const AxisVector d(scale * unit(rng), scale * unit(rng), scale * unit(rng),
                         range.lower < 0.0 ? unit(rng) : 0.5 + 0.5 * scale * unit(rng));
      const AllocationResult ra = alike.allocate(d, a);
      const AllocationResult rb = general.allocate(d, b);
      ASSERT_LE((a - b).cwiseAbs().maxCoeff(), kPaths)
          << geometry << " demand " << d.transpose() << "\n one pass " << a.transpose()
          << "\n general  " << b.transpose();
      ASSERT_LE((ra.unallocated - rb.unallocated).cwiseAbs().maxCoeff(), kPaths) << geometry;
      const AllocationResult recomputed =
          describe_allocation(basis.effectiveness, d, a, range, basis.controlled);
      ASSERT_LE((ra.unallocated - recomputed.unallocated).cwiseAbs().maxCoeff(), kReportRounding)
          << geometry << " demand " << d.transpose();
      ASSERT_EQ(ra.axis_limited, recomputed.axis_limited) << geometry;
      ASSERT_EQ(ra.saturated_upper, recomputed.saturated_upper) << geometry;
      ASSERT_EQ(ra.saturated_lower, recomputed.saturated_lower) << geometry;
      ASSERT_GE(a.minCoeff(), range.lower);
      ASSERT_LE(a.maxCoeff(), range.upper);
    }
  }
}

// A mix that fits the range is returned as it is, to the last bit (the
// same commands `clip` gives, which only clamps), and a spread that fits but
// sits too high or too low is moved by one shift, the same for every motor:
// no scaling creeps in by rounding. (A form that rescaled on every cycle
// rounded here.)
TEST(ShiftStrategy, AMixThatFitsIsKeptExactly) {
  // Commands minus the linear mix: one number, to the rounding of a sum of
  // unit terms (the test's row-major product against the kernel's columns).
  constexpr double kOneShiftRounding = 1e-15;
  for (const char* preset : {"quad_x", "hexa_x", "octo_x"}) {
    const auto c =
        config::load_config_text(std::string("geometry: {preset: ") + preset + "}\n", "s.yaml");
    const CommandRange range{0.0, 1.0};
    const ShiftAllocator shift(MixingBasis(c.mixing), range);
    const ClipAllocator clip(MixingBasis(c.mixing), range);
    std::mt19937 rng(21);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    MotorVector shifted;
    MotorVector clipped;
    int inside = 0;
    int moved = 0;
    for (int k = 0; k < 20000; ++k) {
      const AxisVector d(0.2 * unit(rng), 0.2 * unit(rng), 0.2 * unit(rng), 0.5 + 0.6 * unit(rng));
      shift.allocate(d, shifted);
      clip.allocate(d, clipped);
      const MotorVector linear = c.mixing * d;
      if (linear.maxCoeff() - linear.minCoeff() > 0.9) continue;
      if (linear.minCoeff() > 1e-9 && linear.maxCoeff() < 1.0 - 1e-9) {
        ++inside;
        for (Eigen::Index i = 0; i < shifted.size(); ++i) {
          ASSERT_EQ(shifted[i], clipped[i])
              << preset << " motor " << i << " demand " << d.transpose();
        }
      } else {
        ++moved;
        // One shift for all: each command minus the clip-free mix is the same
        // number (the clip's mix is the linear one where it is in range).
        const MotorVector step = shifted - linear;
        ASSERT_LE(step.maxCoeff() - step.minCoeff(), kOneShiftRounding)
            << preset << " " << d.transpose();
      }
    }
    EXPECT_GT(inside, 5000) << preset;
    EXPECT_GT(moved, 2000) << preset;
  }
}

// A torque spread wider than the range is shrunk to exactly the range and
// shifted into it: both ends are used. (Rounding once left the shift out on
// about half of such demands, leaving the range half unused.)
TEST(ShiftStrategy, AWideSpreadFillsTheRange) {
  const auto c = config::load_config_text("geometry: {preset: quad_x}\n", "q.yaml");
  const ShiftAllocator shift(MixingBasis(c.mixing), CommandRange{0.0, 1.0});
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  MotorVector u;
  int wide = 0;
  for (int k = 0; k < 20000; ++k) {
    const AxisVector d(unit(rng), unit(rng), unit(rng), (unit(rng) + 1.0) / 2.0);
    const MotorVector linear = c.mixing * d;
    if (linear.maxCoeff() - linear.minCoeff() <= 1.0) continue;
    ++wide;
    shift.allocate(d, u);
    ASSERT_NEAR(u.minCoeff(), 0.0, kAllocation) << d.transpose();
    ASSERT_NEAR(u.maxCoeff(), 1.0, kAllocation) << d.transpose();
  }
  EXPECT_GT(wide, 10000);
}

// A vehicle whose thrust column is not uniform (rotors off the symmetric
// positions, one stronger) takes shift's general path. Its promise: thrust
// gives way first (the torques are delivered exactly whenever some shift
// fits), and otherwise the torques are scaled down together, keeping their
// direction, by the least amount after which a shift fits: a slightly larger
// share would not fit with any shift. Checked by brute force over shifts.
TEST(ShiftStrategy, UnevenVehicleKeepsTheTorqueDirectionAtTheLargestScale) {
  const auto c = config::load_config_text(
      "geometry:\n  rotors:\n"
      "    - {position: [0.9, 1.1], spin: ccw, thrust_coefficient: 1.3}\n"
      "    - {position: [-1.2, -0.8], spin: ccw}\n"
      "    - {position: [1.0, -1.0], spin: cw}\n"
      "    - {position: [-0.7, 1.2], spin: cw}\n",
      "uneven.yaml");
  const MixingBasis basis(c.mixing);
  const auto thrust = c.mixing.col(index(Axis::kThrust));
  ASSERT_GT(thrust.maxCoeff() - thrust.minCoeff(), 0.05) << "the general path is not exercised";
  const CommandRange range{0.0, 1.0};
  const ShiftAllocator shift(basis, range);
  // Torques scaled alike: the same share of each demanded torque delivered.
  constexpr double kSameShare = 1e-9;
  // How much larger a share is tried to show that no shift fits it.
  constexpr double kLargerShare = 1e-6;
  const MotorVector direction = thrust / thrust.maxCoeff();
  // Whether some shift k along the thrust column puts every motor in range
  // (the interval of k, from each motor).
  const auto some_shift_fits = [&](const MotorVector& u) {
    double lo = -1e300;
    double hi = 1e300;
    for (Eigen::Index i = 0; i < u.size(); ++i) {
      lo = std::max(lo, (range.lower - u[i]) / direction[i]);
      hi = std::min(hi, (range.upper - u[i]) / direction[i]);
    }
    return lo <= hi;
  };
  std::mt19937 rng(77);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  MotorVector u;
  int scaled = 0;
  for (int k = 0; k < 20000; ++k) {
    const AxisVector d(unit(rng), unit(rng), unit(rng), (unit(rng) + 1.0) / 2.0);
    const AllocationResult r = shift.allocate(d, u);
    ASSERT_GE(u.minCoeff(), range.lower);
    ASSERT_LE(u.maxCoeff(), range.upper);
    // The share of the torques delivered, from the largest demanded torque.
    int largest = 0;
    for (int a = 1; a < 3; ++a) {
      if (std::abs(d[a]) > std::abs(d[largest])) largest = a;
    }
    const double share = 1.0 - r.unallocated[largest] / d[largest];
    for (int a = 0; a < 3; ++a) {
      ASSERT_NEAR(r.unallocated[a], (1.0 - share) * d[a], kSameShare)
          << "axis " << a << " demand " << d.transpose();
    }
    const MotorVector base = thrust * d[index(Axis::kThrust)];
    const MotorVector torque_part = c.mixing * d - base;
    if (some_shift_fits(base + torque_part)) {
      ASSERT_NEAR(share, 1.0, kSameShare) << "a shift fits, yet torque was given up";
    } else {
      ++scaled;
      ASSERT_LT(share, 1.0);
      ASSERT_FALSE(some_shift_fits(base + (share + kLargerShare) * torque_part))
          << "a larger share fits: " << share << " demand " << d.transpose();
    }
  }
  EXPECT_GT(scaled, 2000);
}

// The team quad document's "possible improvement": a negative contribution
// is taken from the power a motor has, down to zero.
TEST(BudgetStrategy, NegativeContributionsComeFromAvailablePower) {
  const auto c = config::load_config_text(
      "geometry: {preset: team_quad}\nmixer: {strategy: budget}\n", "b.yaml");
  const Mixer mixer = config::build_mixer(c);
  MixerOutput out;
  // The worked example at zero throttle: nothing to take from, as before.
  mixer.mix(AxisVector(0.5, 0, 0, 0), out);
  EXPECT_NEAR(out.command[0], 0.125, kAllocation);
  EXPECT_NEAR(out.command[1], 0.0, kAllocation);
  // At half throttle (0.3 of full power) the right motors give 0.125.
  mixer.mix(AxisVector(0.5, 0, 0, 0.5), out);
  EXPECT_NEAR(out.command[0], 0.425, kAllocation);  // FL
  EXPECT_NEAR(out.command[1], 0.175, kAllocation);  // FR
  EXPECT_NEAR(out.command[2], 0.425, kAllocation);  // RL
  EXPECT_NEAR(out.command[3], 0.175, kAllocation);  // RR
  EXPECT_NEAR(out.allocation.unallocated[index(Axis::kRoll)], 0.0, kAllocation);
  // Roll and pitch beyond their share are scaled together, keeping direction.
  mixer.mix(AxisVector(1, 0.5, 0, 0.5), out);
  const double rl = out.command[2] - 0.3;  // roll and pitch both positive on RL
  EXPECT_NEAR(rl, 0.25, kAllocation);
}

TEST(ClipStrategy, ClipsAndReports) {
  const auto c =
      config::load_config_text("geometry: {preset: quad_x}\nmixer: {strategy: clip}\n", "c.yaml");
  const Mixer mixer = config::build_mixer(c);
  MixerOutput out;
  mixer.mix(AxisVector(0.5, 0, 0, 0.9), out);
  EXPECT_NEAR(out.command.maxCoeff(), 1.0, kAllocation);
  EXPECT_NEAR(out.command.minCoeff(), 0.4, kAllocation);
  EXPECT_NE(out.allocation.saturated_upper, 0U);
  EXPECT_TRUE(out.allocation.axis_limited & bit(Axis::kRoll));
}

TEST(OptimalStrategy, DeliversWhatIsAttainableAndBeatsTheOthersWhenNot) {
  const std::string geometry = "geometry: {preset: hexa_x}\n";
  const auto optimal_cfg = config::load_config_text(geometry + "mixer: {strategy: optimal}\n", "o");
  const auto prio_cfg =
      config::load_config_text(geometry + "mixer: {strategy: prioritized}\n", "p");
  const Mixer optimal = config::build_mixer(optimal_cfg);
  const Mixer prioritized = config::build_mixer(prio_cfg);
  MixerOutput a;
  MixerOutput b;
  optimal.mix(AxisVector(0.1, -0.1, 0.05, 0.5), a);
  EXPECT_LT(a.allocation.unallocated.cwiseAbs().maxCoeff(), 1e-6);
  // Full roll and yaw at high thrust: not attainable.
  const AxisVector hard(1.0, 0.0, 1.0, 0.9);
  optimal.mix(hard, a);
  prioritized.mix(hard, b);
  const EffectivenessMatrix e = effectiveness_of(optimal_cfg.mixing);
  const AxisVector w = optimal_cfg.optimal.weights;
  EXPECT_LE(weighted_error(e, w, hard, a.command), weighted_error(e, w, hard, b.command) + 1e-6);
  for (int i = 0; i < a.command.size(); ++i) {
    EXPECT_GE(a.command[i], 0.0);
    EXPECT_LE(a.command[i], 1.0);
  }
}

TEST(Strategies, LegacyAndBudgetAreRefusedForWheels) {
  EXPECT_THROW(config::load_config_text(
                   "geometry: {preset: differential_drive}\nmixer: {strategy: budget}\n", "w"),
               config::ConfigError);
}

}  // namespace
}  // namespace motormix::test
