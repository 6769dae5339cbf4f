#include "realtime_bridge.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <stdexcept>

namespace motormix::avr {

namespace {

constexpr double kChunkUs = 50.0;  // simulated between looks at the pty and the clock
constexpr double kSleepAtLeastUs = 500.0;

}  // namespace

std::int64_t steady_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

RealtimeBridge::RealtimeBridge(const std::string& elf_path, const Escs& escs)
    : board_(elf_path),
      escs_(std::make_unique<BidirEscs>(board_, escs.count, escs.frame_bit_cycles, escs.noise)),
      keep_pin_records_(false) {
  escs_->follow_throttle(escs.full_erpm);
  open_pty_and_start();
}

RealtimeBridge::RealtimeBridge(const std::string& elf_path) : board_(elf_path) {
  open_pty_and_start();
}

void RealtimeBridge::open_pty_and_start() {
  master_ = posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (master_ < 0 || grantpt(master_) != 0 || unlockpt(master_) != 0) {
    throw std::runtime_error("cannot create a pseudo-terminal");
  }
  char name[128];
  if (ptsname_r(master_, name, sizeof name) != 0) throw std::runtime_error("ptsname_r failed");
  slave_path_ = name;
  started_us_ = steady_us();
  thread_ = std::thread([this] { run(); });
}

RealtimeBridge::~RealtimeBridge() {
  stop();
  if (master_ >= 0) ::close(master_);
}

void RealtimeBridge::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
  if (stopped_) return;
  stopped_ = true;
  const std::int64_t now = steady_us();
  const double life_ms = static_cast<double>(now - started_us_) / 1000.0;
  const double absent_ms = static_cast<double>(absent_us(started_us_, now)) / 1000.0;
  if (absent_ms > kBusyShare * life_ms || life_max_lag_us_ > kBusyStallUs)
    std::printf(
        "[chip-busy] the simulated chip was absent %.0f ms of its %.0f ms (%.0f %%) and %.1f ms "
        "behind at worst: the machine was too busy to keep it in real time (%.2f s of computing a "
        "simulated second)\n",
        absent_ms, life_ms, 100.0 * absent_ms / life_ms, life_max_lag_us_ / 1000.0, cost());
}

RealtimeBridge::Receiver RealtimeBridge::receiver() {
  stop();
  const Receiver r{board_.overruns(), board_.longest_unread_us()};
  std::printf("receiver: longest unread %.1f us, overruns %d (depth %d), %llu bytes in\n",
              r.longest_unread_us, r.overruns, AvrBoard::kReceiveDepth,
              static_cast<unsigned long long>(bytes_in()));
  return r;
}

void RealtimeBridge::wait_chip_time(std::int64_t from_us, double chip_ms) {
  const auto chip_us = static_cast<std::int64_t>(chip_ms * 1000.0);
  while (true) {
    const std::int64_t now = steady_us();
    if (now - from_us - absent_us(from_us, now) >= chip_us || now - from_us >= 10 * chip_us) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

std::vector<TimedPulse> RealtimeBridge::take_pulses() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<TimedPulse> out;
  out.swap(pulses_);
  return out;
}

std::int64_t RealtimeBridge::absent_us(std::int64_t from_us, std::int64_t to_us) {
  std::lock_guard<std::mutex> lock(mutex_);
  std::int64_t sum = 0;
  for (const Absence& a : absences_)
    sum += std::max<std::int64_t>(0, std::min(a.to_us, to_us) - std::max(a.from_us, from_us));
  return sum;
}

std::vector<RealtimeBridge::TimedEdge> RealtimeBridge::take_edges() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<TimedEdge> out;
  out.swap(edges_);
  return out;
}

void RealtimeBridge::run() {
  std::int64_t wall0 = steady_us();
  const double sim0 = board_.now_us();
  std::uint8_t buf[512];
  while (!stop_) {
    const ssize_t n = ::read(master_, buf, sizeof buf);
    if (n > 0) {
      board_.send(buf, static_cast<std::size_t>(n));
      bytes_in_ += static_cast<std::uint64_t>(n);
    }
    const std::int64_t busy_from = steady_us();
    board_.run_for_us(kChunkUs);
    busy_us_ += static_cast<std::uint64_t>(steady_us() - busy_from);
    simulated_us_ += static_cast<std::uint64_t>(kChunkUs);
    const std::vector<std::uint8_t> out = board_.take_output();
    if (!out.empty()) {
      // The host reads its end; bytes it leaves unread are dropped, as a
      // USB serial adapter's buffer would.
      [[maybe_unused]] const ssize_t w = ::write(master_, out.data(), out.size());
    }
    const std::vector<PinEdge> edges = board_.take_edges();
    const std::vector<Pulse> pulses = board_.take_pulses();
    if (!edges.empty() || !pulses.empty()) {
      // When an edge happened as seen from outside: now, less the simulated
      // time since it (a simulation running late shows as latency, never
      // hides it).
      const std::int64_t wall_now = steady_us();
      const double sim_now = board_.now_us();
      const auto wall_of = [&](std::uint64_t cycle) {
        return wall_now - static_cast<std::int64_t>(sim_now - static_cast<double>(cycle) / 16.0);
      };
      std::lock_guard<std::mutex> lock(mutex_);
      if (keep_pin_records_)
        for (const PinEdge& e : edges) edges_.push_back({e, wall_of(e.cycle)});
      if (keep_pin_records_)
        for (const Pulse& p : pulses)
          pulses_.push_back({p.channel, wall_of(p.rise_cycle), p.width_us, p.rise_cycle});
    }
    const double sim_elapsed = board_.now_us() - sim0;
    const double wall_elapsed = static_cast<double>(steady_us() - wall0);
    if (sim_elapsed > wall_elapsed) {
      std::this_thread::sleep_for(
          std::chrono::microseconds(static_cast<std::int64_t>(sim_elapsed - wall_elapsed)));
    } else {
      if (wall_elapsed - sim_elapsed > max_lag_us_.load()) max_lag_us_ = wall_elapsed - sim_elapsed;
      life_max_lag_us_ = std::max(life_max_lag_us_, wall_elapsed - sim_elapsed);
    }
    // Late by more than a chunk: catch up from here rather than run fast
    // (time lost is lost, as for a chip whose clock stopped).
    if (wall_elapsed - sim_elapsed > 2 * kSleepAtLeastUs) {
      const auto lost = static_cast<std::int64_t>(wall_elapsed - sim_elapsed);
      wall0 += lost;
      const std::int64_t now = steady_us();
      std::lock_guard<std::mutex> lock(mutex_);
      if (!absences_.empty() && now - lost <= absences_.back().to_us)
        absences_.back().to_us = now;
      else
        absences_.push_back({now - lost, now});
    }
  }
}

}  // namespace motormix::avr
