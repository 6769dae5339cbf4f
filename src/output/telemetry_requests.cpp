#include "output/telemetry_requests.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace motormix::output {

namespace {
constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
}  // namespace

std::vector<int> wired_motors(const config::Hardware& hardware) {
  std::vector<int> wired;
  for (const config::TelemetryPort& p : hardware.telemetry) wired.push_back(p.motor);
  return wired;
}

TelemetryRequests::TelemetryRequests(std::vector<int> wired, double answer_window_s)
    : wired_(std::move(wired)), open_since_s_(wired_.size(), kNone), window_s_(answer_window_s) {}

int TelemetryRequests::next() const { return wired_.empty() ? -1 : wired_[next_]; }

void TelemetryRequests::expire(std::size_t slot, double now_s) {
  double& since = open_since_s_[slot];
  if (!std::isnan(since) && now_s - since > window_s_) {
    ++counts_.unanswered;
    since = kNone;
  }
}

void TelemetryRequests::asked(int channel, double at_s) {
  const auto it = std::find(wired_.begin(), wired_.end(), channel);
  if (it == wired_.end()) return;
  const auto slot = static_cast<std::size_t>(it - wired_.begin());
  expire(slot, at_s);
  // A request still open when the next goes to the same ESC was not answered.
  if (!std::isnan(open_since_s_[slot])) ++counts_.unanswered;
  open_since_s_[slot] = at_s;
  ++counts_.asked;
  next_ = (slot + 1) % wired_.size();
}

std::optional<double> TelemetryRequests::answered(int channel, double now_s) {
  const auto it = std::find(wired_.begin(), wired_.end(), channel);
  if (it == wired_.end()) {
    ++counts_.unasked;
    return std::nullopt;
  }
  const auto slot = static_cast<std::size_t>(it - wired_.begin());
  expire(slot, now_s);
  const double since = open_since_s_[slot];
  if (std::isnan(since) || since > now_s) {
    ++counts_.unasked;
    return std::nullopt;
  }
  open_since_s_[slot] = kNone;
  ++counts_.answered;
  return since;
}

}  // namespace motormix::output
