// What signing adds per message: signing and verifying an encoded
// motor_pwm_t (4 motors, 73 bytes) against encoding and decoding it, the
// baseline, in the same run; and the path motormix runs per message, a
// publisher's Policy::seal and a receiver's Policy::check of each fresh
// message (taken every time). Median of passes of N messages each.
//
//   signing_cost [--messages N] [--passes P]

#include "passes.hpp"

#include <motormix/motor_pwm_t.hpp>
#include <motormix/signing.hpp>
#include <motormix/signing_policy.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

using motormix::bench::median;

int main(int argc, char** argv) {
  int messages = 100000, passes = 7;
  if (!motormix::bench::read_passes(argc, argv, "signing_cost", 10000000, messages, passes))
    return 2;
  motormix::motor_pwm_t m{};
  m.num_motors = 4;
  m.command = {0.1f, 0.2f, 0.3f, 0.4f};
  m.pwm = {1100, 1200, 1300, 1400};
  m.direction = {0, 0, 0, 0};
  m.armed = 1;
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()) +
                                motormix::signing::kTrailerBytes);
  const int size = m.getEncodedSize();
  std::array<std::uint8_t, motormix::signing::kKeyBytes> bytes{};
  bytes[3] = 9;
  const motormix::signing::Key key(bytes);
  const std::int64_t t0 = 1764806400LL * 1000000LL;
  std::vector<double> codec_ns, sign_ns, verify_ns, policy_ns;
  volatile std::uint64_t sink = 0;
  for (int p = 0; p < passes; ++p) {
    motormix::signing::Signer signer(key, 1);
    motormix::signing::Verifier verifier(key);
    auto a = std::chrono::steady_clock::now();
    for (int k = 0; k < messages; ++k) {
      m.utime = k;
      m.encode(buf.data(), 0, size);
      motormix::motor_pwm_t out;
      sink = sink + static_cast<std::uint64_t>(out.decode(buf.data(), 0, size));
    }
    auto b = std::chrono::steady_clock::now();
    for (int k = 0; k < messages; ++k) {
      signer.sign("MOTOR_PWM", buf.data(), static_cast<std::size_t>(size), t0 + k,
                  buf.data() + size);
    }
    auto c = std::chrono::steady_clock::now();
    std::size_t n = 0;
    for (int k = 0; k < messages; ++k) {
      // The same signed message each time: every verification computes the
      // tag; the first is taken, the rest refused as replays after it.
      sink = sink + static_cast<std::uint64_t>(
                        verifier.verify("MOTOR_PWM", buf.data(), buf.size(), t0, &n));
    }
    auto d = std::chrono::steady_clock::now();
    motormix::signing::Policy publisher(motormix::signing::Mode::kRequire, key, 1);
    motormix::signing::Policy receiver(motormix::signing::Mode::kRequire, key, 2);
    for (int k = 0; k < messages; ++k) {
      const std::size_t signed_size =
          publisher.seal("MOTOR_PWM", buf.data(), static_cast<std::size_t>(size), t0 + k);
      sink = sink + receiver.check("MOTOR_PWM", buf.data(), signed_size, t0 + k).payload_size;
    }
    auto e = std::chrono::steady_clock::now();
    if (receiver.counts().signed_accepted != static_cast<std::uint64_t>(messages)) {
      std::fprintf(stderr, "signing_cost: the receiver refused fresh messages\n");
      return 1;
    }
    const auto per = [messages](auto x, auto y) {
      return std::chrono::duration<double, std::nano>(y - x).count() / messages;
    };
    codec_ns.push_back(per(a, b));
    sign_ns.push_back(per(b, c));
    verify_ns.push_back(per(c, d));
    policy_ns.push_back(per(d, e));
  }
  std::printf(
      "encode + decode (baseline): %.0f ns; sign: %.0f ns; verify: %.0f ns; sign + verify: "
      "%.2f us per message; Policy seal + check: %.2f us (median of %d passes of %d; target "
      "<= 2 us)\n",
      median(codec_ns), median(sign_ns), median(verify_ns),
      (median(sign_ns) + median(verify_ns)) / 1000.0, median(policy_ns) / 1000.0, passes, messages);
  return sink == 0 ? 1 : 0;
}
