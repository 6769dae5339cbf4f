#include "bringup/motor_test_client.hpp"

#include <utility>

namespace motormix::bringup {

MotorTestClient::MotorTestClient(std::vector<int> motors, double throttle, double seconds,
                                 double wait_s)
    : motors_(std::move(motors)), throttle_(throttle), seconds_(seconds), wait_s_(wait_s) {}

MotorTestClient::Action MotorTestClient::step(double now_s, std::int64_t utime,
                                              const MotorTestAnswer* latest) {
  Action a;
  if (finished_) {
    a.kind = Action::Kind::kDone;
    return a;
  }
  if (interrupted_) {
    finished_ = true;
    a.kind = Action::Kind::kStopped;  // the caller sends the stop request (motor 0)
    a.utime = utime;
    return a;
  }
  const auto finish = [&](Action::Kind kind) {
    finished_ = true;
    a.kind = kind;
    return a;
  };
  switch (state_) {
    case State::kIdle:
      if (next_ >= motors_.size()) return finish(Action::Kind::kDone);
      a.kind = Action::Kind::kSend;
      a.motor = motors_[next_] + 1;
      a.throttle = throttle_;
      a.seconds = seconds_;
      a.utime = utime;
      asked_utime_ = utime;
      state_ = State::kAsked;
      since_s_ = now_s;
      return a;
    case State::kAsked:
      if (latest != nullptr && latest->request_utime == asked_utime_) {
        if (latest->result != loop::MotorTestResult::kOk) {
          a.refusal = latest->result;
          return finish(Action::Kind::kRefused);
        }
        a.kind = Action::Kind::kSpinning;
        a.motor = motors_[next_] + 1;
        state_ = State::kSpinning;
        since_s_ = now_s;
        return a;
      }
      if (now_s - since_s_ >= wait_s_) return finish(Action::Kind::kNoAnswer);
      return a;
    case State::kSpinning:
      // Until the mixer says the test is over, bounded by its duration.
      if ((latest != nullptr && !latest->running) || now_s - since_s_ >= seconds_ + kEndGraceS) {
        ++next_;
        state_ = State::kPausing;
        since_s_ = now_s;
      }
      return a;
    case State::kPausing:
      if (next_ >= motors_.size()) return finish(Action::Kind::kDone);
      if (now_s - since_s_ >= kPauseBetweenS) state_ = State::kIdle;
      return a;
  }
  return a;
}

}  // namespace motormix::bringup
