#pragma once
// A whole run's distribution of a loop time (how late each cycle woke, the
// time between cycles) in 1 microsecond bins, as cyclictest keeps its own:
// percentiles to the microsecond, and the exact largest value with when it
// happened, so that a stall can be matched with other processes' records.
// Storage is sized once; adding never allocates.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace motormix::node {

class LatencyHistogram {
 public:
  // Bin k holds the values in (k - 1, k] microseconds, so a bin's number is
  // a bound its values do not exceed. Values above `range_us` share the
  // last bin (their percentiles read as range_us); the largest is still
  // kept exactly.
  explicit LatencyHistogram(std::int64_t range_us = 20'000)
      : bins_(static_cast<std::size_t>(std::max<std::int64_t>(range_us, 1)) + 1, 0) {}

  // `at_us`: when it happened (any clock the caller reports in).
  void add(double value_us, std::int64_t at_us) {
    const double clamped =
        std::clamp(std::ceil(value_us), 0.0, static_cast<double>(bins_.size() - 1));
    ++bins_[static_cast<std::size_t>(clamped)];
    ++count_;
    sum_ += value_us;
    if (count_ == 1 || value_us > max_) {
      max_ = value_us;
      max_at_us_ = at_us;
    }
    if (count_ == 1 || value_us < min_) min_ = value_us;
  }

  std::int64_t count() const { return count_; }
  double max() const { return max_; }
  double min() const { return min_; }
  double mean() const { return count_ ? sum_ / static_cast<double>(count_) : 0.0; }
  std::int64_t max_at_us() const { return max_at_us_; }

  // The smallest whole microsecond that at least `fraction` of the values
  // do not exceed (0 when empty): the nearest-rank percentile, rounded up
  // to the microsecond.
  double percentile(double fraction) const {
    if (count_ == 0) return 0.0;
    const auto wanted =
        static_cast<std::int64_t>(std::ceil(fraction * static_cast<double>(count_)));
    std::int64_t seen = 0;
    for (std::size_t us = 0; us < bins_.size(); ++us) {
      seen += bins_[us];
      if (seen >= std::max<std::int64_t>(wanted, 1)) return static_cast<double>(us);
    }
    return static_cast<double>(bins_.size() - 1);
  }

 private:
  std::vector<std::int64_t> bins_;
  std::int64_t count_ = 0;
  double sum_ = 0.0;
  double max_ = 0.0;
  double min_ = 0.0;
  std::int64_t max_at_us_ = 0;
};

}  // namespace motormix::node
