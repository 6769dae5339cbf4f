#pragma once
// An Arduino Nano in simavr running the motormix pulse firmware
// (firmware/pulses): the ELF loaded into a simulated ATmega328P at 16 MHz,
// bytes into its UART at the wire rate, bytes out of it, and every edge of
// the eight pulse pins (D2..D9) with the cycle it happened on. For the
// firmware's tests and for the end-to-end bridge (avr_pty_bridge).

#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <queue>
#include <string>
#include <vector>

struct avr_t;
struct avr_irq_t;
struct avr_uart_t;

namespace motormix::avr {

constexpr double kCpuHz = 16e6;
constexpr int kChannels = 8;

struct PinEdge {
  std::uint64_t cycle;
  int channel;  // 0..7: D2..D9
  bool high;
  bool by_esc = false;  // driven from outside (drive_at: an ESC's reply), not by the chip
};

// A pulse as measured on a pin: where it rose, how long it was high.
struct Pulse {
  int channel;
  std::uint64_t rise_cycle;
  double width_us;
};

class AvrBoard {
 public:
  // Throws std::runtime_error if the ELF cannot be read or simavr lacks
  // the part.
  explicit AvrBoard(const std::string& elf_path, unsigned baud = 250000);
  ~AvrBoard();
  AvrBoard(const AvrBoard&) = delete;
  AvrBoard& operator=(const AvrBoard&) = delete;

  // Runs the core until its cycle counter reaches `cycle` (or it stops:
  // false then).
  bool run_until(std::uint64_t cycle);
  bool run_for_us(double us) { return run_until(cycle() + static_cast<std::uint64_t>(us * 16.0)); }
  std::uint64_t cycle() const;
  double now_us() const { return static_cast<double>(cycle()) / 16.0; }

  // Bytes to the firmware's RX pin, after those already queued, one per
  // byte time (10 bits): each is complete (its stop bit sampled, RXC set)
  // one byte time after its start bit, as on the chip.
  void send(const std::uint8_t* bytes, std::size_t n);
  void send(const std::vector<std::uint8_t>& bytes) { send(bytes.data(), bytes.size()); }
  bool sending() const { return !rx_.empty(); }
  // Bytes still to go to the RX pin.
  std::size_t queued() const { return rx_.size(); }
  // Bytes the firmware sent since the last call.
  std::vector<std::uint8_t> take_output();

  // Pulses completed since the last call, in the order they ended.
  std::vector<Pulse> take_pulses();
  // Edges since the last call (every pin change).
  std::vector<PinEdge> take_edges();
  bool pin_high(int channel) const { return level_[channel]; }
  // The chip drives the pin (DDR set), rather than listening on it.
  bool pin_is_output(int channel) const;

  // The line of a pin driven from outside at a cycle (an ESC answering
  // bidirectional DShot), as the chip's input sees it then: applied between
  // instructions, so within one instruction (1-4 cycles) of `cycle`.
  void drive_at(std::uint64_t cycle, int channel, bool high);
  // Called at every edge the chip makes (not those from drive_at), as it
  // happens: what an emulated ESC answers from.
  void set_edge_listener(std::function<void(const PinEdge&)> listener) {
    listener_ = std::move(listener);
  }
  // Driven while the chip drove the same pin (a bus fight on hardware).
  int drive_conflicts() const { return drive_conflicts_; }

  // Fault injection: clears the interrupt flag in SREG, as a firmware bug
  // that left interrupts off would.
  void disable_interrupts();

  // Callbacks from simavr (public for the C trampolines); a pin's
  // notification hands back its PinParam.
  struct PinParam {
    AvrBoard* board;
    int channel;
  };
  void on_pin(int channel, bool high);
  void on_uart_out(std::uint8_t byte);
  void on_xoff(bool off);
  // Times simavr's receiver was full (bytes then wait, as behind RTS).
  int xoffs() const { return xoffs_; }

  // The ATmega328P's receiver, which simavr does not model (its FIFO holds
  // 64 bytes): two complete bytes in the receive buffer and a third in the
  // shift register; a start bit that comes while all three wait unread is
  // a data overrun, and the byte in the shift register is lost on the chip
  // (datasheet, USART: DOR). Counted here at every start bit; a test that
  // sees one fails: on the chip a frame would have been lost.
  static constexpr int kReceiveDepth = 3;
  int overruns() const { return overruns_; }
  // The longest a complete byte waited before the firmware read it, in
  // microseconds (from its RXC to the read of UDR0). Over about two and a
  // half byte times (100 us at 250000 baud) the next start bit can find the
  // receiver full.
  double longest_unread_us() const { return static_cast<double>(longest_unread_) / 16.0; }
  void reset_longest_unread() { longest_unread_ = 0; }
  // Where the cycles went: with MOTORMIX_AVR_PROFILE=FILE set, every
  // instruction's cycles (an interrupt's entry counted on the one it
  // followed) are added up by program address and appended to FILE as
  // "address cycles" lines when the board goes (tools/avr_profile.py names
  // the functions).

 private:
  struct Pending {
    std::uint64_t cycle;
    std::uint8_t byte;
  };
  void feed_due_bytes();
  void note_reads();
  void apply_due_drives();
  struct Drive {
    std::uint64_t cycle;
    std::uint64_t order;
    int channel;
    bool high;
    bool operator>(const Drive& o) const {
      return cycle != o.cycle ? cycle > o.cycle : order > o.order;
    }
  };
  std::priority_queue<Drive, std::vector<Drive>, std::greater<Drive>> drives_;
  std::uint64_t drive_order_ = 0;
  bool driving_ = false;
  int drive_conflicts_ = 0;
  std::function<void(const PinEdge&)> listener_;
  avr_irq_t* pin_irq_[kChannels] = {};

  avr_t* avr_ = nullptr;
  avr_irq_t* uart_in_ = nullptr;
  bool xoff_ = false;
  int xoffs_ = 0;
  std::string profile_path_;
  std::vector<std::uint64_t> profile_;  // cycles by flash word
  std::uint64_t byte_cycles_;
  std::deque<Pending> rx_;
  std::uint64_t rx_free_at_ = 0;
  ::avr_uart_t* uart_ = nullptr;
  std::uint64_t injected_ = 0;
  std::deque<std::uint64_t> unread_;  // RXC cycles of the bytes not read yet
  int overruns_ = 0;
  std::uint64_t longest_unread_ = 0;
  std::vector<std::uint8_t> tx_;
  std::vector<PinEdge> edges_;
  std::vector<Pulse> pulses_;
  bool level_[kChannels] = {};
  std::uint64_t rise_[kChannels] = {};
  PinParam pin_params_[kChannels] = {};
};

}  // namespace motormix::avr
