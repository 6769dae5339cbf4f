#include "output/kiss_telemetry.hpp"

#include <algorithm>
#include <cmath>

namespace motormix::output {

namespace {

// Beyond these no ESC reports: a frame claiming them is noise that matched
// the CRC (1 in 256 of random windows).
constexpr double kMaxTemperatureC = 150.0;
constexpr double kMaxVoltageV = 80.0;

std::uint16_t be16(const std::uint8_t* p) { return static_cast<std::uint16_t>((p[0] << 8) | p[1]); }

}  // namespace

std::uint8_t kiss_crc8(const std::uint8_t* data, std::size_t len) {
  std::uint8_t crc = 0;
  for (std::size_t i = 0; i < len; ++i) {
    crc ^= data[i];
    for (int b = 0; b < 8; ++b) {
      crc = static_cast<std::uint8_t>((crc & 0x80) != 0 ? (crc << 1) ^ 0x07 : crc << 1);
    }
  }
  return crc;
}

bool KissTelemetryParser::feed(std::uint8_t byte, std::int64_t now_us, KissReading& out) {
  if (any_ && now_us - last_us_ > kGapUs) {
    if (have_ > 0) ++rejected_;  // a frame cut short
    have_ = 0;
  }
  any_ = true;
  last_us_ = now_us;
  if (have_ == kFrameBytes) {  // slide: the window held no frame
    std::copy(window_.begin() + 1, window_.end(), window_.begin());
    --have_;
  }
  window_[have_++] = byte;
  if (have_ < kFrameBytes) return false;
  if (kiss_crc8(window_.data(), kFrameBytes - 1) != window_[kFrameBytes - 1]) return false;
  KissReading r;
  r.temperature_c = window_[0];
  r.voltage_v = be16(&window_[1]) / 100.0;
  r.current_a = be16(&window_[3]) / 100.0;
  r.consumption_mah = be16(&window_[5]);
  r.erpm = be16(&window_[7]) * 100.0;
  have_ = 0;
  if (r.temperature_c > kMaxTemperatureC || r.voltage_v > kMaxVoltageV) {
    ++rejected_;
    return false;
  }
  ++frames_;
  out = r;
  return true;
}

}  // namespace motormix::output
