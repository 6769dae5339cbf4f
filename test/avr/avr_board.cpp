#include "avr_board.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

extern "C" {
#include <avr_extint.h>
#include <avr_ioport.h>
#include <avr_uart.h>
#include <sim_avr.h>
#include <sim_elf.h>
#include <sim_interrupts.h>
#include <sim_irq.h>
#include <sim_regbit.h>
}

namespace motormix::avr {
namespace {

void pin_changed(avr_irq_t*, std::uint32_t value, void* param) {
  auto* p = static_cast<AvrBoard::PinParam*>(param);
  p->board->on_pin(p->channel, value != 0);
}

void uart_out(avr_irq_t*, std::uint32_t value, void* param) {
  static_cast<AvrBoard*>(param)->on_uart_out(static_cast<std::uint8_t>(value));
}

void uart_xoff(avr_irq_t*, std::uint32_t, void* param) {
  static_cast<AvrBoard*>(param)->on_xoff(true);
}
void uart_xon(avr_irq_t*, std::uint32_t, void* param) {
  static_cast<AvrBoard*>(param)->on_xoff(false);
}

}  // namespace

AvrBoard::AvrBoard(const std::string& elf_path, unsigned baud)
    : byte_cycles_(static_cast<std::uint64_t>(kCpuHz * 10.0 / baud)) {
  elf_firmware_t fw{};
  if (elf_read_firmware(elf_path.c_str(), &fw) != 0) {
    throw std::runtime_error("cannot read the firmware " + elf_path);
  }
  avr_ = avr_make_mcu_by_name("atmega328p");
  if (!avr_) throw std::runtime_error("simavr has no atmega328p");
  avr_init(avr_);
  avr_load_firmware(avr_, &fw);  // copies the image: ours to free
  std::free(fw.flash);
  std::free(fw.eeprom);
  avr_->frequency = static_cast<std::uint32_t>(kCpuHz);
  if (const char* path = std::getenv("MOTORMIX_AVR_PROFILE")) {
    profile_path_ = path;
    profile_.assign((avr_->flashend + 1u) / 2u, 0);
  }
  avr_->log = 0;
  // D2 and D3 (motors 1 and 2) are also INT0 and INT1, low-level triggered
  // at reset; the firmware never enables them, but simavr polls such a pin
  // every cycle while it is low, which is most of the time for a pulse pin
  // and nearly always for a DShot one: the simulation ran at half real time
  // (1.78 s per simulated second with DShot, 0.88 with pulses, measured).
  // Off: the firmware sees the same chip (the interrupts stay masked), and
  // a simulated second takes 0.29 s and 0.32 s.
  avr_extint_set_strict_lvl_trig(avr_, 0, 0);
  avr_extint_set_strict_lvl_trig(avr_, 1, 0);

  // Polled UART: simavr would otherwise sleep on every empty poll, and
  // print what the firmware sends.
  std::uint32_t flags = 0;
  avr_ioctl(avr_, AVR_IOCTL_UART_GET_FLAGS('0'), &flags);
  flags &= ~static_cast<std::uint32_t>(AVR_UART_FLAG_POLL_SLEEP | AVR_UART_FLAG_STDIO);
  avr_ioctl(avr_, AVR_IOCTL_UART_SET_FLAGS('0'), &flags);
  avr_irq_register_notify(avr_io_getirq(avr_, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUTPUT),
                          uart_out, this);
  // simavr's receiver holds a few bytes; past that it says XOFF and drops
  // what comes, so bytes wait here until XON.
  avr_irq_register_notify(avr_io_getirq(avr_, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XOFF),
                          uart_xoff, this);
  avr_irq_register_notify(avr_io_getirq(avr_, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_OUT_XON),
                          uart_xon, this);
  uart_in_ = avr_io_getirq(avr_, AVR_IOCTL_UART_GETIRQ('0'), UART_IRQ_INPUT);
  for (avr_io_t* io = avr_->io_port; io != nullptr; io = io->next) {
    if (io->kind != nullptr && std::string(io->kind) == "uart" &&
        reinterpret_cast<avr_uart_t*>(io)->name == '0') {
      uart_ = reinterpret_cast<avr_uart_t*>(io);
    }
  }
  if (uart_ == nullptr) throw std::runtime_error("simavr's atmega328p has no UART0");
  for (int ch = 0; ch < kChannels; ++ch) {
    const char port = ch < 6 ? 'D' : 'B';
    const int bit = ch < 6 ? ch + 2 : ch - 6;
    pin_params_[ch] = {this, ch};
    pin_irq_[ch] = avr_io_getirq(avr_, AVR_IOCTL_IOPORT_GETIRQ(port), bit);
    avr_irq_register_notify(pin_irq_[ch], pin_changed, &pin_params_[ch]);
  }
}

AvrBoard::~AvrBoard() {
  if (!profile_path_.empty()) {
    if (std::FILE* f = std::fopen(profile_path_.c_str(), "a")) {
      for (std::size_t w = 0; w < profile_.size(); ++w) {
        if (profile_[w] != 0) {
          std::fprintf(f, "%zu %llu\n", 2 * w, static_cast<unsigned long long>(profile_[w]));
        }
      }
      std::fclose(f);
    }
  }
  if (avr_) {
    avr_terminate(avr_);  // frees what it allocated, not the part itself
    std::free(avr_);
  }
}

std::uint64_t AvrBoard::cycle() const { return avr_->cycle; }

void AvrBoard::feed_due_bytes() {
  while (!xoff_ && !rx_.empty() && rx_.front().cycle <= avr_->cycle) {
    // simavr sets RXC one of its byte times after the byte is raised, and
    // counts a parity bit 8N1 does not have (11 bits): the wire's 10 here,
    // so that RXC comes when the chip's would.
    uart_->cycles_per_byte = byte_cycles_;
    note_reads();
    const std::uint64_t now = avr_->cycle;
    // This byte's start bit: the bytes complete by now and unread fill the
    // chip's receiver, or not.
    const auto complete = static_cast<int>(
        std::count_if(unread_.begin(), unread_.end(), [&](std::uint64_t c) { return c <= now; }));
    if (complete >= kReceiveDepth) ++overruns_;
    avr_raise_irq(uart_in_, rx_.front().byte);
    rx_.pop_front();
    ++injected_;
    unread_.push_back(now + byte_cycles_);
  }
}

void AvrBoard::note_reads() {
  // simavr's FIFO (64 entries; its cursors as in its fifo_declare.h): what
  // it holds is what the firmware has not read.
  const auto& in = uart_->input;
  const std::uint64_t held = static_cast<std::uint64_t>((in.write + uart_fifo_fifo_size - in.read) &
                                                        (uart_fifo_fifo_size - 1));
  const std::uint64_t now = avr_->cycle;
  while (unread_.size() > held) {
    const std::uint64_t rxc = unread_.front();
    unread_.pop_front();
    if (now > rxc) longest_unread_ = std::max(longest_unread_, now - rxc);
  }
  // RXC as the chip's: set while a complete byte waits, clear otherwise.
  // simavr raises it a byte time after the first byte and then lets the
  // firmware read no faster than one byte a byte time on average since; a
  // firmware catching up after a long wait then reads the bytes the chip
  // would hand it at once a byte time late each, and could read a byte
  // still being shifted in when one waits behind a complete one.
  if (unread_.empty()) return;
  const bool complete = unread_.front() <= now;
  const bool raised = avr_regbit_get(avr_, uart_->rxc.raised) != 0;
  uart_->rx_cnt = 0;  // its pacing off: this model paces
  if (complete && (!raised || !uart_->rxc.pending)) {
    // Level-triggered on the chip: with RXC still set after an interrupt
    // (a byte behind the one it read), the interrupt comes again at once;
    // simavr would wait for its next pacing tick.
    avr_raise_interrupt(avr_, &uart_->rxc);
  } else if (!complete && raised) {
    avr_clear_interrupt(avr_, &uart_->rxc);
    avr_regbit_clear(avr_, uart_->rxc.raised);  // sticky: not cleared by the call above
  }
}

void AvrBoard::on_xoff(bool off) {
  if (off && !xoff_) ++xoffs_;
  xoff_ = off;
}

bool AvrBoard::pin_is_output(int channel) const {
  const char port = channel < 6 ? 'D' : 'B';
  const int bit = channel < 6 ? channel + 2 : channel - 6;
  avr_ioport_state_t state{};
  avr_ioctl(avr_, AVR_IOCTL_IOPORT_GETSTATE(port), &state);
  return ((state.ddr >> bit) & 1u) != 0;
}

void AvrBoard::drive_at(std::uint64_t cycle, int channel, bool high) {
  drives_.push({cycle, drive_order_++, channel, high});
}

void AvrBoard::apply_due_drives() {
  while (!drives_.empty() && drives_.top().cycle <= avr_->cycle) {
    const Drive d = drives_.top();
    drives_.pop();
    if (pin_is_output(d.channel)) ++drive_conflicts_;
    driving_ = true;
    avr_raise_irq(pin_irq_[d.channel], d.high ? 1u : 0u);
    driving_ = false;
  }
}

bool AvrBoard::run_until(std::uint64_t cycle) {
  while (avr_->cycle < cycle) {
    if (!rx_.empty() && rx_.front().cycle <= avr_->cycle) feed_due_bytes();
    if (!drives_.empty() && drives_.top().cycle <= avr_->cycle) apply_due_drives();
    const std::size_t word = avr_->pc / 2u;
    const std::uint64_t before = avr_->cycle;
    const int state = avr_run(avr_);
    if (!unread_.empty()) note_reads();
    if (word < profile_.size()) profile_[word] += avr_->cycle - before;
    if (state == cpu_Done || state == cpu_Crashed) return false;
  }
  return true;
}

void AvrBoard::send(const std::uint8_t* bytes, std::size_t n) {
  std::uint64_t t = std::max<std::uint64_t>(rx_free_at_, avr_->cycle);
  for (std::size_t i = 0; i < n; ++i) {
    rx_.push_back({t, bytes[i]});  // its start bit: complete a byte time later
    t += byte_cycles_;
  }
  rx_free_at_ = t;
}

std::vector<std::uint8_t> AvrBoard::take_output() {
  std::vector<std::uint8_t> out;
  out.swap(tx_);
  return out;
}

std::vector<Pulse> AvrBoard::take_pulses() {
  std::vector<Pulse> out;
  out.swap(pulses_);
  return out;
}

std::vector<PinEdge> AvrBoard::take_edges() {
  std::vector<PinEdge> out;
  out.swap(edges_);
  return out;
}

void AvrBoard::disable_interrupts() { avr_->sreg[S_I] = 0; }

void AvrBoard::on_pin(int channel, bool high) {
  if (level_[channel] == high) return;
  level_[channel] = high;
  const std::uint64_t now = avr_->cycle;
  edges_.push_back({now, channel, high, driving_});
  if (!driving_ && listener_) listener_(edges_.back());
  if (high) {
    rise_[channel] = now;
  } else if (rise_[channel] != 0) {
    pulses_.push_back(
        {channel, rise_[channel], static_cast<double>(now - rise_[channel]) * 1e6 / kCpuHz});
  }
}

void AvrBoard::on_uart_out(std::uint8_t byte) { tx_.push_back(byte); }

}  // namespace motormix::avr
