// The signing policy on arbitrary bytes. Chunks (one length byte, one mode
// byte, then the bytes) are checked by a receiver under `require`: raw, or
// first signed with the key by a publisher (the chunk's mode byte picks the
// channel, moves the clock, and may flip one bit of the signed message).
// What must hold: a message with a bit flipped after signing is never taken;
// the same bytes are never taken twice on a channel; whatever is taken
// carries a tag that a second verifier, with the key and no memory of
// timestamps, finds good (the clock is deterministic, so the fuzzer may
// bring a message signed in an earlier execution: a capture replayed into a
// receiver that never saw it, which is taken once, as documented); the
// payload handed on is never longer than what arrived; every check is
// counted once by its reason; and `off` cuts exactly a trailer-shaped tail.

#include <motormix/signing_policy.hpp>

#include <array>
#include <cstdint>
#include <cstdlib>
#include <set>
#include <string>
#include <vector>

namespace {

motormix::signing::Key fuzz_key() {
  std::array<std::uint8_t, motormix::signing::kKeyBytes> bytes{};
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<std::uint8_t>(i * 13 + 1);
  return motormix::signing::Key(bytes);
}

void require(bool ok) {
  if (!ok) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace motormix::signing;
  static const Key key = fuzz_key();
  static const std::string channels[3] = {"SETPOINT", "PID", "MOTOR_PWM"};
  Policy publisher(Mode::kRequire, key, 4);
  Policy receiver(Mode::kRequire, key, 9);
  Policy off;
  std::int64_t now = 1'764'806'400'000'000;
  std::set<std::vector<std::uint8_t>> taken;  // channel, 0, bytes of every message taken
  std::uint64_t checks = 0;
  std::size_t at = 0;
  while (at + 2 <= size) {
    const std::size_t len = std::min<std::size_t>(data[at], size - at - 2);
    const std::uint8_t mode = data[at + 1];
    std::vector<std::uint8_t> msg(data + at + 2, data + at + 2 + len);
    at += 2 + len;
    const std::string& channel = channels[mode % 3];
    now += static_cast<std::int64_t>((mode >> 2) & 7) * 1'000'000 - 2'000'000;  // -2..+5 s
    bool flipped = false;
    if (mode & 0x20) {
      const std::size_t n = msg.size();
      msg.resize(n + kTrailerBytes);
      publisher.seal(channel, msg.data(), n, now);
      if (mode & 0x40) {
        msg[static_cast<std::size_t>(mode) * 7 % msg.size()] ^=
            static_cast<std::uint8_t>(1U << (mode % 8));
        flipped = true;
      }
    }
    const Inbound in = receiver.check(channel, msg.data(), msg.size(), now);
    ++checks;
    require(in.payload_size <= msg.size());
    if (in.accept) {
      require(!flipped);
      std::vector<std::uint8_t> key_of(channel.begin(), channel.end());
      key_of.push_back(0);
      key_of.insert(key_of.end(), msg.begin(), msg.end());
      require(taken.insert(key_of).second);  // never the same bytes twice
      require(in.payload_size + kTrailerBytes == msg.size());
      Verifier fresh(key, 1e9);  // no timestamps remembered, any clock
      std::size_t n = 0;
      require(fresh.verify(channel, msg.data(), msg.size(), now, &n) == Verdict::kSigned);
    }
    const Inbound plain = off.check(channel, msg.data(), msg.size(), now);
    require(plain.accept);
    require(plain.payload_size ==
            (has_trailer(msg.data(), msg.size()) ? msg.size() - kTrailerBytes : msg.size()));
  }
  const PolicyCounts& c = receiver.counts();
  require(c.signed_accepted + c.unsigned_accepted + c.rejected() == checks);
  require(c.unsigned_accepted == 0);
  return 0;
}
