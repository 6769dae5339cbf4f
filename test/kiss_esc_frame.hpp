#pragma once
// A KISS/BLHeli_32 telemetry frame as an ESC sends it: the ESC's side of
// output/kiss_telemetry.hpp, for the tests that play the ESC. Its CRC-8
// (polynomial 0x07) is written here apart from the parser's, so that each
// checks the other.

#include "output/kiss_telemetry.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

namespace motormix::test {

inline std::array<std::uint8_t, output::KissTelemetryParser::kFrameBytes> kiss_esc_frame(
    const output::KissReading& r) {
  std::array<std::uint8_t, output::KissTelemetryParser::kFrameBytes> f{};
  // Values rounded and clamped to what the frame carries, big-endian.
  auto put = [&f](std::size_t at, double value) {
    const auto v = static_cast<std::uint16_t>(std::clamp(std::lround(value), 0L, 65535L));
    f[at] = static_cast<std::uint8_t>(v >> 8);
    f[at + 1] = static_cast<std::uint8_t>(v & 0xFF);
  };
  f[0] = static_cast<std::uint8_t>(std::clamp(std::lround(r.temperature_c), 0L, 255L));
  put(1, r.voltage_v * 100.0);
  put(3, r.current_a * 100.0);
  put(5, r.consumption_mah);
  put(7, r.erpm / 100.0);
  std::uint8_t crc = 0;
  for (std::size_t i = 0; i + 1 < f.size(); ++i) {
    crc ^= f[i];
    for (int b = 0; b < 8; ++b)
      crc = static_cast<std::uint8_t>((crc & 0x80) != 0 ? (crc << 1) ^ 0x07 : crc << 1);
  }
  f[f.size() - 1] = crc;
  return f;
}

}  // namespace motormix::test
