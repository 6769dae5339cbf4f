// Limited airmode (mixer.prioritized.airmode_limits): its corners are the
// named modes bit for bit, against the oracle table the named modes wrote
// before the limits existed (airmode_oracle_table.hpp); between them the
// thrust rises no further than its cap in the sequence, more of a limit
// delivers more of its axes where the bottom of the range takes them, and
// no command ever leaves the range. Read and imported from PX4's
// MC_AIRMODE_LIM / MC_AIRMODE_YLIM.

#include "airmode_oracle_table.hpp"
#include "test_paths.hpp"
#include "test_support.hpp"

#include <motormix/allocation/prioritized_allocator.hpp>
#include <motormix/config/config_error.hpp>
#include <motormix/config/load_config.hpp>
#include <motormix/config/px4_import.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <memory>
#include <random>

namespace motormix {
namespace {

constexpr double kRangeTolerance = 1e-9;  // commands within the range, rounding aside
constexpr double kRiseTolerance = 1e-9;   // the sequence's rise against its cap

std::string oracle_path() { return test::source_path("test/data/airmode_oracle.txt"); }

TEST(AirmodeLimits, TheCornersAreTheNamedModesBitForBit) {
  std::vector<AxisVector> demands;
  const auto lines = test::airmode_oracle_lines(
      [](const MixingBasis& b, CommandRange r, Airmode mode) {
        return std::make_unique<PrioritizedAllocator>(b, r, limits_of(mode), 0.15);
      },
      &demands);
  if (std::getenv("MOTORMIX_UPDATE_ORACLE") != nullptr) {
    std::ofstream out(oracle_path());
    for (const std::string& l : lines) out << l << "\n";
    GTEST_SKIP() << "wrote " << oracle_path();
  }
  std::ifstream in(oracle_path());
  ASSERT_TRUE(in) << oracle_path();
  std::vector<std::string> expected;
  for (std::string l; std::getline(in, l);) expected.push_back(l);
  ASSERT_EQ(expected.size(), lines.size());
  for (std::size_t i = 0; i < lines.size(); ++i)
    ASSERT_EQ(lines[i], expected[i]) << "line " << i + 1 << ", demand " << demands[i].transpose();
}

struct Vehicle {
  config::Config config;
  MixingBasis basis;
  explicit Vehicle(const char* preset)
      : config(
            config::load_config_text(std::string("geometry: {preset: ") + preset + "}\n", preset)),
        basis(config.mixing) {}
};

double roll_pitch_error(const AllocationResult& r) {
  return std::hypot(r.unallocated[index(Axis::kRoll)], r.unallocated[index(Axis::kPitch)]);
}

// At zero throttle a roll/pitch demand pushes motors under the bottom:
// off gives roll and pitch up, roll_pitch raises the thrust for them. A
// limit between delivers between, and the rise stays within its share of
// the range (the quad's thrust column is 1/4 on every motor: a rise of a
// share s of the range is a thrust step of 4 s).
TEST(AirmodeLimits, MoreOfTheLimitDeliversMoreRollAndPitchAtTheBottom) {
  const Vehicle v("quad_x");
  const CommandRange range{0.0, 1.0};
  const double column = v.basis.mixing.col(index(Axis::kThrust)).cwiseAbs().maxCoeff();
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  MotorVector u;
  int strictly_between = 0;
  for (int k = 0; k < 2000; ++k) {
    AxisVector d;
    d << 0.5 * unit(rng), 0.5 * unit(rng), 0.0, 0.02 * (unit(rng) + 1.0);
    double previous = std::numeric_limits<double>::infinity();
    for (double lim : {0.0, 0.05, 0.2, 0.5, 1.0}) {
      const PrioritizedAllocator a(v.basis, range, AirmodeLimits{lim, 0.0}, 0.15);
      const AllocationResult r = a.allocate(d, u);
      const double error = roll_pitch_error(r);
      EXPECT_LE(error, previous + kRiseTolerance) << "k " << k << " limit " << lim;
      // Delivered thrust above the demand: the rise, in thrust units.
      const double rise = -r.unallocated[index(Axis::kThrust)];
      if (lim < 1.0) {
        EXPECT_LE(rise, lim * (range.upper - range.lower) / column + kRiseTolerance)
            << "k " << k << " limit " << lim;
      }
      for (Eigen::Index i = 0; i < u.size(); ++i) {
        EXPECT_GE(u[i], range.lower - kRangeTolerance);
        EXPECT_LE(u[i], range.upper + kRangeTolerance);
      }
      if (lim == 0.2 && error < previous - 1e-6) ++strictly_between;
      previous = error;
    }
  }
  EXPECT_GT(strictly_between, 100);  // the limit matters, not only its ends
}

// Yaw the same way: at zero throttle, with roll and pitch small, a yaw
// demand is delivered more fully the larger its limit.
TEST(AirmodeLimits, MoreOfTheYawLimitDeliversMoreYawAtTheBottom) {
  const Vehicle v("hexa_x");
  const CommandRange range{0.0, 1.0};
  MotorVector u;
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  int improved = 0;
  for (int k = 0; k < 2000; ++k) {
    AxisVector d;
    d << 0.02 * unit(rng), 0.02 * unit(rng), 0.6 * unit(rng), 0.02 * (unit(rng) + 1.0);
    double previous = std::numeric_limits<double>::infinity();
    for (double ylim : {0.0, 0.1, 0.3, 0.6}) {
      const PrioritizedAllocator a(v.basis, range, AirmodeLimits{1.0, ylim}, 0.15);
      const AllocationResult r = a.allocate(d, u);
      const double yaw_error = std::abs(r.unallocated[index(Axis::kYaw)]);
      EXPECT_LE(yaw_error, previous + kRiseTolerance) << "k " << k << " yaw limit " << ylim;
      if (ylim == 0.3 && yaw_error < previous - 1e-6) ++improved;
      previous = yaw_error;
    }
  }
  EXPECT_GT(improved, 100);
}

// Any limits, any preset with yaw, any demand: never out of range, never
// NaN; zero demand gives zero command.
TEST(AirmodeLimits, NeverOutOfRangeOnAnyVehicleOrLimit) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_real_distribution<double> share(0.0, 1.0);
  MotorVector u;
  for (const char* preset : {"quad_x", "quad_plus", "hexa_x", "hexa_plus", "octo_x", "y6"}) {
    const Vehicle v(preset);
    const CommandRange range{0.0, 1.0};
    for (int l = 0; l < 20; ++l) {
      const AirmodeLimits limits{share(rng), share(rng)};
      const PrioritizedAllocator a(v.basis, range, limits, 0.15);
      a.allocate(AxisVector::Zero(), u);
      EXPECT_TRUE(u.isZero(0.0)) << preset;
      for (int k = 0; k < 500; ++k) {
        const double size = k % 2 == 0 ? 0.3 : 3.0;
        AxisVector d;
        d << size * unit(rng), size * unit(rng), size * unit(rng), 0.5 + 0.7 * unit(rng);
        a.allocate(d, u);
        for (Eigen::Index i = 0; i < u.size(); ++i) {
          ASSERT_TRUE(u[i] >= range.lower - kRangeTolerance &&
                      u[i] <= range.upper + kRangeTolerance)
              << preset << " limits " << limits.roll_pitch << ", " << limits.yaw << " motor " << i
              << " " << u[i];
        }
      }
    }
  }
}

TEST(AirmodeLimits, ReadFromTheConfigurationWithItsErrorsNamed) {
  const auto load = [](const std::string& prioritized) {
    return config::load_config_text(
        "geometry: {preset: hexa_x}\nmixer: {strategy: prioritized, prioritized: " + prioritized +
            "}\n",
        "t");
  };
  const config::Config c = load("{airmode_limits: {roll_pitch: 0.3, yaw: 0.1}}");
  EXPECT_EQ(c.airmode.roll_pitch, 0.3);
  EXPECT_EQ(c.airmode.yaw, 0.1);
  EXPECT_EQ(named_airmode(load("{airmode: roll_pitch}").airmode), Airmode::kRollPitch);
  EXPECT_EQ(named_airmode(load("{airmode_limits: {roll_pitch: 1}}").airmode), Airmode::kRollPitch);
  try {
    load("{airmode: off, airmode_limits: {roll_pitch: 0.2}}");
    FAIL() << "both accepted";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("mixer.prioritized.airmode_limits"), std::string::npos)
        << e.what();
  }
  try {
    load("{airmode_limits: {yaw: 1.5}}");
    FAIL() << "1.5 accepted";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("mixer.prioritized.airmode_limits.yaw"), std::string::npos)
        << e.what();
  }
}

