#pragma once
// Min, mean, max and 99th percentile of samples over a window (one status
// period). Storage is reserved at set-up; adding never allocates (samples
// beyond the capacity are counted in min/mean/max but left out of p99).

#include <algorithm>
#include <array>
#include <cstddef>
#include <limits>
#include <vector>

namespace motormix::node {

class WindowStats {
 public:
  explicit WindowStats(std::size_t capacity) { samples_.reserve(capacity); }

  void add(double v) {
    min_ = std::min(min_, v);
    max_ = std::max(max_, v);
    sum_ += v;
    ++count_;
    if (samples_.size() < samples_.capacity()) samples_.push_back(v);
  }

  // {min, mean, max, p99}; zeros for an empty window. Resets the window.
  std::array<float, 4> take() {
    std::array<float, 4> out{};
    if (count_ > 0) {
      const std::size_t k = (samples_.size() * 99) / 100;
      std::nth_element(samples_.begin(), samples_.begin() + static_cast<long>(k), samples_.end());
      out = {static_cast<float>(min_), static_cast<float>(sum_ / static_cast<double>(count_)),
             static_cast<float>(max_), static_cast<float>(samples_[k])};
    }
    samples_.clear();  // keeps the capacity
    min_ = std::numeric_limits<double>::infinity();
    max_ = -std::numeric_limits<double>::infinity();
    sum_ = 0.0;
    count_ = 0;
    return out;
  }

 private:
  std::vector<double> samples_;
  double min_ = std::numeric_limits<double>::infinity();
  double max_ = -std::numeric_limits<double>::infinity();
  double sum_ = 0.0;
  std::size_t count_ = 0;
};

}  // namespace motormix::node
