#pragma once
// The latest accepted message of one input stream and when it arrived: the
// one freshness rule every input of the loop follows (setpoint, pid,
// battery, motor_status). A stream is fresh while its latest accepted
// message is no older than the stream's timeout, by this host's monotonic
// clock; a rejected message changes nothing here, so the previous one
// keeps ageing toward its timeout.

#include <cstdint>
#include <limits>

namespace motormix::loop {

// Before the first message: no utime to be out of order against, no age.
inline constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::min();

template <typename Sample>
class LatestInput {
 public:
  // `sample` passed its checks at monotonic time now_us.
  void accept(const Sample& sample, std::int64_t now_us) {
    sample_ = sample;
    received_us_ = now_us;
  }

  bool any() const { return received_us_ != kNever; }
  // The accepted sample; a default (all zero) one before the first.
  const Sample& sample() const { return sample_; }
  // The publisher's utime of the sample in force, kNever before the first:
  // what the next one is checked for order against.
  std::int64_t last_utime() const { return any() ? sample_.utime : kNever; }
  // The same, 0 before the first (as messages report it).
  std::int64_t utime_or_zero() const { return any() ? sample_.utime : 0; }

  bool fresh(std::int64_t now_us, std::int64_t timeout_us) const {
    // received_us_ is kNever (most negative) until the first message:
    // compared without subtracting, to stay clear of overflow.
    return any() && now_us - received_us_ <= timeout_us;
  }
  // Milliseconds since the sample in force arrived; -1 before the first.
  double age_ms(std::int64_t now_us) const {
    return any() ? static_cast<double>(now_us - received_us_) / 1e3 : -1.0;
  }

 private:
  Sample sample_{};
  std::int64_t received_us_ = kNever;
};

}  // namespace motormix::loop
