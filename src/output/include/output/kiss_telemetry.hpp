#pragma once
// The ESC telemetry frame of KISS and BLHeli_32 ESCs, read from their
// telemetry wire (115200 baud, one ESC answering at a time): 10 bytes with
// no header, temperature (deg C), voltage (10 mV), current (10 mA),
// consumption (mAh), electrical rpm (100 eRPM), big-endian, then a CRC-8
// (polynomial 0x07) over the nine. Pure: bytes and their arrival time in,
// readings out, no I/O, no heap.
//
// With no header, a frame is found by its CRC over the last ten bytes, and
// a gap on the wire longer than a frame's transmission restarts the search
// (each answer follows a request, so frames arrive apart). A reading whose
// values no ESC could report is refused and counted like a CRC error.

#include <array>
#include <cstddef>
#include <cstdint>

namespace motormix::output {

std::uint8_t kiss_crc8(const std::uint8_t* data, std::size_t len);

struct KissReading {
  double temperature_c = 0.0;
  double voltage_v = 0.0;
  double current_a = 0.0;
  double consumption_mah = 0.0;
  double erpm = 0.0;
};

class KissTelemetryParser {
 public:
  static constexpr std::size_t kFrameBytes = 10;
  // A silence longer than this between two bytes starts a new frame (a
  // frame takes 0.87 ms at 115200 baud).
  static constexpr std::int64_t kGapUs = 2000;

  // One byte that arrived at now_us. True when it completed a valid frame
  // (then in *out).
  bool feed(std::uint8_t byte, std::int64_t now_us, KissReading& out);

  std::uint64_t frames() const { return frames_; }
  // Bursts that ended (a gap) with bytes no frame took, and frames with
  // values no ESC reports.
  std::uint64_t rejected() const { return rejected_; }

 private:
  std::array<std::uint8_t, kFrameBytes> window_{};
  std::size_t have_ = 0;
  std::int64_t last_us_ = 0;
  bool any_ = false;
  std::uint64_t frames_ = 0, rejected_ = 0;
};

}  // namespace motormix::output
