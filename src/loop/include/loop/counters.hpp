#pragma once
// What the loop counted since start: cycles, accepted messages, rejections
// by reason (of what a message says: its bytes were the bus's to refuse,
// bus::Refusals), failsafes, refusals. Reported in mixer_status_t and summed over
// the stretches of a replayed log.

#include <array>
#include <cstdint>

namespace motormix::loop {

struct Counters {
  std::int64_t cycles = 0;
  std::int64_t setpoint_received = 0;
  std::int64_t pid_received = 0;
  std::int64_t rejected_nonfinite = 0;
  std::int64_t rejected_range = 0;
  std::int64_t rejected_out_of_order = 0;
  std::int64_t rejected_future = 0;
  std::int64_t failsafe_events = 0;
  std::int64_t arming_refused = 0;                     // armed requests refused by the arming check
  std::int64_t arming_refused_throttle = 0;            // ... the throttle above arm_max_throttle
  std::int64_t arming_refused_not_disarmed_first = 0;  // ... no armed=false first
  std::int64_t motor_status_received = 0;
  std::int64_t battery_received = 0;
  std::int64_t rejected_size = 0;  // wrong array sizes
  std::int64_t motor_tests_started = 0;
  std::int64_t motor_tests_refused = 0;
  std::int64_t esc_telemetry_received = 0;
  std::int64_t attitude_received = 0;

  std::int64_t rejected() const {
    return rejected_nonfinite + rejected_range + rejected_out_of_order + rejected_future +
           rejected_size;
  }

  // Every counter once: the sum below walks this list, and the
  // static_assert after the struct fails the build when a counter is added
  // above but not here.
  static constexpr std::array kAll = {&Counters::cycles,
                                      &Counters::setpoint_received,
                                      &Counters::pid_received,
                                      &Counters::rejected_nonfinite,
                                      &Counters::rejected_range,
                                      &Counters::rejected_out_of_order,
                                      &Counters::rejected_future,
                                      &Counters::failsafe_events,
                                      &Counters::arming_refused,
                                      &Counters::arming_refused_throttle,
                                      &Counters::arming_refused_not_disarmed_first,
                                      &Counters::motor_status_received,
                                      &Counters::battery_received,
                                      &Counters::rejected_size,
                                      &Counters::motor_tests_started,
                                      &Counters::motor_tests_refused,
                                      &Counters::esc_telemetry_received,
                                      &Counters::attitude_received};

  Counters& operator+=(const Counters& other) {
    for (const auto field : kAll) this->*field += other.*field;
    return *this;
  }
};
static_assert(sizeof(Counters) == Counters::kAll.size() * sizeof(std::int64_t),
              "a counter is missing from Counters::kAll");

}  // namespace motormix::loop
