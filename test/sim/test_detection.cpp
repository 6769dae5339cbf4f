// motormix's failure detector in closed loop, in lockstep: a hexa X and an
// octo X losing each motor at hover, never reported, found by each source
// (telemetry, rates, both) in time and named right, the vehicle flying on;
// and no false alarm over at least an hour of healthy flight per vehicle and
// source set, every healthy scenario, strategy and ten seeds. The campaigns'
// seeds are drawn fresh on every run and printed (MOTORMIX_SIM_SEED=N
// replays one: test_support.hpp).
//
// Optimized builds only (test/CMakeLists.txt): about 4000 flights.

#include "sim/lockstep.hpp"
#include "sim/scenario.hpp"
#include "test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <future>
#include <sstream>

namespace motormix::sim {
namespace {

using test::source_path;

// The targets, named.
constexpr double kTelemetryLatencyS = 0.100;
constexpr double kRatesLatencyS = 0.250;
constexpr double kAltitudeLossM = 1.0;
constexpr double kFailureAttitudeMaxDeg = 20.0;
// Rates alone must first see the vehicle turn the wrong way before they can
// name the motor; with the simulator's realism (a filtered, vibrating gyro,
// rotors with momentum) the hexa's worst was 22.5 degrees (0.10).
constexpr double kRatesOnlyAttitudeMaxDeg = 30.0;
constexpr int kTargetSeeds = 3;
// A thrown prop: the issue asks 50 ms. Measured with the simulator's
// realism (ESCs at 100-500 Hz, 2-6 ms late, 3 % of frames lost) on seeds
// 21-23, every motor of the hexa X, octo X and quad X in hover and gusts:
// worst 37.5 ms, median 20 (its current falls at once; 10 ms of persistence).
constexpr double kPropLostLatencyS = 0.050;
// A broken tip: the issue asks 500 ms (or flown through); its load names
// it in 32-50 ms.
constexpr double kPropDamagedLatencyS = 0.500;
constexpr int kFalseAlarmSeeds = 10;
constexpr double kFalseAlarmSecondsPerVehicle = 3600.0;

config::Config load(const std::string& file, const std::vector<std::string>& overrides) {
  return config::load_config_file(source_path("config/" + file), overrides);
}

// The k-th seed of this run's campaign: fresh on every run, printed once
// (test_support.hpp). Flights keep their seed in their trace.
int fresh_seed(int k) {
  return static_cast<int>(test::campaign_seed_base() % 1'000'000'000ULL) + k;
}

// One flight of `c` through `s` whose motor `motor` fails (`kind`) at
// `at_s`, reported by nobody: what motormix's detector makes of it.
SimResult fly_unreported(const config::Config& c, const Scenario& s, int motor, double at_s,
                         FailureKind kind = FailureKind::kStop, int seed = 1,
                         const FrameObserver& observer = {}, const Realism& realism = Realism{}) {
  SimOptions o;
  o.realism = realism;
  o.seed = static_cast<std::uint64_t>(seed);
  o.undetected = true;
  o.failures.push_back({motor, at_s, kind});
  return run_lockstep(c, config::build_mixer(c), s, o, observer);
}

// A stopped motor freewheels down under its own air drag when the rotors
// have momentum (the default): it loses its thrust over a few hundred
// milliseconds, and the rates source names it later than the issue's
// 250 ms (AFreewheelingStopIsFoundByTheRatesAlone); the outputs source
// seconds after it (4.6-6.9 s on the octo X, against about 1.5 s for a
// prompt stop: the mixer's integrators take that long to push the dead
// motor's command to the top). The sources without
// telemetry are held to their targets on a motor that stops at once (the
// world without rotor momentum, where the stop follows the motor lag).
const Realism kPromptStop = [] {
  Realism r;
  r.rotor_momentum = false;
  return r;
}();

// One failure at at_s on `motor`: not crashed, no false alarm, named right
// within latency_s, the altitude and the attitude within their bounds.
void expect_found_in_time(const SimResult& r, int motor, double at_s, double latency_s,
                          double attitude_max_deg) {
  ASSERT_EQ(r.failures.size(), 1U);
  const FailureOutcome& f = r.failures.front();
  EXPECT_FALSE(r.crashed) << r.crash_reason;
  EXPECT_EQ(r.false_detections, 0);
  EXPECT_EQ(f.detected_motor, motor);
  ASSERT_GE(f.detected_at_s, at_s);
  EXPECT_LE(f.detected_at_s - at_s, latency_s);
  EXPECT_LE(r.altitude_loss_m, kAltitudeLossM);
  EXPECT_LE(r.failure_attitude_error_max_deg, attitude_max_deg);
}

struct Source {
  const char* name;
  const char* sources;  // failure_detection.sources
  double latency_s;
  double attitude_max_deg;
};
constexpr Source kSources[] = {
    {"telemetry", "[telemetry]", kTelemetryLatencyS, kFailureAttitudeMaxDeg},
    {"rates", "[rates]", kRatesLatencyS, kRatesOnlyAttitudeMaxDeg},
    {"both", "[telemetry, rates]", kTelemetryLatencyS, kFailureAttitudeMaxDeg}};

struct FailureCase {
  const char* scenario;
  double at_s;  // at hover: between the scenario's steps or gusts
};
constexpr FailureCase kCases[] = {{"steps", 10.5}, {"gusts", 7.0}};

TEST(DetectedFailures, EveryMotorOfHexaAndOctoFoundInTimeAndNamed) {
  int flights = 0;
  for (const char* file : {"hexa_x.yaml", "octo_x.yaml"}) {
    for (const char* strategy : {"optimal", "prioritized"}) {
      for (const Source& source : kSources) {
        const config::Config c =
            load(file, {std::string("mixer.strategy=") + strategy,
                        std::string("failure_detection.sources=") + source.sources});
        for (const FailureCase& fc : kCases) {
          const Scenario s = load_scenario(fc.scenario);
          for (int motor = 0; motor < c.motors(); ++motor) {
            if (!test::in_sim_grid(motor, c.motors())) continue;
            for (int k = 0; k < test::sim_grid_seeds(kTargetSeeds); ++k) {
              const int seed = fresh_seed(k);
              std::ostringstream where;
              where << file << " " << strategy << " " << source.name << " " << fc.scenario << " m"
                    << motor + 1 << " seed " << seed;
              SCOPED_TRACE(where.str());
              const bool telemetry =
                  std::string(source.sources).find("telemetry") != std::string::npos;
              const SimResult r = fly_unreported(c, s, motor, fc.at_s, FailureKind::kStop, seed, {},
                                                 telemetry ? Realism{} : kPromptStop);
              ++flights;
              expect_found_in_time(r, motor, fc.at_s, source.latency_s, source.attitude_max_deg);
            }
          }
        }
      }
    }
  }
  if (!test::reduced_sim_grid()) {
    EXPECT_EQ(flights, 2 * 3 * 2 * (6 + 8) * kTargetSeeds);
  }
}

// A freewheeling stop (the default world) found by the rates alone: its
// thrust goes over a few hundred milliseconds, so the rates see it later
// than a prompt stop (measured 0.41 s median, 0.51 s worst over 168 flights,
// attitude 23 degrees at most). Bound with a fifth of margin; the issue's
// 250 ms holds for a prompt stop only (above).
constexpr double kFreewheelRatesLatencyS = 0.6;

TEST(DetectedFailures, AFreewheelingStopIsFoundByTheRatesAlone) {
  int flights = 0;
  for (const char* file : {"hexa_x.yaml", "octo_x.yaml"}) {
    for (const char* strategy : {"optimal", "prioritized"}) {
      const config::Config c = load(
          file, {std::string("mixer.strategy=") + strategy, "failure_detection.sources=[rates]"});
      const Scenario s = load_scenario("steps");
      for (int motor = 0; motor < c.motors(); ++motor) {
        if (!test::in_sim_grid(motor, c.motors())) continue;
        SCOPED_TRACE(std::string(file) + " " + strategy + " m" + std::to_string(motor + 1));
        const SimResult r = fly_unreported(c, s, motor, 10.5);
        ++flights;
        expect_found_in_time(r, motor, 10.5, kFreewheelRatesLatencyS, kRatesOnlyAttitudeMaxDeg);
      }
    }
  }
  if (!test::reduced_sim_grid()) {
    EXPECT_EQ(flights, 2 * (6 + 8));
  }
}

// Where a prop fails: hexa and octo in the scenario at 7 s (3 m up); a quad
// at 10 m in spin_landing (its own failure dropped) at 8 s, high enough to
// spin up and land.
struct PropFlight {
  Scenario scenario;
  double at_s;
};
PropFlight prop_flight(const config::Config& c, const char* scenario) {
  if (c.motors() > 4) return {load_scenario(scenario), 7.0};
  Scenario s =
      load_scenario(std::string(scenario) == "gusts" ? "spin_landing_gusts" : "spin_landing");
  s.timeline.erase(std::remove_if(s.timeline.begin(), s.timeline.end(),
                                  [](const ScenarioEvent& e) { return e.fail.has_value(); }),
                   s.timeline.end());
  return {s, 8.0};
}

TEST(DetectedFailures, AThrownPropIsFoundByItsEscOnTheRightMotor) {
  // The unloaded motor outruns its command and draws next to nothing: rpm
  // too high for it, or its load too low. Hexa and octo keep flying on the
  // rest; the quad lands spinning (docs/motor-loss-landing.md).
  // Also in a world whose motors lag 50 ms both ways on their speed (as
  // RotorPy plays PX4's SIH quad X): the motor across from the thrown one,
  // driven to zero, slows exactly as configured and must never be named.
  int flights = 0;
  for (const bool speed_lag : {false, true}) {
    for (const char* file : {"hexa_x.yaml", "octo_x.yaml", "quad_x.yaml"}) {
      std::vector<std::string> overrides = {"failure_detection.enabled=true"};
      if (speed_lag) {
        overrides.insert(overrides.end(),
                         {"vehicle.motor_lag=speed", "vehicle.time_constant_up_s=0.05",
                          "vehicle.time_constant_down_s=0.05"});
      }
      const config::Config c = load(file, overrides);
      const bool keeps_flying = c.motors() > 4;  // the quad lands instead
      for (const char* scenario : {"hover", "gusts"}) {
        const PropFlight p = prop_flight(c, scenario);
        for (int motor = 0; motor < c.motors(); ++motor) {
          if (!test::in_sim_grid(motor, c.motors())) continue;
          for (int k = 0; k < test::sim_grid_seeds(2); ++k) {
            const int seed = fresh_seed(100 + k);
            SCOPED_TRACE(std::string(file) + (speed_lag ? " speed lag 50 ms " : " ") + scenario +
                         " m" + std::to_string(motor + 1) + " seed " + std::to_string(seed));
            const SimResult r =
                fly_unreported(c, p.scenario, motor, p.at_s, FailureKind::kPropLost, seed);
            ++flights;
            ASSERT_EQ(r.failures.size(), 1U);
            const FailureOutcome& f = r.failures.front();
            EXPECT_EQ(f.detected_motor, motor);
            EXPECT_EQ(f.detected_by, DetectionSource::kTelemetry);
            ASSERT_GE(f.detected_at_s, p.at_s);
            EXPECT_LE(f.detected_at_s - p.at_s, kPropLostLatencyS);
            EXPECT_EQ(r.false_detections, 0);
            // A quad in wind and gusts: 3 of 16 flights (seeds 11-15) hit the
            // ground at 2.3-4.5 m/s after the tumble a thrown prop starts
            // (75 degrees); not asserted, in issue 48's closing note.
            const bool quad_in_gusts = !keeps_flying && std::string(scenario) == "gusts";
            if (!quad_in_gusts) {
              EXPECT_FALSE(r.crashed) << r.crash_reason;
            }
            if (keeps_flying) {
              EXPECT_LE(r.altitude_loss_m, kAltitudeLossM);
            } else if (!quad_in_gusts) {
              EXPECT_GE(r.touchdown_speed_mps, 0.0) << "did not touch down";
              EXPECT_LE(r.touchdown_speed_mps, kCrashSpeedMps);
            }
          }
        }
      }
    }
  }
  EXPECT_GT(flights, 0);
}

TEST(DetectedFailures, ABrokenPropTipIsFoundByItsLoad) {
  // 45 % less thrust, rpm 11 % high (under rpm_high_ratio), but 40 % of a
  // whole prop's current at that rpm: named by its load on the right motor.
  // Hexa and octo fly on the rest, quads land spinning.
  for (const char* file : {"hexa_x.yaml", "octo_x.yaml", "quad_x.yaml", "team_quad.yaml"}) {
    const config::Config c = load(file, {"failure_detection.enabled=true"});
    for (int motor = 0; motor < c.motors(); ++motor) {
      if (!test::in_sim_grid(motor, c.motors())) continue;
      SCOPED_TRACE(std::string(file) + " m" + std::to_string(motor + 1));
      const PropFlight p = prop_flight(c, "hover");
      const SimResult r =
          fly_unreported(c, p.scenario, motor, p.at_s, FailureKind::kPropDamaged, 11);
      EXPECT_FALSE(r.crashed) << r.crash_reason;
      EXPECT_EQ(r.false_detections, 0);
      const FailureOutcome& f = r.failures.front();
      EXPECT_EQ(f.detected_motor, motor);
      EXPECT_EQ(f.detected_by, DetectionSource::kTelemetry);
      ASSERT_GE(f.detected_at_s, p.at_s);
      EXPECT_LE(f.detected_at_s - p.at_s, kPropDamagedLatencyS);
    }
  }
}

// One vehicle's healthy flights: every scenario, strategy and seed.
struct FalseAlarmTally {
  // Armed seconds of the flights that did not crash: a flight that flips
  // (budget, shift and clip mixers in flips) is not an hour of healthy flight.
  double healthy_armed_s = 0.0;
  int flights = 0;
  int crashed = 0;
  std::vector<std::string> false_alarms;
};

FalseAlarmTally fly_healthy(const std::string& file, const char* sources) {
  FalseAlarmTally tally;
  for (const char* strategy :
       {"legacy_budget", "budget", "shift", "clip", "prioritized", "optimal"}) {
    if (test::reduced_sim_grid() && std::string(strategy) != "prioritized") continue;
    const config::Config c =
        load(file, {std::string("mixer.strategy=") + strategy, "failure_detection.enabled=true",
                    std::string("failure_detection.sources=") + sources});
    for (const char* scenario : {"hover", "steps", "flips", "gusts", "battery_sag"}) {
      const Scenario s = load_scenario(scenario);
      for (int k = 0; k < test::sim_grid_seeds(kFalseAlarmSeeds); ++k) {
        const int seed = fresh_seed(1000 + k);
        SimOptions o;
        o.seed = static_cast<std::uint64_t>(seed);
        const SimResult r = run_lockstep(c, config::build_mixer(c), s, o);
        ++tally.flights;
        if (r.crashed) {
          ++tally.crashed;
        } else {
          tally.healthy_armed_s += r.armed_s;
        }
        if (r.false_detections != 0) {
          std::ostringstream what;
          what << file << " " << sources << " " << strategy << " " << scenario << " seed " << seed
               << ": " << r.false_detections << " false detection(s)";
          tally.false_alarms.push_back(what.str());
        }
      }
    }
  }
  return tally;
}

// Each source set that reads telemetry: the default (telemetry and rates)
// and telemetry alone (rates alone declare on the ground in flights a
// strategy cannot fly: TheRatesAloneDeclareOnlyOnTheGroundWhereAStrategyCannotFly).
constexpr const char* kFalseAlarmSources[] = {"[telemetry, rates]", "[telemetry]"};

TEST(DetectedFailures, NoFalseAlarmInAnHourOfHealthyFlightPerVehicle) {
  const std::vector<std::string> vehicles =
      test::reduced_sim_grid()
          ? std::vector<std::string>{"quad_x.yaml", "hexa_x.yaml"}
          : std::vector<std::string>{"quad_x.yaml",      "quad_plus.yaml", "team_quad.yaml",
                                     "hexa_x.yaml",      "hexa_plus.yaml", "h_hexa.yaml",
                                     "y6.yaml",          "octo_x.yaml",    "octo_plus.yaml",
                                     "octo_coax_x8.yaml"};
  for (const char* sources : kFalseAlarmSources) {
    // Two vehicles at a time: the machines have two cores.
    std::vector<FalseAlarmTally> tallies(vehicles.size());
    for (std::size_t i = 0; i < vehicles.size(); i += 2) {
      auto second = i + 1 < vehicles.size()
                        ? std::async(std::launch::async, fly_healthy, vehicles[i + 1], sources)
                        : std::future<FalseAlarmTally>();
      tallies[i] = fly_healthy(vehicles[i], sources);
      if (second.valid()) tallies[i + 1] = second.get();
    }
    for (std::size_t i = 0; i < vehicles.size(); ++i) {
      SCOPED_TRACE(vehicles[i] + " sources " + sources);
      for (const std::string& alarm : tallies[i].false_alarms) ADD_FAILURE() << alarm;
      if (test::reduced_sim_grid()) continue;  // one seed: no hour, but every alarm above
      EXPECT_GE(tallies[i].healthy_armed_s, kFalseAlarmSecondsPerVehicle)
          << tallies[i].crashed << " of " << tallies[i].flights << " flights crashed";
      std::printf("%s, sources %s: %.0f armed s in %d flights that did not crash (%d crashed)\n",
                  vehicles[i].c_str(), sources, tallies[i].healthy_armed_s,
                  tallies[i].flights - tallies[i].crashed, tallies[i].crashed);
      EXPECT_EQ(tallies[i].flights, 6 * 5 * kFalseAlarmSeeds);
    }
  }
}

// The failures a detector must not confuse with a stop: a healthy motor
// whose ESC telemetry dies is never declared while the rates decide, and
// flights that lived without the detector live with it.
// The rates alone are not clean on flights a strategy cannot fly: the
// `budget` strategy's 60 % throttle cap leaves the H hexa on a tired pack
// skimming the ground through battery_sag's roll steps, and there a tilted
// body's ground contact and ground effect turn it as a lost motor would
// (SIM.md's false-alarm table counts those apart). Each such declaration is
// made on the ground, none in flight; with telemetry beside the rates (the
// default) there is none at all.
constexpr double kOnTheGroundM = 0.5;  // tools/detection_table.py's ON_GROUND_M
TEST(DetectedFailures, TheRatesAloneDeclareOnlyOnTheGroundWhereAStrategyCannotFly) {
  const Scenario s = load_scenario("battery_sag");
  int declarations = 0;
  for (int seed : {1, 3}) {
    SimOptions o;
    o.seed = static_cast<std::uint64_t>(seed);
    const config::Config rates =
        load("h_hexa.yaml", {"mixer.strategy=budget", "failure_detection.sources=[rates]"});
    const SimResult r = run_lockstep(rates, config::build_mixer(rates), s, o);
    for (const SimResult::Declaration& d : r.declarations) {
      ++declarations;
      EXPECT_TRUE(d.height_m < kOnTheGroundM || d.crashed)
          << "seed " << seed << ": m" << d.motor + 1 << " at " << d.at_s << " s, " << d.height_m
          << " m up";
    }
    const config::Config both =
        load("h_hexa.yaml", {"mixer.strategy=budget", "failure_detection.enabled=true"});
    EXPECT_EQ(run_lockstep(both, config::build_mixer(both), s, o).false_detections, 0)
        << "seed " << seed;
  }
  // The case this test is about still happens (else it proves nothing).
  EXPECT_GT(declarations, 0);
}

TEST(DetectedFailures, DeadTelemetryOnAWorkingMotorIsNotAFailureWithRates) {
  for (const char* file : {"hexa_x.yaml", "octo_x.yaml"}) {
    const config::Config c = load(file, {"failure_detection.sources=[telemetry, rates]"});
    const Scenario s = load_scenario("steps");
    for (int motor = 0; motor < c.motors(); ++motor) {
      if (!test::in_sim_grid(motor, c.motors())) continue;
      SCOPED_TRACE(std::string(file) + " m" + std::to_string(motor + 1));
      const SimResult r = fly_unreported(c, s, motor, 10.5, FailureKind::kTelemetry);
      EXPECT_FALSE(r.crashed);
      EXPECT_EQ(r.false_detections, 0);
    }
  }
}

// The outputs source, the slow last resort, in closed loop: an octo X
// (a hexa falls before its second of persistence: SIM.md) losing each motor
// with the strategies that drive the motor that lost thrust to full
// (prioritized, shift): found every time, and the motor named is the one
// that stopped (a detector naming a fixed motor passes one motor in eight).
TEST(DetectedFailures, TheOutputsSourceNamesTheMotorThatStopped) {
  int flights = 0;
  for (const char* strategy : {"prioritized", "shift"}) {
    const config::Config c = load("octo_x.yaml", {"failure_detection.sources=[outputs]",
                                                  std::string("mixer.strategy=") + strategy});
    // The scorecard's cell: motor_out, its own failure replaced by each motor's at 6 s.
    Scenario s = load_scenario("motor_out");
    s.timeline.erase(std::remove_if(s.timeline.begin(), s.timeline.end(),
                                    [](const ScenarioEvent& e) { return e.fail.has_value(); }),
                     s.timeline.end());
    for (int motor = 0; motor < c.motors(); ++motor) {
      if (!test::in_sim_grid(motor, c.motors())) continue;
      for (int k = 0; k < test::sim_grid_seeds(2); ++k) {
        const int seed = fresh_seed(200 + k);
        SCOPED_TRACE(std::string(strategy) + " m" + std::to_string(motor + 1) + " seed " +
                     std::to_string(seed));
        const SimResult r =
            fly_unreported(c, s, motor, 6.0, FailureKind::kStop, seed, {}, kPromptStop);
        ++flights;
        ASSERT_EQ(r.failures.size(), 1U);
        const FailureOutcome& f = r.failures.front();
        EXPECT_FALSE(r.crashed) << r.crash_reason;
        EXPECT_EQ(r.false_detections, 0);
        EXPECT_GE(f.detected_at_s, 0.0) << "not found";
        EXPECT_EQ(f.detected_motor, motor);
        EXPECT_EQ(f.detected_by, DetectionSource::kOutputs);
      }
    }
  }
  if (!test::reduced_sim_grid()) {
    EXPECT_EQ(flights, 32);
  }
}

// A loose telemetry wire on a working motor (#51): on every aircraft preset,
// with every source set that takes telemetry, the vehicle keeps flying. No
// spin landing ever starts, a quad never declares the motor (silence alone
// is declared only on six rotors or more, without the rates source), and
// the altitude holds.
constexpr double kLooseWireAltitudeM = 0.5;
TEST(DetectedFailures, ALooseTelemetryWireNeverStartsALandingOnAnyAircraft) {
  const Scenario s = load_scenario("hover");
  int flights = 0;
  for (const char* file :
       {"quad_x.yaml", "quad_plus.yaml", "team_quad.yaml", "hexa_x.yaml", "hexa_plus.yaml",
        "h_hexa.yaml", "y6.yaml", "octo_x.yaml", "octo_plus.yaml", "octo_coax_x8.yaml"}) {
    for (const char* sources :
         {"[telemetry]", "[telemetry, rates]", "[telemetry, rates, outputs]"}) {
      const config::Config probe = load(file, {});
      if (probe.motors() < 6 && std::string(sources).find("outputs") != std::string::npos)
        continue;  // the outputs source needs six rotors (refused at load)
      const config::Config c = load(file, {std::string("failure_detection.sources=") + sources});
      for (int motor = 0; motor < c.motors(); ++motor) {
        if (!test::in_sim_grid(motor, c.motors())) continue;
        SCOPED_TRACE(std::string(file) + " " + sources + " m" + std::to_string(motor + 1));
        bool landing = false;
        const FrameObserver watch = [&landing](const SimFrame& f) {
          landing = landing || f.cycle->landing.state != DescentPhase::kOff;
        };
        const SimResult r = fly_unreported(c, s, motor, 8.0, FailureKind::kTelemetry, 1, watch);
        ++flights;
        EXPECT_FALSE(r.crashed) << r.crash_reason;
        EXPECT_FALSE(landing) << "a spin landing started";
        EXPECT_TRUE(r.reached_altitude);
        EXPECT_LE(r.altitude_error_max_m, kLooseWireAltitudeM);
        if (c.motors() < 6) {
          EXPECT_TRUE(r.declarations.empty()) << "a quad stopped a working motor";
        }
      }
    }
  }
  EXPECT_GE(flights, test::reduced_sim_grid() ? 40 : 100);
}

TEST(DetectedFailures, WhatFlewWithoutTheDetectorFliesWithIt) {
  for (const char* file : {"hexa_x.yaml", "octo_x.yaml"}) {
    const config::Config off = load(file, {});
    const config::Config on = load(file, {"failure_detection.enabled=true"});
    const Scenario s = load_scenario("steps");
    for (FailureKind kind : {FailureKind::kHalfThrust, FailureKind::kIntermittent,
                             FailureKind::kDesync, FailureKind::kTelemetry}) {
      for (int motor = 0; motor < off.motors(); ++motor) {
        if (!test::in_sim_grid(motor, off.motors())) continue;
        SCOPED_TRACE(std::string(file) + " " + to_string(kind) + " m" + std::to_string(motor + 1));
        SimOptions o;
        o.undetected = true;
        o.failures.push_back({motor, 10.5, kind});
        const SimResult without = run_lockstep(off, config::build_mixer(off), s, o);
        const SimResult with = run_lockstep(on, config::build_mixer(on), s, o);
        if (!without.crashed) {
          EXPECT_FALSE(with.crashed) << with.crash_reason;
        }
        EXPECT_EQ(with.false_detections, 0);
      }
    }
  }
}

}  // namespace
}  // namespace motormix::sim
