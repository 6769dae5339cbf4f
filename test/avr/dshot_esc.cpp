#include "dshot_esc.hpp"

#include <algorithm>

namespace motormix::avr {

namespace {
constexpr std::size_t kBits = 16;
constexpr double kFrameGapBits = 3.0;
}  // namespace

DshotEsc::DshotEsc(int channel, double nominal_bit_cycles, bool inverted)
    : channel_(channel), nominal_(nominal_bit_cycles), inverted_(inverted) {}

void DshotEsc::feed(const std::vector<PinEdge>& edges) {
  for (const PinEdge& e : edges) feed(e);
}

void DshotEsc::feed(const PinEdge& e) {
  const bool active = inverted_ ? !e.high : e.high;
  if (e.by_esc || e.channel != channel_ || active == high_) return;
  high_ = active;
  if (active) {
    // A rise long after the last edge starts a frame; what was there
    // and is not a whole frame is broken.
    const std::uint64_t last = !falls_.empty() ? falls_.back() : 0;
    if (!rises_.empty() && static_cast<double>(e.cycle - last) > kFrameGapBits * nominal_) {
      ++broken_;
      rises_.clear();
      falls_.clear();
    }
    rises_.push_back(e.cycle);
  } else if (!rises_.empty()) {
    falls_.push_back(e.cycle);
    if (falls_.size() == kBits) finish();
  }
}

void DshotEsc::finish() {
  DshotFrame f{};
  f.start_cycle = rises_.front();
  f.bit_mean = static_cast<double>(rises_[15] - rises_[0]) / 15.0;
  f.bit_min = 1e9;
  double frame_bit = 0.0;  // the mean bit: the decision threshold is half of it
  for (std::size_t i = 1; i < kBits; ++i) {
    const double bit = static_cast<double>(rises_[i] - rises_[i - 1]);
    f.bit_min = std::min(f.bit_min, bit);
    f.bit_max = std::max(f.bit_max, bit);
    frame_bit += bit / (kBits - 1);
  }
  std::uint16_t word = 0;
  f.zero_high_min = f.one_high_min = 1e9;
  for (std::size_t i = 0; i < kBits; ++i) {
    const double high = static_cast<double>(falls_[i] - rises_[i]);
    const bool one = high > frame_bit / 2.0;
    word = static_cast<std::uint16_t>((word << 1) | (one ? 1u : 0u));
    double& lo = one ? f.one_high_min : f.zero_high_min;
    double& hi = one ? f.one_high_max : f.zero_high_max;
    lo = std::min(lo, high);
    hi = std::max(hi, high);
  }
  if (f.zero_high_min > 1e8) f.zero_high_min = 0.0;
  if (f.one_high_min > 1e8) f.one_high_min = 0.0;
  const std::uint16_t data = static_cast<std::uint16_t>(word >> 4);
  f.value = static_cast<std::uint16_t>(data >> 1);
  f.telemetry = (data & 1u) != 0;
  unsigned sum = data ^ (data >> 4) ^ (data >> 8);
  if (inverted_) sum = ~sum;
  f.crc_ok = (sum & 0x0Fu) == (word & 0x0Fu);
  frames_.push_back(f);
  rises_.clear();
  falls_.clear();
}

std::vector<DshotFrame> DshotEsc::take_frames() {
  std::vector<DshotFrame> out;
  out.swap(frames_);
  return out;
}

}  // namespace motormix::avr
