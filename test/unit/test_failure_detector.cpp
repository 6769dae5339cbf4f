// The failure detector alone, on synthetic vehicles with time passed in:
// each source finds the motor that stopped and names it, and none of them
// fires on one bad sample, a sagging battery, a gust, a stale stream or
// while detection is not allowed.

#include <motormix/safety/failure_detector.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <random>

namespace motormix::test {
namespace {

constexpr std::int64_t kCycleUs = 2500;  // 400 Hz
constexpr double kHover = 0.5;
constexpr double kFullRpm = 10000.0;
// Detection latency the tests allow beyond each source's own persistence:
// one motor lag to show the loss, a sample period or two, the filters.
constexpr double kTelemetrySlackS = 0.08;
constexpr double kRatesSlackS = 0.12;

std::uint8_t bits(DetectorSources a) { return static_cast<std::uint8_t>(a); }

// A flat hexa X of 2 kg, 0.25 m arms: each rotor's torque at full thrust
// (15 N), alternating spins.
FailureDetectorSettings hexa(std::uint8_t sources) {
  FailureDetectorSettings s;
  s.motors = 6;
  s.sources = sources;
  s.silence_declares = true;  // as the configuration sets it for six rotors
  s.torque_per_thrust.setZero(3, 6);
  for (int i = 0; i < 6; ++i) {
    const double a = (30.0 + 60.0 * i) * 3.14159265358979 / 180.0;
    const Eigen::Vector3d p(0.25 * std::cos(a), 0.25 * std::sin(a), 0.0);
    const Eigen::Vector3d f(0, 0, -15.0);
    const double spin = i % 2 == 0 ? 1.0 : -1.0;
    s.torque_per_thrust.col(i) = p.cross(f) + spin * 0.016 * -f;
  }
  s.inertia_kgm2 = Eigen::Vector3d(0.03, 0.03, 0.05);
  s.rotational_drag = 0.002;
  s.min_residual_nm = 0.3 * s.torque_per_thrust.col(0).norm() * kHover;
  return s;
}

MotorVector hover(int motors) { return MotorVector::Constant(motors, kHover); }

// Feeds each motor's rpm for its actual thrust (sqrt law) to the detector.
void feed_telemetry(FailureDetector& d, const MotorVector& actual, double scale, std::int64_t t) {
  for (int i = 0; i < actual.size(); ++i) {
    d.on_telemetry(i, scale * kFullRpm * std::sqrt(std::max(actual[i], 0.0)), NAN, t);
  }
}

TEST(FailureDetector, TelemetryNamesTheMotorThatStopped) {
  FailureDetector d(hexa(bits(DetectorSources::kTelemetry)));
  MotorVector actual = hover(6);
  std::int64_t t = 0;
  const std::int64_t fail_at = 500'000;
  for (; t < 2'000'000 && d.detection().failed == 0; t += kCycleUs) {
    if (t >= fail_at) actual[2] *= std::exp(-kCycleUs / 1e6 / 0.05);  // spins down
    feed_telemetry(d, actual, 1.0, t);
    d.update(hover(6), 0, true, t);
  }
  ASSERT_EQ(d.detection().failed, MotorMask{1} << 2);
  EXPECT_EQ(d.detection().motor, 2);
  EXPECT_EQ(d.detection().source, DetectionSource::kTelemetry);
  const double latency = static_cast<double>(d.detection().at_us - fail_at) / 1e6;
  EXPECT_LE(latency, d.settings().telemetry_persist_s + kTelemetrySlackS);
}

TEST(FailureDetector, TelemetryNamesTheMotorThatLostItsProp) {
  // A thrown prop unloads its motor: at the same command it runs a third
  // faster. Too fast is as much a sign as too slow.
  FailureDetector d(hexa(bits(DetectorSources::kTelemetry)));
  MotorVector actual = hover(6);
  std::int64_t t = 0;
  const std::int64_t fail_at = 500'000;
  for (; t < 2'000'000 && d.detection().failed == 0; t += kCycleUs) {
    if (t >= fail_at)
      actual[4] =
          hover(6)[4] * (1.0 + 0.78 * (1.0 - std::exp(-static_cast<double>(t - fail_at) / 6e3)));
    feed_telemetry(d, actual, 1.0, t);
    d.update(hover(6), 0, true, t);
  }
  ASSERT_EQ(d.detection().failed, MotorMask{1} << 4);
  EXPECT_EQ(d.detection().source, DetectionSource::kTelemetry);
  const double latency = static_cast<double>(d.detection().at_us - fail_at) / 1e6;
  EXPECT_LE(latency, d.settings().telemetry_persist_s + kTelemetrySlackS);
}

// Motors whose lag acts on the rotor's speed, not its thrust (RotorPy, PX4's
// SIH, Gazebo): 50 ms both ways, as PX4's SIH quad X. Motor kThrown of a
// quad X loses its prop and, as those simulators play it, keeps following
// its command; the controller drives it to full and the motor across from
// it (kAcross) to zero, which then slows exactly as configured, its thrust
// falling twice as fast as its speed. That motor follows its command: it
// must never be declared. Returns what was declared within a second.
MotorMask speed_lag_quad_after_a_thrown_prop(std::uint8_t sources) {
  constexpr double kTau = 0.05;
  constexpr int kThrown = 0, kAcross = 1;  // quad X: m1 front right, m2 rear left
  FailureDetectorSettings s;
  s.motors = 4;
  s.sources = sources;
  s.time_constant_up_s = s.time_constant_down_s = kTau;
  FailureDetector d(s);
  MotorVector command = hover(4);
  std::array<double, 4> speed{};  // fraction of full speed, lagged
  for (int i = 0; i < 4; ++i) speed[static_cast<std::size_t>(i)] = std::sqrt(kHover);
  const std::int64_t fail_at = 500'000;
  const double alpha = 1.0 - std::exp(-kCycleUs / 1e6 / kTau);
  for (std::int64_t t = 0; t < 1'500'000; t += kCycleUs) {
    if (t >= fail_at) {
      command[kThrown] = 1.0;
      command[kAcross] = 0.0;
    }
    for (int i = 0; i < 4; ++i) {
      auto& w = speed[static_cast<std::size_t>(i)];
      w += (std::sqrt(command[i]) - w) * alpha;
      d.on_telemetry(i, kFullRpm * w, NAN, t);
    }
    d.update(command, 0, true, t);
  }
  return d.detection().failed & (MotorMask{1} << kAcross);
}

// The spin landing's first cycles on a light quad with fast motors (thrust
// to weight 10, hovering at a tenth of full thrust, 5 ms speed lag, as
// RotorPy's Hummingbird): motor 1 stopped and declared, the two beside it
// raised from hover to full, the one across from it dropped near idle. The
// ESCs' readings are fresh (bidirectional DShot, a simulator), the detector
// assumes the default 20 ms latency: the raised motors' readings run ahead
// of the thrust 10 ms ago. The motor across, slowing exactly as commanded,
// must not be declared. Returns what was declared beside motor 1.
MotorMask spin_up_with_fresh_readings() {
  constexpr double kTau = 0.005;
  constexpr double kLightHover = 0.1;
  constexpr int kStopped = 0, kAcross = 1;  // quad X: m1 front right, m2 rear left
  FailureDetectorSettings s;
  s.motors = 4;
  s.sources = bits(DetectorSources::kTelemetry);
  s.time_constant_up_s = s.time_constant_down_s = kTau;
  s.min_motor_thrust = 0.16 * kLightHover;  // the default for this vehicle
  FailureDetector d(s);
  MotorVector command = MotorVector::Constant(4, kLightHover);
  std::array<double, 4> speed{};
  for (auto& w : speed) w = std::sqrt(kLightHover);
  const std::int64_t fail_at = 500'000;
  const double alpha = 1.0 - std::exp(-kCycleUs / 1e6 / kTau);
  MotorMask excluded = 0;
  for (std::int64_t t = 0; t < 1'000'000; t += kCycleUs) {
    if (t >= fail_at) {
      excluded = MotorMask{1} << kStopped;
      command.setConstant(1.0);
      command[kStopped] = 0.0;
      command[kAcross] = 0.02;
    }
    for (int i = 0; i < 4; ++i) {
      auto& w = speed[static_cast<std::size_t>(i)];
      w += (std::sqrt(command[i]) - w) * alpha;
      d.on_telemetry(i, kFullRpm * w, NAN, t);
    }
    d.update(command, excluded, true, t);
  }
  return d.detection().failed & ~(MotorMask{1} << kStopped);
}

TEST(FailureDetector, TheMotorAcrossADeadOneIsNotDeclaredWhileTheOthersSpinUp) {
  EXPECT_EQ(spin_up_with_fresh_readings(), 0U)
      << "a motor slowing as commanded beside two spinning up was declared";
}

TEST(FailureDetector, AMotorSlowingAsItsSpeedLagHasItIsNotDeclared) {
  EXPECT_EQ(speed_lag_quad_after_a_thrown_prop(bits(DetectorSources::kTelemetry)), 0U)
      << "the motor across from a thrown prop, slowing as commanded, was declared";
}

// Every motor stepping from 0.15 of full thrust to 0.9 and back, each
// following with the motor lag; one ESC's readings arrive `late_us` after
// they were measured (a slow telemetry line). Returns what was declared.
MotorMask late_esc_through_steps(FailureDetectorSettings s, std::int64_t late_us) {
  FailureDetector d(s);
  MotorVector command = MotorVector::Constant(6, 0.15), actual = command;
  std::vector<MotorVector> past;  // actual, one entry per cycle
  for (std::int64_t t = 0; t < 2'000'000; t += kCycleUs) {
    if (t == 1'000'000) command.setConstant(0.9);
    if (t == 1'300'000) command.setConstant(0.15);
    for (int i = 0; i < 6; ++i) {
      const double tau = command[i] > actual[i] ? s.time_constant_up_s : s.time_constant_down_s;
      actual[i] += (command[i] - actual[i]) * (1.0 - std::exp(-kCycleUs / 1e6 / tau));
    }
    past.push_back(actual);
    MotorVector reported = actual;
    const auto back = static_cast<std::size_t>(late_us / kCycleUs);
    reported[3] = past[past.size() > back ? past.size() - 1 - back : 0][3];
    feed_telemetry(d, reported, 1.0, t);
    d.update(command, 0, true, t);
  }
  return d.detection().failed;
}

// Each motor's rpm for its thrust and its battery current (cube of the rpm
// for a whole prop); motor `weak` turns at the rpm of its command but draws
// `load` of that current (a broken tip).
void feed_rpm_and_current(FailureDetector& d, const MotorVector& actual, int weak, double load,
                          std::int64_t t) {
  for (int i = 0; i < actual.size(); ++i) {
    const double x = std::max(actual[i], 0.0);
    const double current = 20.0 * x * std::sqrt(x) * (i == weak ? load : 1.0);
    d.on_telemetry(i, kFullRpm * std::sqrt(x), current, t);
  }
}

TEST(FailureDetector, APropDrawingTooLittleForItsRpmIsNamed) {
  // A broken tip: rpm as its command asks (within rpm_high_ratio), current
  // at 40 % of a whole prop's at that rpm: named by its load.
  FailureDetector d(hexa(bits(DetectorSources::kTelemetry)));
  std::int64_t t = 0;
  const std::int64_t fail_at = 500'000;
  for (; t < 1'500'000 && d.detection().failed == 0; t += kCycleUs) {
    feed_rpm_and_current(d, hover(6), 4, t >= fail_at ? 0.4 : 1.0, t);
    d.update(hover(6), 0, true, t);
  }
  ASSERT_EQ(d.detection().failed, MotorMask{1} << 4);
  EXPECT_EQ(d.detection().source, DetectionSource::kTelemetry);
  const double latency = static_cast<double>(d.detection().at_us - fail_at) / 1e6;
  EXPECT_LE(latency, d.settings().telemetry_persist_s + kTelemetrySlackS);
}

// A suspicion held `persist` seconds is declared on the update that brings
// it there: each update with the evidence adds a cycle, the first at the
// evidence's own moment.
constexpr double kCycleS = kCycleUs / 1e6;
constexpr double kHalfCycleS = 0.5 * kCycleS;
double persisted_after(double persist) {
  return std::max(0.0, std::ceil(persist / kCycleS - 1e-9) - 1.0) * kCycleS;
}

// Each telemetry threshold holds on both sides: one motor (m1) reports,
// from a step at `onset`, a share of the rpm and of the current its command
// gives (steady hover, a reading every cycle; `rpm` false: current only),
// and is declared just past telemetry_persist_s when the share is a tenth
// beyond its threshold, never in 2 s when a tenth inside. Seconds from the
// step to the declaration, or -1.
double declared_after(const FailureDetectorSettings& s, double rpm_share, double current_share,
                      bool rpm = true, int reporting = 6) {
  FailureDetector d(s);
  const std::int64_t onset = 500'000;
  for (std::int64_t t = 0; t < onset + 2'000'000 && d.detection().failed == 0; t += kCycleUs) {
    for (int i = 0; i < reporting; ++i) {
      const bool weak = i == 0 && t >= onset;
      const double x = kHover;
      const double current = 20.0 * x * std::sqrt(x) * (weak ? current_share : 1.0);
      d.on_telemetry(i, rpm ? kFullRpm * std::sqrt(x) * (weak ? rpm_share : 1.0) : NAN, current, t);
    }
    d.update(hover(6), 0, true, t);
  }
  if (d.detection().failed == 0) return -1.0;
  EXPECT_EQ(d.detection().motor, 0);
  return static_cast<double>(d.detection().at_us - onset) / 1e6;
}

TEST(FailureDetector, EachTelemetryThresholdHoldsOnBothSides) {
  const FailureDetectorSettings s = hexa(bits(DetectorSources::kTelemetry));
  constexpr double kBand = 0.1;  // a tenth of the threshold either side
  // Declared on the update whose evidence, a cycle's worth each from the
  // step's own, adds up to telemetry_persist_s.
  const auto declared_in_time = [&](double after) {
    EXPECT_NEAR(after, persisted_after(s.telemetry_persist_s), kHalfCycleS);
  };
  // Too slow for its command: rpm_ratio. The current follows the rpm as a
  // whole prop's does (the cube), so the load check stays out of it.
  const auto slow = [&](double share) { return declared_after(s, share, share * share * share); };
  declared_in_time(slow(s.rpm_ratio * (1.0 - kBand)));
  EXPECT_LT(slow(s.rpm_ratio * (1.0 + kBand)), 0.0);
  // Too fast (a thrown prop): rpm_high_ratio.
  const auto fast = [&](double share) { return declared_after(s, share, share * share * share); };
  declared_in_time(fast(s.rpm_high_ratio * (1.0 + kBand)));
  EXPECT_LT(fast(s.rpm_high_ratio * (1.0 - kBand)), 0.0);
  // Drawing too little for its rpm (a broken tip): load_ratio.
  declared_in_time(declared_after(s, 1.0, s.load_ratio * (1.0 - kBand)));
  EXPECT_LT(declared_after(s, 1.0, s.load_ratio * (1.0 + kBand)), 0.0);
  // Current alone (no rpm reported): current_ratio.
  declared_in_time(declared_after(s, 1.0, s.current_ratio * (1.0 - kBand), false));
  EXPECT_LT(declared_after(s, 1.0, s.current_ratio * (1.0 + kBand), false), 0.0);
  // Fewer ESCs reporting than min_reporting: no median to judge against,
  // nothing declared however slow; with min_reporting, declared.
  EXPECT_LT(declared_after(s, 0.2, 0.008, true, s.min_reporting - 1), 0.0);
  EXPECT_GT(declared_after(s, 0.2, 0.008, true, s.min_reporting), 0.0);
}

// A motor commanded below min_motor_thrust is not judged, nor for the
// telemetry latency after it rises above it: its ESC's reading can still be
// of the speed it had there, where rpm says little (this one's motor does
// not turn at all below the gate, and takes 15 ms to start).
TEST(FailureDetector, AMotorRisingFromBelowTheGateIsJudgedOnlyPastItsLatency) {
  const FailureDetectorSettings s = hexa(bits(DetectorSources::kTelemetry));
  FailureDetector d(s);
  constexpr double kLow = 0.05;
  constexpr std::int64_t kStartsAfterUs = 15'000;
  ASSERT_LT(kLow, s.min_motor_thrust);
  ASSERT_LT(kStartsAfterUs, static_cast<std::int64_t>(s.telemetry_latency_s * 1e6));
  MotorVector command = hover(6);
  command[0] = kLow;
  const std::int64_t step = 1'000'000;
  for (std::int64_t t = 0; t < 2'000'000; t += kCycleUs) {
    if (t >= step) command[0] = kHover;
    MotorVector actual = command;
    if (t < step + kStartsAfterUs) actual[0] = 0.0;  // not turning yet
    feed_telemetry(d, actual, 1.0, t);
    d.update(command, 0, true, t);
  }
  EXPECT_EQ(d.detection().failed, 0U);
}

// Silence needs most ESCs still reporting: the telemetry stream dying
// whole (its wire, its UART) is no motor's failure.
TEST(FailureDetector, EveryEscFallingSilentAtOnceIsNoFailure) {
  const FailureDetectorSettings s = hexa(bits(DetectorSources::kTelemetry));
  ASSERT_TRUE(s.silence_declares);
  FailureDetector d(s);
  for (std::int64_t t = 0; t < 3'000'000; t += kCycleUs) {
    if (t < 1'000'000) feed_telemetry(d, hover(6), 1.0, t);
    d.update(hover(6), 0, true, t);
  }
  EXPECT_EQ(d.detection().failed, 0U);
  EXPECT_EQ(d.detection().telemetry_silent, 0U);
}

TEST(FailureDetector, ACurrentReadingAtOrBelowZeroIsTheMostUnloaded) {
  // A thrown prop draws nothing: its ESC's current is noise around zero,
  // and a reading of -0.1 A or 0 A is the least load of all, not "no load
  // measured" (so it was once skipped, and the prop found only when its rpm
  // had risen, up to 85 ms later in the simulator).
  for (const double current : {-0.1, 0.0}) {
    FailureDetector d(hexa(bits(DetectorSources::kTelemetry)));
    const std::int64_t fail_at = 500'000;
    std::int64_t t = 0;
    for (; t < 1'500'000 && d.detection().failed == 0; t += kCycleUs) {
      feed_rpm_and_current(d, hover(6), -1, 1.0, t);
      if (t >= fail_at) d.on_telemetry(2, kFullRpm * std::sqrt(kHover), current, t);
      d.update(hover(6), 0, true, t);
    }
    ASSERT_EQ(d.detection().failed, MotorMask{1} << 2) << current << " A";
    const double latency = static_cast<double>(d.detection().at_us - fail_at) / 1e6;
    EXPECT_LE(latency, d.settings().telemetry_persist_s + kTelemetrySlackS) << current << " A";
  }
}

TEST(FailureDetector, ALoadIsNotWeighedNearIdleNorWithTheCheckOff) {
  // At 15 % thrust an ESC's current offset swamps the load; with
  // load_ratio 0 it is never judged.
  for (const bool off : {false, true}) {
    FailureDetectorSettings s = hexa(bits(DetectorSources::kTelemetry));
    if (off) s.load_ratio = 0.0;
    FailureDetector d(s);
    const MotorVector thrust = MotorVector::Constant(6, off ? kHover : 0.15);
    for (std::int64_t t = 0; t < 1'000'000; t += kCycleUs) {
      feed_rpm_and_current(d, thrust, 1, 0.4, t);
      d.update(thrust, 0, true, t);
    }
    EXPECT_EQ(d.detection().failed, 0U) << (off ? "load_ratio 0" : "near idle");
  }
}

TEST(FailureDetector, ALateReadingOfAMotorFollowingItsCommandIsNeitherSlowNorFast) {
  FailureDetectorSettings s = hexa(bits(DetectorSources::kTelemetry));
  s.telemetry_persist_s = 0.0;  // about the window, not the persistence
  EXPECT_EQ(late_esc_through_steps(s, 17'500), 0U);
  // Readings 22.5 ms late: within the 20 ms window (and the speed lag's
  // lower thrust), nothing; judged as if on time, they declare it (too slow
  // while it speeds up): the window matters.
  EXPECT_EQ(late_esc_through_steps(s, 22'500), 0U);
  s.telemetry_latency_s = 0.0;
  EXPECT_EQ(late_esc_through_steps(s, 22'500), MotorMask{1} << 3);
}

TEST(FailureDetector, OneBadReadingIsNotAFailure) {
  FailureDetector d(hexa(bits(DetectorSources::kTelemetry)));
  for (std::int64_t t = 0; t < 1'000'000; t += kCycleUs) {
    feed_telemetry(d, hover(6), 1.0, t);
    if (t == 400'000) d.on_telemetry(4, 0.0, NAN, t);  // one glitch
    d.update(hover(6), 0, true, t);
  }
  EXPECT_EQ(d.detection().failed, 0U);
}

TEST(FailureDetector, ASaggingBatteryMovesEveryMotorAndTriggersNothing) {
  FailureDetector d(hexa(bits(DetectorSources::kTelemetry)));
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (std::int64_t t = 0; t < 3'000'000; t += kCycleUs) {
    const double scale = 1.0 - 0.4 * static_cast<double>(t) / 3e6;  // rpm down 40 %
    MotorVector actual = hover(6);
    for (int i = 0; i < 6; ++i) actual[i] *= 1.0 + noise(rng);
    feed_telemetry(d, actual, scale, t);
    d.update(hover(6), 0, true, t);
  }
  EXPECT_EQ(d.detection().failed, 0U);
}

TEST(FailureDetector, NothingIsDeclaredWhileNotAllowed) {
  FailureDetector d(hexa(bits(DetectorSources::kTelemetry)));
  MotorVector actual = hover(6);
  actual[1] = 0.0;
  for (std::int64_t t = 0; t < 1'000'000; t += kCycleUs) {
    feed_telemetry(d, actual, 1.0, t);
    d.update(hover(6), 0, false, t);
    EXPECT_EQ(d.suspicion_s(DetectionSource::kTelemetry, 1), 0.0);
  }
  EXPECT_EQ(d.detection().failed, 0U);
  // Allowed from here on: the evidence must build up again first.
  const std::int64_t allowed_at = 1'000'000;
  for (std::int64_t t = allowed_at; d.detection().failed == 0; t += kCycleUs) {
    feed_telemetry(d, actual, 1.0, t);
    d.update(hover(6), 0, true, t);
  }
  EXPECT_GE(d.detection().at_us - allowed_at,
            static_cast<std::int64_t>(d.settings().telemetry_persist_s * 1e6) - kCycleUs);
}

TEST(FailureDetector, ASilentEscIsAFailureOnlyWhereStoppingItCostsNothingAndWithoutRates) {
  // silence_declares: what the configuration sets for six rotors or more;
  // a quad's setting (false) never declares silence, whatever the sources.
  for (const bool silence_declares : {true, false}) {
    for (const bool with_rates : {false, true}) {
      SCOPED_TRACE(std::string(with_rates ? "telemetry and rates" : "telemetry alone") +
                   (silence_declares ? ", silence may declare" : ", silence never declares"));
      const std::uint8_t sources =
          bits(DetectorSources::kTelemetry) | (with_rates ? bits(DetectorSources::kRates) : 0);
      FailureDetectorSettings settings = hexa(sources);
      settings.silence_declares = silence_declares;
      FailureDetector d(settings);
      for (std::int64_t t = 0; t < 1'000'000; t += kCycleUs) {
        MotorVector actual = hover(6);
        for (int i = 0; i < 6; ++i) {
          if (i != 5 || t < 300'000) d.on_telemetry(i, kFullRpm * std::sqrt(actual[i]), NAN, t);
        }
        d.on_rates(Eigen::Vector3d::Zero(), t, t);  // a steady hover
        d.update(hover(6), 0, true, t);
      }
      if (with_rates || !silence_declares) {
        EXPECT_EQ(d.detection().failed, 0U);
        EXPECT_EQ(d.detection().telemetry_silent, MotorMask{1} << 5);  // flagged for the status
      } else {
        EXPECT_EQ(d.detection().failed, MotorMask{1} << 5);
        EXPECT_EQ(d.detection().source, DetectionSource::kTelemetrySilent);
      }
    }
  }
}

// Silence is judged against each ESC's own reporting interval: an ESC asked
// in turn with others (here one reading every 150 ms, kSlowPeriodUs) is
// never silent between its readings, and is once it stops; a fast ESC is
// silent after telemetry_timeout_s, no sooner.
TEST(FailureDetector, SilenceIsJudgedAgainstEachEscsOwnInterval) {
  constexpr std::int64_t kSlowPeriodUs = 150'000;  // longer than telemetry_timeout_s
  constexpr std::int64_t kStopUs = 2'000'000;
  FailureDetectorSettings settings = hexa(bits(DetectorSources::kTelemetry));
  ASSERT_LT(settings.telemetry_timeout_s * 1e6, kSlowPeriodUs);
  FailureDetector d(settings);
  std::int64_t silent_at = -1, last_reading = 0;
  for (std::int64_t t = 0; t < 4'000'000; t += kCycleUs) {
    for (int i = 0; i < 6; ++i) {
      const bool slow = i == 2;
      if (slow && (t % kSlowPeriodUs != 0 || t >= kStopUs)) continue;
      if (slow) last_reading = t;
      d.on_telemetry(i, kFullRpm * std::sqrt(kHover), NAN, t);
    }
    d.update(hover(6), 0, true, t);
    const bool flagged = (d.detection().telemetry_silent >> 2 & 1U) != 0;
    if (t < kStopUs + kSlowPeriodUs) {
      ASSERT_FALSE(flagged) << "a slow ESC between its readings, t = " << t;
      ASSERT_EQ(d.detection().failed, 0U) << "t = " << t;
    } else if (flagged && silent_at < 0) {
      silent_at = t;
    }
  }
  // Silent after six of its own intervals (150 ms each: the documented
  // rule, docs/failure-detection.md, written here rather than read from the
  // detector's constant), not after the 100 ms timeout; then declared
  // (silence_declares, a hexa).
  constexpr double kDocumentedSilentIntervals = 6.0;
  const double after_s = static_cast<double>(silent_at - last_reading) / 1e6;
  EXPECT_NEAR(after_s, kDocumentedSilentIntervals * kSlowPeriodUs / 1e6, 0.02);
  EXPECT_EQ(d.detection().failed, MotorMask{1} << 2);
  EXPECT_EQ(d.detection().source, DetectionSource::kTelemetrySilent);
}

// Silence is never sooner than telemetry_timeout_s: an ESC reporting every
// cycle (six of its intervals: 15 ms) that stops is flagged silent the
// cycle its last reading is telemetry_timeout_s old, not before.
TEST(FailureDetector, AFastEscIsSilentAfterTheTimeoutNotAfterItsIntervals) {
  const FailureDetectorSettings s = hexa(bits(DetectorSources::kTelemetry));
  FailureDetector d(s);
  const std::int64_t stop = 1'000'000;
  std::int64_t last = 0, flagged_at = -1;
  for (std::int64_t t = 0; t < 2'000'000 && flagged_at < 0; t += kCycleUs) {
    for (int i = 0; i < 6; ++i) {
      if (i == 3 && t >= stop) continue;
      if (i == 3) last = t;
      d.on_telemetry(i, kFullRpm * std::sqrt(kHover), NAN, t);
    }
    d.update(hover(6), 0, true, t);
    if ((d.detection().telemetry_silent >> 3 & 1U) != 0) flagged_at = t;
  }
  ASSERT_GE(flagged_at, 0);
  EXPECT_NEAR(static_cast<double>(flagged_at - last) / 1e6, s.telemetry_timeout_s, kCycleS);
}

// The body's rates under the rotors' torque plus `external`, integrated at
// the cycle rate, fed to the detector as a gyro would.
class RatesVehicle {
 public:
  explicit RatesVehicle(const FailureDetectorSettings& s) : s_(s) {}
  void step(FailureDetector& d, const MotorVector& actual, const Eigen::Vector3d& external,
            std::int64_t t) {
    const Eigen::Vector3d torque = s_.torque_per_thrust * actual - s_.rotational_drag * w_ -
                                   w_.cross(s_.inertia_kgm2.cwiseProduct(w_)) + external;
    w_ += torque.cwiseQuotient(s_.inertia_kgm2) * (kCycleUs / 1e6);
    d.on_rates(w_, t, t);
  }

 private:
  FailureDetectorSettings s_;
  Eigen::Vector3d w_ = Eigen::Vector3d::Zero();
};

TEST(FailureDetector, RatesNameEveryMotorOfAHexa) {
  const FailureDetectorSettings s = hexa(bits(DetectorSources::kRates));
  for (int motor = 0; motor < 6; ++motor) {
    SCOPED_TRACE(motor);
    FailureDetector d(s);
    RatesVehicle body(s);
    MotorVector actual = hover(6);
    const std::int64_t fail_at = 500'000;
    for (std::int64_t t = 0; t < 1'500'000 && d.detection().failed == 0; t += kCycleUs) {
      if (t >= fail_at) actual[motor] *= std::exp(-kCycleUs / 1e6 / 0.05);
      body.step(d, actual, Eigen::Vector3d::Zero(), t);
      d.update(hover(6), 0, true, t);
    }
    ASSERT_EQ(d.detection().failed, MotorMask{1} << motor);
    EXPECT_EQ(d.detection().source, DetectionSource::kRates);
    EXPECT_LE(static_cast<double>(d.detection().at_us - fail_at) / 1e6,
              s.rates_persist_s + kRatesSlackS);
  }
}

TEST(FailureDetector, RatesIgnoreAGustAndATorqueNoMotorCouldMake) {
  const FailureDetectorSettings s = hexa(bits(DetectorSources::kRates));
  FailureDetector d(s);
  RatesVehicle body(s);
  for (std::int64_t t = 0; t < 3'000'000; t += kCycleUs) {
    Eigen::Vector3d external = Eigen::Vector3d::Zero();
    // A gust below the smallest residual judged, then a large torque about
    // yaw alone: no single motor's loss points that way.
    if (t > 500'000 && t < 1'000'000) external = Eigen::Vector3d(0.8, 0.0, 0.0) * s.min_residual_nm;
    if (t > 1'500'000 && t < 2'500'000) external = Eigen::Vector3d(0.0, 0.0, 2.0);
    body.step(d, hover(6), external, t);
    d.update(hover(6), 0, true, t);
  }
  EXPECT_EQ(d.detection().failed, 0U);
}

// The rates source on a hexa: motor m2 (index 1), commanded `thrust`,
// keeps `keep` of it from a step at 0.5 s, with `external` beside it from
// the same moment; telemetry, if a source, reports every motor as its
// command asks. Seconds from the step to the declaration, or -1 in 1.5 s.
double rates_declared_after(const FailureDetectorSettings& s, double thrust, double keep,
                            const Eigen::Vector3d& external = Eigen::Vector3d::Zero()) {
  constexpr int kMotor = 1;
  FailureDetector d(s);
  RatesVehicle body(s);
  MotorVector command = hover(6);
  command[kMotor] = thrust;
  MotorVector actual = command;
  const std::int64_t onset = 500'000;
  for (std::int64_t t = 0; t < onset + 1'500'000 && d.detection().failed == 0; t += kCycleUs) {
    if (t >= onset) actual[kMotor] = keep * thrust;
    if (s.sources & bits(DetectorSources::kTelemetry)) feed_telemetry(d, command, 1.0, t);
    body.step(d, actual, t >= onset ? external : Eigen::Vector3d::Zero(), t);
    d.update(command, 0, true, t);
  }
  if (d.detection().failed == 0) return -1.0;
  EXPECT_EQ(d.detection().motor, kMotor);
  return static_cast<double>(d.detection().at_us - onset) / 1e6;
}

// Each of the rates source's knobs holds on both sides of its value.
TEST(FailureDetector, EachRatesThresholdHoldsOnBothSides) {
  const FailureDetectorSettings s = hexa(bits(DetectorSources::kRates));
  constexpr double kBand = 0.15;  // of each threshold, either side
  // min_loss: the share of the motor's thrust gone.
  EXPECT_GT(rates_declared_after(s, kHover, 1.0 - s.min_loss * (1.0 + kBand)), 0.0);
  EXPECT_LT(rates_declared_after(s, kHover, 1.0 - s.min_loss * (1.0 - kBand)), 0.0);
  // min_residual_nm: a whole loss of a motor commanded so little that its
  // torque is under the smallest residual judged, and one just over it.
  const double column = s.torque_per_thrust.col(1).norm();
  const double at_residual = s.min_residual_nm / column;  // the thrust whose loss is exactly it
  ASSERT_GT(at_residual * (1.0 - kBand), s.min_motor_thrust);
  EXPECT_GT(rates_declared_after(s, at_residual * (1.0 + kBand), 0.0), 0.0);
  EXPECT_LT(rates_declared_after(s, at_residual * (1.0 - kBand), 0.0), 0.0);
  // max_off_axis: a whole loss with a torque across its column beside it
  // (horizontal, perpendicular), as a share of the loss's torque.
  const Eigen::Vector3d loss = s.torque_per_thrust.col(1) * kHover;
  const Eigen::Vector3d across = loss.cross(Eigen::Vector3d::UnitZ()).normalized() * loss.norm();
  EXPECT_GT(rates_declared_after(s, kHover, 0.0, across * s.max_off_axis * (1.0 - kBand)), 0.0);
  EXPECT_LT(rates_declared_after(s, kHover, 0.0, across * s.max_off_axis * (1.0 + kBand)), 0.0);
}

// The persistence is what is configured: the same loss declared with
// rates_persist_s and with none differ by exactly it.
TEST(FailureDetector, TheRatesPersistenceIsTheConfiguredOne) {
  FailureDetectorSettings s = hexa(bits(DetectorSources::kRates));
  const double with = rates_declared_after(s, kHover, 0.0);
  const double persist = s.rates_persist_s;
  s.rates_persist_s = 0.0;
  const double without = rates_declared_after(s, kHover, 0.0);
  ASSERT_GT(with, 0.0);
  ASSERT_GE(without, 0.0);
  EXPECT_NEAR(with - without, persisted_after(persist), kHalfCycleS);
}

// An ESC reporting the speed its command asks for vetoes the rates: a
// torque exactly like motor m2's loss, m2's ESC at its commanded rpm, is an
// outside push. With rates alone the same torque is m2's loss.
TEST(FailureDetector, AHealthyEscVetoesTheRates) {
  const FailureDetectorSettings s = hexa(bits(DetectorSources::kRates));
  const FailureDetectorSettings both =
      hexa(bits(DetectorSources::kRates) | bits(DetectorSources::kTelemetry));
  const Eigen::Vector3d push = -s.torque_per_thrust.col(1) * kHover;
  EXPECT_GT(rates_declared_after(s, kHover, 1.0, push), 0.0);
  EXPECT_LT(rates_declared_after(both, kHover, 1.0, push), 0.0);
}

// The rates model is the vehicle's: a healthy hexa whose motors follow
// their commands with the configured lag (time_constant_up_s and _down_s),
// commanded in steps of a fifth of hover every 150 ms on every motor at its
// own phase, leaves no residual but rounding (a model lag half the
// motors' own left 2.4 % of the smallest judged after each step).
TEST(FailureDetector, AHealthyVehicleFollowingTheModelledLagLeavesNoResidual) {
  const FailureDetectorSettings s = hexa(bits(DetectorSources::kRates));
  constexpr double kResidualShare = 0.002;
  FailureDetector d(s);
  RatesVehicle body(s);
  MotorVector command = hover(6), actual = hover(6);
  double worst = 0.0;
  for (std::int64_t t = 0; t < 3'000'000; t += kCycleUs) {
    for (int i = 0; i < 6; ++i) {
      const bool high = ((t / 150'000) + i) % 2 == 0;
      command[i] = kHover * (high ? 1.1 : 0.9);
      const double tau = command[i] > actual[i] ? s.time_constant_up_s : s.time_constant_down_s;
      actual[i] += (command[i] - actual[i]) * (1.0 - std::exp(-kCycleS / tau));
    }
    body.step(d, actual, Eigen::Vector3d::Zero(), t);
    d.update(command, 0, true, t);
    if (t > 500'000) worst = std::max(worst, d.rates_residual().norm());
  }
  EXPECT_EQ(d.detection().failed, 0U);
  EXPECT_LT(worst, kResidualShare * s.min_residual_nm);
}

// The gyro's vibration through the rates filter (rates_filter_hz, two
// first-order stages on the differentiated rates): a 100 Hz roll-rate
// vibration of 0.05 rad/s on a hovering hexa leaves a roll residual of the
// amplitude the filter's own response gives, worked here from its
// discrete form: I_x |D| |H|^2 A (D the difference over a cycle, H one
// stage), to a tenth (a cut-off half again higher doubles it).
TEST(FailureDetector, TheRatesFilterTakesTheVibrationDownAsConfigured) {
  const FailureDetectorSettings s = hexa(bits(DetectorSources::kRates));
  constexpr double kVibrationHz = 100.0, kAmplitude = 0.05, kWithin = 0.1;
  constexpr double kPi = 3.14159265358979;
  FailureDetector d(s);
  // The amplitude from the RMS over whole periods (four samples each: the
  // largest sample depends on the phase).
  double sum_sq = 0.0;
  int n = 0;
  for (std::int64_t t = 0; t < 2'000'000; t += kCycleUs) {
    const double w = kAmplitude * std::sin(2.0 * kPi * kVibrationHz * static_cast<double>(t) / 1e6);
    d.on_rates(Eigen::Vector3d(w, 0.0, 0.0), t, t);
    d.update(hover(6), 0, false, t);
    if (t >= 1'000'000) {
      sum_sq += d.rates_residual().x() * d.rates_residual().x();
      ++n;
    }
  }
  const double peak = std::sqrt(2.0 * sum_sq / n);
  const double omega_t = 2.0 * kPi * kVibrationHz * kCycleS;
  const double a = 1.0 - std::exp(-kCycleS * 2.0 * kPi * s.rates_filter_hz);
  const double stage =
      a / std::abs(std::complex<double>(1.0) - (1.0 - a) * std::polar(1.0, -omega_t));
  const double difference = 2.0 * std::sin(omega_t / 2.0) / kCycleS;
  const double expected = s.inertia_kgm2.x() * difference * stage * stage * kAmplitude;
  EXPECT_NEAR(peak, expected, kWithin * expected);
}

// A motor below min_motor_thrust is not judged by the rates either: on a
// hexa whose smallest judged residual is a twentieth of a hover motor's,
// a motor commanded at 0.06 stopping outright is not declared (nor its
// torque ever near a failure's); at 0.12 it is.
TEST(FailureDetector, TheRatesJudgeNoMotorBelowTheGate) {
  FailureDetectorSettings s = hexa(bits(DetectorSources::kRates));
  s.min_residual_nm = 0.05 * s.torque_per_thrust.col(1).norm() * kHover;
  ASSERT_LT(0.06, s.min_motor_thrust);
  EXPECT_LT(rates_declared_after(s, 0.06, 0.0), 0.0);
  EXPECT_GT(rates_declared_after(s, 0.12, 0.0), 0.0);
}

// The torque scale learned in healthy flight stays within 0.7..1.3
// (docs/failure-detection.md): a hexa manoeuvring on rotors that give 0.5
// or 2 times the modelled torque never learns beyond the bounds (0.5: the
// lower bound; 2: nothing, no factor inside them explains it), and one whose
// rotors give 0.85 times learns about that (measured 0.88: the prior and
// the rocking body's filtered phase keep it a little short). Unbounded, it
// learned 0.60 and 1.80.
TEST(FailureDetector, TheLearnedTorqueScaleStaysWithinItsBounds) {
  constexpr double kDocumentedMinScale = 0.7, kDocumentedMaxScale = 1.3;
  constexpr double kLearnedWithin = 0.06;
  for (const double truth : {0.5, 0.85, 2.0}) {
    SCOPED_TRACE(truth);
    const FailureDetectorSettings s = hexa(bits(DetectorSources::kRates));
    FailureDetectorSettings real = s;
    real.torque_per_thrust *= truth;
    FailureDetector d(s);
    RatesVehicle body(real);
    for (std::int64_t t = 0; t < 30'000'000; t += kCycleUs) {
      // Every motor swinging by a tenth of hover at its own phase: roll,
      // pitch and yaw torques all moving, the body rocking.
      MotorVector command = hover(6);
      for (int i = 0; i < 6; ++i)
        command[i] += 0.1 * kHover *
                      std::sin(2.0 * 3.14159265358979 * 0.7 * static_cast<double>(t) / 1e6 + i);
      body.step(d, command, Eigen::Vector3d::Zero(), t);
      d.update(command, 0, true, t);
    }
    ASSERT_EQ(d.detection().failed, 0U);
    std::printf("rotors at %.2f of the model: scale learned %.3f\n", truth, d.torque_scale());
    EXPECT_GE(d.torque_scale(), kDocumentedMinScale - 1e-9);
    EXPECT_LE(d.torque_scale(), kDocumentedMaxScale + 1e-9);
    if (truth > kDocumentedMinScale && truth < kDocumentedMaxScale) {
      EXPECT_NEAR(d.torque_scale(), truth, kLearnedWithin);
    }
  }
}

TEST(FailureDetector, StaleRatesJudgeNothing) {
  const FailureDetectorSettings s = hexa(bits(DetectorSources::kRates));
  FailureDetector d(s);
  RatesVehicle body(s);
  MotorVector actual = hover(6);
  // Motor 4 stops at 200 ms; the gyro stream dies 10 ms later, its last
  // samples already showing the loss. Held, they would name the motor.
  for (std::int64_t t = 0; t < 1'000'000; t += kCycleUs) {
    if (t >= 200'000) actual[3] = 0.0;
    if (t < 210'000) body.step(d, actual, Eigen::Vector3d::Zero(), t);
    d.update(hover(6), 0, true, t);
  }
  EXPECT_EQ(d.detection().failed, 0U);
}

TEST(FailureDetector, OutputsFindTheMotorDrivenToFullForLong) {
  // Every motor in turn: the one named is the one driven to full (a
  // detector naming a fixed motor passes for one motor only).
  for (int motor = 0; motor < 6; ++motor) {
    SCOPED_TRACE("m" + std::to_string(motor + 1));
    FailureDetectorSettings s = hexa(bits(DetectorSources::kOutputs));
    FailureDetector d(s);
    MotorVector commands = hover(6);
    commands[motor] = 1.0;
    // Shorter than the persistence: nothing.
    std::int64_t t = 0;
    for (; t < 1'200'000; t += kCycleUs) d.update(commands, 0, true, t);
    for (; t < 1'700'000; t += kCycleUs) d.update(hover(6), 0, true, t);
    EXPECT_EQ(d.detection().failed, 0U);
    for (; t < 5'000'000 && d.detection().failed == 0; t += kCycleUs)
      d.update(commands, 0, true, t);
    EXPECT_EQ(d.detection().failed, MotorMask{1} << motor);
    EXPECT_EQ(d.detection().motor, motor);
    EXPECT_EQ(d.detection().source, DetectionSource::kOutputs);
  }
}

// Each of the outputs source's knobs holds: a motor far above the others
// but under outputs_high is not a failure (a vehicle manoeuvring drives
// motors unevenly), nor one at full while the median is within
// outputs_margin of it (a climb at full throttle), and the one driven to
// full from hover is declared after the filter's rise to outputs_high and
// outputs_persist_s more, to the cycle.
TEST(FailureDetector, OutputsJudgeTheirHighTheirMarginAndTheirPersistence) {
  const FailureDetectorSettings s = hexa(bits(DetectorSources::kOutputs));
  constexpr double kRiseToleranceS = 0.01;  // a cycle and the filter's discretization
  const auto run = [&](double top, double others, double seconds) {
    FailureDetector d(s);
    std::int64_t t = 0;
    for (; t < 5'000'000; t += kCycleUs) d.update(hover(6), 0, true, t);  // settled at hover
    MotorVector commands = MotorVector::Constant(6, others);
    commands[2] = top;
    const std::int64_t from = t;
    for (; t < from + static_cast<std::int64_t>(seconds * 1e6) && d.detection().failed == 0;
         t += kCycleUs)
      d.update(commands, 0, true, t);
    return d.detection().failed == 0 ? -1.0 : static_cast<double>(d.detection().at_us - from) / 1e6;
  };
  // Under the high mark, however far above the others: nothing in 10 s.
  ASSERT_LT(0.85, s.outputs_high);
  ASSERT_GE(0.85 - 0.4, s.outputs_margin);
  EXPECT_LT(run(0.85, 0.4, 10.0), 0.0);
  // At full, the others within the margin: nothing.
  ASSERT_LT(1.0 - 0.7, s.outputs_margin);
  EXPECT_LT(run(1.0, 0.7, 10.0), 0.0);
  // From hover to full: the low-pass from kHover reaches outputs_high
  // (the margin is reached before it), then the persistence.
  ASSERT_LT(s.outputs_margin, s.outputs_high - kHover);
  const double rise_s = s.outputs_filter_s * std::log((1.0 - kHover) / (1.0 - s.outputs_high));
  EXPECT_NEAR(run(1.0, kHover, 10.0), rise_s + s.outputs_persist_s, kRiseToleranceS);
}

// The outputs source judges only the first failure: with a motor already
// out the others' commands are uneven by design (the one across from it
// driven high), and say nothing of a second.
TEST(FailureDetector, OutputsJudgeNothingOnceAMotorIsOut) {
  const FailureDetectorSettings s = hexa(bits(DetectorSources::kOutputs));
  FailureDetector d(s);
  MotorVector commands = hover(6);
  commands[0] = 0.0;  // out
  commands[3] = 1.0;  // across from it, at full
  for (std::int64_t t = 0; t < 10'000'000; t += kCycleUs)
    d.update(commands, MotorMask{1} << 0, true, t);
  EXPECT_EQ(d.detection().failed, 0U);
}

TEST(FailureDetector, ResetForgetsDeclarations) {
  FailureDetector d(hexa(bits(DetectorSources::kOutputs)));
  MotorVector commands = hover(6);
  commands[0] = 1.0;
  for (std::int64_t t = 0; t < 5'000'000; t += kCycleUs) d.update(commands, 0, true, t);
  ASSERT_NE(d.detection().failed, 0U);
  d.reset();
  EXPECT_EQ(d.detection().failed, 0U);
  EXPECT_EQ(d.detection().source, DetectionSource::kNone);
}

TEST(FailureDetector, MotorsAlreadyFailedAreNotJudgedAgain) {
  FailureDetector d(hexa(bits(DetectorSources::kTelemetry)));
  MotorVector actual = hover(6);
  actual[0] = 0.0;
  for (std::int64_t t = 0; t < 1'000'000; t += kCycleUs) {
    feed_telemetry(d, actual, 1.0, t);
    d.update(hover(6), MotorMask{1}, true, t);
  }
  EXPECT_EQ(d.detection().failed, 0U);
}

}  // namespace
}  // namespace motormix::test
