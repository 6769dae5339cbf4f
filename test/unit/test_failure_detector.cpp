// The failure detector alone, on synthetic vehicles with time passed in:
// each source finds the motor that stopped and names it, and none of them
// fires on one bad sample, a sagging battery, a gust, a stale stream or
// while detection is not allowed.

#include <motormix/failure_detector.hpp>

#include <gtest/gtest.h>

#include <cmath>
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
  // Silent after kSilentIntervals of its own interval (150 ms each), not
  // after the 100 ms timeout; then declared (silence_declares, a hexa).
  const double after_s = static_cast<double>(silent_at - last_reading) / 1e6;
  EXPECT_NEAR(after_s, kSilentIntervals * kSlowPeriodUs / 1e6, 0.02);
  EXPECT_EQ(d.detection().failed, MotorMask{1} << 2);
  EXPECT_EQ(d.detection().source, DetectionSource::kTelemetrySilent);
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
