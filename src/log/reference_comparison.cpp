#include "log/reference_comparison.hpp"

#include "bus/receive.hpp"

#include <algorithm>
#include <cmath>

namespace motormix::lcmlog {

namespace {

// A command this close to 0 or 1 is at the end of its range.
constexpr double kAtLimit = 1e-6;

bool at_limit(double c) { return c <= kAtLimit || c >= 1.0 - kAtLimit; }

}  // namespace

ReferenceComparer::ReferenceComparer(std::string channel, int motors)
    : motors_(motors), differences_(static_cast<std::size_t>(motors)) {
  result_.channel = std::move(channel);
}

void ReferenceComparer::on_output(const motor_pwm_t& out, std::uint8_t limited, bool spooling_up) {
  Output o{out.setpoint_utime, out.pid_utime, out.armed != 0, limited, spooling_up, {}};
  std::copy_n(out.command.begin(), std::min<std::size_t>(out.command.size(), o.command.size()),
              o.command.begin());
  recent_.push_back(o);
  if (recent_.size() > kRecentOutputs) recent_.pop_front();
}

void ReferenceComparer::on_reference(const void* data, int size, double t_s) {
  ++result_.references;
  // Through the bus library's door: wire shape and lengths checked first.
  motor_pwm_t ref{};
  if (size < 0 ||
      bus::decode_exact(data, static_cast<std::size_t>(size), ref) != bus::Refusal::kNone ||
      ref.num_motors != motors_) {
    ++result_.unpaired;
    return;
  }
  if (!ref.armed) {
    ++result_.reference_disarmed;
    return;
  }
  // The latest output from exactly these inputs: after both had arrived.
  const auto mine = std::find_if(recent_.rbegin(), recent_.rend(), [&](const Output& o) {
    return o.setpoint_utime == ref.setpoint_utime && o.pid_utime == ref.pid_utime;
  });
  if (mine == recent_.rend()) {
    ++result_.unpaired;
    return;
  }
  if (!mine->armed) {
    ++result_.motormix_disarmed;
    return;
  }
  ++result_.compared;
  double largest = 0.0;
  bool saturated = false;
  for (int i = 0; i < motors_; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const double ours = mine->command[k], theirs = ref.command[k];
    const double d = std::abs(ours - theirs);
    differences_[k].push_back(d);
    largest = std::max(largest, d);
    saturated = saturated || at_limit(ours) || at_limit(theirs);
    if (d > result_.worst) {
      result_.worst = d;
      result_.worst_motor = i + 1;
      result_.worst_at_s = t_s;
    }
  }
  if (largest <= ReferenceComparison::kSameCommand) return;
  if (mine->spooling_up) {
    ++result_.differing_spool_up;
  } else if (saturated) {
    ++result_.differing_saturated;
  } else if (mine->limited != 0) {
    ++result_.differing_limited;
  } else {
    ++result_.differing_other;
  }
}

ReferenceComparison ReferenceComparer::finish() {
  result_.max_difference.assign(static_cast<std::size_t>(motors_), 0.0);
  result_.p99_difference.assign(static_cast<std::size_t>(motors_), 0.0);
  for (std::size_t k = 0; k < differences_.size(); ++k) {
    std::vector<double>& d = differences_[k];
    if (d.empty()) continue;
    std::sort(d.begin(), d.end());
    result_.max_difference[k] = d.back();
    // Nearest rank.
    const auto rank = static_cast<std::size_t>(std::ceil(0.99 * static_cast<double>(d.size())));
    result_.p99_difference[k] = d[std::max<std::size_t>(rank, 1) - 1];
  }
  return result_;
}

}  // namespace motormix::lcmlog
