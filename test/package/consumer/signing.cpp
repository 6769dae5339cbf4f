// An outside project signing and verifying a message with the installed
// motormix::signing (libsodium linked through it).
#include <motormix/signing.hpp>

#include <array>
#include <cstdio>
#include <vector>

int main() {
  std::array<std::uint8_t, motormix::signing::kKeyBytes> bytes{};
  bytes[0] = 42;
  const motormix::signing::Key key(bytes);
  motormix::signing::Signer signer(key, 9);
  const std::vector<std::uint8_t> payload = {1, 2, 3, 4};
  const std::int64_t now_us = 1764806400LL * 1000000LL;
  const auto signed_msg = signer.signed_copy("SETPOINT", payload.data(), payload.size(), now_us);
  motormix::signing::Verifier verifier(key);
  std::size_t n = 0;
  const auto verdict =
      verifier.verify("SETPOINT", signed_msg.data(), signed_msg.size(), now_us, &n);
  std::printf("signing: %s, payload %zu bytes\n", motormix::signing::to_string(verdict), n);
  return verdict == motormix::signing::Verdict::kSigned && n == payload.size() ? 0 : 1;
}
