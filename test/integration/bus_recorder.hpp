#pragma once
// Records the mixer's outputs from the bus on a background thread and lets a
// test wait, with a bounded timeout, for a condition on what has arrived.

#include <motormix/mixer_status_t.hpp>
#include <motormix/motor_pwm_t.hpp>
#include <motormix/signing.hpp>

#include <lcm/lcm-cpp.hpp>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace motormix::test {

class BusRecorder {
 public:
  // keep_pwm = false: count motor_pwm_t messages and keep only the last one
  // (long runs: the soak would otherwise hold hundreds of thousands).
  // A signed message is read as a reader that does not verify reads it (the
  // trailer cut off); with `key`, every message is also verified and the
  // ones that do not verify are counted (unverified()).
  BusRecorder(const std::string& pwm_channel, const std::string& status_channel,
              bool keep_pwm = true, const signing::Key* key = nullptr)
      : keep_pwm_(keep_pwm), verifier_(key ? std::make_unique<signing::Verifier>(*key) : nullptr) {
    lcm_.subscribe(pwm_channel, &BusRecorder::on_pwm, this)->setQueueCapacity(100000);
    lcm_.subscribe(status_channel, &BusRecorder::on_status, this)->setQueueCapacity(100000);
    thread_ = std::thread([this] {
      while (!stop_) lcm_.handleTimeout(20);
    });
  }
  ~BusRecorder() {
    stop_ = true;
    thread_.join();
  }
  BusRecorder(const BusRecorder&) = delete;
  BusRecorder& operator=(const BusRecorder&) = delete;

  bool good() { return lcm_.good(); }

  // Waits until `done(pwm, status)` holds; false on timeout.
  bool wait_until(const std::function<bool(const std::vector<motor_pwm_t>&,
                                           const std::vector<mixer_status_t>&)>& done,
                  std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    return changed_.wait_for(lock, timeout, [&] { return done(pwm_, status_); });
  }

  std::vector<motor_pwm_t> pwm() {
    std::lock_guard<std::mutex> lock(mutex_);
    return pwm_;
  }
  std::vector<mixer_status_t> status() {
    std::lock_guard<std::mutex> lock(mutex_);
    return status_;
  }
  std::vector<std::chrono::steady_clock::time_point> pwm_times() {
    std::lock_guard<std::mutex> lock(mutex_);
    return pwm_times_;
  }
  // For each status_ entry, how many motor_pwm_t messages had arrived before
  // it. The mixer publishes a cycle's outputs, then its status, on one
  // socket, so with a status every cycle, entry k's outputs are pwm_[n_k - 1].
  std::vector<std::size_t> pwm_before_status() {
    std::lock_guard<std::mutex> lock(mutex_);
    return pwm_before_status_;
  }
  std::size_t pwm_count() {
    std::lock_guard<std::mutex> lock(mutex_);
    return pwm_seen_;
  }
  motor_pwm_t last_pwm() {
    std::lock_guard<std::mutex> lock(mutex_);
    return last_pwm_;
  }
  int undecodable() {
    std::lock_guard<std::mutex> lock(mutex_);
    return undecodable_;
  }
  // Messages that carried a signature / that did not verify (with a key).
  int signed_messages() {
    std::lock_guard<std::mutex> lock(mutex_);
    return signed_;
  }
  int unverified() {
    std::lock_guard<std::mutex> lock(mutex_);
    return unverified_;
  }

 private:
  // Untyped subscriptions, decoded here: undecodable messages are counted
  // as failures of the test, not skipped by LCM with a line on stderr.
  template <typename Message>
  bool decode(const lcm::ReceiveBuffer* rbuf, const std::string& channel, Message& msg) {
    const auto* data = static_cast<const std::uint8_t*>(rbuf->data);
    std::size_t size = rbuf->data_size;
    if (signing::has_trailer(data, size)) {
      std::lock_guard<std::mutex> lock(mutex_);
      ++signed_;
    }
    if (verifier_) {
      // Only this thread verifies; the count is read under the mutex.
      const auto v = verifier_->verify(channel, data, size, wall_clock_us(), &size);
      if (v != signing::Verdict::kSigned) {
        std::lock_guard<std::mutex> lock(mutex_);
        ++unverified_;
      }
    } else if (signing::has_trailer(data, size)) {
      size -= signing::kTrailerBytes;
    }
    return msg.decode(rbuf->data, 0, static_cast<int>(size)) == static_cast<int>(size);
  }
  static std::int64_t wall_clock_us() {
    return std::chrono::duration_cast<std::chrono::microseconds>(
               std::chrono::system_clock::now().time_since_epoch())
        .count();
  }
  void on_pwm(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    motor_pwm_t msg{};
    const bool ok = decode(rbuf, channel, msg);
    std::lock_guard<std::mutex> lock(mutex_);
    if (!ok) {
      ++undecodable_;
    } else {
      ++pwm_seen_;
      last_pwm_ = msg;
      if (keep_pwm_) {
        pwm_.push_back(msg);
        pwm_times_.push_back(std::chrono::steady_clock::now());
      }
    }
    changed_.notify_all();
  }
  void on_status(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    mixer_status_t msg{};
    const bool ok = decode(rbuf, channel, msg);
    std::lock_guard<std::mutex> lock(mutex_);
    if (ok) {
      status_.push_back(msg);
      pwm_before_status_.push_back(pwm_seen_);
    } else {
      ++undecodable_;
    }
    changed_.notify_all();
  }

  const bool keep_pwm_;
  std::unique_ptr<signing::Verifier> verifier_;
  int signed_ = 0;
  int unverified_ = 0;
  lcm::LCM lcm_;
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<motor_pwm_t> pwm_;
  std::vector<mixer_status_t> status_;
  std::vector<std::chrono::steady_clock::time_point> pwm_times_;  // arrival of each pwm_ entry
  std::vector<std::size_t> pwm_before_status_;                    // see pwm_before_status()
  std::size_t pwm_seen_ = 0;
  motor_pwm_t last_pwm_{};
  int undecodable_ = 0;
  std::thread thread_;
};

}  // namespace motormix::test
