#pragma once
// The client side of the motor test (`motormix motor-test`), with time
// passed in: asks a running, disarmed `motormix run` to spin each motor of
// a list in turn, waits for the mixer's answer to that very request (its
// status echoes the request's utime), stops at the first refusal or
// silence, waits for each test to end before the next, and asks the mixer
// to stop the test when interrupted. The rules a test must satisfy are the
// mixer's (loop/motor_test_runner.hpp); this only asks and reports.

#include "loop/motor_test_runner.hpp"

#include <cstdint>
#include <vector>

namespace motormix::bringup {

// What the mixer's latest status says of motor tests.
struct MotorTestAnswer {
  std::int64_t request_utime = 0;
  loop::MotorTestResult result = loop::MotorTestResult::kOk;
  bool running = false;
};

class MotorTestClient {
 public:
  static constexpr double kPauseBetweenS = 1.0;  // in a sequence, between two motors
  static constexpr double kEndGraceS = 1.0;      // past a test's duration, waiting for its end

  // motors: 0-based, in the order to test.
  MotorTestClient(std::vector<int> motors, double throttle, double seconds, double wait_s);

  struct Action {
    enum class Kind {
      kSend,      // publish a request: motor (1-based; 0 stops), throttle, seconds, utime
      kSpinning,  // the mixer obeyed: motor `motor` spins (tell the user), keep serving
      kWait,      // keep serving the bus
      kDone,
      kNoAnswer,  // no answer within wait_s: is the mixer running?
      kRefused,   // refused, with `refusal`
      kStopped,   // interrupted: a stop request was sent
    } kind = Kind::kWait;
    int motor = 0;  // 1-based for kSend and kSpinning
    double throttle = 0.0;
    double seconds = 0.0;
    std::int64_t utime = 0;
    loop::MotorTestResult refusal = loop::MotorTestResult::kOk;
  };

  // latest: the mixer's latest answer, if any status was heard. utime: this
  // host's wall clock, stamped on a request sent now.
  Action step(double now_s, std::int64_t utime, const MotorTestAnswer* latest);
  void on_interrupt() { interrupted_ = true; }
  bool finished() const { return finished_; }

 private:
  enum class State { kIdle, kAsked, kSpinning, kPausing };
  std::vector<int> motors_;
  double throttle_, seconds_, wait_s_;
  std::size_t next_ = 0;
  State state_ = State::kIdle;
  double since_s_ = 0.0;
  std::int64_t asked_utime_ = 0;
  bool interrupted_ = false;
  bool finished_ = false;
};

}  // namespace motormix::bringup
