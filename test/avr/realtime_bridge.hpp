#pragma once
// The simulated board in real time behind a pseudo-terminal: a thread runs
// the firmware in simavr paced to the wall clock, passes bytes between the
// pty and the chip's UART, and records every pulse with the wall time its
// rising edge had (steady clock). `motormix output` opens the pty's other
// end as if it were the Nano's USB serial port.

#include "avr_board.hpp"
#include "bidir_esc.hpp"

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace motormix::avr {

struct TimedPulse {
  int channel;
  std::int64_t rise_wall_us;  // steady clock, microseconds: when it was seen to rise
  double width_us;
  std::uint64_t rise_cycle;  // the chip's: one per period, shared by its channels
};

class RealtimeBridge {
 public:
  explicit RealtimeBridge(const std::string& elf_path);
  // With ESCs on the pins answering bidirectional DShot (bidir_esc.hpp),
  // their motors following the throttle up to full_erpm; no edges or pulses
  // are kept (take_edges() and take_pulses() stay empty: a second of edges is
  // a million).
  struct Escs {
    int count = 4;
    double frame_bit_cycles = 16e6 / 600e3;  // DShot600
    double full_erpm = 140000.0;             // 14 poles at 20000 rpm
    BidirEscNoise noise;
  };
  RealtimeBridge(const std::string& elf_path, const Escs& escs);
  // The ESCs' motor stopping (see BidirEscs::stop_motor); needs the ESCs.
  void stop_motor(int channel) { escs_->stop_motor(channel); }
  ~RealtimeBridge();
  RealtimeBridge(const RealtimeBridge&) = delete;
  RealtimeBridge& operator=(const RealtimeBridge&) = delete;

  const std::string& device() const { return slave_path_; }
  std::vector<TimedPulse> take_pulses();
  // Every pin edge since the last call (DShot: 32 a frame a channel), with
  // the wall time it had (as a pulse's rise: now less the simulated time
  // since it).
  struct TimedEdge {
    PinEdge edge;
    std::int64_t wall_us;
  };
  std::vector<TimedEdge> take_edges();
  // How far the simulation fell behind the wall clock at worst, us.
  double max_lag_us() const { return max_lag_us_.load(); }
  void reset_max_lag() { max_lag_us_ = 0.0; }
  std::uint64_t bytes_in() const { return bytes_in_.load(); }
  void stop();

 private:
  void run();
  void open_pty_and_start();

  AvrBoard board_;
  std::unique_ptr<BidirEscs> escs_;
  bool keep_pin_records_ = true;
  int master_ = -1;
  std::string slave_path_;
  std::mutex mutex_;
  std::vector<TimedPulse> pulses_;
  std::vector<TimedEdge> edges_;
  std::atomic<bool> stop_{false};
  std::atomic<double> max_lag_us_{0.0};
  std::atomic<std::uint64_t> bytes_in_{0};
  std::thread thread_;
};

std::int64_t steady_us();

}  // namespace motormix::avr
