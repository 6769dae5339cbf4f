#pragma once
// The simulated board in real time behind a pseudo-terminal: a thread runs
// the firmware in simavr paced to the wall clock, passes bytes between the
// pty and the chip's UART, and records every pulse with the wall time its
// rising edge had (steady clock). `motormix output` opens the pty's other
// end as if it were the Nano's USB serial port.

#include "avr_board.hpp"
#include "bidir_esc.hpp"

#include <algorithm>
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
  // Wall time (steady clock, us) in [from_us, to_us) when the chip was not
  // running: it fell behind the wall clock by more than a millisecond and
  // caught up by skipping the time (a busy machine; the chip's clock stood
  // still). A run judges real-time behaviour only where this is zero, and
  // counts what the chip could do in the time it ran.
  std::int64_t absent_us(std::int64_t from_us, std::int64_t to_us);
  bool present(std::int64_t from_us, std::int64_t to_us) { return absent_us(from_us, to_us) == 0; }
  // Sleeps until the chip has run `chip_ms` since `from_us` (the wall time
  // it was absent added), at most ten times that long.
  void wait_chip_time(std::int64_t from_us, double chip_ms);
  std::uint64_t bytes_in() const { return bytes_in_.load(); }
  // Wall time the simulation took per simulated second so far (its speed on
  // this machine, as busy as it is: above 1 it cannot keep real time).
  double cost() const {
    return static_cast<double>(busy_us_.load()) /
           static_cast<double>(std::max<std::uint64_t>(1, simulated_us_.load()));
  }
  // Stops the simulation. When the chip was absent for more than
  // kBusyShare of its life, or fell behind by more than kBusyStallUs at
  // once (the machine starved its thread, and likely the processes beside
  // it too), it says so on stdout with the tag [chip-busy]: the run could
  // not judge real time (test/avr/retry_when_busy.py runs such a failed
  // test again). A quiet machine: at most 0.8 % absent and 4.6 ms behind.
  void stop();
  // The chip's receiver over the whole run, at its real depth
  // (AvrBoard::overruns, longest_unread_us); stops the simulation first,
  // and prints them.
  struct Receiver {
    int overruns;
    double longest_unread_us;
  };
  Receiver receiver();
  static constexpr double kBusyShare = 0.02;
  static constexpr double kBusyStallUs = 5000.0;

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
  struct Absence {
    std::int64_t from_us, to_us;
  };
  std::vector<Absence> absences_;  // in order, merged
  std::atomic<bool> stop_{false};
  bool stopped_ = false;
  std::int64_t started_us_ = 0;
  std::atomic<double> max_lag_us_{0.0};
  double life_max_lag_us_ = 0.0;  // the run thread's, never reset
  std::atomic<std::uint64_t> bytes_in_{0};
  std::atomic<std::uint64_t> busy_us_{0}, simulated_us_{0};
  std::thread thread_;
};

std::int64_t steady_us();

}  // namespace motormix::avr
