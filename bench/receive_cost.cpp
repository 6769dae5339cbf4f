// What the bus's guard (bus::receive) costs per message: a 4-motor
// motor_pwm_t taken through it (policy off: fingerprint, length against the
// bytes, exact decode) against LCM's bare decode into the same reused
// message, the baseline, in the same run; and refusing a hostile one (array
// length 2^31-1), which LCM's bare decode cannot do without allocating
// gigabytes or throwing. Median of passes of N messages each.
//
//   receive_cost [--messages N] [--passes P]

#include "bus/receive.hpp"

#include "passes.hpp"

#include <motormix/motor_pwm_t.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

using motormix::bench::median;

int main(int argc, char** argv) {
  int messages = 1000000, passes = 7;
  if (!motormix::bench::read_passes(argc, argv, "receive_cost", 100000000, messages, passes))
    return 2;
  motormix::motor_pwm_t m{};
  m.num_motors = 4;
  m.command = {0.1f, 0.2f, 0.3f, 0.4f};
  m.pwm = {1100, 1200, 1300, 1400};
  m.direction = {0, 0, 0, 0};
  m.armed = 1;
  std::vector<std::uint8_t> good(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(good.data(), 0, static_cast<int>(good.size()));
  std::vector<std::uint8_t> hostile = good;
  hostile[16] = 0x7f;  // num_motors 2^31-1 (bytes 16..19, big-endian)
  hostile[17] = hostile[18] = hostile[19] = 0xff;
  const int size = static_cast<int>(good.size());
  // Through a volatile pointer: the bytes are not constants to the optimizer
  // (which would otherwise fold LCM's decode, and warn about it at -O3).
  const std::uint8_t* volatile good_bytes = good.data();
  const std::uint8_t* volatile hostile_bytes = hostile.data();
  motormix::signing::Policy off;
  motormix::bus::Refusals counts;
  std::vector<double> bare_ns, guarded_ns, refused_ns;
  volatile std::uint64_t sink = 0;
  motormix::motor_pwm_t out{};
  for (int p = 0; p < passes; ++p) {
    auto a = std::chrono::steady_clock::now();
    for (int k = 0; k < messages; ++k)
      sink = sink + static_cast<std::uint64_t>(out.decode(good_bytes, 0, size));
    auto b = std::chrono::steady_clock::now();
    for (int k = 0; k < messages; ++k) {
      sink = sink + static_cast<std::uint64_t>(motormix::bus::receive(off, "MOTOR_PWM", good_bytes,
                                                                      good.size(), 0, out, counts));
      sink = sink + static_cast<std::uint64_t>(out.num_motors);
    }
    auto c = std::chrono::steady_clock::now();
    for (int k = 0; k < messages; ++k)
      sink = sink + static_cast<std::uint64_t>(motormix::bus::receive(
                        off, "MOTOR_PWM", hostile_bytes, hostile.size(), 0, out, counts));
    auto d = std::chrono::steady_clock::now();
    const auto per = [messages](auto x, auto y) {
      return std::chrono::duration<double, std::nano>(y - x).count() / messages;
    };
    bare_ns.push_back(per(a, b));
    guarded_ns.push_back(per(b, c));
    refused_ns.push_back(per(c, d));
  }
  if (counts.taken != static_cast<std::uint64_t>(messages) * static_cast<std::uint64_t>(passes) ||
      counts.bad_length != counts.taken) {
    std::fprintf(stderr, "receive_cost: the guard took or refused the wrong messages\n");
    return 1;
  }
  std::printf(
      "LCM decode (baseline): %.1f ns; bus::receive, taken: %.1f ns (%.2fx); hostile length "
      "refused: %.1f ns (median of %d passes of %d)\n",
      median(bare_ns), median(guarded_ns), median(guarded_ns) / median(bare_ns), median(refused_ns),
      passes, messages);
  return sink == 0 ? 1 : 0;
}