TEST(AirmodeLimits, ImportedFromPx4sLimitedAirmode) {
  config::Px4Parameters p;
  p.format = "params";
  p.values["CA_ROTOR_COUNT"] = 4;
  const double xy[4][2] = {{0.15, 0.25}, {-0.15, -0.19}, {0.15, -0.25}, {-0.15, 0.19}};
  for (int i = 0; i < 4; ++i) {
    const std::string r = "CA_ROTOR" + std::to_string(i);
    p.values[r + "_PX"] = xy[i][0];
    p.values[r + "_PY"] = xy[i][1];
    p.values[r + "_KM"] = i < 2 ? 0.05 : -0.05;
  }
  p.values["MC_AIRMODE"] = 1;  // superseded by the limits
  p.values["MC_AIRMODE_LIM"] = 0.35;
  p.values["MC_AIRMODE_YLIM"] = 0;
  const config::Px4Import imported = config::import_px4(p, "test");
  const config::Config c = config::load_config_text(imported.yaml, "imported");
  EXPECT_EQ(c.airmode.roll_pitch, 0.35);
  EXPECT_EQ(c.airmode.yaw, 0.0);
  EXPECT_NE(imported.yaml.find("MC_AIRMODE_LIM 0.35"), std::string::npos) << imported.yaml;
  for (const std::string& n : imported.not_mapped)
    EXPECT_EQ(n.find("MC_AIRMODE"), std::string::npos) << n;
}

}  // namespace
}  // namespace motormix
