#include "bidir_esc.hpp"

#include <algorithm>
#include <cmath>

namespace motormix::avr {
namespace {
constexpr double kCpuCyclesPerUs = 16.0;
constexpr int kReplyBits = 21;
// Nibble -> GCR code (the decoding table of the flight controllers,
// inverted).
constexpr std::uint8_t kGcr[16] = {0x19, 0x1B, 0x12, 0x13, 0x1D, 0x15, 0x16, 0x17,
                                   0x1A, 0x09, 0x0A, 0x0B, 0x1E, 0x0D, 0x0E, 0x0F};
constexpr std::uint16_t kStoppedCode = 0xFFF;
}  // namespace

std::uint16_t erpm_period_us(double erpm) {
  const double period = erpm > 0.0 ? 60e6 / erpm : 1e9;
  if (period >= 511.0 * 128.0) return static_cast<std::uint16_t>(511u << 7);
  auto p = static_cast<std::uint32_t>(std::lround(period));
  unsigned e = 0;
  while ((p >> e) > 511u) ++e;
  return static_cast<std::uint16_t>((p >> e) << e);
}

namespace {
// The 12-bit exponent/mantissa code of a period erpm_period_us made.
std::uint16_t period_code(std::uint16_t period_us) {
  if (static_cast<unsigned>(period_us) >= (511u << 7)) return kStoppedCode;
  unsigned e = 0;
  while ((static_cast<unsigned>(period_us) >> e) > 511u) ++e;
  return static_cast<std::uint16_t>((e << 9) | (static_cast<unsigned>(period_us) >> e));
}
}  // namespace

BidirEscs::BidirEscs(AvrBoard& board, int count, double frame_bit_cycles, BidirEscNoise noise)
    : board_(board),
      reply_bit_cycles_(frame_bit_cycles * 4.0 / 5.0),
      noise_(noise),
      rng_(noise.seed),
      erpm_(static_cast<std::size_t>(count), 0.0),
      answers_(static_cast<std::size_t>(count)) {
  std::uniform_real_distribution<double> clock(-noise.clock_error_max, noise.clock_error_max);
  for (int ch = 0; ch < count; ++ch) {
    escs_.emplace_back(ch, frame_bit_cycles, true);
    clock_.push_back(1.0 + clock(rng_));
  }
  board_.set_edge_listener([this](const PinEdge& e) { on_edge(e); });
}

void BidirEscs::on_edge(const PinEdge& e) {
  if (e.channel < 0 || e.channel >= static_cast<int>(escs_.size())) return;
  const auto ch = static_cast<std::size_t>(e.channel);
  escs_[ch].feed(e);
  for (const DshotFrame& f : escs_[ch].take_frames()) {
    if (follow_erpm_ > 0.0 && f.crc_ok) {
      constexpr double kMinThrottle = 48.0, kSteps = 1999.0;
      erpm_[ch] = f.value >= kMinThrottle ? follow_erpm_ * (f.value - kMinThrottle) / kSteps : 0.0;
    }
    if ((stopped_.load() >> ch) & 1u) erpm_[ch] = 0.0;
    Answer a;
    a.frame = f;
    a.erpm = erpm_[ch];
    std::uniform_real_distribution<double> u(0.0, 1.0);
    if (f.crc_ok && u(rng_) >= noise_.lost_share) {
      a.sent = erpm_period_us(a.erpm);
      a.spiked = u(rng_) < noise_.spike_share;
      reply(e.channel, e.cycle, a.sent);
      if (a.spiked) {
        // A spike somewhere in the reply: the other level for 2-4 cycles.
        const double at = u(rng_) * kReplyBits * reply_bit_cycles_;
        const auto start = static_cast<std::uint64_t>(static_cast<double>(e.cycle) + at +
                                                      noise_.delay_us_min * kCpuCyclesPerUs);
        const bool level = !board_.pin_high(e.channel);
        board_.drive_at(start, e.channel, level);
        board_.drive_at(start + 2 + static_cast<std::uint64_t>(u(rng_) * 3.0), e.channel, !level);
      }
    }
    answers_[ch].push_back(a);
  }
}

void BidirEscs::reply(int channel, std::uint64_t after_cycle, std::uint16_t period_us) {
  const std::uint16_t code = period_code(period_us);
  unsigned sum = code ^ (code >> 4) ^ (code >> 8);
  const auto value = static_cast<std::uint16_t>((code << 4) | (~sum & 0x0Fu));
  std::uint32_t bits = 1;  // the start bit
  for (int q = 3; q >= 0; --q) bits = (bits << 5) | kGcr[(value >> (4 * q)) & 0x0Fu];
  std::uniform_real_distribution<double> delay(noise_.delay_us_min, noise_.delay_us_max);
  std::uniform_real_distribution<double> jitter(-noise_.edge_jitter_cycles,
                                                noise_.edge_jitter_cycles);
  const double bit = reply_bit_cycles_ * clock_[static_cast<std::size_t>(channel)];
  const double start = static_cast<double>(after_cycle) + delay(rng_) * kCpuCyclesPerUs;
  bool level = true;  // idle
  for (int i = 0; i < kReplyBits; ++i) {
    if (((bits >> (kReplyBits - 1 - i)) & 1u) == 0u) continue;
    level = !level;
    const double at = start + i * bit + jitter(rng_);
    board_.drive_at(static_cast<std::uint64_t>(std::max(at, 0.0)), channel, level);
  }
  // Released: the pull-ups take the line back up at the end of the last bit.
  if (!level) {
    const double at = start + kReplyBits * bit + jitter(rng_);
    board_.drive_at(static_cast<std::uint64_t>(at), channel, true);
  }
}

}  // namespace motormix::avr
